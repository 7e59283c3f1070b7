"""The reduced path stepped in the modal coordinates of its free part (fivid.solver._reduced_kernels) against the
same reduced system stepped in its physical Craig-Bampton coordinates with the dense inverse mass (the reference
kernel, tests/solver/_reduced_reference.py: fivid's own loop before the modal coordinates)."""

import numpy as np
import pytest

from tests.helpers.reduced_setup import coarse, run_inputs  # noqa: F401  (shared set-up; coarse is a fixture)

EPS = np.finfo(float).eps


def _rel(x, y):
    """Largest difference of each record column relative to the column's largest magnitude."""
    scale = np.abs(y).max(axis=0)
    return np.nanmax(np.abs(x - y).max(axis=0) / np.where(scale > 0.0, scale, 1.0))


@pytest.mark.parametrize("reduced", ["reduced", True])
def test_modal_stepping_is_the_physical_one_to_round_off(coarse, reduced):
    """A 3 ms preload-and-slide contact run on the coarse rig (mass-scaled and plain reductions): transducer forces,
    energies, works, sensor and contact records of the modal loop equal the physical loop's.

    Tolerance from float resolution: the modal coordinates carry the eigensolver's round-off, relative
    ``eps lambda_max / lambda_min`` on the lowest mode (Rayleigh quotients are used for ``Lambda``; the dropped
    off-diagonal of ``Phi^T K Phi`` is below it); the run amplifies a relative round-off perturbation by the factor
    ``A`` that the physical loop shows against itself when ``M_FF^-1`` is computed by Cholesky instead of ``inv``
    (a perturbation of ``eps cond(M_FF)``). Allowed: ``10 A eps lambda_max / lambda_min``, the 10 for the
    constants of the eigenvector bound (measured: 1.1 to 1.9 times ``A eps lambda_max / lambda_min``, i.e. 4e-10 to
    3e-9 of each record's largest value; a missing term of the step moves the records by 1e-4 or more)."""
    from fivid.solver.driver import prepare_run
    from fivid.solver.reduced import integrate_reduced
    from tests.solver._reduced_reference import integrate_physical

    prep = prepare_run(coarse, **run_inputs(3e-3, reduced=reduced, basis_cache=False))
    rs = prep.reduced
    nf = rs.n_free
    raw = integrate_reduced(prep.model, rs, prep.friction, prep.settings)
    ref = integrate_physical(prep)
    ref_chol = integrate_physical(prep, cholesky=True)
    assert float(np.nanmax(raw.contact[:, :, 0])) > 0.0  # the slaves closed: the contact solve took part
    floor = max(_rel(a, b) for a, b in zip(ref_chol, ref))
    amplification = floor / (EPS * np.linalg.cond(rs.M[:nf, :nf]))
    lam = rs.kernel["lam"]
    tol = 10.0 * amplification * EPS * lam.max() / lam.min()
    assert 0.0 < floor < 1e-9
    for got, want in zip((raw.rec, raw.sens_v, raw.contact), ref):
        assert _rel(got, want) <= tol


def test_modal_arrays_diagonalise_the_free_part():
    """``Phi^T M_FF Phi = I`` and ``Phi^T K_FF Phi = Lambda`` to round-off on a random symmetric positive definite
    pair (``Lambda`` the Rayleigh quotients); the coupling blocks are ``Phi^T K_FG``, ``Phi^T M_FG`` and
    ``W = Phi_b Phi_b^T`` is the boundary block of ``M_FF^-1``."""
    from fivid.solver.reduced import modal_arrays

    rng = np.random.default_rng(3)
    n, nf, nb = 12, 10, 2
    a = rng.standard_normal((n, n))
    b = rng.standard_normal((n, n))
    K = a @ a.T + n * np.eye(n)
    M = b @ b.T + n * np.eye(n)
    m = modal_arrays(M, K, nf, nb)
    phi = m["phi"]
    np.testing.assert_allclose(phi.T @ M[:nf, :nf] @ phi, np.eye(nf), atol=100 * EPS)
    kk = phi.T @ K[:nf, :nf] @ phi
    np.testing.assert_allclose(kk, np.diag(m["lam"]), atol=100 * EPS * np.abs(kk).max())
    np.testing.assert_allclose(m["kfg"], phi.T @ K[:nf, nf:], rtol=1e-12)
    np.testing.assert_allclose(m["bfg"], phi.T @ M[:nf, nf:], rtol=1e-12)
    np.testing.assert_allclose(m["wmat"], np.linalg.inv(M[:nf, :nf])[:2 * nb, :2 * nb], rtol=1e-10)
    np.testing.assert_array_equal(m["kgf"], m["kfg"].T)
    np.testing.assert_array_equal(m["bgf"], m["bfg"].T)


def test_delassus_contact_solve_reaches_the_shared_solves_multipliers(coarse):
    """Two slaves on a three-node master edge with a dense symmetric positive definite inverse mass ``W`` whose
    coupling pulls slave 1 down when slave 0 is pushed out: slave 0 starts 1 mm inside its master, slave 1 1.5 mm
    outside (beyond the candidate margin: idle, so it joins the sweeps only after the first pass closes it; its
    force then lifts slave 0 off, which ends open). The
    Delassus solve of the reduced loop (its sweeps and exact steps) and the shared projected Gauss-Seidel
    (``contact_solve`` with the dense ``W``, every slave swept) reach the same multipliers, states and corrected
    ``u``, ``v``.

    Tolerance: both iterate until an increment moves no node pair by more than ``tol = 1e-16`` m against
    corrections of ~1e-3 m, so each stops within ``1e-13 / (1 - r)`` (relative) of the common fixed point for a
    contraction rate ``r`` of the sweeps; 1e-9 allows ``r`` up to ``1 - 1e-4``."""
    from fivid.contact import kernel_row, kernel_tables
    from fivid.contact._layout_kernels import N_CNODE, N_GEO
    from fivid.solver._contact_kernels import contact_solve
    from fivid.solver._kernels import GS_SWEEPS, N_ACC
    from fivid.solver._reduced_kernels import delassus_contact_solve

    c = coarse.contacts[0]
    pair_par = np.array([kernel_row(c.law, c.friction, c.rigid)], dtype=float)
    tabs = kernel_tables([c.law])
    nb, ns, dt, tol = 5, 2, 1e-3, 1e-16
    X = np.array([0.5, 1.5, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # master nodes 2, 3, 4 along y = 0
    rng = np.random.default_rng(2)
    A = rng.standard_normal((2 * nb, 2 * nb))
    W = A @ A.T / 10.0 + np.eye(2 * nb)
    W[6, 5] = W[5, 6] = -0.9 * np.sqrt(W[5, 5] * W[6, 6])
    W += 0.2 * np.eye(2 * nb)
    assert np.linalg.eigvalsh(W).min() > 0.0
    u0 = np.zeros(2 * nb)
    u0[nb], u0[nb + 1] = -1e-3, 1.5e-3
    v0 = 1e-3 * rng.standard_normal(2 * nb)
    slaves, pairs, ptr, masters = np.array([0, 1]), np.array([0, 0]), np.array([0, 3]), np.array([2, 3, 4])
    mu = np.full(ns, 0.3)
    out = {}
    for name in ("shared", "delassus"):
        u, v = u0.copy(), v0.copy()
        seg, geo, lam, cstate = np.array([0, 1]), np.zeros((ns, N_GEO)), np.zeros((ns, 2)), np.zeros(ns, np.int64)
        if name == "shared":
            contact_solve(X, u, v, nb, dt, dt, np.zeros(2 * nb), W, slaves, pairs, ptr, masters, np.array([1.0]),
                          pair_par, tabs, np.ones(ns), seg, geo, lam, cstate, mu, 500, tol, np.arange(nb),
                          np.zeros((nb, N_CNODE)), np.inf)
        else:
            acc = np.zeros(N_ACC)
            delassus_contact_solve(X, u, v, nb, dt, dt, W, slaves, pairs, ptr, masters, np.array([1.0]), pair_par,
                                   tabs, np.ones(ns), seg, geo, lam, cstate, mu[None, :], 0.0, np.zeros(ns), 500, tol,
                                   acc, np.zeros(ns, np.int64), np.zeros((ns, ns, 4)), np.zeros((ns, 2, 2 * nb)),
                                   np.zeros((ns, 4)), np.zeros((ns, 2)), np.zeros(ns, np.int64),
                                   np.zeros((2 * ns, 2 * ns + 1)))
            assert 0 < acc[GS_SWEEPS] < 500
        out[name] = (u, v, lam, cstate)
    (ua, va, la, ca), (ub, vb, lb, cb) = out["shared"], out["delassus"]
    assert la[1, 0] > 0.0 and ca.tolist() == [0, 1]  # slave 1 joined and sticks; slave 0, lifted by it, opened
    np.testing.assert_array_equal(cb, ca)
    np.testing.assert_allclose(lb, la, rtol=1e-9)
    assert np.abs(ub - ua).max() <= 1e-9 * np.abs(ua - u0).max()
    assert np.abs(vb - va).max() <= 1e-9 * np.abs(va - v0).max()


@pytest.mark.parametrize("rows, nf", [(104, 279), (34, 276), (7, 13), (1, 5), (0, 4)])
def test_boundary_step_is_the_one_row_loop_bit_for_bit(rows, nf):
    """The blocked boundary product of the modal loop (``_boundary_step``: four rows of ``Phi_b`` per pass) gives
    the one-row loop's values bit for bit (each row's sum vectorised in the same order), on the fine rig's block
    size (104 x 279), the coarse one's and row counts that leave remainders; the one-row loop (the kernel before
    the blocking) compiled here with the same reassociation. Equal values make the records of a run equal too:
    the blocking changes no other operation (``_boundary_motion``, once per output interval, is unchanged)."""
    from numba import njit

    from fivid.solver._reduced_kernels import _boundary_step

    @njit(cache=False, fastmath={"contract", "reassoc"})
    def one_row_step(phib, qd, qb, qdb, dt):
        for j in range(phib.shape[0]):
            sd = 0.0
            for i in range(phib.shape[1]):
                sd += phib[j, i] * qd[i]
            qdb[j] = sd
            qb[j] += dt * sd

    rng = np.random.default_rng(rows)
    phib = rng.standard_normal((rows, nf)) * np.exp(rng.uniform(-20.0, 0.0, nf))  # modal scales spread over 1e9
    qd = rng.standard_normal(nf)
    qb0 = rng.standard_normal(rows)
    got = [qb0.copy(), np.zeros(rows)]
    want = [qb0.copy(), np.zeros(rows)]
    _boundary_step(phib, qd, got[0], got[1], 5e-7)
    one_row_step(phib, qd, want[0], want[1], 5e-7)
    np.testing.assert_array_equal(got, want)
    # and it is the product (not vacuous): within the summation's round-off bound nf eps sum |phi_ji qd_i|
    assert np.all(np.abs(got[1] - phib @ qd) <= nf * EPS * (np.abs(phib) @ np.abs(qd)))


@pytest.mark.parametrize("rows, nf, closed", [(104, 279, 1), (104, 279, 5), (34, 276, 2), (8, 13, 0)])
def test_modal_impulse_is_the_one_row_loop_bit_for_bit(rows, nf, closed):
    """The contact impulse on the modes ``Phi_b^T c`` (``_modal_impulse``: four nonzero rows per pass over the modes)
    gives the one-row loop's values bit for bit (the same additions in the same order), for ``closed`` slaves'
    worth of nonzero rows (six each: a slave and its two master nodes, x and y; adjacent slaves share master
    nodes) on the fine and coarse rigs' block sizes; the one-row loop (the kernel before) compiled here alike."""
    from numba import njit

    from fivid.solver._reduced_kernels import _modal_impulse

    @njit(cache=False)
    def one_row(phib, cimp, gimp):
        for i in range(phib.shape[1]):
            gimp[i] = 0.0
        for j in range(phib.shape[0]):
            c = cimp[j]
            if c != 0.0:
                for i in range(phib.shape[1]):
                    gimp[i] += phib[j, i] * c

    rng = np.random.default_rng(rows + closed)
    phib = rng.standard_normal((rows, nf)) * np.exp(rng.uniform(-20.0, 0.0, nf))
    nb = rows // 2
    cimp = np.zeros(rows)
    for k in range(closed):
        for node in (nb // 2 + k, k, k + 1):  # slave, master nodes a and b
            cimp[[node, node + nb]] += rng.standard_normal(2)
    got, want = np.full(nf, np.nan), np.full(nf, np.nan)
    _modal_impulse(phib, cimp, got, np.zeros(rows, dtype=np.int64))
    one_row(phib, cimp, want)
    np.testing.assert_array_equal(got, want)
    assert np.all(np.abs(got - phib.T @ cimp) <= rows * EPS * (np.abs(phib.T) @ np.abs(cimp)))  # not vacuous
