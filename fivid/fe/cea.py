"""Complex eigenvalue analysis (CEA) of frictional contact: eigenvalues against the friction coefficient.

The model is linearised about steady sliding under the preload (seed 002, Massi et al.; DESIGN §4): the
static contact solve (:mod:`fivid.fe.static`) gives the slave nodes closed under the normal load, and only
these become penalty normal springs ``K_n``; the friction force ``mu p`` at them adds the non-symmetric
``mu K_f`` (:mod:`fivid.fe.contact`), so

    M u'' + C u' + (K + K_n + mu K_f) u = 0.

The equation is projected on the lowest mass-normalised modes of the frictionless system
``(K + K_n, M)``, enriched with the static responses to unit loads at the contact nodes and
re-diagonalised (Rayleigh-Ritz), which turns it into an ``m``-dof dense problem with ``M_r = I``;
the state-space eigenvalues ``lambda = sigma + i omega`` are computed at each μ.
A mode is unstable when ``sigma > 0`` (negative modal damping). Each mode is followed along the μ
sweep by matching eigenvectors (MAC) between consecutive μ; its critical μ is the first crossing of
``sigma = 0``, refined by root finding (Brent); its partner is the mode it coalesces with (closest frequency at
the crossing).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError
from fivid.fe.assembly import damping_matrix, stiffness_matrix
from fivid.fe.contact import linearise_preloaded_contact
from fivid.fe.modal import _contact_state_attrs, _default_shift, constrained_matrices, lowest_modes
from fivid.fe.prestress import geometric_stiffness_matrix
from fivid.schema import apply_cf_attrs, new_history

__all__ = ["ModalProjection", "project_on_modes", "complex_eigenvalue_sweep", "Linearisation",
           "complex_eigenvalue_analysis", "cea_mode_shapes", "cea_to_json"]

log = logging.getLogger("fivid")


class ModalProjection:
    """A second-order system ``q'' + C_r q' + (K_r + mu Kf_r) q = 0`` in mass-normalised coordinates.

    Parameters
    ----------
    K_r, C_r, Kf_r : ndarray, shape (m, m)
        Reduced stiffness [s-2], damping [s-1] and friction coupling [s-2] (per unit μ).
    basis : ndarray, shape (n, m), optional
        The modes ``Phi`` used (kept for expanding shapes).
    """

    def __init__(self, K_r, C_r, Kf_r, basis=None):
        self.K_r = np.asarray(K_r, dtype=float)
        self.C_r = np.asarray(C_r, dtype=float)
        self.Kf_r = np.asarray(Kf_r, dtype=float)
        self.basis = basis
        w = np.sqrt(np.clip(np.diag(self.K_r), 0.0, None))
        # Diagonal similarity scaling z = [S q, q'] with S ~ omega: A's blocks become O(omega) instead of
        # O(omega^2) and O(1), which keeps the dense eigen solver's backward error eps*||A|| small.
        self._s = np.maximum(w, 1e-3 * max(w.max(), 1.0))

    @property
    def n(self) -> int:
        """Number of reduced dofs."""
        return self.K_r.shape[0]

    def state_matrix(self, mu: float) -> np.ndarray:
        """The first-order matrix A (scaled) whose eigenvalues are the system's ``lambda`` [s-1]."""
        m, s = self.n, self._s
        A = np.zeros((2 * m, 2 * m))
        A[:m, m:] = np.diag(s)
        A[m:, :m] = -(self.K_r + mu * self.Kf_r) / s[None, :]
        A[m:, m:] = -self.C_r
        return A

    def _select(self, lam: np.ndarray) -> np.ndarray:
        """Indices of one eigenvalue per reduced dof: every ``Im > 0`` member of a complex pair, then (over-damped
        modes give two real eigenvalues each, LAPACK returns them with ``Im == 0`` exactly) the real ones with
        the largest real parts."""
        upper = np.flatnonzero(lam.imag > 0)
        real = np.flatnonzero(lam.imag == 0)
        real = real[np.argsort(-lam.real[real], kind="stable")]
        return np.concatenate([upper, real])[: self.n]

    def eigen(self, mu: float) -> tuple[np.ndarray, np.ndarray]:
        """One eigenvalue per reduced dof and its displacement vector ``q`` (unit-norm columns).

        For an under-damped mode the upper-half-plane member of its complex pair; for an over-damped mode the
        less stable of its two real eigenvalues.
        """
        import scipy.linalg

        lam, vec = scipy.linalg.eig(self.state_matrix(mu))
        keep = self._select(lam)
        q = vec[: self.n, keep] / self._s[:, None]
        q /= np.linalg.norm(q, axis=0)
        return lam[keep], q

    def eigenvalues(self, mu: float) -> np.ndarray:
        """All ``2m`` eigenvalues [s-1] at ``mu`` (no vectors: several times cheaper than :meth:`eigen`)."""
        import scipy.linalg

        return scipy.linalg.eigvals(self.state_matrix(mu))


def project_on_modes(K, M, C, K_f, n_basis: int | None = None, *, static_loads=None,
                     sigma: float | None = None) -> ModalProjection:
    """Project ``M u'' + C u' + (K + mu K_f) u = 0`` on the lowest modes of ``(K, M)`` (Rayleigh-Ritz).

    Parameters
    ----------
    K, M, C, K_f : sparse or dense, shape (n, n)
        Symmetric stiffness (contact normal springs included) [N m-1], mass [kg], damping [N s m-1],
        friction coupling per unit μ [N m-1].
    n_basis : int, optional
        Number of modes (default: all ``n``; dense solution for small systems).
    static_loads : array_like or sparse, shape (n, r), optional
        Load patterns whose static responses ``(K - sigma M)^-1 F`` are added to the basis (modal truncation
        augmentation, Dickens et al. 1997). Friction acts through point forces at the contact nodes, which a
        truncated set of global modes represents poorly (the local flexibility is in the discarded modes); with
        the contact nodes' unit normal and tangential loads the reduced eigenvalues converge to the full-order
        ones far faster (see tests/fe/test_fe_cea.py). The enriched basis is M-orthonormalised and re-diagonalised
        on ``K``, so the reduced stiffness stays diagonal.
    sigma : float, optional
        Shift of the modal solver and of the static solves (default: small negative).
    """
    import scipy.linalg
    import scipy.sparse as sp

    n = K.shape[0]
    Phi = lowest_modes(K, M, n if n_basis is None else min(n_basis, n), sigma=sigma)[1]
    if static_loads is not None and Phi.shape[1] < n:
        import scipy.sparse.linalg as spla

        shift = _default_shift(sp.csr_matrix(K), sp.csr_matrix(M)) if sigma is None else sigma
        F = static_loads.toarray() if sp.issparse(static_loads) else np.asarray(static_loads, dtype=float)
        R = spla.splu(sp.csc_matrix(K - shift * M)).solve(F)
        R -= Phi @ (Phi.T @ (M @ R))  # M-orthogonal to the modes
        g = R.T @ (M @ R)
        w, U = scipy.linalg.eigh(0.5 * (g + g.T))
        keep = w > 1e-10 * w.max()  # drop load responses (nearly) inside the span of the modes or of each other
        R = R @ (U[:, keep] / np.sqrt(w[keep]))
        V = np.hstack([Phi, R])
        k_v = V.T @ (K @ V)
        _, Q = scipy.linalg.eigh(0.5 * (k_v + k_v.T))  # V^T M V = I: a standard eigenproblem
        Phi = V @ Q
    K_r = Phi.T @ (K @ Phi)
    C_r = Phi.T @ (C @ Phi)
    Kf_r = Phi.T @ (K_f @ Phi)
    return ModalProjection(0.5 * (K_r + K_r.T), C_r, Kf_r, Phi)


def _mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Modal assurance criterion between the columns of two complex matrices (unit-norm columns)."""
    return np.abs(a.conj().T @ b) ** 2


def complex_eigenvalue_sweep(projection: ModalProjection, mu, *, n_report: int | None = None,
                             refine: bool = True, progress=None) -> dict:
    """Eigenvalues of a projected system along a μ sweep, each mode followed by eigenvector continuity.

    Parameters
    ----------
    projection : ModalProjection
    mu : array_like, shape (n_mu,)
        Friction coefficients [-], increasing.
    n_report : int, optional
        Compute critical μ and partners for the lowest ``n_report`` modes only (default: all); the top of
        a modal basis is truncation-affected and not worth the root finding.
    refine : bool
        Refine each critical μ by root finding (Brent) between the sweep points that bracket it.
    progress : callable, optional
        Called with the number of μ points done after each one (e.g. ``tqdm.update``).

    Returns
    -------
    dict
        ``eigenvalues`` (n_mu, m) complex [s-1], modes ordered by frequency at ``mu[0]``;
        ``critical_mu`` (m,) [-], NaN when ``Re(lambda) <= tol`` over the whole sweep, ``mu[0]`` when
        already unstable there;
        ``partner`` (m,) int, the mode closest in frequency at the crossing (-1 if stable);
        ``tolerance`` [s-1], the threshold on ``Re(lambda)`` (see below).
    """
    from scipy.optimize import linear_sum_assignment

    mu = np.asarray(mu, dtype=float)
    if mu.ndim != 1 or mu.size < 1 or np.any(np.diff(mu) <= 0):
        raise ConfigError(f"mu must be a non-empty increasing 1-D array, got {mu!r}", key="mu")
    m = projection.n
    lam = np.zeros((mu.size, m), dtype=complex)
    vecs = []
    l0, q0 = projection.eigen(mu[0])
    order = np.lexsort((l0.imag, l0.imag == 0))  # oscillating modes by frequency, then over-damped ones
    lam[0], q_prev = l0[order], q0[:, order]
    vecs.append(q_prev)
    if progress is not None:
        progress(1)
    for k in range(1, mu.size):
        lk, qk = projection.eigen(mu[k])
        cost = 1.0 - _mac(q_prev, qk)
        rows, cols = linear_sum_assignment(cost)
        lam[k, rows] = lk[cols]
        q_prev = qk[:, cols]
        vecs.append(q_prev)
        if progress is not None:
            progress(1)
    # Threshold on Re(lambda): the dense eigen solver's backward error is ~eps*||A||, and near a
    # coalescence (a defective double eigenvalue) the eigenvalue error grows to ~sqrt(eps)*||A||;
    # ||A|| ~ omega_max of the scaled state matrix. Real parts above this are instability, not noise.
    tol = np.sqrt(np.finfo(float).eps) * float(np.abs(lam).max())
    critical = np.full(m, np.nan)
    partner = np.full(m, -1)
    for i in range(m if n_report is None else min(n_report, m)):
        up = np.flatnonzero(lam[:, i].real > tol)
        if up.size == 0:
            continue
        k = int(up[0])
        others = np.delete(np.arange(m), i)
        if others.size:
            partner[i] = int(others[np.argmin(np.abs(lam[k, others].imag - lam[k, i].imag))])
        if k == 0:
            critical[i] = mu[0]
            continue
        if not refine:
            r0, r1 = lam[k - 1, i].real, lam[k, i].real
            critical[i] = mu[k - 1] + (mu[k] - mu[k - 1]) * (tol - r0) / (r1 - r0)
            continue
        critical[i] = _refine_critical(projection, mu[k - 1], mu[k], lam[k - 1, i], lam[k, i], tol)
    return {"mu": mu, "eigenvalues": lam, "critical_mu": critical, "partner": partner, "tolerance": tol}


def _refine_critical(projection, a, b, lam_a, lam_b, tol, rtol: float = 1e-12) -> float:
    """Root of ``Re(lambda(mu)) - tol`` in ``[a, b]`` (Brent), following the eigenvalue nearest the path lam_a -> lam_b."""
    from scipy.optimize import brentq

    def excess(c):
        lc = projection.eigenvalues(c)
        target = lam_a + (lam_b - lam_a) * (c - a) / (b - a)
        return lc[np.argmin(np.abs(lc - target))].real - tol

    return float(brentq(excess, a, b, xtol=rtol * max(abs(b), 1.0), rtol=4 * np.finfo(float).eps))


@dataclass(frozen=True)
class Linearisation:
    """What the linearised system of a CEA includes.

    Attributes
    ----------
    damping : bool
        Rayleigh damping and dashpots (default True; False: the conservative system, pure mode coupling).
    prestress : bool or None
        Linearise about the prestressed state: the initial-stress stiffness ``K_sigma`` of the preload solve's
        static state added to ``K`` (:mod:`fivid.fe.prestress`: small-strain, reference-configuration form); the
        Rayleigh damping is then ``alpha M + beta (K + K_sigma)``, the explicit solver's. None (default): the
        model's ``prestress`` key.
    augment : bool
        The static responses to unit normal and tangential loads at the contact nodes added to the modal basis
        (see :func:`project_on_modes`; default True).
    """

    damping: bool = True
    prestress: bool | None = None
    augment: bool = True


def complex_eigenvalue_analysis(model, mu, *, normal_load: float | None = None, n_modes: int = 20,
                                n_basis: int | None = None, linearisation: Linearisation = Linearisation(),
                                velocities: dict | None = None, refine: bool = True, progress=None):
    """CEA of ``model`` over the friction coefficients ``mu``.

    Parameters
    ----------
    model : Model
        Needs at least one contact pair and a sliding direction (a base motion, or ``velocities``).
    mu : array_like
        Increasing friction coefficients [-].
    normal_load : float
        Transducer normal force [N] (required): the static preload solve under it gives the closed slave nodes,
        the only ones with contact springs and friction coupling
        (:func:`fivid.fe.contact.linearise_preloaded_contact`; friction during the preload: the pairs' ``mu``).
    n_modes : int
        Number of lowest modes reported.
    n_basis : int, optional
        Size of the modal basis (default ``max(3 * n_modes, 40)``); modes near the top of the basis
        are affected by truncation, so it is larger than ``n_modes``.
    linearisation : Linearisation
        Damping, prestress (``K_sigma``) and the augmentation of the modal basis by the static contact responses
        (``n_basis`` counts the modes only).
    velocities : dict, optional
        Body name -> rigid velocity [m s-1] overriding the base motion for the sliding direction.
    refine : bool
        Refine each critical μ by root finding (otherwise linear interpolation on the sweep).
    progress : callable, optional
        Called with 1 after each μ point (e.g. ``tqdm.update``).

    Returns
    -------
    xarray.Dataset
        ``frequency(mu, mode)`` [Hz], ``real_part(mu, mode)`` [s-1], ``damping_ratio(mu, mode)`` [1],
        ``critical_mu(mode)`` [1] (NaN when stable over the range), ``partner(mode)`` (-1 if none).
    """
    damping, prestress, augment = linearisation.damping, linearisation.prestress, linearisation.augment
    proj, contact, state, n_basis = _linearised_projection(model, normal_load, n_modes, n_basis, damping, augment,
                                                           velocities, prestress)
    from threadpoolctl import threadpool_limits

    # Many dense eigen problems of size 2 n_basis: one BLAS thread each is faster than a threaded BLAS fighting
    # over the cores for such small matrices (measured 10-25x slower on a loaded 2-core machine).
    with threadpool_limits(limits=1, user_api="blas"):
        res = complex_eigenvalue_sweep(proj, mu, n_report=n_modes, refine=refine, progress=progress)
    return _cea_dataset(model, res, proj.n, contact, state, normal_load=normal_load, n_modes=n_modes, damping=damping,
                        augment=augment, refine=refine, prestress=prestress)


def _linearised_projection(model, normal_load, n_modes, n_basis, damping, augment, velocities, prestress):
    """The model linearised about its preload and projected on its (augmented) modal basis: ``(projection,
    contact, state, n_basis)`` (see :func:`complex_eigenvalue_analysis` for the arguments)."""
    import scipy.sparse as sp

    if not model.contacts:
        raise ConfigError("CEA needs a contact pair: the model config has no 'contacts'", key="contacts")
    contact, state = linearise_preloaded_contact(model, normal_load, velocities=velocities)
    if not np.any(contact.direction):
        raise ConfigError("CEA needs a sliding direction: no body slides relative to another (add a velocity "
                          "motion with role 'base' to the config)", key="motions")
    prestress = model.prestress if prestress is None else bool(prestress)
    K, M, free = constrained_matrices(model, mass="consistent", include_contact=True, contact=contact,
                                      prestress=state.u if prestress else None)
    Kf = contact.friction_stiffness_matrix()[free][:, free]
    if damping:
        K_damp = stiffness_matrix(model)
        if prestress:
            K_damp = K_damp + geometric_stiffness_matrix(model, state.u)
        C = damping_matrix(model, mass="consistent", stiffness=K_damp)[free][:, free]
    else:
        C = sp.csr_matrix(K.shape)
    n_basis = max(3 * n_modes, 40) if n_basis is None else int(n_basis)
    if n_basis < n_modes:
        raise ConfigError(f"n_basis ({n_basis}) must be >= n_modes ({n_modes})", key="n_basis")
    loads = sp.hstack([contact.G_n, contact.G_t]).T.tocsr()[free] if augment else None
    proj = project_on_modes(K, M, C, Kf, n_basis, static_loads=loads)
    return proj, contact, state, n_basis


def cea_mode_shapes(model, mu: float, *, normal_load: float | None = None, n_modes: int = 20,
                    n_basis: int | None = None, damping: bool = True, prestress: bool = False):
    """Complex eigenvalues and mode shapes of the linearised system at one friction coefficient.

    The same linearisation and (augmented) modal projection as :func:`complex_eigenvalue_analysis`; the reduced
    eigenvectors are expanded on the basis to the model's dofs.

    Parameters
    ----------
    model : Model
    mu : float
        Friction coefficient [-].
    normal_load, n_modes, n_basis, damping, prestress
        As :func:`complex_eigenvalue_analysis`.

    Returns
    -------
    eigenvalues : ndarray of complex, shape (n_modes,)
        ``lambda`` [s-1] (upper half plane), by increasing frequency.
    shapes : ndarray of complex, shape (n_modes, n_nodes, 2)
        Displacement shapes at every node (x, y), constrained dofs zero; arbitrary complex scale.
    """
    proj, contact, state, _ = _linearised_projection(model, normal_load, n_modes, n_basis, damping, True, None,
                                                     prestress)
    free = model.free_dofs
    lam, q = proj.eigen(float(mu))
    order = np.lexsort((lam.imag, lam.imag == 0))[:n_modes]
    full = np.zeros((order.size, model.n_dofs), dtype=complex)
    full[:, free] = (proj.basis @ q[:, order]).T
    return lam[order], full.reshape(order.size, -1, 2)


def _cea_dataset(model, res, n_basis, contact, state, *, normal_load, n_modes, damping, augment, refine,
                 prestress=False):
    """The CEA sweep ``res`` (:func:`complex_eigenvalue_sweep`) as a Dataset of the lowest ``n_modes`` modes, with
    the model, the basis size ``n_basis``, the contact state and the analysis settings recorded."""
    import xarray as xr

    n = min(n_modes, n_basis)
    lam = res["eigenvalues"][:, :n]
    partner = np.where(res["partner"][:n] < n, res["partner"][:n], -1)
    ds = xr.Dataset(
        {
            "frequency": (("mu", "mode"), lam.imag / (2 * np.pi), {"units": "Hz", "long_name": "damped frequency Im(lambda)/(2 pi)"}),
            "real_part": (("mu", "mode"), lam.real, {"units": "s-1", "long_name": "real part of the eigenvalue (> 0: unstable)"}),
            "damping_ratio": (("mu", "mode"), -lam.real / np.abs(lam), {"units": "1", "long_name": "modal damping ratio -Re/|lambda|"}),
            "critical_mu": ("mode", res["critical_mu"][:n], {"units": "1", "long_name": "friction coefficient at which Re(lambda) crosses 0 (NaN: stable over the sweep; the first mu if already unstable there)"}),
            "partner": ("mode", partner + np.where(partner >= 0, 1, 0), {"units": "1", "long_name": "mode number of the coalescing partner (-1: stable, or the partner is not among the reported modes)"}),
        },
        coords={
            "mu": ("mu", res["mu"], {"units": "1", "long_name": "friction coefficient"}),
            "mode": ("mode", np.arange(1, n + 1), {"units": "1", "long_name": "mode number, by frequency at the first mu"}),
        },
        attrs={
            "title": "fivid complex eigenvalue analysis",
            "model_source": model.source,
            "model": model.describe(),
            "n_dofs": model.n_dofs,
            "n_basis": n_basis,
            "basis_augmented": int(bool(augment)),
            "damping": int(bool(damping)),
            "prestress": int(bool(prestress)),
            "rayleigh_alpha": model.rayleigh_alpha,
            "rayleigh_beta": model.rayleigh_beta,
            "instability_tolerance": res["tolerance"],
            "contact_nodes": int(contact.stiffness.size),
            "history": new_history(f"complex_eigenvalue_analysis(normal_load={normal_load!r}, n_modes={n_modes}, "
                                   f"n_basis={n_basis}, damping={bool(damping)}, augment={bool(augment)}, "
                                   f"refine={bool(refine)}, prestress={bool(prestress)})"),
            **_contact_state_attrs(model, state),
        },
    )
    log.info("CEA: %s, basis %d, %d of %d modes unstable in [%g, %g]", model.describe(), n_basis,
             int(np.isfinite(res['critical_mu'][:n]).sum()), n, res["mu"][0], res["mu"][-1])
    return apply_cf_attrs(ds)


def cea_to_json(ds) -> dict:
    """JSON summary of a CEA: ``{"mu": [...], "modes": [{"mode", "frequency_hz", "real_part", "critical_mu", "partner"}]}``."""
    modes = []
    for i, m in enumerate(ds["mode"].values):
        crit = float(ds["critical_mu"].values[i])
        p = int(ds["partner"].values[i])
        modes.append({
            "mode": int(m),
            "frequency_hz": ds["frequency"].values[:, i].tolist(),
            "real_part": ds["real_part"].values[:, i].tolist(),
            "critical_mu": crit if np.isfinite(crit) else None,
            "partner": p if p > 0 else None,
        })
    crit = ds["critical_mu"].values
    unstable = [
        {"mode": int(ds["mode"].values[i]), "partner": (int(ds["partner"].values[i]) if ds["partner"].values[i] > 0 else None),
         "critical_mu": float(crit[i]), "frequency_hz": float(np.interp(crit[i], ds["mu"].values, ds["frequency"].values[:, i]))}
        for i in np.argsort(np.where(np.isfinite(crit), crit, np.inf)) if np.isfinite(crit[i])
    ]
    return {
        "mu": ds["mu"].values.tolist(),
        "modes": modes,
        "unstable": unstable,
        "n_dofs": int(ds.attrs["n_dofs"]),
        "n_basis": int(ds.attrs["n_basis"]),
        "damping": bool(ds.attrs["damping"]),
        "prestress": bool(ds.attrs.get("prestress", 0)),
        "normal_load_n": float(ds.attrs["normal_load"]),
        "closed_slave_nodes": np.atleast_1d(ds.attrs["closed_slave_nodes"]).tolist(),
        "contact": __import__("json").loads(ds.attrs.get("contact_summary", "[]")),
        "model": ds.attrs["model"],
        "model_source": ds.attrs["model_source"],
    }
