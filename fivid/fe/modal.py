"""Modal analysis: sparse generalized eigenproblem ``K phi = omega^2 M phi`` by shift-invert Lanczos.

Constrained dofs (clamps and imposed motions, ``Model.fixed_dofs``) are eliminated. The shift is
negative, ``sigma = -(2 pi f_s)^2``: all eigenvalues of a positive semi-definite pencil are ``>= 0 > sigma``,
so the ``n`` eigenvalues nearest to ``sigma`` are exactly the ``n`` smallest, rigid-body modes
(``omega = 0``) of a free body included, and ``K - sigma M`` is positive definite (factorisable)
even when ``K`` is singular.
"""

from __future__ import annotations

import logging
from dataclasses import replace
from os import PathLike

import numpy as np

from fivid.errors import ConfigError
from fivid.fe.assembly import consistent_mass, lumped_mass, stiffness_matrix
from fivid.fe.contact import linearise_preloaded_contact
from fivid.fe.prestress import geometric_stiffness_matrix, static_state
from fivid.fe.static import contact_geometry
from fivid.schema import apply_cf_attrs, new_history
from fivid.storage import check_writable, write_netcdf

__all__ = ["constrained_matrices", "lowest_modes", "modal_analysis", "write_modes", "modes_to_json"]

log = logging.getLogger("fivid")

#: below this many free dofs the dense symmetric solver is used (exact, and faster than ARPACK).
DENSE_LIMIT = 600


def constrained_matrices(model, *, mass: str = "consistent", include_contact: bool = False,
                         contact=None, normal_load: float | None = None, prestress=None):
    """Stiffness and mass restricted to the free dofs.

    Parameters
    ----------
    model : Model
    mass : {"consistent", "lumped"}
    include_contact : bool
        Add the linearised normal contact springs ``K_n`` at the slave nodes closed under ``normal_load``
        (frictionless: tangentially free, as a sliding contact whose Coulomb force is a constant follower force).
    contact : ContactLinearisation, optional
        Reuse an existing linearisation (then ``normal_load`` is not used).
    normal_load : float, optional
        Transducer normal force [N] of the static preload solve (:func:`fivid.fe.contact.linearise_preloaded_contact`);
        needed with ``include_contact`` unless ``contact`` is given.
    prestress : ndarray (n_dofs,), optional
        Static displacement [m] of a preloaded state: its initial-stress stiffness ``K_sigma``
        (:func:`fivid.fe.prestress.geometric_stiffness_matrix`) is added to ``K``.

    Returns
    -------
    K, M : scipy.sparse.csr_matrix
        [N m-1], [kg], shape (n_free, n_free).
    free : ndarray of int
        The free dofs (``Model.free_dofs``).
    """
    import scipy.sparse as sp

    K = stiffness_matrix(model)
    if include_contact and model.contacts:
        if contact is None:
            contact = linearise_preloaded_contact(model, normal_load)[0]
        K = K + contact.normal_stiffness_matrix()
    if prestress is not None:
        K = K + geometric_stiffness_matrix(model, prestress)
    if mass == "consistent":
        M = consistent_mass(model)
    elif mass == "lumped":
        M = sp.diags(lumped_mass(model))
    else:
        raise ConfigError(f"mass must be 'consistent' or 'lumped', got {mass!r}", key="mass")
    free = model.free_dofs
    return sp.csr_matrix(K)[free][:, free], sp.csr_matrix(M)[free][:, free], free


def _default_shift(K, M) -> float:
    """A negative shift small against the lowest elastic eigenvalues: ``-1e-8 mean(diag K)/mean(diag M)``.

    ``diag K / diag M`` is the squared frequency of one element (~ omega_max^2); the lowest modes of a
    meshed body are many orders lower, and 1e-8 keeps ``K - sigma M`` well conditioned for free bodies.
    """
    return -1e-8 * float(K.diagonal().mean() / M.diagonal().mean())


def lowest_modes(K, M, n_modes: int, *, sigma: float | None = None):
    """The ``n_modes`` smallest eigenpairs of ``K phi = lambda M phi``, mass-normalised.

    Parameters
    ----------
    K, M : sparse or dense, symmetric
        ``M`` positive definite.
    n_modes : int
    sigma : float, optional
        Shift [s-2] (default: :func:`_default_shift`); must be below the smallest eigenvalue.

    Returns
    -------
    eigenvalues : ndarray, shape (n,)
        ``omega^2`` [s-2], ascending (``n = min(n_modes, n_dofs)``).
    vectors : ndarray, shape (n_dofs, n)
        ``phi^T M phi = I`` [kg-1/2]; sign fixed so that each vector's largest entry is positive.
    """
    from threadpoolctl import threadpool_limits

    n = K.shape[0]
    k = int(min(n_modes, n))
    if k < 1:
        raise ConfigError(f"n_modes must be >= 1 and the model must have free dofs, got n_modes={n_modes}, {n} dofs",
                          key="n_modes")
    # ARPACK's vector operations and the dense solver on these sizes are faster on one BLAS thread than on a
    # threaded BLAS competing for the cores (measured 5x on a loaded 2-core machine).
    with threadpool_limits(limits=1, user_api="blas"):
        lam, vec = _eigen_pairs(K, M, k, sigma)
    norm = np.sqrt(np.einsum("ij,ij->j", vec, M @ vec))
    vec = vec / norm
    big = np.argmax(np.abs(vec), axis=0)
    vec = vec * np.sign(vec[big, np.arange(k)])
    return lam, vec


def _eigen_pairs(K, M, k, sigma):
    import scipy.linalg
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    n = K.shape[0]
    if n <= DENSE_LIMIT or k >= n - 1:
        Kd = K.toarray() if sp.issparse(K) else np.asarray(K)
        Md = M.toarray() if sp.issparse(M) else np.asarray(M)
        lam, vec = scipy.linalg.eigh(Kd, Md, subset_by_index=[0, k - 1])
    else:
        if sigma is None:
            sigma = _default_shift(K, M)
        # a fixed start vector: ARPACK's own is random (LAPACK's generator state), so the last digits of the
        # frequencies changed from run to run; with it (and one BLAS thread) the result is bit-reproducible
        v0 = np.random.default_rng(0).standard_normal(n)
        lam, vec = spla.eigsh(sp.csc_matrix(K), k=k, M=sp.csc_matrix(M), sigma=sigma, which="LM", v0=v0)
        order = np.argsort(lam)
        lam, vec = lam[order], vec[:, order]
    return lam, vec


def modal_analysis(model, n_modes: int = 30, *, mass: str = "consistent", include_contact: bool = False,
                   normal_load: float | None = None, sigma: float | None = None, prestress: bool | None = None,
                   interface_scale: float = 1.0, preload=None):
    """Natural frequencies and mass-normalised mode shapes of ``model`` with its constraints.

    Parameters
    ----------
    model : Model
    n_modes : int
        Number of lowest modes.
    mass : {"consistent", "lumped"}
        Mass matrix (consistent is the more accurate for frequencies; lumped is what the explicit solver uses).
    include_contact : bool
        Couple the bodies by normal penalty springs at the slave nodes closed under ``normal_load`` (static
        preload solve, :mod:`fivid.fe.static`; tangentially free: the sliding contact's Coulomb force is a
        constant follower force, no stiffness). DESIGN §4: linearise about the sliding equilibrium.
    normal_load : float, optional
        Transducer normal force [N] of the preload; required with ``include_contact`` on a model with contacts,
        unless the model's pressure loads press the contact (then None: the state under those loads).
    sigma : float, optional
        Shift [s-2] of the shift-invert solver (default: small negative).
    prestress : bool, optional
        (None: the model's ``prestress`` key.) Vibrations about the prestressed state: add the initial-stress
        stiffness ``K_sigma`` of the static state
        (with ``include_contact`` on a model with contacts the preload solve's state, otherwise the linear
        static response to the pressure loads and the displacement motions, :func:`fivid.fe.prestress.static_state`);
        small-strain,
        reference-configuration form, see :mod:`fivid.fe.prestress`. Tension stiffens, compression softens;
        a negative ``omega^2`` (frequency reported 0) means the preload exceeds a buckling load.
    interface_scale : float
        Factor on the linearised contact's normal springs (with ``include_contact``; default 1, the model's
        interface). A large factor gives the rigid-interface limit: a frequency's deficit from that limit falls as
        ``1 / interface_scale`` (the springs are in series with the bodies), e.g. seed 002's rigid inner disc of
        the transient against the deformable one of the CEA (``interface: rigid`` targets of ``fivid update``).
    preload : Preload, optional
        With ``include_contact``: the static state under ``normal_load`` already solved
        (:func:`fivid.fe.static.preload_state` with each pair's ``mu``, e.g. read from the pipeline's cache,
        :func:`fivid.solver.preload_cache.cached_preload`); default: solved here.

    Returns
    -------
    xarray.Dataset
        ``frequency(mode)`` [Hz] (rigid-body modes have 0), ``eigenvalue(mode)`` = omega^2 [s-2],
        ``mode_shape(mode, node, component)`` [kg-1/2] (zero at constrained dofs; component 0 is x, 1 is y, named
        by the label ``component_name(component)``), node coordinates ``x(node)``, ``y(node)`` [m] and
        ``body(node)``; attrs record the model source and settings.
    """
    import xarray as xr

    contact = state = None
    if include_contact and model.contacts:
        contact, state = linearise_preloaded_contact(model, normal_load, state=preload)
        if interface_scale != 1.0:
            if not (interface_scale > 0 and np.isfinite(interface_scale)):
                raise ConfigError(f"interface_scale must be a positive finite factor, got {interface_scale!r}",
                                  key="interface_scale")
            contact = replace(contact, stiffness=contact.stiffness * float(interface_scale))
    u0 = None
    prestress = model.prestress if prestress is None else bool(prestress)
    if prestress:
        u0 = state.u if state is not None else static_state(model)
    K, M, free = constrained_matrices(model, mass=mass, include_contact=include_contact, contact=contact,
                                      prestress=u0)
    lam, vec = lowest_modes(K, M, n_modes, sigma=sigma)
    shapes = np.zeros((len(lam), model.n_dofs))
    shapes[:, free] = vec.T
    freq = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
    body = np.concatenate([np.full(b.n_nodes, b.name, dtype=object) for b in model.blocks]).astype(str)
    ds = xr.Dataset(
        {
            "frequency": ("mode", freq, {"units": "Hz", "long_name": "natural frequency"}),
            "eigenvalue": ("mode", lam, {"units": "s-2", "long_name": "eigenvalue omega^2 of K phi = omega^2 M phi"}),
            "mode_shape": (("mode", "node", "component"), shapes.reshape(len(lam), model.n_nodes, 2),
                           {"units": "kg-1/2", "long_name": "mass-normalised mode shape (phi^T M phi = 1)"}),
        },
        coords={
            "mode": ("mode", np.arange(1, len(lam) + 1), {"units": "1", "long_name": "mode number, ascending frequency"}),
            "node": ("node", np.arange(model.n_nodes), {"units": "1", "long_name": "global node number"}),
            # a label (CF 6.1), not a coordinate variable: text coordinate variables are char arrays, 2-D, not CF
            "component_name": ("component", np.array(["x", "y"]), {"long_name": "displacement component"}),
            "x": ("node", model.coords[:, 0], {"units": "m", "long_name": "node x coordinate"}),
            "y": ("node", model.coords[:, 1], {"units": "m", "long_name": "node y coordinate"}),
            "body": ("node", body, {"long_name": "body the node belongs to"}),
        },
        attrs={
            "title": "fivid modal analysis",
            "model_source": model.source,
            "model": model.describe(),
            "plane": model.plane,
            "n_dofs": model.n_dofs,
            "n_free_dofs": int(free.size),
            "mass_matrix": mass,
            "include_contact": int(bool(include_contact)),
            "prestress": int(bool(prestress)),
            "history": new_history(f"modal_analysis(n_modes={n_modes}, mass={mass!r}, "
                                   f"include_contact={bool(include_contact)}, normal_load={normal_load!r}, "
                                   f"prestress={bool(prestress)})"),
        },
    )
    if state is not None:
        ds.attrs.update(_contact_state_attrs(model, state))
    log.info("modal analysis: %s, %d modes, f1 = %.6g Hz", model.describe(), len(lam), freq[0])
    return apply_cf_attrs(ds)


def _contact_state_attrs(model, state) -> dict:
    """Attributes recording the preloaded contact state a linearisation is about."""
    import json

    nodes = contact_geometry(model).slave_node[state.active]
    return {
        "normal_load": float(state.normal_load),
        "preload_displacement": float(state.displacement),
        "closed_slave_nodes": np.asarray(nodes, dtype=np.int64),
        "closed_normal_force": np.asarray(state.normal_force[state.active], dtype=float),
        "contact_summary": json.dumps(state.summary(model)),
    }


def write_modes(ds, path: str | PathLike, *, overwrite: bool = False):
    """Write a modal-analysis Dataset to netCDF atomically (refuses to replace a file unless ``overwrite``)."""
    check_writable(path, overwrite=overwrite)
    return write_netcdf(ds, path, overwrite=overwrite)


def modes_to_json(ds) -> dict:
    """The JSON summary of a modal analysis: ``{"frequencies_hz": [...], ...}`` (with the preloaded contact:
    its load, closed nodes and per pair the contact length, pressures and normal stiffness)."""
    import json
    return {
        "frequencies_hz": [float(f) for f in ds["frequency"].values],
        "n_modes": int(ds.sizes["mode"]),
        "n_dofs": int(ds.attrs["n_dofs"]),
        "n_free_dofs": int(ds.attrs["n_free_dofs"]),
        "mass_matrix": ds.attrs["mass_matrix"],
        "include_contact": bool(ds.attrs["include_contact"]),
        "prestress": bool(ds.attrs.get("prestress", 0)),
        **({"normal_load_n": float(ds.attrs["normal_load"]),
            "closed_slave_nodes": np.atleast_1d(ds.attrs["closed_slave_nodes"]).tolist(),
            "contact": json.loads(ds.attrs.get("contact_summary", "[]"))}
           if "normal_load" in ds.attrs else {}),
        "model": ds.attrs["model"],
        "model_source": ds.attrs["model_source"],
    }
