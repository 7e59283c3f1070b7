"""Arclength continuation and Floquet stability: against fixed-frequency solves and linear closed forms."""

from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import eigh

from fivid.damper.continuation import continue_frequency_response
from fivid.damper.hbm import HarmonicBalance
from fivid.damper.model import load_damper_model
from fivid.damper.stability import floquet_multipliers
from fivid.fe.beam import cantilever_beam

CONFIGS = Path(__file__).resolve().parents[2] / "configs" / "dampers"


@pytest.fixture(scope="module")
def model1():
    return load_damper_model(CONFIGS / "seed004_model1.yaml")


@pytest.mark.parametrize("normal_load", [2.0, 10.0])
def test_branch_points_solve_the_fixed_frequency_problem(model1, normal_load):
    hb = HarmonicBalance.from_model(model1, normal_load)
    curve = continue_frequency_response(hb, 15, 130, stability=False)
    assert curve.frequency[0] == pytest.approx(15, rel=1e-14) and curve.frequency[-1] == pytest.approx(130, rel=1e-14)
    assert 20 <= curve.frequency.size < 1000
    idx = np.linspace(0, curve.frequency.size - 1, 12).astype(int)
    for i in idx:
        om = 2 * np.pi * curve.frequency[i]
        u, _ = hb.solve(om, np.column_stack([curve.contact[i].real, curve.contact[i].imag]).ravel())
        # both converged to |R| <= 1e-10 |u| (corrector: 1e-8 in scaled units); the Jacobian's
        # condition (< 1e3 here) turns that into <= 1e-5 on u
        assert np.allclose(u[0::2] + 1j * u[1::2], curve.contact[i], rtol=0, atol=1e-5 * np.abs(curve.contact[i, 0]))


def test_floquet_free_limit_is_modal_decay(model1):
    """Always slipping (F_s -> 0): multipliers are exp(lambda_r T) of the free damped modes,
    |mu| = exp(-zeta omega_r T) (closed form), plus 0 for the slaved slider."""
    hb = HarmonicBalance(model1.modal, model1.contact_stiffness, 1e-9, 2.0)
    om = 2 * np.pi * 40.0
    u, it = hb.solve(om)
    sol = hb.solution(u, om, it)
    assert sol.slipping.all()
    mu = floquet_multipliers(model1.modal, model1.contact_stiffness, sol.slipping, om, n_modes=8)
    w = model1.modal.natural_frequencies[:8]
    expected = np.sort(np.repeat(np.exp(-0.005 * w * 2 * np.pi / om), 2))[::-1]
    # expm to float precision; products of 128 propagators: ~128 x 1e-16
    assert np.allclose(np.abs(mu[:-1]), expected, rtol=1e-11, atol=1e-13)
    assert abs(mu[-1]) < 1e-12


def test_floquet_stuck_limit_matches_fe_state_matrix(model1):
    """Never slipping: multipliers exp(lambda T) of the FE beam with the contact spring (+1, neutral slider)."""
    n_modes = model1.modal.natural_frequencies.size
    om = 2 * np.pi * 50.0
    stuck = np.zeros(128, dtype=bool)
    mu = floquet_multipliers(model1.modal, model1.contact_stiffness, stuck, om, n_modes=n_modes)
    b = cantilever_beam(0.5, 0.04, 0.008, 210e9, 7850, n_elements=20, points=(0.5, 0.25, 0.35), tip_mass=0.0725)
    w2, phi = eigh(b.stiffness, b.mass)
    c = b.mass @ phi @ np.diag(2 * 0.005 * np.sqrt(w2)) @ phi.T @ b.mass
    k = b.stiffness.copy()
    ic = b.transverse_dof(0.5)
    k[ic, ic] += model1.contact_stiffness
    n = k.shape[0]
    minv = np.linalg.inv(b.mass)
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ k, -minv @ c]])
    lam = np.linalg.eigvals(a)
    expected = np.sort(np.abs(np.exp(lam * 2 * np.pi / om)))[::-1]
    assert abs(mu[0]) == pytest.approx(1.0, abs=1e-9)
    # the few largest (least damped) agree to float precision x the conditioning of the stiff modes
    assert np.allclose(np.abs(mu[1:7]), expected[:6], rtol=1e-8)


def test_branch_is_stable_for_model1(model1):
    """Seed 004's sweeps are measured steady responses: the computed branch should be stable."""
    curve = continue_frequency_response(HarmonicBalance.from_model(model1, 2.0), 40, 110)
    assert np.all(np.isfinite(curve.max_multiplier))
    assert curve.stable.all()
    assert np.max(curve.max_multiplier) <= 1 + 1e-9


def _stick_pattern_envelope(stick):
    """Stick runs widened and narrowed by one sample at each end (switch located to +-1 sample)."""
    wide = np.roll(stick, 1) | stick | np.roll(stick, -1)
    narrow = np.roll(stick, 1) & stick & np.roll(stick, -1)
    return wide, narrow


@pytest.mark.parametrize("normal_load, frequency", [(2.0, 60.0), (10.0, 95.0)])
def test_floquet_multiplier_predicts_time_domain_decay(model1, normal_load, frequency):
    """Perturb the Newmark steady state: the perturbation decays per period like the largest Floquet
    multiplier (stick-slip orbits, where the multiplier is well below the free-beam value)."""
    from fivid.friction._jenkins_kernels import newmark_jenkins

    fs, k = model1.slip_force(normal_load), model1.contact_stiffness
    om = 2 * np.pi * frequency
    n = 1024
    hb = HarmonicBalance(model1.modal, k, fs, 2.0, harmonics=tuple(range(1, 32, 2)), samples_per_period=n)
    sol = hb.sweep([frequency])[0]
    assert 0.2 < sol.slipping.mean() < 0.9
    mu = abs(floquet_multipliers(model1.modal, k, sol.slipping, om, n_modes=12)[0])
    # tolerance: the stick/slip switches are known to +-1 sample; the multiplier with every stick run
    # widened or narrowed by one sample bounds the effect
    stick = ~sol.slipping
    tol = max(abs(abs(floquet_multipliers(model1.modal, k, ~s, om, n_modes=12)[0]) - mu)
              for s in _stick_pattern_envelope(stick))
    w = model1.modal.natural_frequencies
    args = (w**2, 2 * model1.modal.damping_ratios * w, model1.modal.contact, model1.modal.excitation,
            model1.modal.measurement)
    dt = 2 * np.pi / om / n
    q, v, a, state = np.zeros(w.size), np.zeros(w.size), model1.modal.excitation * 2.0, np.zeros(2)
    out = [np.empty(n) for _ in range(3)]
    periods = 0
    # to steady state: the transient decays like mu^n; settle until it is 1e-8 of the orbit, far below
    # the 1e-4 perturbation
    for periods in range(int(np.ceil(np.log(1e-8) / np.log(mu)))):
        newmark_jenkins(*args, 2.0, om, dt, periods * n * dt, k, fs, q, v, a, state, *out)
    runs = [[q.copy(), v.copy(), a.copy(), state.copy()] for _ in range(2)]
    runs[1][0][0] += 1e-4 * np.max(np.abs(q))
    dist = []
    for p in range(50):
        t0 = (periods + 1 + p) * n * dt
        for rq, rv, ra, rs in runs:
            newmark_jenkins(*args, 2.0, om, dt, t0, k, fs, rq, rv, ra, rs, *out)
        dist.append(np.linalg.norm(np.concatenate([(runs[1][0] - runs[0][0]) * w, runs[1][1] - runs[0][1]])))
    rate = (dist[45] / dist[15]) ** (1 / 30)
    assert abs(rate - mu) <= tol
    assert mu < np.exp(-0.005 * w[0] * 2 * np.pi / om) - 0.01  # friction adds damping to the orbit
