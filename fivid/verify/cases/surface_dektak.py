"""A real stylus profile against the instrument's own printed roughness parameters (Bruker Dektak)."""

from __future__ import annotations

import numpy as np

from fivid.surface import evaluate_profile, instrument_results, read_profile
from fivid.verify.case import Case, Curve, Outcome, Plot

__all__ = ["CASES", "dektak_evaluation"]

UM = 1e-6
#: the instrument's R and M cursors [m]: the window its printed results are computed over
WINDOW = (468 * UM, 733 * UM)


def dektak_evaluation(path):
    """Read the Dektak export at ``path`` and evaluate it as the instrument did: the cursor window, a least-squares
    line removed, no filter; returns ``(profile, evaluation, instrument results)``."""
    p = read_profile(path)
    return p, evaluate_profile(p, window=WINDOW, form="line"), instrument_results(p)


def _make(parameter: str):
    def compute(quick: bool, data) -> Outcome:
        p, ev, ins = dektak_evaluation(data)
        x = p["x"].values
        z = p.values
        inside = (x >= WINDOW[0]) & (x <= WINDOW[1])
        xi, zi = x[inside], z[inside]
        line = np.polyval(np.polyfit(xi, zi, 1), xi)
        plot = Plot("x [µm]", "height, least-squares line removed [nm]",
                    (Curve(xi * 1e6, (zi - line) * 1e9, "Dektak profile, cursor window"),
                     Curve(xi[[0, -1]] * 1e6, np.full(2, ins["Ra"] * 1e9), "instrument's Ra", "dashed")))
        return Outcome(float(ev.parameters[parameter]), float(ins[parameter]), 0.02, plot, {
            "points in the window": int(ev.settings["n_points"]),
            **{f"{k}: fivid / instrument": float(ev.parameters[k] / ins[k]) for k in ("Ra", "Rq", "RzDIN", "Rsk")},
        })
    compute.__name__ = compute.__qualname__ = f"compute_{parameter.lower()}"
    return compute


compute_ra = _make("Ra")
compute_rq = _make("Rq")

_SOURCE = ("measurement: Bruker Dektak export dektak-1.csv of ContactEngineering/SurfaceTopography "
           "(test/file_format_examples, MIT licence), its header's analytical results; parameters as ISO 4287 / "
           "ISO 21920-2")
_METHOD = ("fivid.surface.read_profile, evaluate_profile(window=R..M cursors 468-733 µm, form='line', no filter) "
           "on the shipped file (fivid/verify/data/profiles); same for --quick")
_TOL = ("2 %: the instrument prints 3 significant digits (±0.1 %); the rest allows for its undocumented levelling "
        "and end-point conventions inside the window (observed -0.11 % on Ra, +0.04 % on Rq)")

CASES = (
    Case(name="dektak_ra", title="Dektak stylus profile: Ra against the instrument",
         quantity="arithmetic mean roughness Ra over the cursor window", unit="m",
         reference="the instrument's own printed Ra (5.25 nm)", source=_SOURCE, method=_METHOD, tolerance_basis=_TOL,
         compute=compute_ra, real_data="profiles/dektak-1.csv"),
    Case(name="dektak_rq", title="Dektak stylus profile: Rq against the instrument",
         quantity="root-mean-square roughness Rq over the cursor window", unit="m",
         reference="the instrument's own printed Rq", source=_SOURCE, method=_METHOD, tolerance_basis=_TOL,
         compute=compute_rq, real_data="profiles/dektak-1.csv"),
)
