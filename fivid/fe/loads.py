"""Applied loads: consistent nodal forces of pressure loads, and the linear static response to them.

The explicit solver ramps these forces (:mod:`fivid.solver.setup`); the static contact preload
(:mod:`fivid.fe.static`) and modal analysis about it include them at full value.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import ConfigError
from fivid.fe.assembly import stiffness_matrix

__all__ = ["pressure_forces", "external_load_vector", "static_response"]


def pressure_forces(model, load) -> np.ndarray:
    """Consistent nodal forces of one :class:`~fivid.fe.model.PressureLoad` at full pressure [N], shape (n_dofs,).

    A uniform traction ``-p n`` on a straight segment ``(a, b)`` of length ``L`` integrates against the linear
    shape functions to ``-p t L/2 n`` on each end node (exact). With the outward normal
    ``n L = (dy, -dx)`` (``b - a`` turned clockwise) each node gets ``-p t/2 (dy, -dx)``; reference geometry.
    The resultant on a straight edge is ``-p L_edge t n``; on a closed edge it is zero.
    """
    block = model.block(load.body)
    seg = np.asarray(load.segments, dtype=np.int64).reshape(-1, 2)
    d = model.coords[seg[:, 1]] - model.coords[seg[:, 0]]
    fx = -0.5 * load.pressure * block.thickness * d[:, 1]
    fy = 0.5 * load.pressure * block.thickness * d[:, 0]
    f = np.zeros(model.n_dofs)
    for end in (0, 1):
        np.add.at(f, 2 * seg[:, end], fx)
        np.add.at(f, 2 * seg[:, end] + 1, fy)
    return f


def external_load_vector(model) -> np.ndarray:
    """Sum of the nodal forces of all pressure loads at their full (end-of-ramp) values [N], shape (n_dofs,)."""
    f = np.zeros(model.n_dofs)
    for load in model.loads:
        f += pressure_forces(model, load)
    return f


def static_response(model, *, imposed: np.ndarray | None = None) -> np.ndarray:
    """Linear static displacement [m] under the full pressure loads, constrained dofs held at zero (or at
    ``imposed``), shape (n_dofs,).

    Solves ``K_ff u_f = F_f - K_fc u_c`` (springs included; contacts ignored: for a contact preload use
    :func:`fivid.fe.static.preload_state`).

    Parameters
    ----------
    model : Model
    imposed : ndarray (n_dofs,), optional
        Displacements [m] of the constrained dofs (``Model.fixed_dofs``; other entries ignored), default 0.

    Raises
    ------
    ConfigError
        The constrained model is not fixed against rigid-body motion (``K_ff`` singular).
    """
    import scipy.sparse.linalg as sla

    K = stiffness_matrix(model).tocsc()
    free = model.free_dofs
    F = external_load_vector(model)
    u = np.zeros(model.n_dofs)
    fixed = np.asarray(model.fixed_dofs, dtype=np.int64)
    if imposed is not None:
        u[fixed] = np.asarray(imposed, dtype=float)[fixed]
        F = F - K[:, fixed] @ u[fixed]
    if free.size == 0:
        return u
    Kff = K[free][:, free]
    try:
        lu = sla.splu(Kff)
    except RuntimeError:
        raise ConfigError("the static response needs a model held against rigid-body motion (clamps or motions); "
                          "K restricted to the free dofs is singular") from None
    uf = lu.solve(F[free])
    scale = float(np.abs(F).max()) or 1.0
    if not np.all(np.isfinite(uf)) or np.abs(Kff @ uf - F[free]).max() > 1e-6 * scale:
        raise ConfigError("the static response needs a model held against rigid-body motion (clamps or motions); "
                          "K restricted to the free dofs is singular")
    u[free] = uf
    return u
