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

CONFIGS = Path(__file__).resolve().parents[1] / "configs" / "dampers"


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
