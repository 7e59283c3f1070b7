"""A block on a rough (power-law) contact rings at the bar-on-spring frequency of the contact's tangent stiffness."""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from fivid.fe import load_model
from fivid.solver import OutputOptions, RunSchedule, simulate
from fivid.verify.case import Case, Curve, Outcome, Plot
from fivid.verify.models import block_on_line

__all__ = ["CASES", "bar_on_spring_frequency", "POWER_LAW", "PRESSURE", "KICK"]

E, RHO = 210e9, 7850.0
W, H, T = 0.01, 0.002, 0.01  # the block of fivid.verify.models.block_on_line [m]
C_POW, N_POW = 2e13, 1.5  # power law p = c d^n [Pa]: contact stiffness ~1e7 N/m, 1e-3 of the block's E A / H
POWER_LAW = {"law": "power", "coefficient": C_POW, "exponent": N_POW}
PRESSURE, KICK = 1e6, 2e4  # preload and the stepped extra pressure [Pa]


def bar_on_spring_frequency(force: float) -> tuple[float, float, float]:
    """Vertical frequency [Hz] of the block (an elastic bar of height H, free top) on the contact's tangent
    stiffness k = n F / d at the static penetration d = (F / (A c))^(1/n): β tan β = k H / (E A); returns
    ``(frequency, k [N/m], d [m])``."""
    d = (force / (W * T * C_POW)) ** (1 / N_POW)
    k = N_POW * force / d
    ratio = k * H / (E * W * T)
    beta = brentq(lambda b: b * np.tan(b) - ratio, 1e-9, 1.0)
    return float(beta * np.sqrt(E / RHO) / (2 * np.pi * H)), float(k), float(d)


def _compute(quick: bool, data) -> Outcome:
    model = load_model(block_on_line(law=POWER_LAW, pressure=PRESSURE, kick=KICK))
    ds = simulate(model, schedule=RunSchedule(duration=2e-3, sample_rate=2e6, settle_time=0.0),
                  output=OutputOptions(oversample=1, progress=False))
    f_ref, _, d = bar_on_spring_frequency((PRESSURE + KICK) * W * T)
    t, x = ds.time.values, ds.sensor_displacement.values
    sel = t > 1.1e-3
    xs, ts = x[sel] - x[sel].mean(), t[sel]
    up = np.flatnonzero((xs[:-1] < 0) & (xs[1:] >= 0))
    tc = ts[up] - xs[up] * (ts[up + 1] - ts[up]) / (xs[up + 1] - xs[up])  # interpolated zero crossings
    f = (len(tc) - 1) / (tc[-1] - tc[0])
    work = float(ds.load_work.max())
    plot = Plot("time [ms]", "top displacement [nm]",
                (Curve(t * 1e3, x * 1e9, "fivid"),
                 Curve(ts * 1e3, (x[sel].mean() + np.abs(xs).max() * np.sin(2 * np.pi * f_ref * (ts - tc[0]))) * 1e9,
                       "closed-form frequency", "dashed")))
    return Outcome(float(f), f_ref, 5e-4, plot, {
        "largest energy-balance error / load work": float(np.abs(ds.energy_balance_error.values).max() / work),
        "final contact energy / A c d^(n+1)/(n+1)": float(ds.contact_energy[-1])
        / (C_POW * W * T * d ** (N_POW + 1) / (N_POW + 1)),
    })


CASES = (Case(
    name="rough_contact_ringing",
    title="Ringing of a block on a rough (power-law) contact",
    quantity="frequency of the ringing after a 2 % pressure step",
    unit="Hz",
    reference="the bar-on-spring frequency β√(E/ρ)/(2πH), β tan β = kH/(EA), with the tangent stiffness k = nF/d of "
              "the power law p = c dⁿ at the final load",
    source="closed form of a bar on an elastic foundation (e.g. S. S. Rao, Vibration of Continuous Systems, Wiley "
           "2007, §9.4); rough-contact power law as in Greenwood & Williamson, Proc. R. Soc. A 295 (1966) 300-319",
    method="fivid.solver.simulate: a 10 × 2 mm steel block (10 × 4 Q4) preloaded by 1 MPa on the rigid line with "
           "p = 2e13 d^1.5, a 2 % pressure step over 1 µs at 1 ms; the frequency from interpolated zero crossings at "
           "2 MHz output; same for --quick",
    tolerance_basis="5e-4: the amplitude (1.3 % of d) shifts a power-law oscillator by O((a/d)²) ~ 2e-4, the "
                    "penalty's end-of-step treatment by (ωΔt)²/2 ~ 4e-5, zero crossings interpolated at 150 samples "
                    "per period",
    compute=_compute,
),)
