"""Jenkins (Masing) element: energy per cycle in closed form, and fitted to real friction-damper loops."""

from __future__ import annotations

import numpy as np

from fivid.damper.loop_fit import fit_jenkins_loop
from fivid.friction.jenkins import jenkins_force, loop_energy
from fivid.io.hysteresis import read_hysteresis
from fivid.verify.case import Case, Curve, Outcome, Plot

__all__ = ["CASES", "DAMPER_FILES", "real_loop_fits"]

#: the measured loops (band tension 20, 35, 80 lb) in the friction_damper folder of the real data
DAMPER_FILES = ("1Hz20lbtension.json", "1Hz35lbtension.json", "1Hz80lbtension.json")


def _closed_form(quick: bool, data) -> Outcome:
    k, fs = 3.9e5, 4.5  # seed 004's contact stiffness [N/m] and slip force 0.45 x 10 N
    a = 5.0 * fs / k
    n = 4000
    t = np.linspace(0, 3, 3 * n + 1)
    x = a * np.sin(2 * np.pi * t)
    f = jenkins_force(x, k, fs)
    w = loop_energy(x[-n - 1:], f[-n - 1:])
    plot = Plot("displacement [µm]", "force [N]", (Curve(x[-n - 1:] * 1e6, f[-n - 1:], "fivid jenkins_force, last cycle"),
                                                   Curve(np.array([-a, -a + 2 * fs / k, a, a - 2 * fs / k, -a]) * 1e6,
                                                         np.array([-fs, fs, fs, -fs, -fs]),
                                                         "closed-form parallelogram", "dashed")))
    return Outcome(float(w), 4 * fs * (a - fs / k), 2 * fs * 2 * np.pi * a / n, plot,
                   {"amplitude / slip displacement": 5.0, "samples per cycle": n})


def real_loop_fits(folder):
    """Jenkins fits of the three measured loops in ``folder``; returns ``[(file, record, fit), ...]``."""
    out = []
    for name in DAMPER_FILES:
        rec = read_hysteresis(folder / name)
        out.append((name, rec, fit_jenkins_loop(rec.displacement, rec.force)))
    return out


def _real(quick: bool, data) -> Outcome:
    fits = real_loop_fits(data)
    errors = [f.summary()["energy_relative_error"] for _, _, f in fits]
    worst = int(np.argmax(np.abs(errors)))
    name, rec, fit = fits[worst]
    measured = float(np.mean(fit.energy_per_cycle_measured))
    model = float(np.mean(fit.energy_per_cycle_model))
    xs = np.linspace(rec.displacement.min(), rec.displacement.max(), 2)
    curves = [Curve(r.displacement * 1e3, r.force / 1e3, f"measured, {n.split('Hz')[1].split('tension')[0]}")
              for n, r, _ in fits]
    curves.append(Curve(xs * 1e3, np.zeros(2), "zero force", "dashed"))
    return Outcome(model, measured, 0.10, Plot("displacement [mm]", "friction force [kN]", tuple(curves)), {
        "loop with the largest energy error": name,
        **{f"{n}: energy error": float(e) for n, (_, _, _), e in zip(DAMPER_FILES, fits, errors)},
        **{f"{n}: R²": float(f.r_squared) for n, _, f in fits},
        **{f"{n}: slip force [N]": float(f.slip_force) for n, _, f in fits},
    })


CASES = (
    Case(name="jenkins_energy_per_cycle", title="Jenkins element: energy dissipated per cycle",
         quantity="area of the steady force-displacement loop", unit="J",
         reference="W = 4Fs(a - Fs/k) for a harmonic displacement of amplitude a > Fs/k",
         source="closed form of the elasto-plastic (Jenkins/Masing) element; e.g. L. Gaul, R. Nitsche, The role of "
                "friction in mechanical joints, Appl. Mech. Rev. 54 (2001) 93-106",
         method="fivid.friction.jenkins.jenkins_force and loop_energy (trapezoid) over the last of three cycles at "
                "4000 samples per cycle, k = 3.9e5 N/m, Fs = 4.5 N, a = 5 Fs/k; same for --quick",
         tolerance_basis="2Fs|dx|max = 2Fs·2πa/n absolute: the loop's sides are straight, so the trapezoid rule is "
                         "exact except over the two samples where stick turns to slip",
         compute=_closed_form, error="absolute"),
    Case(name="jenkins_real_loops", title="Jenkins element fitted to measured friction-damper loops",
         quantity="energy per cycle of the fitted Jenkins element (the loop of the three farthest from its "
                  "measurement)", unit="J",
         reference="the measured loop area per cycle of a banded rotary friction damper (1 Hz, ±1 in, band tension "
                   "20, 35 and 80 lb)",
         source="measurement: D. Coble, P. Huggins, L. Cao, J. Ricles, A. Downey, Dataset-Friction-Damper-with-Backlash "
                "(GitHub ARTS-Laboratory, 2022, CC BY-SA 4.0); A. Downey et al., Engineering Structures 113 (2016) "
                "287-298",
         method="fivid.io.hysteresis.read_hysteresis and fivid.damper.loop_fit.fit_jenkins_loop (least squares of "
                "stiffness and slip force) on each file; same for --quick",
         tolerance_basis="10 % model-form tolerance, not an estimator bound: the element's square corners against "
                         "the measured loops' rounded corners and backlash ringing (observed 2-8 %)",
         compute=_real, real_data="friction_damper"),
)
