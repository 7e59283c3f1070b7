"""Finite-element models: meshes, element matrices, assembly, modal analysis."""
