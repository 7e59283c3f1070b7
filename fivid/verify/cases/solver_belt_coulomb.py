"""Spring-held block on a moving belt with one friction coefficient: steady harmonic slip at sqrt(k/m)."""

from __future__ import annotations

import numpy as np

from fivid.fe import load_model
from fivid.solver import OutputOptions, RunSchedule, simulate
from fivid.verify.case import Case, Curve, Outcome, Plot
from fivid.verify.models import block_on_base

__all__ = ["CASES", "block_on_belt_run", "BLOCK_MASS"]

MU, K, V = 0.3, 1.24e4, 0.05  # [-], [N/m], belt speed [m/s]
BLOCK_MASS = 7850.0 * 0.004 * 0.004 * 0.01  # the 4 x 4 x 10 mm steel block [kg]


def block_on_belt_run():
    """The block on the base driven at V after a 0.1 ms ramp; returns the dataset."""
    model = load_model(block_on_base(mu=MU, spring=K, base_velocity=V, load=-2e-9, base_ramp="0.1 ms"))
    return simulate(model, schedule=RunSchedule(duration=0.008, sample_rate=100e3, settle_time=1e-4),
                    output=OutputOptions(oversample=1, progress=False))


def _compute(quick: bool, data) -> Outcome:
    ds = block_on_belt_run()
    t, x, N = ds.time.values, ds.sensor_displacement.values, ds.contact_normal_force.values
    te = ds.attrs["transient_end"]
    omega = np.sqrt(K / BLOCK_MASS)
    slipping = ds.slip_fraction.values > 0.5
    onset = np.flatnonzero(slipping & (t > te))[0]
    steady = t > t[onset] + 2e-3
    xe = MU * N[steady].mean() / K
    xs = x[steady]
    up = np.flatnonzero((xs[:-1] < xe) & (xs[1:] >= xe))
    period = float(np.diff(t[steady][up]).mean())
    ft = ds.contact_tangential_force.values[steady]
    plot = Plot("time [ms]", "block displacement [µm]",
                (Curve(t * 1e3, x * 1e6, "fivid"),
                 Curve(t[steady] * 1e3, (xe + V / omega * np.sin(omega * (t[steady] - t[steady][up[0]]))) * 1e6,
                       "closed form: μN/k + (V/ω) sin ωt", "dashed")))
    return Outcome(period, 2 * np.pi / omega, 0.01, plot, {
        "slip onset displacement / (μN/k)": float(x[onset] / (MU * N[onset] / K)),
        "stick fraction while riding the belt": float(ds.stick_fraction.values[(t > te) & (t < t[onset] - 1e-4)].mean()),
        "half peak-to-peak amplitude / (V/ω)": float(0.5 * (xs.max() - xs.min()) / (V / omega)),
        "mid-position / (μN/k)": float(0.5 * (xs.max() + xs.min()) / xe),
        "mean |Ft| / N / μ": float(abs(ft.mean()) / N[steady].mean() / MU),
    })


CASES = (Case(
    name="belt_coulomb_period",
    title="Spring-held block on a moving belt (Coulomb friction)",
    quantity="period of the steady slip oscillation",
    unit="s",
    reference="2π/ω, ω² = k/m: after sticking until kx = μN the block slips for ever, harmonically about μN/k with "
              "amplitude V/ω",
    source="closed form of the Coulomb oscillator on a moving belt: K. Popp, P. Stelter, Stick-slip vibrations and "
           "chaos, Phil. Trans. R. Soc. Lond. A 332 (1990) 89-105",
    method="fivid.solver.simulate: the 4 × 4 mm block (2 × 2 Q4) on a base driven at 50 mm/s (μ = 0.3, k = 1.24e4 "
           "N/m); period from the up-crossings of μN/k over the steady part. Same run for --quick",
    tolerance_basis="1 %: crossings sampled every 1/200 of a period, the elastic block's static correction "
                    "(f/f_internal)² ~ 1e-6 and its ~2 % normal-force rocking",
    compute=_compute,
),)
