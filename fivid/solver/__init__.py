"""The explicit transient solver with frictional contact (DESIGN §5, §7).

Central differences with lumped mass and Rayleigh damping (stiffness part folded into one stencil pass),
node-to-segment contact by forward-increment Lagrange multipliers with Coulomb stick/slip, friction
coefficients per node and step from a friction-law object, the rig's loading sequence, anti-aliased
outputs and an energy balance. :func:`simulate` takes its inputs in groups: ``simulate(model, condition,
friction, *, schedule, integration, output)`` (:class:`OperatingCondition`, :class:`FrictionInput`,
:class:`RunSchedule`, :class:`IntegrationOptions`, :class:`OutputOptions`). Numba kernels live in
:mod:`fivid.solver._stencil_kernels`, ``_contact_kernels``, ``_loop_kernels`` and ``_reduced_kernels``
(compilation setting in :mod:`fivid.solver._kernels`) and are imported only when a simulation runs.
"""

from fivid.errors import SimulationDiverged
from fivid.friction.inputs import FrictionInput, OperatingCondition
from fivid.solver.driver import simulate
from fivid.solver.options import IntegrationOptions, OutputOptions, RunSchedule, SimulationInputs
from fivid.solver.step_halving import time_step_halving
from fivid.solver.timestep import critical_time_step, stable_step

__all__ = ["simulate", "OperatingCondition", "FrictionInput", "RunSchedule", "IntegrationOptions", "OutputOptions",
           "SimulationInputs", "critical_time_step", "stable_step", "time_step_halving", "SimulationDiverged"]
