"""Complex eigenvalue analysis: the 2-DOF mode-coupling model in closed form, contact linearisation, rig sweeps."""

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from fivid.errors import FividError
from fivid.fe import load_model
from fivid.fe.cea import cea_to_json, complex_eigenvalue_analysis, complex_eigenvalue_sweep, project_on_modes
from fivid.fe.contact import ContactLinearisation, linearise_contact
from fivid.fe.modal import modal_analysis
from fivid.verify import evaluate_case, select_cases
from fivid.verify.cases.fe_hoffmann_threshold import C, K1, K2, K3, M, hoffmann_model

ROOT = Path(__file__).resolve().parents[2]
COARSE = ROOT / "configs" / "models" / "triboair_coarse.yaml"
LOAD = 5.0  # [N] normal load of the rig's preload (the sample runs' 5 N)


@pytest.mark.parametrize("damped", [False, True])
@pytest.mark.parametrize("belt", [+1, -1], ids=["belt+x", "belt-x"])
def test_two_dof_mode_coupling_threshold_matches_closed_form(damped, belt):
    """The minimal model of Hoffmann et al. (its closed form and tolerances in the cases hoffmann_threshold and
    hoffmann_threshold_damped, run here). Belt moving in -x is the mirror image (x -> -x) of the +x case with k1
    and k2 swapped: same threshold."""
    name = "hoffmann_threshold_damped" if damped else "hoffmann_threshold"
    (case,) = select_cases([name])
    if belt > 0:
        result = evaluate_case(case, False, None)
        assert result.status == "passed", result
        assert result.outcome.details["modes destabilised"] == 1  # one of the pair destabilises, one is stabilised
    m, k3, c = M, K3, C
    K_s, contact, *_ = hoffmann_model(m, *((K1, K2) if belt > 0 else (K2, K1)), k3, c)
    if belt < 0:
        contact = ContactLinearisation(contact.G_n, contact.G_t, contact.stiffness, -contact.direction, contact.pair)
    Kf = contact.friction_stiffness_matrix().toarray()
    assert np.allclose(Kf, [[0.0, belt * k3], [0.0, 0.0]])  # normal displacement drives the tangential force only
    K = K_s + contact.normal_stiffness_matrix().toarray()
    proj = project_on_modes(K, m * np.eye(2), c * np.eye(2) if damped else 0 * np.eye(2), Kf)
    mu = np.linspace(0.0, 2.0, 41)
    res = complex_eigenvalue_sweep(proj, mu)
    *_, mu_c, mu_c_damped = hoffmann_model()
    expected = mu_c_damped if damped else mu_c
    assert 0.0 < expected < 2.0
    crit = res["critical_mu"]
    assert np.isfinite(crit).sum() == 1
    i = int(np.flatnonzero(np.isfinite(crit))[0])
    assert crit[i] == pytest.approx(expected, rel=case.compute(False, None).tolerance)
    assert res["partner"][i] == 1 - i
    lam = res["eigenvalues"]
    before, after = mu < expected, mu > expected
    if not damped:
        # conservative below mu_c: purely imaginary pair; above: one pair lambda = +-sigma + i omega, same omega
        assert np.abs(lam[before].real).max() < res["tolerance"]
        np.testing.assert_allclose(lam[after, 0].imag, lam[after, 1].imag, rtol=1e-7)
        np.testing.assert_allclose(lam[after, 0].real, -lam[after, 1].real, rtol=1e-7)
    else:
        assert lam[before].real.max() < 0 and lam[after, i].real.min() > 0


def test_contact_linearisation_of_the_rig_geometry():
    model = load_model(COARSE)
    lin = linearise_contact(model)
    c = model.contacts[0]
    n = c.slave_nodes.size
    assert lin.G_n.shape == (n, model.n_dofs)
    # tributary areas add up to the contact length (10 mm) times the beam width (10 mm)
    per_area = lin.stiffness / c.normal_stiffness
    assert per_area.sum() == pytest.approx(0.01 * 0.01, rel=1e-12)
    # the lower beam (master) slides in +x under the upper beam: friction drags the slave in +x;
    # the master top edge runs right to left (t = -x), so d = sign(v_rel . t) = -1
    assert np.all(lin.direction == -1)
    # gap: rigid translations of the whole model leave it unchanged; lifting the slave by delta opens it by delta
    for rigid in ([1.0, 0.0], [0.0, 1.0]):
        assert np.abs(lin.G_n @ np.tile(rigid, model.n_nodes)).max() < 1e-15
    u = np.zeros(model.n_dofs)
    u[2 * c.slave_nodes + 1] = 1e-6
    np.testing.assert_allclose(lin.G_n @ u, 1e-6, rtol=1e-12)
    Kn, Kf = lin.normal_stiffness_matrix(), lin.friction_stiffness_matrix()
    assert abs(Kn - Kn.T).max() == 0 and abs(Kf - Kf.T).max() > 0
    # friction force on the slave for a penetration delta: + mu k delta along +x (f = -mu Kf u)
    u[:] = 0
    u[2 * c.slave_nodes + 1] = -1e-6
    f = -(Kf @ u)
    np.testing.assert_allclose(f[2 * c.slave_nodes], lin.stiffness * 1e-6, rtol=1e-12)


def test_rig_cea_at_zero_friction_equals_the_coupled_modal_analysis():
    model = load_model(COARSE)
    ds = complex_eigenvalue_analysis(model, [0.0, 0.5], normal_load=LOAD, n_modes=10, damping=False)
    modes = modal_analysis(model, 10, include_contact=True, normal_load=LOAD)
    # the basis modes are eigenvectors of the mu = 0 system: only the dense solver's rounding separates them
    np.testing.assert_allclose(ds["frequency"].values[0], modes["frequency"].values, rtol=1e-9)
    damped = complex_eigenvalue_analysis(model, [0.0, 0.5], normal_load=LOAD, n_modes=10)
    # C = alpha M + beta K is positive semi-definite: a passive, frictionless system decays
    assert np.all(damped["real_part"].values[0] < 0)
    zeta = damped["damping_ratio"].values[0]
    f = damped["frequency"].values[0]
    w = 2 * np.pi * f
    rayleigh = model.rayleigh_alpha / (2 * w) + model.rayleigh_beta * w / 2
    # the basis diagonalises K + K_n, not K alone: beta's share differs by the contact springs' share of the modal
    # strain energy, so only the order of magnitude is checked against the uncoupled Rayleigh formula
    assert np.all((zeta > 0.2 * rayleigh) & (zeta < 5 * rayleigh))


def test_rig_mode_coupling_pairs_coalesce_at_their_critical_mu():
    model = load_model(COARSE)
    mu = np.linspace(0.0, 1.5, 31)
    ds = complex_eigenvalue_analysis(model, mu, normal_load=LOAD, n_modes=20, damping=False)
    crit = ds["critical_mu"].values
    unstable = np.flatnonzero(np.isfinite(crit))
    assert unstable.size >= 1  # the conservative rig flutters for some mu below 1.5 (mode coupling exists)
    paired = [i for i in unstable if ds["partner"].values[i] > 0]  # -1: the partner is above the reported modes
    assert paired
    for i in paired:
        p = int(ds["partner"].values[i]) - 1
        after = mu > crit[i] + 0.05
        fi, fp = ds["frequency"].values[after, i], ds["frequency"].values[after, p]
        # past the threshold the pair shares one frequency (a complex-conjugate pair of the real system)
        np.testing.assert_allclose(fi[:3], fp[:3], rtol=1e-6)
    j = cea_to_json(ds)
    assert len(j["modes"]) == 20 and j["mu"] == pytest.approx(list(mu))
    assert [u["mode"] for u in j["unstable"]] == sorted((unstable + 1).tolist(), key=lambda k: crit[k - 1])
    assert all(m["critical_mu"] is None for m in j["modes"] if m["mode"] - 1 not in unstable)


def test_cea_needs_contact_and_sliding():
    beam = {"bodies": {"b": {"corners": [[0, 0], [0.1, 0], [0.1, 0.01], [0, 0.01]], "divisions": [10, 2],
                             "material": {"E": 210e9, "nu": 0.3, "rho": 7850}, "thickness": 0.01, "clamp": ["left"]}}}
    with pytest.raises(FividError, match="contact"):
        complex_eigenvalue_analysis(load_model(beam), [0.0, 1.0], normal_load=LOAD)
    import yaml

    cfg = yaml.safe_load(COARSE.read_text())
    cfg["motions"] = [mo for mo in cfg["motions"] if mo["role"] != "base"]
    with pytest.raises(FividError, match="sliding direction"):
        complex_eigenvalue_analysis(load_model(cfg), [0.0, 1.0], normal_load=LOAD)


def test_modal_basis_converges_to_the_full_order_eigenvalues_and_augmentation_helps():
    """Reference: the full-order state-space pencil [[0, I], [-(K + mu Kf), -C]] z = lambda [[I, 0], [0, M]] z,
    solved by ARPACK shift-invert around each reduced eigenvalue (no projection). The modal truncation error of
    the 12 lowest oscillating modes must fall as the basis grows, and the static responses to contact-node loads
    (modal truncation augmentation) must cut it by at least 10x at the same number of modes: friction acts by
    point forces whose local flexibility lives in the discarded modes."""
    import scipy.sparse.linalg as spla
    from threadpoolctl import threadpool_limits

    from fivid.fe.assembly import damping_matrix, stiffness_matrix
    from fivid.fe.modal import constrained_matrices

    from fivid.fe.contact import linearise_preloaded_contact

    model = load_model(COARSE)
    lin = linearise_preloaded_contact(model, LOAD)[0]
    K, M, free = constrained_matrices(model, include_contact=True, contact=lin)
    Kf = lin.friction_stiffness_matrix()[free][:, free]
    C = damping_matrix(model, mass="consistent", stiffness=stiffness_matrix(model))[free][:, free]
    loads = sp.hstack([lin.G_n, lin.G_t]).T.tocsr()[free]
    mu = 1.0
    eye = sp.identity(K.shape[0], format="csr")
    A = sp.bmat([[None, eye], [-(K + mu * Kf), -C]], format="csc").astype(complex)
    B = sp.bmat([[eye, None], [None, M]], format="csc").astype(complex)

    def error(n_basis, augmented):
        proj = project_on_modes(K, M, C, Kf, n_basis, static_loads=loads if augmented else None)
        lam, _ = proj.eigen(mu)
        lam = lam[lam.imag > 0]
        lam = lam[np.argsort(lam.imag)][:12]
        ref = np.array([spla.eigs(A, k=1, M=B, sigma=x, which="LM", return_eigenvectors=False)[0] for x in lam])
        return np.abs((lam - ref) / ref).max()

    with threadpool_limits(limits=1, user_api="blas"):  # small dense and sparse solves: one thread is faster
        plain = [error(n, False) for n in (20, 40)]
        enriched = [error(n, True) for n in (20, 40)]
    assert plain[1] < plain[0] and enriched[1] < enriched[0]
    assert enriched[1] < plain[1] / 10, (plain, enriched)


def test_preloaded_contact_closes_the_tip_only_and_carries_the_load():
    """Static contact solve on the coarse rig: the clamp bends the upper beam, whose free-end corner (the slave
    node of smallest x) alone touches; equilibrium: its normal force is the transducer's 5 N (the load path runs
    through the contact only), to the direct solver's rounding (~1e-12 relative). The linearisation keeps exactly
    the rows of the closed nodes of the all-nodes operators."""
    from fivid.fe.contact import linearise_preloaded_contact
    from fivid.fe.static import contact_geometry

    model = load_model(COARSE)
    lin, state = linearise_preloaded_contact(model, LOAD)
    geo = contact_geometry(model)
    tip = int(np.argmin(model.coords[geo.slave_node, 0]))
    assert np.flatnonzero(state.active).tolist() == [tip]
    assert state.normal_force.sum() == pytest.approx(LOAD, rel=1e-9)
    assert np.all(state.normal_force[~state.active] == 0)
    full = linearise_contact(model)
    assert lin.slave.tolist() == [tip]
    assert abs(lin.G_n - full.G_n[[tip]]).max() == 0 and abs(lin.G_t - full.G_t[[tip]]).max() == 0
    assert lin.stiffness.tolist() == [full.stiffness[tip]] and lin.direction.tolist() == [full.direction[tip]]
    with pytest.raises(FividError, match="normal load"):
        modal_analysis(model, 4, include_contact=True)
