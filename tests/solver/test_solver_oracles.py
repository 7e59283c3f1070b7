"""The explicit contact solver against closed forms (DESIGN §9): impacting bars, energy conservation,
Coulomb free decay, a spring-held block on a moving belt. Each oracle has one home, its verification case
(fivid/verify/cases/solver_*.py: model, closed form, tolerance and its basis); these tests run the cases at full
resolution and check the further properties each case reports. Models are synthetic (fivid/verify/models.py)."""

import pytest

from fivid.verify import evaluate_case, select_cases


def _run(name):
    """The verification case ``name`` at full resolution; it must pass, and its outcome is returned."""
    (case,) = select_cases([name])
    result = evaluate_case(case, False, None)
    assert result.status == "passed", (result.reason, result.error, result.outcome)
    return result.outcome


def test_impacting_bars_carpenter():
    """Carpenter, Taylor & Katona 1991 (case impacting_bars: the plateau force within 0.5 %). Further: end of
    contact within one element transit each way plus one output sample, 2/(2n) + 1/100 of 2L/c; rigid-body velocity
    within 2/n of v0 (the energy left in vibration and the impact loss are O(h)); the energy balance to round-off."""
    d = _run("impacting_bars").details
    n = d["elements per bar"]
    assert abs(d["end of contact / (2L/c)"] - 1.0) <= 1.0 / n + 0.01
    assert abs(d["left bar velocity after / v0"] + 1.0) <= 2.0 / n
    assert abs(d["right bar velocity after / v0"] - 1.0) <= 2.0 / n
    assert d["largest energy-balance error / initial kinetic energy"] <= 1e-12


def test_impact_loss_converges_at_first_order():
    """Case impact_loss_order: observed order 1 within the fit's 95 % interval on 10-80 elements per bar, a positive
    loss."""
    assert _run("impact_loss_order").details["loss on the finest mesh"] > 0.0


def test_energy_bounded_without_damping_and_friction():
    """Case energy_conservation: the shadow energy KE + W_int constant to 1e-10 over 1e5 steps. Further: the
    physical E = KE + U differs from it by u^T K v dt / 2, at most (omega_max dt / 2) E by Cauchy-Schwarz, and
    oscillates without trend: first- and last-quarter means agree within 4 standard errors of the fluctuation."""
    d = _run("energy_conservation").details
    assert d["time steps"] >= 1e5
    assert d["largest |E/E0 - 1| of KE + U"] <= d["its bound ω_max Δt / 2"]
    assert abs(d["last-quarter minus first-quarter mean of KE + U / E0"]) < 4 * d["standard error of that difference / E0"]


def test_coulomb_free_decay():
    """Case coulomb_free_decay: every half cycle loses 2 mu N_w / k within 2e-3. Further: it comes to rest inside
    the dead band |x| <= mu N / k, sticking; while sliding the multipliers sit on the Coulomb cone (|Ft| = mu N to
    the Gauss-Seidel tolerance)."""
    d = _run("coulomb_free_decay").details
    assert d["half cycles"] >= 5
    assert d["largest |x| at rest / (μN/k)"] <= 1.0
    assert d["stick fraction at rest"] > 0.95  # edge nodes may micro-slip while the block rocks
    assert d["median |Ft|/N while sliding / μ"] == pytest.approx(1.0, rel=1e-9)


def test_block_on_moving_belt():
    """Case belt_coulomb_period: period 2 pi / omega within 1 %. Further: slip starts when k x = mu N; the block
    rides the belt sticking until then (the leading edge may micro-slip: partial slip, Cattaneo-Mindlin); it then
    oscillates about x_e = mu N / k with amplitude V / omega, and the mean friction force is mu N. Tolerances:
    3 % on the amplitude and x_e (the elastic block's normal force varies ~2 % as it rocks), 2 % on the mean
    friction/normal ratio."""
    d = _run("belt_coulomb_period").details
    assert d["slip onset displacement / (μN/k)"] == pytest.approx(1.0, rel=0.03)
    assert d["stick fraction while riding the belt"] > 0.9
    assert d["half peak-to-peak amplitude / (V/ω)"] == pytest.approx(1.0, rel=0.03)
    assert d["mid-position / (μN/k)"] == pytest.approx(1.0, rel=0.03)
    assert d["mean |Ft| / N / μ"] == pytest.approx(1.0, rel=0.02)
