"""Observed convergence orders fitted on three or more meshes, with a tolerance from the fit's own residual.

A convergence order read through two points has no error bar: the pre-asymptotic drift it hides is exactly what a
reviewer asks about. Here the order is the least-squares slope of ``log err`` against ``log h`` over ``n >= 3``
meshes and its tolerance the two-sided Student-t interval of that slope (``n - 2`` degrees of freedom): a drifting
order shows up as residual and widens the interval by what the data themselves say (Roache, *Verification and
Validation in Computational Science and Engineering*, 1998, ch. 5 on observed orders from several grids).
"""

from __future__ import annotations

import numpy as np
from scipy import stats

__all__ = ["fitted_order", "order_tolerance"]


def fitted_order(h, err) -> tuple[float, float, int]:
    """Least-squares slope of ``log err`` against ``log h`` over n >= 3 meshes.

    Parameters
    ----------
    h : sequence of float
        Element sizes (or steps) [any unit; only ratios matter].
    err : sequence of float
        The positive error measure on those meshes (an error against a reference, or successive differences).

    Returns
    -------
    tuple
        ``(order, standard_error, dof)``: the slope, its standard error from the fit's residual
        (``sqrt(SSR / (n - 2) / Sxx)``) and ``dof = n - 2``.

    Examples
    --------
    >>> h = [0.4, 0.2, 0.1, 0.05]
    >>> order, se, dof = fitted_order(h, [3.0 * x**2 for x in h])
    >>> round(order, 12), se < 1e-12, dof
    (2.0, True, 2)
    """
    x = np.log(np.asarray(h, dtype=float))
    y = np.log(np.asarray(err, dtype=float))
    if x.size < 3:
        raise ValueError(f"an order fitted with a residual needs at least 3 meshes, got {x.size}")
    if not np.all(np.isfinite(y)):
        raise ValueError(f"the errors must be positive and finite to fit an order, got {list(err)}")
    slope, intercept = np.polyfit(x, y, 1)
    resid = y - (slope * x + intercept)
    sxx = float(np.sum((x - x.mean()) ** 2))
    stderr = float(np.sqrt(np.sum(resid**2) / (x.size - 2) / sxx))
    return float(slope), stderr, x.size - 2


def order_tolerance(stderr: float, dof: int, *, confidence: float = 0.95) -> float:
    """Half-width of the two-sided ``confidence`` Student-t interval of a fitted order, plus the float floor 1e-9.

    Examples
    --------
    >>> round(order_tolerance(0.01, 2), 6)  # t_{0.975, 2} = 4.302653
    0.043027
    """
    return float(stats.t.ppf(0.5 + confidence / 2, dof) * stderr + 1e-9)
