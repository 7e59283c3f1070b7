"""Stick-slip of a spring-held block on a belt with static > kinetic friction: the period in closed form."""

from __future__ import annotations

import numpy as np

from fivid.fe import load_model
from fivid.fe.assembly import lumped_mass
from fivid.solver import OutputOptions, RunSchedule, simulate
from fivid.verify.case import Case, Curve, Outcome, Plot
from fivid.verify.models import block_on_belt

__all__ = ["CASES", "stick_slip_run", "stick_slip_closed_form"]

MU, MU_S, V, K = 0.3, 0.5, 0.05, 1.24e4  # kinetic, static [-], belt speed [m/s], spring [N/m]
MASS = 7850.0 * 0.004 * 0.004 * 0.01  # the block [kg]


def stick_slip_closed_form(normal_force: float, mu=MU, mu_s=MU_S, belt=V, k=K, m=MASS) -> tuple[float, float]:
    """Period [s] and stick fraction of the rigid stick-slip oscillator: T = 2 A0/V + (π + 2ψ)/ω with
    A0 = (μs - μk) N / k, ψ = atan(V / (ω A0)); sticking 2 A0 / V of each period."""
    w = np.sqrt(k / m)
    a0 = (mu_s - mu) * normal_force / k
    psi = np.arctan(belt / (w * a0))
    period = 2 * a0 / belt + (np.pi + 2 * psi) / w
    return float(period), float(2 * a0 / belt / period)


def stick_slip_run():
    """The block on the rigid belt for 30 ms at 1 MHz output; returns ``(model, dataset)``."""
    model = load_model(block_on_belt(mu=MU, mu_static=MU_S, belt=V, spring=K))
    return model, simulate(model, schedule=RunSchedule(duration=0.03, sample_rate=1e6, settle_time=0.0),
                           output=OutputOptions(oversample=1, progress=False))


def _compute(quick: bool, data) -> Outcome:
    model, ds = stick_slip_run()
    t, x = ds.time.values, ds.sensor_displacement.values
    belt = ds.sel(contact="belt")
    N = float(belt.contact_normal_force.values[t > 1e-3].mean())
    period, stick = stick_slip_closed_form(N)
    slip = belt.slip_fraction.values > 0.5
    on = np.flatnonzero(slip[1:] & ~slip[:-1]) + 1
    on = on[t[on] > 1e-3]
    on = on[np.concatenate([[True], np.diff(t[on]) > 0.1 * period])]  # a one-sample re-stick is no new cycle
    node = int(model.contacts[0].slave_nodes[0])
    m_node = lumped_mass(model)[2 * node]
    tol = (MU_S * N * ds.attrs["time_step"] / m_node / ((MU_S - MU) * N / MASS) + 2e-6 / 4) / period
    measured = (t[on[-1]] - t[on[0]]) / (on.size - 1)
    cycles = (t >= t[on[0]]) & (t < t[on[-1]])
    sliding = slip & (t > 1e-3)
    ratio = np.abs(belt.contact_tangential_force.values[sliding]) / belt.contact_normal_force.values[sliding]
    plot = Plot("time [ms]", "block displacement [µm]",
                (Curve(t * 1e3, x * 1e6, "fivid"),
                 Curve(t[on] * 1e3, np.full(on.size, MU_S * N / K * 1e6), "slip onsets at μs N / k (closed form)",
                       "points")))
    return Outcome(float(measured), period, float(tol), plot, {
        "cycles": int(on.size - 1),
        "first slip displacement / (μs N / k)": float(x[on[0]] / (MU_S * N / K)),
        "stick fraction": float(1 - slip[cycles].mean()),
        "stick fraction, closed form": stick,
        "median |Ft|/N while slipping / μk": float(np.median(ratio) / MU),
        "largest energy-balance error / drive work": float(np.abs(ds.energy_balance_error.values).max()
                                                           / float(ds.drive_work.max())),
    })


CASES = (Case(
    name="belt_stick_slip",
    title="Stick-slip on a moving belt (static > kinetic friction)",
    quantity="stick-slip period",
    unit="s",
    reference="T = 2A0/V + (π + 2ψ)/ω, A0 = (μs - μk)N/k, ψ = atan(V/(ωA0)): the block rides the belt until "
              "kx = μs N, slips about μk N/k and sticks again when its speed is back to V",
    source="K. Popp, P. Stelter, Stick-slip vibrations and chaos, Phil. Trans. R. Soc. Lond. A 332 (1990) 89-105; "
           "closed form of the rigid oscillator",
    method="fivid.solver.simulate: a 4 × 4 mm block (ν = 0) on a rigid belt at 50 mm/s (μs = 0.5, μk = 0.3, "
           "k = 1.24e4 N/m, N = 10 N) for 30 ms; the period from the slip onsets over 4+ cycles. Same run for --quick",
    tolerance_basis="derived from the explicit stick test: the node sticks once the force that stops it within one "
                    "step is below μs N, up to v* = μs N Δt / m_node early, Δt_stick ≤ v*/a with a = (μs - μk)N/m; "
                    "plus 1 µs sampling of the onsets over the cycles, relative to T",
    compute=_compute,
),)
