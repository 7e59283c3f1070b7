"""Small model configs (mappings for fivid.fe.load_model) shared by the solver tests. Synthetic geometry.

The benchmark models (impacting bars, block on a base) live once, with the verification cases that use them
(fivid/verify/models.py)."""

import numpy as np

from fivid.verify.models import STEEL, block_on_base, impacting_bars

__all__ = ["STEEL", "block_on_base", "impacting_bars", "cantilever", "stencil_bound", "stencil_matrix", "F32_RES"]

#: float32's unit round-off: a coefficient rounded to nearest moves by at most this fraction of itself
F32_RES = 2.0 ** -24


def stencil_bound(K, w, n_terms: int = 32):
    """Largest ``|f_stencil - K w|`` per dof [N] for the block stencils against the assembled ``K`` (scipy sparse):
    float64 round-off, ``n_terms eps sum_j |K_ij w_j|`` (at most 4 elements x 8 terms per entry, summed in another
    order), plus the float32 rounding of the mapped patches' coefficients in difference form
    (:func:`fivid.solver.stencil._difference_form`), ``2^-24 sum_j |K_ij| |w_j - w_own(j)|`` with ``own(j)`` the
    row's own node's dof of ``j``'s component (0 on the own node: the difference form leaves it out)."""
    K = K.tocoo()
    r, c, d = K.row, K.col, np.abs(K.data)
    n = K.shape[0]
    diff = np.bincount(r, d * np.abs(w[c] - w[2 * (r // 2) + c % 2]), minlength=n)
    plain = np.bincount(r, d * np.abs(w[c]), minlength=n)
    return F32_RES * diff + n_terms * np.finfo(float).eps * plain


def stencil_matrix(st, n_dofs: int):
    """The matrix the stencil kernel applies (global dof order), column by column from unit vectors: the reference
    K of a time-loop test whose stencil is not the assembled K to round-off (float32 mapped coefficients)."""
    from fivid.solver.stencil import apply_stencils

    return np.stack([apply_stencils(st, e) for e in np.eye(n_dofs)], axis=1)


def cantilever(*, nx=16, ny=3, v0=0.5, mapped=False, sheared=False, beta=0.0, spring=None):
    """A steel cantilever 32 x 6 mm clamped on the left, initial transverse velocity ``v0``; optionally a
    trapezoidal (mapped) or parallelogram (sheared: uniform, not rectangular) outline and a spring to ground
    at the tip."""
    top_right = ["32 mm", "5 mm"] if mapped else ["34 mm", "6 mm"] if sheared else ["32 mm", "6 mm"]
    top_left = ["2 mm", "6 mm"] if sheared else ["0 mm", "6 mm"]
    cfg = {
        "name": "cantilever",
        "plane": "stress",
        "materials": {"steel": STEEL},
        "bodies": {"beam": {"corners": [["0 mm", "0 mm"], ["32 mm", "0 mm"], top_right, top_left],
                            "divisions": [nx, ny], "material": "steel", "thickness": "5 mm", "clamp": ["left"],
                            "initial_velocity": ["0 m/s", f"{v0} m/s"]}},
        "damping": {"alpha": "0 s-1", "beta": f"{beta} s"},
        "sensors": [{"name": "tip", "body": "beam", "at": ["32 mm", "0 mm"], "direction": "y"}],
    }
    if spring:
        cfg["springs"] = [{"name": "tip_spring", "a": {"body": "beam", "at": ["32 mm", "0 mm"]}, "b": "ground",
                           "component": "y", "stiffness": f"{spring} N/m", "damping": "0.01 N s/m"}]
    return cfg
