"""Hertz line contact of a roller on a rigid flat: half-width and peak pressure, Richardson-extrapolated."""

from __future__ import annotations

import functools

import numpy as np

from fivid.fe import load_model
from fivid.fe.static import preload_state
from fivid.study.convergence import observed_order
from fivid.verify.case import Case, Curve, Outcome, Plot
from fivid.verify.models import roller_on_flat

__all__ = ["CASES", "hertz_closed_form", "hertz_meshes", "MESHES"]

E, NU = 210e9, 0.3
FORCE, THICKNESS, RADIUS = 4.5e4, 0.01, 0.01  # [N], [m], [m]
#: (circumferential, radial) divisions of the three meshes, h halved each time
MESHES = ((60, 10), (120, 20), (240, 40))


def hertz_closed_form() -> tuple[float, float]:
    """Hertz half-width a = sqrt(4 F' R / (π E*)) [m] and peak pressure p0 = 2 F' / (π a) [Pa], plane strain."""
    e_star = E / (1 - NU ** 2)
    a = np.sqrt(4 * FORCE / THICKNESS * RADIUS / (np.pi * e_star))
    return float(a), float(2 * FORCE / THICKNESS / (np.pi * a))


@functools.lru_cache(maxsize=2)
def hertz_meshes(meshes=MESHES) -> dict:
    """Half-width (from the nodal forces' second moment, ∫x²p/∫p = a²/4) and peak pressure (least squares of
    p² = p0²(1 - x²/a²)) on each mesh; ``{"h", "a", "p0", "force", "x", "p"}`` (x, p: the finest mesh's)."""
    out = {"h": [], "a": [], "p0": [], "force": []}
    for n, m in meshes:
        model = load_model(roller_on_flat(n, m))
        s = preload_state(model, FORCE)
        x = model.coords[s.geometry.slave_node, 0][s.active]
        f = s.normal_force[s.active]
        xc = x - np.sum(x * f) / f.sum()
        out["a"].append(2 * np.sqrt(np.sum(xc ** 2 * f) / f.sum()))
        c, *_ = np.linalg.lstsq(np.stack([np.ones(x.size), xc ** 2], 1), s.pressure[s.active] ** 2, rcond=None)
        out["p0"].append(np.sqrt(c[0]))
        out["h"].append(np.pi / 3 * RADIUS / n)
        out["force"].append(float(s.normal_force.sum()))
        out["x"], out["p"] = xc, s.pressure[s.active]
    return out


def _plot(res, a_h, p0_h) -> Plot:
    xs = np.linspace(-a_h, a_h, 201)
    return Plot("x [µm]", "contact pressure [GPa]",
                (Curve(res["x"] * 1e6, res["p"] / 1e9, "fivid, finest mesh", "points"),
                 Curve(xs * 1e6, p0_h * np.sqrt(1 - (xs / a_h) ** 2) / 1e9, "Hertz", "dashed")))


def _make(quantity: str):
    def compute(quick: bool, data) -> Outcome:
        res = hertz_meshes(MESHES)  # 2 s: the same meshes for --quick
        a_h, p0_h = hertz_closed_form()
        ref = a_h if quantity == "a" else p0_h
        est = observed_order(res["h"], res[quantity])
        finest = res[quantity][-1]
        return Outcome(float(est["extrapolated"]), ref, 0.01, _plot(res, a_h, p0_h), {
            "element sizes at the contact [µm]": ", ".join(f"{h * 1e6:.0f}" for h in res["h"]),
            "values on the meshes": ", ".join(f"{v:.5g}" for v in res[quantity]),
            "observed order": est["order"],
            "finest mesh / closed form": float(finest / ref),
            "total normal force / applied": float(res["force"][-1] / FORCE),
        })
    compute.__name__ = compute.__qualname__ = f"compute_{quantity}"
    return compute


compute_a = _make("a")
compute_p0 = _make("p0")

_SOURCE = ("H. Hertz, Über die Berührung fester elastischer Körper, J. reine angew. Math. 92 (1882) 156-171; "
           "K. L. Johnson, Contact Mechanics, Cambridge 1985, §4.3 (line contact)")
_METHOD = ("fivid.fe.static.preload_state (static Newton with the contact law) of the lower 60° sector of a steel "
           "roller R = 10 mm, plane strain, pressed by 4.5 MN/m on a rigid flat; meshes 60 × 10, 120 × 20, 240 × 40 "
           "graded toward the contact (the same for --quick); Richardson extrapolation with the "
           "observed order (fivid.study.convergence.observed_order)")
_TOL = ("1 %: a/R = 0.05, and a finite roller differs from Hertz's half-space by O((a/R)²) = 0.25 %; the "
        "Richardson remainder of three meshes is a fraction of the finest mesh's error (< 5 %)")

CASES = (
    Case(name="hertz_half_width", title="Hertz line contact: contact half-width", quantity="contact half-width a",
         unit="m", reference="a = √(4F'R/(πE*)), E* = E/(1 - ν²)", source=_SOURCE, method=_METHOD,
         tolerance_basis=_TOL, compute=compute_a),
    Case(name="hertz_peak_pressure", title="Hertz line contact: peak pressure", quantity="peak contact pressure p0",
         unit="Pa", reference="p0 = 2F'/(πa)", source=_SOURCE, method=_METHOD, tolerance_basis=_TOL,
         compute=compute_p0),
)
