"""The impact loss of forward-increment contact converges at first order in the element size."""

from __future__ import annotations

import numpy as np

from fivid.verify.case import Case, Curve, Outcome, Plot
from fivid.verify.orders import fitted_order, order_tolerance
from fivid.verify.cases.solver_impacting_bars import simulate_bars

__all__ = ["CASES", "impact_loss_order"]


def impact_loss_order(meshes) -> tuple[float, float, np.ndarray]:
    """Observed order of the impact's dissipated fraction of kinetic energy over ``meshes`` (elements per bar, at
    least three): the slope of log(loss) against log(h), h = 1/n; returns ``(order, tolerance, losses)`` with the
    tolerance of :func:`fivid.verify.orders.order_tolerance` (95 % interval from the fit's residual)."""
    ns = np.asarray(meshes, float)
    losses = []
    for n in meshes:
        _, ds, _ = simulate_bars(int(n))
        losses.append(ds.impact_dissipation.values[-1] / ds.kinetic_energy.values[0])
    losses = np.asarray(losses)
    order, stderr, dof = fitted_order(1.0 / ns, losses)
    return order, order_tolerance(stderr, dof), losses


def _compute(quick: bool, data) -> Outcome:
    meshes = (10, 20, 40) if quick else (10, 20, 40, 80)
    order, tol, losses = impact_loss_order(meshes)
    h = 0.01 / np.asarray(meshes, float)
    fit = losses[-1] * (h / h[-1]) ** order
    plot = Plot("element size [m]", "impact loss / initial kinetic energy [-]",
                (Curve(h, losses, "fivid", "points"), Curve(h, fit, f"fitted order {order:.3f}", "dashed")),
                "log", "log")
    return Outcome(order, 1.0, tol, plot, {"meshes (elements per bar)": ", ".join(map(str, meshes)),
                                           "loss on the finest mesh": float(losses[-1])})


CASES = (Case(
    name="impact_loss_order",
    title="Impact loss of the contact method: first order in h",
    quantity="observed convergence order of the energy lost at impact",
    unit="",
    reference="1: the forward-increment multipliers stop the touching node pair plastically, losing the relative "
              "kinetic energy of two nodal masses, O(h) of the total",
    source="N. J. Carpenter, R. L. Taylor, M. G. Katona, Int. J. Numer. Methods Eng. 32 (1991) 103-128 (the "
           "method); the order follows from its lumped-mass node-pair stop",
    method="impacting bars (case impacting_bars) on 10, 20, 40 and 80 elements per bar (--quick: 10, 20, 40); "
           "slope of log(loss) against log(h) by least squares over all meshes",
    tolerance_basis="the two-sided 95 % Student-t interval of the fitted slope from the fit's own residual (n - 2 "
                    "degrees of freedom, fivid.verify.orders)",
    compute=_compute,
    error="absolute",
),)
