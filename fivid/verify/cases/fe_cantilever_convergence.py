"""Observed mesh-convergence order of the first frequency of a Q4 cantilever: 2."""

from __future__ import annotations

import numpy as np

from fivid.fe import load_model
from fivid.fe.modal import modal_analysis
from fivid.verify.case import Case, Curve, Outcome, Plot

__all__ = ["CASES", "cantilever_model", "first_frequencies", "DEPTH"]

STEEL = {"E": 210e9, "nu": 0.3, "rho": 7850.0}
DEPTH = 0.01  # beam depth [m]


def cantilever_model(length: float, ny: int, **extra):
    """A steel cantilever ``length`` x 10 mm (thickness 10 mm), clamped on the left, square Q4 with ``ny`` through
    the depth."""
    nx = int(round(ny * length / DEPTH))
    return load_model({"bodies": {"beam": {"corners": [[0, 0], [length, 0], [length, DEPTH], [0, DEPTH]],
                                           "divisions": [nx, ny], "material": STEEL, "thickness": 0.01,
                                           "clamp": ["left"], **extra}}})


def first_frequencies(length: float, divisions) -> np.ndarray:
    """First natural frequency [Hz] on meshes of ``divisions`` elements through the depth."""
    return np.array([modal_analysis(cantilever_model(length, ny), 1)["frequency"].values[0] for ny in divisions])


def _compute(quick: bool, data) -> Outcome:
    length = 0.1
    divisions = (4, 8, 16) if quick else (4, 8, 16, 32)
    f = first_frequencies(length, divisions)
    d = -np.diff(f)  # successive differences ~ C h^p
    h = length / (10 * np.asarray(divisions[:-1], float))
    sel = slice(-2, None)  # the two finest pairs
    p = float(np.polyfit(np.log(h[sel]), np.log(d[sel]), 1)[0])
    plot = Plot("element size [m]", "f(h) - f(h/2) [Hz]",
                (Curve(h, d, "fivid", "points"), Curve(h, d[-1] * (h / h[-1]) ** 2, "order 2", "dashed")),
                "log", "log")
    return Outcome(p, 2.0, 0.1, plot, {"elements through the depth": ", ".join(map(str, divisions)),
                                       "first frequencies [Hz]": ", ".join(f"{x:.2f}" for x in f),
                                       "monotone from above": bool(np.all(np.diff(f) < 0))})


CASES = (Case(
    name="cantilever_convergence_order",
    title="Mesh convergence of the Q4 cantilever",
    quantity="observed convergence order of the first natural frequency",
    unit="",
    reference="2: full-integration bilinear Q4 has an O(h) energy-norm error, so eigenvalue and frequency errors are "
              "O(h²); shear locking at a fixed element aspect ratio is also O(h²) (it inflates the constant)",
    source="G. Strang, G. Fix, An Analysis of the Finite Element Method, Prentice-Hall 1973, §6.3 (eigenvalue "
           "error 2(k - m) + ... = O(h²) for bilinear elements)",
    method="fivid.fe.modal.modal_analysis of a 100 × 10 mm steel cantilever (plane stress) on 4, 8, 16 and 32 "
           "square Q4 through the depth (--quick: 4, 8, 16); without a reference value the successive differences "
           "d_k = f(h_k) - f(h_k/2) ~ C h^p are fitted, log d against log h over the two finest pairs",
    tolerance_basis="±0.1 on the order: the pre-asymptotic drift measured between the two finest pairs",
    compute=_compute,
    error="absolute",
),)
