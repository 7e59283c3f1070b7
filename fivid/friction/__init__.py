"""Friction laws and elements: Coulomb, perturbed Coulomb, Jenkins (Masing) and Iwan."""
