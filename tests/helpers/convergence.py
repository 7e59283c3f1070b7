"""Observed convergence orders fitted on three or more meshes, with a tolerance from the fit's own residual (the
fit itself is the verification manual's, :mod:`fivid.verify.orders`)."""

from __future__ import annotations

from fivid.verify.orders import fitted_order, order_tolerance

__all__ = ["fitted_order", "assert_order"]


def assert_order(h, err, expected: float, *, confidence: float = 0.95) -> float:
    """Check that the order fitted on (h, err) is ``expected`` within the two-sided Student-t interval of the fit
    (``t_{(1+confidence)/2, n-2} x standard error``) plus the float floor ``1e-9``; returns the fitted order."""
    order, stderr, dof = fitted_order(h, err)
    tol = order_tolerance(stderr, dof, confidence=confidence)
    assert abs(order - expected) <= tol, (
        f"observed order {order:.4f} (fit over {dof + 2} meshes, standard error {stderr:.3g}) is not "
        f"{expected} within {tol:.3g}; errors {list(err)} at h {list(h)}")
    return order
