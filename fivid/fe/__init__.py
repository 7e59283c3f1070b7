"""Finite-element models of a rig: config -> structured Q4 blocks, assembly, modal analysis, CEA.

:mod:`fivid.fe.beam` (Euler-Bernoulli cantilever of the damper models) is imported from its module.

Heavy dependencies (scipy.sparse, xarray) are imported inside the functions that use them.
"""

from fivid.fe.assembly import (
    consistent_mass,
    damping_matrix,
    element_mass_q4,
    element_stiffness_q4,
    lumped_mass,
    stiffness_matrix,
)
from fivid.fe.damping import RayleighFit, fit_rayleigh_least_squares, rayleigh_through_two_ratios
from fivid.fe.build import load_model
from fivid.fe.cea import cea_to_json, complex_eigenvalue_analysis
from fivid.fe.contact import linearise_contact, linearise_preloaded_contact
from fivid.fe.loads import external_load_vector, pressure_forces, static_response
from fivid.fe.modal import modal_analysis, modes_to_json, write_modes
from fivid.fe.model import (
    Block,
    ContactPair,
    Material,
    Model,
    Motion,
    PointMass,
    PressureLoad,
    Reaction,
    Sensor,
    Spring,
)
from fivid.fe.prestress import buckling_load_factors, geometric_stiffness_matrix
from fivid.fe.static import preload_state

__all__ = [
    "Block",
    "ContactPair",
    "Material",
    "Model",
    "Motion",
    "PointMass",
    "PressureLoad",
    "Reaction",
    "Sensor",
    "Spring",
    "load_model",
    "element_stiffness_q4",
    "element_mass_q4",
    "stiffness_matrix",
    "lumped_mass",
    "consistent_mass",
    "damping_matrix",
    "rayleigh_through_two_ratios",
    "fit_rayleigh_least_squares",
    "RayleighFit",
    "pressure_forces",
    "external_load_vector",
    "static_response",
    "linearise_contact",
    "linearise_preloaded_contact",
    "preload_state",
    "geometric_stiffness_matrix",
    "buckling_load_factors",
    "modal_analysis",
    "modes_to_json",
    "write_modes",
    "complex_eigenvalue_analysis",
    "cea_to_json",
]
