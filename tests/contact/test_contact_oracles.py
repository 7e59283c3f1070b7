"""Contact laws, rigid moving surfaces and static/kinetic friction against closed forms (issue 13).

References: the elastic bar on a spring (frequency equation beta tan beta = k L / (E A)), Hertz line contact
(plane strain), the rigid-mass stick-slip oscillator on a moving belt (mu_s > mu_k) and the Coulomb oscillator's
free decay, the torque balance of a held ring on a rotating shaft.
"""

import numpy as np
import pytest

from tests.helpers.contact_models import block_on_belt, block_on_line, ring_on_shaft
from fivid.fe import load_model
from fivid.fe.modal import modal_analysis
from fivid.fe.static import preload_state
from fivid.solver import OutputOptions, RunSchedule, simulate
from fivid.verify import evaluate_case, select_cases
from fivid.verify.cases.contact_rough_ringing import N_POW, POWER_LAW, bar_on_spring_frequency

E, RHO = 210e9, 7850.0
W, H, T = 0.01, 0.002, 0.01  # block_on_line
LAW = POWER_LAW


def test_power_law_static_stiffness_is_the_laws_derivative():
    """Uniform pressure on a block on a rigid flat: every node sits at d = (p / c)^(1/n) and the reported
    normal stiffness is the law's derivative summed, n F / d. Newton stops at a relative penetration change of
    1e-10 and the floating block carries a 1e-10 regularisation: 1e-8 is ample."""
    for p in (2e5, 1e6):
        model = load_model(block_on_line(law=LAW, pressure=p))
        state = preload_state(model, None)
        force = p * W * T
        _, k, d = bar_on_spring_frequency(force)
        (pair,) = state.summary(model)
        assert pair["normal_force_n"] == pytest.approx(force, rel=1e-8)
        assert pair["normal_stiffness_n_per_m"] == pytest.approx(k, rel=1e-8)
        assert pair["contact_length_m"] == pytest.approx(W, rel=1e-12)
        np.testing.assert_allclose(state.penetration[state.active], d, rtol=1e-8)


def test_modes_move_with_load_as_the_contact_tangent():
    """Preloaded modes: the block's bounce on the rough contact rings at the bar-on-spring frequency of the
    tangent stiffness at each load; it rises as F^((n-1)/(2n)). Tolerance: the bar formula is 1D (the 2D block's
    Poisson coupling changes its 1.8e-4 correction by a fraction of itself) -> 1e-4."""
    freqs = []
    for p in (2e5, 1e6):
        ds = modal_analysis(load_model(block_on_line(law=LAW, pressure=p)), 4, include_contact=True)
        f_ref = bar_on_spring_frequency(p * W * T)[0]
        f = ds.frequency.values
        bounce = f[np.argmin(np.abs(f - f_ref))]
        assert bounce == pytest.approx(f_ref, rel=1e-4)
        freqs.append(bounce)
    assert freqs[1] / freqs[0] == pytest.approx(5 ** ((N_POW - 1) / (2 * N_POW)), rel=2e-4)


def test_mass_on_rough_contact_rings_at_sqrt_k_over_m_in_the_explicit_solver():
    """A 2 % pressure step on the preloaded block: the explicit solver's ringing has the bar-on-spring frequency of
    the tangent at the final load (case rough_contact_ringing, 5e-4, the basis there). Further: the energy balance
    closes to round-off with the stored contact energy, and the stored energy A c d^(n+1)/(n+1) at the final
    equilibrium is matched to 5 % (the record's last sample sits somewhere on the ringing of amplitude ~ the kick's
    penetration change, 1.02^(1/n) - 1 = 1.3 % of d, i.e. +-(n+1) 1.3 % = 3.3 % of the energy)."""
    (case,) = select_cases(["rough_contact_ringing"])
    result = evaluate_case(case, False, None)
    assert result.status == "passed", result
    d = result.outcome.details
    assert d["largest energy-balance error / load work"] <= 1e-9
    assert d["final contact energy / A c d^(n+1)/(n+1)"] == pytest.approx(1.0, rel=0.05)


def test_belt_stick_slip_with_static_and_kinetic_friction():
    """Rigid oscillator on a belt with mu_s > mu_k (case belt_stick_slip: its closed-form period within the bound
    derived from the explicit stick test). Further: the first slip at k x = mu_s N (2e-3), the stick fraction
    2 A0 / V / T within the same bound as the period, the multiplier on the kinetic cone while slipping, the energy
    balance to 1e-9 of the drive's work."""
    (case,) = select_cases(["belt_stick_slip"])
    result = evaluate_case(case, False, None)
    assert result.status == "passed", result
    d, tol = result.outcome.details, result.outcome.tolerance
    assert d["cycles"] >= 4
    assert d["first slip displacement / (μs N / k)"] == pytest.approx(1.0, rel=2e-3)
    assert d["stick fraction"] == pytest.approx(d["stick fraction, closed form"], rel=tol)
    assert d["median |Ft|/N while slipping / μk"] == pytest.approx(1.0, rel=1e-9)
    assert d["largest energy-balance error / drive work"] <= 1e-9


def test_coulomb_free_decay_on_a_rigid_flat_with_equal_coefficients():
    """mu_s = mu_k, belt at rest, the block released at v0 (amplitude kept below the tipping limit
    k A h/2 < N W / 4): each half cycle loses 2 mu N / k of amplitude until it sticks inside |x| <= mu N / k.
    The friction node's N varies with the block's inertia moment, so the rigid Coulomb oscillator's energy
    identity is used with the displacement-weighted N of each half cycle, k (A1^2 - A2^2) / 2 = mu int N |dx|.
    Extremes sampled at 2000 samples per period are low by <= (pi/2000)^2 / 2 ~ 1.2e-6 of A: 1e-4 of a
    decrement; doubled, 2e-4."""
    mu, k = 0.1, 1.24e4
    model = load_model(block_on_belt(mu=mu, mu_static=mu, belt=0.0, spring=k, v0=1.2))
    ds = simulate(model, schedule=RunSchedule(duration=0.012, sample_rate=1e6, settle_time=0.0),
                  output=OutputOptions(oversample=1, progress=False))
    from scipy.signal import find_peaks

    t, x = ds.time.values, ds.sensor_displacement.values
    N = ds.sel(contact="belt").contact_normal_force.values
    ext = np.sort(np.concatenate([find_peaks(x, prominence=1e-5)[0], find_peaks(-x, prominence=1e-5)[0]]))
    ext = ext[t[ext] > 0.3e-3]  # after the pressure ramp
    assert ext.size >= 3
    for a, b in zip(ext[:-1], ext[1:]):
        dx = np.abs(np.diff(x[a:b + 1]))
        n_w = (0.5 * (N[a:b] + N[a + 1:b + 1]) * dx).sum() / dx.sum()
        assert (abs(x[a]) - abs(x[b])) / (2 * mu * n_w / k) == pytest.approx(1.0, abs=2e-4)
    rest = t > t[ext[-1]] + 1e-3
    assert np.abs(x[rest]).max() <= mu * N[rest].mean() / k


def test_ring_on_frictionless_rotating_shaft_stays_at_rest():
    """mu = 0: the turning shaft exerts only normal forces, through its centre: the ring does not turn."""
    model = load_model(ring_on_shaft(0.0))
    ds = simulate(model, schedule=RunSchedule(duration=0.01, sample_rate=20e3, settle_time=0.0),
                  output=OutputOptions(progress=False))
    assert np.abs(ds.sensor_displacement.values).max() < 1e-12  # vs 7e-5 m with mu = 0.1
    assert float(np.abs(ds.drive_work).max()) == 0.0


def test_friction_torque_of_a_rotating_shaft_is_mu_n_r():
    """mu = 0.1, shaft at 600 rpm (1.9 m/s at the surface, far above the ring's vibration speeds): every contact
    node slips and the holder springs carry the friction torque mu N R (case shaft_friction_torque, 1e-6). Further:
    the multipliers on the cone (Ft / N = mu to 1e-12), the drive's work goes into friction (and the holder's
    spring energy, 2e-3), the energy balance to 1e-10."""
    (case,) = select_cases(["shaft_friction_torque"])
    result = evaluate_case(case, False, None)
    assert result.status == "passed", result
    d = result.outcome.details
    assert d["slip fraction at the end"] == 1.0
    assert d["Ft / N / μ at the end"] == pytest.approx(1.0, rel=1e-12)
    assert d["drive work / friction dissipation"] == pytest.approx(1.0, rel=2e-3)
    assert d["largest energy-balance error / drive work"] <= 1e-10


@pytest.mark.parametrize("name", ["hertz_half_width", "hertz_peak_pressure"])
def test_hertz_line_contact_converges_to_the_closed_form(name):
    """Roller on a rigid flat, plane strain (cases hertz_half_width, hertz_peak_pressure: Richardson values within
    1 % of Hertz). Further: the finest mesh within the issue's 5 %, a convergent observed order, the applied force
    carried to 1e-9."""
    (case,) = select_cases([name])
    result = evaluate_case(case, False, None)
    assert result.status == "passed", result
    d = result.outcome.details
    assert abs(d["finest mesh / closed form"] - 1) < 0.05
    assert d["observed order"] is not None and d["observed order"] > 0.5
    assert d["total normal force / applied"] == pytest.approx(1.0, rel=1e-9)
