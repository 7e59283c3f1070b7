"""The explicit transient solver with frictional contact (DESIGN §5, §7).

Central differences with lumped mass and Rayleigh damping (stiffness part folded into one stencil pass),
node-to-segment contact by forward-increment Lagrange multipliers with Coulomb stick/slip, friction
coefficients per node and step from a friction-law object, the rig's loading sequence, anti-aliased
outputs and an energy balance. Numba kernels live in :mod:`fivid.solver._stencil_kernels`, ``_contact_kernels``, ``_loop_kernels`` and
``_reduced_kernels`` (compilation setting in :mod:`fivid.solver._kernels`) and are imported only
when a simulation runs.
"""

from fivid.solver.driver import SimulationDiverged, simulate
from fivid.solver.step_halving import time_step_halving
from fivid.solver.timestep import critical_time_step, stable_step

__all__ = ["simulate", "critical_time_step", "stable_step", "time_step_halving", "SimulationDiverged"]
