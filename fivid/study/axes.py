"""The conditions a study can sweep, with their SI units and long names (the ``sweep:`` keys of a study config)."""

from __future__ import annotations

__all__ = ["AXES"]

#: sweepable condition -> (SI units, long name); `seed` is an integer
AXES = {
    "normal_load": ("N", "normal load"),
    "sliding_velocity": ("m s-1", "sliding velocity"),
    "roughness_ra": ("m", "roughness Ra"),
    "mu": ("1", "kinetic friction coefficient"),
    "mu_static": ("1", "static friction coefficient"),
    "seed": ("1", "random seed"),
    "mesh": ("1", "mesh refinement factor (divisions x factor)"),
    "time_step": ("1", "time step as a fraction of the critical step"),
}
