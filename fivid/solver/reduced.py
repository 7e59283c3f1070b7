"""Craig-Bampton reduced-order path of the explicit solver (``simulate(..., reduced=...)``, issue 17).

Boundary (kept physical): the contact nodes that can be active during the run -- every slave node, and the
master nodes within the slaves' sliding range (base velocity x run time, plus two master segments) -- and the
sensor nodes, both dofs each; plus one coordinate per group of constrained dofs moving together (a driven
edge, or a held edge whose reaction the force transducer sums: the group's coordinate is the edge's common
displacement and its generalised force is the sum of the edge's reactions). Clamped dofs outside the
transducer are eliminated. Interior: the static response to each boundary coordinate (constraint modes,
``Psi_I = -K_II^-1 K_IB``) plus the fixed-interface modes (``K_II phi = omega^2 M_II phi``, lumped ``M``) up to
a cut-off (default 3 x the top of the analysis band, ``sample_rate / 2``) or a given number of modes.

Mass: ``M_r = T^T M T`` is dense. The contact correction is applied through the reduced system's exact
inverse mass (not a lumped boundary mass): a contact force ``f_c`` on the boundary dofs moves the free
coordinates by ``dt^2 M_FF^-1 [:, c] f_c``. Inside the Gauss-Seidel sweeps only the boundary block
``W = (M_FF^-1)_cc`` is needed (the gap's response to a multiplier is ``dt^2 g^T W g``, with the xy coupling of
``W``), and the accumulated impulse moves the modes once after the solve. Why not lump: a row-sum or diagonal
boundary mass changes the reduced system's dynamics (its modes and the mass each contact node carries, by
the interior's inertia), so it would need its own verification; the exact inverse keeps the reduced model's
kinetic energy ``v^T M_r v / 2`` the one the contact works against, so the energy balance closes to
round-off (tested), and costs ``2 n_b`` operations per multiplier update instead of 6.

Damping: the model's scheme on the reduced matrices, ``C_r = alpha M_r + beta K_r`` (band-limited: ``beta K_r``
on the filtered velocity). Rayleigh damping is diagonal in the modes of the reduced system, so each of its modes
gets exactly the model's damping curve ``fivid.fe.damping.damping_ratio(f)`` -- the modal damping of the issue,
without a second definition of it. The stable step follows from the reduced system's own ``omega_max``
(:func:`fivid.solver.timestep.stable_step_of`).

Selective mass scaling (optional, :func:`scale_high_modes`, via :func:`prepare_reduced`): the reduced system's own
modes above a target frequency are slowed to it by added modal mass, the modes below kept exactly. The modes it
slows are the local constraint modes of single boundary nodes, which otherwise keep the reduced ``omega_max``
near the mesh's; the step then grows by ``omega_max / omega_target``. Its in-band error on the rig's contact
runs is measured in docs/solver.md ("Reduced-order path"): it falls with the target and, on the default rig, is
the dominant error of the fast configurations.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from fivid.contact._layout_kernels import N_CNODE, N_GEO

from fivid.errors import ConfigError, SimulationDiverged
from fivid.fe.assembly import lumped_mass, stiffness_matrix
from fivid.solver.basis_cache import basis_key, cached_basis, content_key, model_key
from fivid.solver.integrate import RUNAWAY_FACTOR, RawRecords, chunked, shortest_master_segment, velocity_filter_gain
from fivid.solver.setup import KIND_FIXED
from fivid.solver.timestep import stable_step_of

__all__ = ["ReducedSystem", "MassScaling", "reduced_system", "scale_high_modes", "prepare_reduced", "integrate_reduced"]


@dataclass
class ReducedSystem:
    """A Craig-Bampton reduction of a model, with the kernel arrays of :mod:`fivid.solver._reduced_kernels`.

    Attributes (sizes: ``nb`` boundary nodes, ``nm`` modes, ``ng`` groups, ``n = 2 nb + nm + ng``)
    ----------
    nodes : ndarray (nb,)
        Global node numbers of the physical boundary nodes.
    T : ndarray (n_dofs, n)
        ``u = T q`` (global dof order).
    M, K : ndarray (n, n)
        Reduced mass [kg] and stiffness [N m-1] (``K`` block-diagonal: constraint and fixed-interface modes are
        K-orthogonal; the round-off coupling is dropped and recorded as ``stiffness_coupling``).
    mode_frequencies : ndarray (nm,)
        Fixed-interface mode frequencies kept [Hz].
    cutoff : float
        Frequency cut-off of the kept modes [Hz] (the largest kept one when a number of modes was asked).
    first_truncated : float
        Frequency of the first fixed-interface mode left out [Hz].
    static_residual : float
        Largest relative (mass-norm) part of the interior's quasi-static response to a boundary acceleration
        (``K_II^-1 M_II Psi_I``) that the kept modes miss [-]: the error of leaving out the higher modes.
    kernel : dict
        Arrays of :func:`fivid.solver._reduced_kernels.run_modal_steps`.
    mass_scaling : MassScaling or None
        The selective mass scaling applied to ``M`` (:func:`scale_high_modes`).
    unscaled_mass : ndarray (n, n) or None
        ``M`` before the mass scaling [kg].
    truncation_flexibility : ndarray (2 nb, 2 nb) or None
        ``G = Psi^T M_II R_m`` [kg s2]: the boundary flexibility of the fixed-interface modes left out, ``sum_{j > k} L_j L_j^T / omega_j^2`` (:mod:`fivid.solver.reduced_error`).
    omega_top : float
        Highest angular frequency of the free reduced system [rad s-1], computed with the basis.
    basis_key, basis_source, setup_seconds
        The basis's cache key (sha256), ``"cache"`` or ``"built"``, and its build time [s] (0 from the cache).
    """

    nodes: np.ndarray
    T: np.ndarray
    M: np.ndarray
    K: np.ndarray
    n_free: int
    n_groups: int
    mode_frequencies: np.ndarray
    cutoff: float
    first_truncated: float
    static_residual: float
    stiffness_coupling: float
    sliding_range: float
    kernel: dict
    mass_scaling: "MassScaling | None" = None
    unscaled_mass: "np.ndarray | None" = None
    truncation_flexibility: "np.ndarray | None" = None
    omega_top: float = math.nan
    basis_key: str = ""
    basis_source: str = ""
    setup_seconds: float = 0.0

    @property
    def size(self) -> int:
        """Number of reduced coordinates."""
        return self.M.shape[0]

    def natural_frequencies(self, n: int) -> np.ndarray:
        """The ``n`` lowest natural frequencies [Hz] with the groups held (constraints as in modal analysis)."""
        import scipy.linalg

        nf = self.n_free
        lam = scipy.linalg.eigh(self.K[:nf, :nf], self.M[:nf, :nf], eigvals_only=True, subset_by_index=[0, n - 1])
        return np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)

    def omega_max(self) -> float:
        """Highest angular frequency of the free reduced system [rad s-1]."""
        import scipy.linalg

        if math.isfinite(self.omega_top):
            return self.omega_top
        nf = self.n_free
        lam = scipy.linalg.eigh(self.K[:nf, :nf], self.M[:nf, :nf], eigvals_only=True, subset_by_index=[nf - 1, nf - 1])
        return float(np.sqrt(max(float(lam[0]), 0.0)))

    def attrs(self) -> dict:
        """What a run records about the truncation."""
        nm = self.mode_frequencies.size
        return {
            "reduced": 1,
            "reduced_method": "Craig-Bampton: physical contact and sensor nodes, driven/transducer edge groups, "
                              "fixed-interface modes; contact through the reduced inverse mass",
            "reduced_size": int(self.size),
            "reduced_boundary_nodes": int(self.nodes.size),
            "reduced_boundary_coordinates": int(2 * self.nodes.size + self.n_groups),
            "reduced_modes": int(nm),
            "reduced_cutoff": float(self.cutoff),
            "reduced_first_truncated_frequency": float(self.first_truncated),
            "reduced_static_residual": float(self.static_residual),
            "reduced_sliding_range": float(self.sliding_range),
            "reduced_basis_key": self.basis_key,
            "reduced_basis_source": self.basis_source,
            "reduced_setup_time": float(self.setup_seconds),
            **self._scaling_attrs(),
        }

    def _scaling_attrs(self) -> dict:
        ms = self.mass_scaling
        if ms is None or ms.target <= 0.0:
            return {"reduced_mass_scaling": 0.0}
        return {"reduced_mass_scaling": ms.target, "reduced_mass_scaled_modes": ms.n_scaled,
                "reduced_unscaled_top_frequency": ms.top_frequency,
                "reduced_added_mass_fraction": ms.added_mass_fraction}


def _groups(ka):
    """Group coordinates of the constrained dofs: ``(dof lists, motion parameters, transducer weights)``;
    clamped dofs outside the transducer are eliminated (empty group list for them)."""
    keys = {}
    for c, d in enumerate(ka.con_global):
        g = int(ka.con_grp[c])
        react = (float(ka.con_react[c, 0]), float(ka.con_react[c, 1]))
        if int(ka.grp_par[g, 0]) == KIND_FIXED and react == (0.0, 0.0):
            continue
        keys.setdefault((g, react), []).append(int(d))
    dofs = [np.array(v, dtype=np.int64) for v in keys.values()]
    par = np.array([ka.grp_par[g] for g, _ in keys], dtype=float).reshape(-1, 4)
    react = np.array([r for _, r in keys], dtype=float).reshape(-1, 2)
    return dofs, par, react


def _master_range(model, pair, slave_x, comp, reach):
    """The contiguous part of ``pair``'s master nodes within ``reach`` [m] of the slaves along ``comp``."""
    m = np.asarray(pair.master_nodes, dtype=np.int64)
    if m.size < 2:
        return m
    x = model.coords[m, comp]
    seg = float(np.abs(np.diff(x)).max())
    inside = np.flatnonzero((x >= slave_x.min() - reach - 2 * seg) & (x <= slave_x.max() + reach + 2 * seg))
    if inside.size == 0:
        raise ConfigError(f"contacts.{pair.name}: no master node within the slaves' sliding range; the reduced path "
                          "needs the slaves above their master edge")
    i0, i1 = max(int(inside.min()) - 1, 0), min(int(inside.max()) + 1, m.size - 1)
    return m[i0:i1 + 1]


#: basis keys of the (model content, run) pairs this process keyed already (:func:`reduced_system`)
_BASIS_KEYS: dict[str, str] = {}


def reduced_system(model, ka, *, sliding_distance: float, band_top: float, n_modes: int | None = None,
                   cutoff: float | None = None, mass_scaling=None, cache: bool = True,
                   cache_dir=None) -> ReducedSystem:
    """Craig-Bampton reduction of ``model`` for a run (see the module docstring), its basis read from or stored in
    the basis cache (:mod:`fivid.solver.basis_cache`).

    Parameters
    ----------
    model : Model
    ka : KernelArrays
        The full model's kernel arrays (constraint groups, transducer weights, contact pairs).
    sliding_distance : float
        How far the slaves can slide along the base motion during the run [m].
    band_top : float
        Top of the analysis band [Hz]; the default mode cut-off is 3 times it.
    n_modes : int, optional
        Keep this many fixed-interface modes instead of a cut-off.
    cutoff : float, optional
        Mode cut-off [Hz] (default ``3 band_top``).
    mass_scaling : float, optional
        Selective mass scaling target [Hz] (:func:`scale_high_modes`); ``None`` or ``0``: none.
    cache : bool
        Read/store the basis in the cache (False: always build, store nothing).
    cache_dir : path-like, optional
        Cache folder (default :func:`fivid.solver.basis_cache.cache_dir`).
    """
    if any(s.damping > 0.0 for s in model.springs):
        raise ConfigError("the reduced path does not integrate dashpots (springs with damping); run the full model")
    if model.loads:
        raise ConfigError("the reduced path does not apply pressure loads yet; run the full model (reduced=None)")
    g_dofs, g_par, g_react = _groups(ka)
    base = model.motion("base")
    comp = base.component if base is not None else 0
    # ---- boundary nodes: slaves, reachable masters, sensors
    masters = []
    for p, pair in enumerate(model.contacts):
        sl = ka.slave_global[ka.slave_pair == p]
        masters.append(_master_range(model, pair, model.coords[sl, comp], comp, sliding_distance))
    nodes = np.unique(np.concatenate([ka.slave_global, *masters, [s.node for s in model.sensors]]).astype(np.int64))
    bdofs = np.concatenate([2 * nodes, 2 * nodes + 1])
    constrained = np.intersect1d(bdofs, ka.con_global)
    if constrained.size:
        raise ConfigError(f"the reduced path keeps contact and sensor nodes free, but dof(s) {constrained[:5].tolist()} "
                          "of them are constrained (clamp or motion); run the full model")
    f_cut = float(cutoff) if cutoff is not None else 3.0 * float(band_top)
    target = float(mass_scaling) if mass_scaling is not None and float(mass_scaling) > 0.0 else 0.0
    parts = (nodes, g_dofs, ka.con_global, None if n_modes is None else int(n_modes), f_cut, target,
             float(model.rayleigh_alpha), float(model.rayleigh_beta), float(model.damping_cutoff))
    # the key hashes the assembled K and m; they are functions of the model's content, so a process that keyed this
    # model and run before (a pipeline worker's next task) takes the key from _BASIS_KEYS without assembling them
    memo = content_key("basis key of", model_key(model), *parts)
    matrices = []
    key = _BASIS_KEYS.get(memo)
    if key is None:
        matrices = [stiffness_matrix(model, include_springs=True).tocsr(), lumped_mass(model)]
        key = basis_key(*matrices, *parts)
        if len(_BASIS_KEYS) >= 64:
            _BASIS_KEYS.clear()
        _BASIS_KEYS[memo] = key

    def build():
        K, m = matrices or (stiffness_matrix(model, include_springs=True).tocsr(), lumped_mass(model))
        return _build_basis(K, m, bdofs, ka.con_global, g_dofs, n_modes, f_cut, target)

    summary = {"model": model.describe(), "source": str(getattr(model, "source", "")), "boundary_nodes": int(nodes.size),
               "n_modes": n_modes, "cutoff_hz": f_cut, "mass_scaling_hz": target}
    if cache:
        b, source, seconds = cached_basis(key, build, folder=cache_dir, summary=summary)
    else:
        t0 = time.perf_counter()
        b, source, seconds = build(), "built (not cached)", 0.0
        seconds = time.perf_counter() - t0
    nb = nodes.size
    nf, ng = int(b["n_free"]), len(g_dofs)
    n = nf + ng
    Mr, Kb, M0 = b["M"], b["K"], b["M0"]
    kernel = _contact_arrays(model, ka, nodes, masters)
    kernel.update(nb=nb, nf=nf, grp_par=np.ascontiguousarray(g_par), g_react=np.ascontiguousarray(g_react),
                  minv_c=np.zeros(2 * nb), **modal_arrays(Mr, Kb, nf, nb))
    sc = b["scaling"]
    scaling = MassScaling(Mr[:nf, :nf], float(sc[0]), int(sc[1]), float(sc[2]), float(sc[3]))
    freq = b["mode_frequencies"]
    return ReducedSystem(nodes=nodes, T=b["T"], M=Mr, K=Kb, n_free=nf, n_groups=ng, mode_frequencies=freq,
                         cutoff=float(b["cutoff"]), first_truncated=float(b["first_truncated"]),
                         static_residual=float(b["static_residual"]), stiffness_coupling=float(b["stiffness_coupling"]),
                         sliding_range=float(sliding_distance), kernel=kernel, mass_scaling=scaling,
                         unscaled_mass=M0, truncation_flexibility=b["flexibility"],
                         omega_top=float(b["omega_max"]), basis_key=key, basis_source=source, setup_seconds=seconds)


def modal_arrays(M, K, nf, nb) -> dict:
    """The arrays of :func:`fivid.solver._reduced_kernels.run_modal_steps`: the reduced system ``(M, K)`` (free
    coordinates first, ``nf`` of them, the first ``2 nb`` the physical boundary dofs; then the groups) in the modal
    coordinates of its free part, ``K_FF Phi = M_FF Phi Lambda``, ``Phi^T M_FF Phi = I``.

    Returns ``lam`` (``Lambda``, [s-2]), ``phi`` (``Phi``: physical free coordinates = ``Phi eta``), ``phib`` (its
    boundary rows), ``wmat = Phi_b Phi_b^T`` (the boundary block of ``M_FF^-1``, [kg-1]), ``kfg = Phi^T K_FG`` and
    its transpose ``kgf``, ``kgg = K_GG``, ``bfg = Phi^T M_FG`` and its transpose ``bgf``, ``mgg = M_GG``. Dropping the off-diagonal round-off
    of ``Phi^T K_FF Phi`` (relative to ``Lambda``'s top, about the eigensolver's ``1e-15``) is the only difference
    from stepping the physical coordinates.
    """
    import scipy.linalg
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):  # 0.02 s on one thread; 0.1-0.4 s on two under load
        _, phi = scipy.linalg.eigh(K[:nf, :nf], M[:nf, :nf]) if nf else (None, np.zeros((0, 0)))
    # the Rayleigh quotients phi_i^T K phi_i, not the eigensolver's values: these carry its relative error
    # eps lambda_max / lambda_i on the low modes (1.6e-10 on the coarse rig), the quotients only its second order
    lam = np.einsum("ij,ij->j", phi, K[:nf, :nf] @ phi)
    phib = np.ascontiguousarray(phi[:2 * nb])
    c = np.ascontiguousarray
    kfg, bfg = c(phi.T @ K[:nf, nf:]), c(phi.T @ M[:nf, nf:])
    return dict(lam=c(lam), phi=c(phi), phib=phib, wmat=c(phib @ phib.T), kfg=kfg, kgf=c(kfg.T), kgg=c(K[nf:, nf:]),
                bfg=bfg, bgf=c(bfg.T), mgg=c(M[nf:, nf:]))


def _count_below(Kii, Mii, omega2):
    """Number of eigenvalues of ``(Kii, Mii)`` below ``omega2`` [s-2] (Sylvester's law of inertia: the negative
    pivots of a symmetric-mode LU of ``Kii - omega2 Mii``), or None when the factorisation fails."""
    import scipy.sparse.linalg as spla

    try:
        lu = spla.splu((Kii - omega2 * Mii).tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options=dict(SymmetricMode=True))
    except RuntimeError:  # exactly singular: omega2 is an eigenvalue
        return None
    return int(np.sum(lu.U.diagonal() < 0.0))


def _fixed_interface_modes(Kii, Mii, lu, n_modes, f_cut):
    """The fixed-interface modes ``(frequencies [Hz], vectors)``: ``n_modes`` (+1), or those up to ``f_cut`` (+1,
    the first one left out). Shift-invert Lanczos (ARPACK) about 0 on the interior's factorisation ``lu`` (the one
    of the constraint modes: no second factorisation), its size set in advance by an inertia count."""
    import scipy.sparse.linalg as spla
    from threadpoolctl import threadpool_limits

    n = Kii.shape[0]
    if n_modes is not None:
        k = int(n_modes) + 1
    else:
        count = _count_below(Kii, Mii, (2.0 * np.pi * f_cut) ** 2)
        k = (count + 1) if count is not None else 40
    op = spla.LinearOperator(Kii.shape, matvec=lu.solve, matmat=lu.solve, dtype=float)
    while True:
        k = min(k, n - 1)
        # ARPACK's vector work and the solves are faster on one BLAS thread on this machine class (fe/modal.py)
        with threadpool_limits(limits=1, user_api="blas"):
            # a fixed start vector: the same model gives the same basis in every process (ARPACK's default is random)
            lam, phi = spla.eigsh(Kii, k=k, M=Mii, sigma=0.0, OPinv=op, which="LM", ncv=min(n, int(1.3 * k) + 20),
                                  v0=np.ones(n))
        order = np.argsort(lam)
        lam, phi = lam[order], phi[:, order]
        phi = phi / np.sqrt(np.einsum("ij,ij->j", phi, Mii @ phi))
        big = np.argmax(np.abs(phi), axis=0)  # sign: largest entry positive (as fivid.fe.modal.lowest_modes)
        phi = phi * np.sign(phi[big, np.arange(phi.shape[1])])
        freq = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
        if n_modes is not None or freq[-1] > f_cut or k >= n - 1:
            return freq, phi
        # the inertia count failed or was short: next batch from the mode count of a 2-D continuum, N(f) ~ f^2
        k = max(2 * k, int(math.ceil(1.15 * k * (f_cut / max(float(freq[-1]), 1e-300)) ** 2)) + 2)


def _build_basis(K, m, bdofs, con_global, g_dofs, n_modes, f_cut, target) -> dict:
    """The expensive, run-independent part of :func:`reduced_system`: the arrays stored in the basis cache.

    Measured on the default rig (13 524 dofs, 94 boundary dofs, 176 modes below 460.8 kHz, 2-core machine at load
    2): the shift-invert Lanczos iteration dominates (5-7 s: ARPACK's orthogonalisation and ~800 triangular solves);
    the factorisations (0.06 s the interior's, 0.2 s the inertia count's), the constraint modes, the dense products
    and the mass scaling take about 1 s together.
    """
    import scipy.linalg
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    from threadpoolctl import threadpool_limits

    n_dofs = m.size
    nb2 = bdofs.size
    ng = len(g_dofs)
    interior = np.setdiff1d(np.arange(n_dofs), np.concatenate([bdofs, con_global]))
    Kii = K[interior][:, interior].tocsc()
    Kib = K[interior][:, bdofs].toarray()
    Kig = np.column_stack([np.asarray(K[interior][:, d].sum(axis=1)).ravel() for d in g_dofs]) if ng else \
        np.zeros((interior.size, 0))
    try:
        lu = spla.splu(Kii, permc_spec="MMD_AT_PLUS_A")
    except RuntimeError:
        raise ConfigError("the interior of the reduced model is not held (a body without clamp or driven edge); run "
                          "the full model") from None
    psi = -lu.solve(np.column_stack([Kib, Kig]))
    Mii = sp.diags(m[interior]).tocsr()
    freq, phi = _fixed_interface_modes(Kii, Mii, lu, n_modes, f_cut)
    keep = int(min(n_modes, freq.size - 1)) if n_modes is not None else int(np.sum(freq <= f_cut))
    phi = phi[:, :keep]
    first_truncated = float(freq[keep]) if keep < freq.size else math.inf
    nm = keep
    nf = nb2 + nm
    n = nf + ng
    T = np.zeros((n_dofs, n))
    T[bdofs, np.arange(nb2)] = 1.0
    T[interior, :nb2] = psi[:, :nb2]
    T[interior, nb2:nf] = phi
    for j, d in enumerate(g_dofs):
        T[d, nf + j] = 1.0
    T[interior, nf:] = psi[:, nb2:]
    Mr = T.T @ (m[:, None] * T)
    Mr = 0.5 * (Mr + Mr.T)
    Kr = T.T @ (K @ T)
    Kr = 0.5 * (Kr + Kr.T)
    cidx = np.concatenate([np.arange(nb2), np.arange(nf, n)]).astype(np.int64)
    coupling = float(np.abs(Kr[nb2:nf][:, cidx]).max() / np.abs(Kr[np.ix_(cidx, cidx)]).max()) if nm else 0.0
    modes = np.arange(nb2, nf)
    Kb = np.zeros_like(Kr)
    Kb[np.ix_(cidx, cidx)] = Kr[np.ix_(cidx, cidx)]
    Kb[modes, modes] = np.diag(Kr)[modes]
    # ---- static-correction residual: the interior's quasi-static response to boundary accelerations,
    # R = K_II^-1 M_II Psi, less what the kept modes carry; its boundary flexibility G = Psi^T M_II R_m is the
    # truncated modes' static contribution sum_{j > k} L_j L_j^T / omega_j^2 (fivid.solver.reduced_error)
    mi = m[interior][:, None]
    R = lu.solve(mi * psi)
    Rm = R - phi @ (phi.T @ (mi * R))
    mnorm = lambda a: np.sqrt(np.einsum("ij,ij->j", a, mi * a))
    residual = float(np.max(mnorm(Rm) / np.maximum(mnorm(R), 1e-300))) if R.size else 0.0
    flex = psi[:, :nb2].T @ (mi * Rm[:, :nb2])
    flex = 0.5 * (flex + flex.T)
    M0 = Mr.copy()
    with threadpool_limits(limits=1, user_api="blas"):
        scaling = scale_high_modes(Kb[:nf, :nf], Mr[:nf, :nf], target or None)
        Mr[:nf, :nf] = scaling.mass
        if scaling.target > 0.0 and nf:  # every mode above the target now sits at it: no eigensolve needed
            omega_max = 2.0 * math.pi * (scaling.target if scaling.n_scaled else scaling.top_frequency)
        elif nf:
            lam = scipy.linalg.eigh(Kb[:nf, :nf], Mr[:nf, :nf], eigvals_only=True, subset_by_index=[nf - 1, nf - 1])
            omega_max = float(np.sqrt(max(float(lam[0]), 0.0)))
        else:
            omega_max = 0.0
    return dict(T=T, M=Mr, M0=M0, K=Kb, n_free=np.int64(nf), mode_frequencies=freq[:keep],
                cutoff=np.float64(f_cut if n_modes is None else float(freq[keep - 1]) if keep else 0.0),
                first_truncated=np.float64(first_truncated), static_residual=np.float64(residual),
                stiffness_coupling=np.float64(coupling), flexibility=flex, omega_max=np.float64(omega_max),
                scaling=np.array([scaling.target, scaling.n_scaled, scaling.top_frequency,
                                  scaling.added_mass_fraction], dtype=float))


@dataclass
class MassScaling:
    """Result of :func:`scale_high_modes`: the scaled mass and what was done to it."""

    mass: np.ndarray
    target: float  # [Hz]; 0: no scaling
    n_scaled: int  # modes moved down to the target
    top_frequency: float  # [Hz] highest frequency of the unscaled system
    added_mass_fraction: float  # trace(M' - M) / trace(M) [-]


def scale_high_modes(k, m, target):
    """Selective mass scaling in the system's own modes: every mode above ``target`` [Hz] gets its modal mass
    multiplied by ``(f_i / target)^2``, so it vibrates at ``target``; the modes below keep their frequencies and
    shapes exactly.

    With ``K X = M X Omega^2``, ``X^T M X = I`` and ``H`` the modes above the target,
    ``M' = M + (M X_H) diag(s - 1) (M X_H)^T``, ``s_i = (omega_i / omega_t)^2``: ``M' X_L = M X_L`` for the kept
    modes (``X_H^T M X_L = 0``), so ``K X_L = M' X_L Omega_L^2``, and ``M' X_H = M X_H diag(s)``. ``M'`` stays
    symmetric positive definite and ``K`` is untouched: the static compliance is exact, and the receptance of a
    scaled mode at a frequency ``f`` below the target is off by a factor ``(1 - (f/f_i)^2) / (1 - (f/f_t)^2)``
    (the scaled modes' share of the receptance: 0.05 % off at 10 kHz for a 460.8 kHz target, 12 % at a third of
    the target). The stable step then follows from ``omega_t`` instead of the
    stiff, local constraint modes of single contact nodes (issue 17: these set the reduced ``omega_max`` near
    the mesh's own).

    Parameters
    ----------
    k, m : ndarray (n, n)
        Stiffness [N m-1] and mass [kg] of the free coordinates (symmetric, ``m`` positive definite).
    target : float or None
        Target frequency [Hz]; ``None`` or ``0``: no scaling (``m`` returned as is).
    """
    import scipy.linalg

    if target is None or float(target) <= 0.0 or k.shape[0] == 0:
        return MassScaling(m, 0.0, 0, math.nan, 0.0)
    lam, x = scipy.linalg.eigh(k, m)
    lam = np.clip(lam, 0.0, None)
    top = float(np.sqrt(lam[-1]) / (2.0 * np.pi))
    w_t2 = (2.0 * np.pi * float(target)) ** 2
    high = lam > w_t2
    if not np.any(high):
        return MassScaling(m, float(target), 0, top, 0.0)
    mx = m @ x[:, high]
    scaled = m + (mx * (lam[high] / w_t2 - 1.0)) @ mx.T
    scaled = 0.5 * (scaled + scaled.T)
    return MassScaling(scaled, float(target), int(high.sum()), top,
                       float((np.trace(scaled) - np.trace(m)) / np.trace(m)))


def prepare_reduced(prep, *, n_modes: int | None = None, cutoff: float | None = None, mass_scaling=None, safety=0.9):
    """The run ``prep`` (a :class:`fivid.solver.driver.PreparedRun`, full or reduced) on a reduced system built
    with these options (:func:`reduced_system`), its step chosen as ``prepare_run`` does: ``T / ceil(T / (safety
    dt_crit))`` with ``T`` the recording interval and ``dt_crit`` from the reduced system's own ``omega_max``.
    Same schedule, preload, friction table and records. ``mass_scaling`` [Hz]: :func:`scale_high_modes`."""
    import dataclasses

    model, s = prep.model, prep.settings
    fs = float(prep.inputs.schedule.sample_rate)
    t_int = 1.0 / (s.oversample * fs)
    total = s.n_intervals * t_int
    base = model.motion("base")
    v_max = float(prep.inputs.condition.sliding_velocity or 0.0) if base is not None else 0.0
    rs = reduced_system(model, prep.arrays, sliding_distance=v_max * total, band_top=fs / 2,
                        n_modes=n_modes, cutoff=cutoff, mass_scaling=mass_scaling)
    stab = stable_step_of(rs.omega_max(), float(model.rayleigh_alpha), float(model.rayleigh_beta),
                          float(model.damping_cutoff))
    n_sub = max(1, math.ceil(t_int / (float(safety) * stab.critical_time_step) * (1.0 - 1e-12)))
    settings = dataclasses.replace(s, time_step=t_int / n_sub, critical_time_step=stab.critical_time_step,
                                   omega_max=stab.omega_max, steps_per_interval=n_sub)
    return dataclasses.replace(prep, reduced=rs, settings=settings)


def _contact_arrays(model, ka, nodes, masters) -> dict:
    """Contact and sensor arrays of the reduced layout (boundary node ``k`` at x-index ``k``, ``npd = nb``)."""
    slot = np.full(model.n_nodes, -1, dtype=np.int64)
    slot[nodes] = np.arange(nodes.size)
    ptr = np.concatenate([[0], np.cumsum([mm.size for mm in masters])]).astype(np.int64)
    mnodes = np.concatenate(masters).astype(np.int64) if masters else np.zeros(0, dtype=np.int64)
    seg = np.zeros(ka.slave_global.size, dtype=np.int64)
    for k, (s, p) in enumerate(zip(ka.slave_global, ka.slave_pair)):
        mm = masters[p]
        if mm.size >= 2:
            mid = 0.5 * (model.coords[mm[:-1]] + model.coords[mm[1:]])
            seg[k] = int(np.argmin(np.linalg.norm(mid - model.coords[s], axis=1)))
    cn = np.unique(np.concatenate([ka.slave_global, mnodes])).astype(np.int64)
    cnode_slot = np.full(nodes.size, -1, dtype=np.int64)
    cnode_slot[slot[cn]] = np.arange(cn.size)
    sens_dir = np.array([np.asarray(s.direction, float) for s in model.sensors]).reshape(-1, 2)
    return dict(
        X=np.concatenate([model.coords[nodes, 0], model.coords[nodes, 1]]),
        slave_node=slot[ka.slave_global], slave_pair=ka.slave_pair, master_ptr=ptr, master_nodes=slot[mnodes],
        pair_sign=ka.pair_sign, pair_par=ka.pair_par, law_tab=ka.law_tab, s_area=ka.s_area, seg=seg,
        cnodes=slot[cn], cnode_slot=cnode_slot,
        sens_node=slot[np.array([s.node for s in model.sensors], dtype=np.int64)],
        sens_dir=np.ascontiguousarray(sens_dir),
    )


def integrate_reduced(model, rs: ReducedSystem, fric, settings, *, progress=None):
    """Run the reduced time loop of ``settings.n_intervals`` output intervals (see
    :func:`fivid.solver.integrate.integrate`) in the modal coordinates of the free part
    (:func:`fivid.solver._reduced_kernels.run_modal_steps`); returns :class:`fivid.solver.integrate.RawRecords`
    with the final state expanded to the global dofs."""
    from fivid.solver import _kernels as K  # lazy: pulls numba
    from fivid.solver._reduced_kernels import run_modal_steps  # lazy: pulls numba

    a = rs.kernel
    dt = settings.time_step
    n_sub = settings.steps_per_interval
    n_int = settings.n_intervals
    n, nb, nf = rs.size, a["nb"], a["nf"]
    phi = a["phi"]
    # initial velocity: the M-orthogonal projection of the model's onto the reduced basis, in modal coordinates
    v_full = model.initial_velocity()
    qd_r = np.linalg.solve(rs.M, rs.T.T @ (_lumped(model) * v_full)) if np.any(v_full) else np.zeros(n)
    qd = np.concatenate([phi.T @ (rs.M[:nf, :nf] @ qd_r[:nf]), qd_r[nf:]])
    for g in range(n - nf):
        p = a["grp_par"][g]
        qd[nf + g] = K.constrained_velocity(int(p[0]), p[1], p[2], p[3], -dt, dt)
    q = np.zeros(n)
    beta = float(model.rayleigh_beta)
    a_filt = velocity_filter_gain(model.damping_cutoff, dt)
    vf = qd.copy()
    w = q + beta * qd
    p_mom = np.concatenate([qd[:nf] + a["bfg"] @ qd[nf:], a["bfg"].T @ qd[:nf] + a["mgg"] @ qd[nf:]])  # M~ qd
    qb, qdb = a["phib"] @ q[:nf], a["phib"] @ qd[:nf]
    ns = a["slave_node"].size
    n_pairs = a["master_ptr"].size - 1
    state = dict(geo=np.zeros((ns, N_GEO)), lam=np.zeros((ns, 2)), cstate=np.zeros(ns, dtype=np.int64),
                 mu_now=np.zeros(ns), vold_c=np.zeros((a["cnodes"].size, N_CNODE)), seg=a["seg"].copy())
    rec = np.full((n_int, K.N_REC), np.nan)
    sens_v = np.full((n_int, a["sens_node"].size, 2), np.nan)
    contact = np.full((n_int, n_pairs, 5), np.nan)
    sens_v0 = a["sens_dir"][:, 0] * qdb[a["sens_node"]] + a["sens_dir"][:, 1] * qdb[a["sens_node"] + nb]
    ke0 = float(0.5 * qd @ p_mom)
    acc = np.zeros(K.N_ACC)
    diag = np.zeros(2, dtype=np.int64)
    gs_tol = settings.gs_tolerance * shortest_master_segment(a["X"], nb, a["master_ptr"], a["master_nodes"],
                                                             a["slave_node"], a["slave_pair"])
    mu_tab = np.ascontiguousarray(fric.mu)
    bufs = [np.zeros(n) for _ in range(3)]
    cimp, gimp = np.zeros(2 * nb), np.zeros(nf)

    def step(r0, nr):
        status, _ = run_modal_steps(
            r0 * n_sub, nr * n_sub, dt, float(model.rayleigh_alpha), beta, a_filt, n_sub, nb, nf,
            a["lam"], a["kfg"], a["kgf"], a["kgg"], np.ones(nf), a["bfg"], a["bgf"], a["mgg"], a["phib"], a["grp_par"],
            np.zeros((n - nf, 2)), a["g_react"],
            a["X"], a["slave_node"], a["slave_pair"], a["master_ptr"], a["master_nodes"], a["pair_sign"],
            a["pair_par"], a["law_tab"], a["s_area"], a["minv_c"], a["wmat"], state["seg"], state["geo"],
            state["lam"], state["cstate"], settings.gs_max_iterations, gs_tol, mu_tab, float(fric.rate),
            state["mu_now"], state["vold_c"], a["cnode_slot"], a["cnodes"], a["sens_node"], a["sens_dir"],
            q, qd, w, vf, bufs[0], p_mom, bufs[1], bufs[2], qb, qdb, cimp, gimp, acc, np.zeros(2),
            rec[r0:r0 + nr], sens_v[r0:r0 + nr], contact[r0:r0 + nr], RUNAWAY_FACTOR, diag)
        if status != K.OK:
            worst = int(diag[1])
            raise SimulationDiverged(
                f"the reduced simulation diverged at step {int(diag[0])} (t = {int(diag[0]) * dt:.6g} s): "
                f"{'NaN or infinite values' if status == K.NAN else 'runaway energy'}; largest speed at "
                f"{_coordinate_name(worst, nb, nf)}. Time step {dt:.4g} s, critical "
                f"{settings.critical_time_step:.4g} s; run the full model or lower the step (time_step=...)")

    chunked(step, n_int, max(1, int(3e7 // max(1, n * n_sub * (2 * nb + 8)))), progress, settings.oversample)
    phys = lambda x: np.concatenate([phi @ x[:nf], x[nf:]])  # noqa: E731  (modal -> physical reduced coordinates)
    return RawRecords(rec, sens_v, sens_v0, contact, rs.T @ phys(q), rs.T @ phys(qd), ke0, acc, n_int * n_sub)


def _lumped(model):
    return lumped_mass(model)


def _coordinate_name(i, nb, nf):
    """The physical boundary coordinate ``i`` (``< 2 nb``, the kernel's divergence diagnosis) in words; ``nf`` unused
    beyond it (the modal amplitudes have no node)."""
    return f"boundary node {i % nb} (global node in ReducedSystem.nodes), {'xy'[(i // nb) % 2]}"
