"""Jenkins element marching kernel (L0: numpy and numba only).

A Jenkins element is a spring of stiffness ``k`` in series with a Coulomb slider of slip force
``fs``. Driven by a displacement history it is rate independent: the force at sample ``j`` follows
from the force at ``j - 1`` by an elastic predictor and a return to the slip surface (exact for a
piecewise-linear path between samples).
"""

from numba import njit

__all__ = ["jenkins_march"]


@njit(cache=True)
def jenkins_march(x, stiffness, slip_force, initial_force, n_passes, force_out, anchor_out):
    """March a batch of Jenkins elements along displacement histories.

    Parameters
    ----------
    x : ndarray, shape (n_paths, n_samples)
        Displacements [m]. With ``n_passes > 1`` each row is one period, marched repeatedly.
    stiffness, slip_force : float
        Spring stiffness [N/m] and slip force [N] (> 0).
    initial_force : ndarray, shape (n_paths,)
        Force before the first sample's increment [N] (|f| <= slip_force), taken at ``x[:, 0]``.
    n_passes : int
        Number of passes over the samples; the outputs hold the last pass.
    force_out : ndarray, shape (n_paths, n_samples)
        Element force [N] (written).
    anchor_out : ndarray of int64, shape (n_paths, n_samples)
        Where the element sticks, the sample index at which the current stick phase began
        (its force there was +-slip_force); ``-1`` while slipping; ``-2`` while still stuck in the
        initial state (never slipped).
    """
    n_paths, n = x.shape
    for p in range(n_paths):
        f = initial_force[p]
        anchor = -2
        if abs(f) >= slip_force:
            anchor = -1
        xprev = x[p, 0]
        for _ in range(n_passes):
            for j in range(n):
                xj = x[p, j]
                trial = f + stiffness * (xj - xprev)
                if trial > slip_force:
                    f = slip_force
                    anchor = -1
                elif trial < -slip_force:
                    f = -slip_force
                    anchor = -1
                else:
                    if anchor == -1:
                        anchor = j - 1 if j > 0 else n - 1
                    f = trial
                force_out[p, j] = f
                anchor_out[p, j] = anchor
                xprev = xj
    return 0
