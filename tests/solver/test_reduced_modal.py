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
