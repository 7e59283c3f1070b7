"""Observed convergence orders fitted on three or more meshes, with a tolerance from the fit's own residual."""

from __future__ import annotations

import numpy as np
from scipy import stats

__all__ = ["fitted_order", "assert_order"]


def fitted_order(h, err) -> tuple[float, float, int]:
    """Least-squares slope of ``log err`` against ``log h`` over n >= 3 meshes.

    Returns ``(order, standard_error, dof)``: the standard error of the slope from the fit's residual
    (``sqrt(SSR / (n - 2) / Sxx)``), with ``dof = n - 2`` degrees of freedom. Pre-asymptotic curvature (the error
    not yet ``C h^p``) shows up as residual, so it widens the tolerance by what the data themselves say.
    """
    x = np.log(np.asarray(h, dtype=float))
    y = np.log(np.asarray(err, dtype=float))
    if x.size < 3:
        raise ValueError(f"an order fitted with a residual needs at least 3 meshes, got {x.size}")
    slope, intercept = np.polyfit(x, y, 1)
    resid = y - (slope * x + intercept)
    sxx = float(np.sum((x - x.mean()) ** 2))
    stderr = float(np.sqrt(np.sum(resid**2) / (x.size - 2) / sxx))
    return float(slope), stderr, x.size - 2


def assert_order(h, err, expected: float, *, confidence: float = 0.95) -> float:
    """Check that the order fitted on (h, err) is ``expected`` within the two-sided Student-t interval of the fit
    (``t_{(1+confidence)/2, n-2} x standard error``) plus the float floor ``1e-9``; returns the fitted order."""
    order, stderr, dof = fitted_order(h, err)
    tol = stats.t.ppf(0.5 + confidence / 2, dof) * stderr + 1e-9
    assert abs(order - expected) <= tol, (
        f"observed order {order:.4f} (fit over {dof + 2} meshes, standard error {stderr:.3g}) is not "
        f"{expected} within {tol:.3g}; errors {list(err)} at h {list(h)}")
    return order
