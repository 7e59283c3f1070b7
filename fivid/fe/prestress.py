"""Prestress (geometric, initial-stress) stiffness of the Q4 blocks about a preloaded static state.

Small vibrations about a statically preloaded state ``u_0`` whose in-plane Cauchy stress is ``S`` see, besides
the elastic stiffness ``K``, the initial-stress stiffness

    K_sigma = sum_e t sum_g G_g^T S_g G_g det J_g,     S_g = [[s_xx, s_xy], [s_xy, s_yy]] at Gauss point g,

with ``G`` the displacement-gradient operator (per component, ``dN_a/dx_j``), 2x2 Gauss like ``K``
(:mod:`fivid.fe.assembly`). It is the second-order (Green-Lagrange) part of the strain energy,
``1/2 int S : (grad w)^T grad w dV``, of a perturbation ``w`` carried by the preload's stress: tension stiffens
(a string, a hoop-stretched ring), compression softens, and ``K + lambda K_sigma`` singular is linearised
buckling (:func:`buckling_load_factors`).

Assumptions and their limit (the "small vibration about the prestressed state" form):

* the static state is the linear (small-strain, small-rotation) solution in the reference configuration, and
  its stress enters at its reference-configuration value; the geometry is not updated. This is the classical
  linearised buckling / stress-stiffening form. It holds while the preload's strains and rotations are small
  (``|eps| << 1``, rotations << 1 rad): the neglected terms are of relative order ``|eps|`` against ``K_sigma``
  (e.g. the initial-displacement stiffness), and of order ``|S|/E`` against ``K``. Past a buckling load, or with
  large preload rotations, a geometrically non-linear (large-rotation) solve is needed; it is not provided.
* pressure loads are dead loads (fixed direction): no load stiffness is added. A follower pressure would add
  one of order ``p t`` per unit length, which matters for a pressurised ring's breathing modes.
* plane strain: the out-of-plane stress ``s_zz = nu (s_xx + s_yy)`` exists but does no work on in-plane
  perturbations, so only the in-plane stress enters (the same operator serves both plane states).
* a model with ``prestress: true`` carries the term everywhere: modes and CEA add ``K_sigma`` (and the Rayleigh
  ``beta`` acts on ``K + K_sigma``), the explicit solver folds it into its stencil and adds the reference force
  ``K_sigma u0`` as a load ramped with the preload, so its internal force is ``K w + K_sigma (w - r(t) u0)``
  (:func:`fivid.solver.stencil.block_stencils`, :func:`fivid.solver.setup.kernel_arrays`): the same linear
  system about the same static state ``u0`` (:func:`prestress_state`).
"""

from __future__ import annotations

import numpy as np

from fivid.errors import ConfigError
from fivid.fe.assembly import GAUSS_POINTS_2X2, _assemble, shape_gradients_q4, stiffness_matrix, strain_displacement_q4
from fivid.fe.loads import static_response
from fivid.fe.static import preload_state, pressed_by_itself

__all__ = ["gauss_point_stress_q4", "block_gauss_point_stress", "element_geometric_stiffness_q4",
           "block_geometric_stiffness", "geometric_stiffness_matrix", "buckling_load_factors", "static_state",
           "prestress_state", "preload_ramp_end"]


def gauss_point_stress_q4(xy: np.ndarray, u_e: np.ndarray, D: np.ndarray) -> np.ndarray:
    """In-plane Cauchy stress ``(s_xx, s_yy, s_xy) = D B_g u_e`` at the 2x2 Gauss points (order of
    :data:`fivid.fe.assembly.GAUSS_POINTS_2X2`).

    Parameters
    ----------
    xy : ndarray, shape (..., 4, 2)
        Element node coordinates [m], counter-clockwise.
    u_e : ndarray, shape (..., 8)
        Element displacements ``x0, y0, ..., x3, y3`` [m].
    D : ndarray, shape (3, 3)
        Elasticity matrix [Pa] (:meth:`fivid.fe.model.Material.elasticity_matrix`).

    Returns
    -------
    ndarray, shape (..., 4, 3)
        Stress at each Gauss point [Pa].
    """
    xy = np.asarray(xy, dtype=float)
    out = np.zeros(xy.shape[:-2] + (4, 3))
    for g, (xi, eta) in enumerate(GAUSS_POINTS_2X2):
        B = strain_displacement_q4(shape_gradients_q4(xy, xi, eta)[0])
        out[..., g, :] = np.einsum("kl,...lj,...j->...k", D, B, u_e)
    return out


def block_gauss_point_stress(block, u: np.ndarray) -> np.ndarray:
    """Gauss-point stress of every element of a block under the global displacement ``u`` [m],
    shape (ny, nx, 4, 3) [Pa] (``s_xx, s_yy, s_xy``)."""
    u = np.asarray(u, dtype=float)
    D = block.material.elasticity_matrix(block.plane)
    return gauss_point_stress_q4(block.element_corners(), u[block.element_dofs()], D)


def element_geometric_stiffness_q4(xy: np.ndarray, stress: np.ndarray, thickness: float) -> np.ndarray:
    """Q4 initial-stress stiffness ``t sum_g G_g^T S_g G_g det J_g`` [N m-1] (2x2 Gauss).

    Parameters
    ----------
    xy : ndarray, shape (..., 4, 2)
        Element node coordinates [m], counter-clockwise.
    stress : ndarray, shape (..., 4, 3)
        In-plane stress ``(s_xx, s_yy, s_xy)`` at the Gauss points [Pa] (:func:`gauss_point_stress_q4`).
    thickness : float
        Out-of-plane thickness [m].

    Returns
    -------
    ndarray, shape (..., 8, 8)
        Symmetric; the same 4x4 block ``H_ab = t sum_g dN_a . S_g dN_b det J_g`` acts on the x and on the y
        components (no x-y coupling). Positive semi-definite under tension, negative under compression.
    """
    xy = np.asarray(xy, dtype=float)
    stress = np.asarray(stress, dtype=float)
    H = np.zeros(xy.shape[:-2] + (4, 4))
    for g, (xi, eta) in enumerate(GAUSS_POINTS_2X2):
        dN, det = shape_gradients_q4(xy, xi, eta)
        s = stress[..., g, :]
        S = np.stack([np.stack([s[..., 0], s[..., 2]], -1), np.stack([s[..., 2], s[..., 1]], -1)], -2)
        H += np.einsum("...ai,...ij,...bj->...ab", dN, S, dN) * det[..., None, None]
    K = np.zeros(xy.shape[:-2] + (8, 8))
    K[..., 0::2, 0::2] = H
    K[..., 1::2, 1::2] = H
    return thickness * K


def block_geometric_stiffness(block, u: np.ndarray) -> np.ndarray:
    """Initial-stress stiffness of every element of a block under the static state ``u`` [m] (global dofs),
    shape (ny, nx, 8, 8) [N m-1], the layout of :func:`fivid.fe.assembly.block_element_stiffness` (the explicit
    solver adds it to the elastic element stiffness, :func:`fivid.solver.stencil.block_stencils`)."""
    return element_geometric_stiffness_q4(block.element_corners(), block_gauss_point_stress(block, u),
                                          block.thickness)


def geometric_stiffness_matrix(model, u: np.ndarray):
    """Global initial-stress stiffness ``K_sigma`` [N m-1] of the static state ``u`` (scipy.sparse CSR,
    ``n_dofs x n_dofs``, constraints not applied); see the module docstring for the assumptions.

    Parameters
    ----------
    model : Model
    u : ndarray, shape (n_dofs,)
        Static displacement of the preloaded state [m] (e.g. :func:`fivid.fe.static.preload_state` ``.u`` or
        :func:`fivid.fe.loads.static_response`).
    """
    u = np.asarray(u, dtype=float)
    if u.shape != (model.n_dofs,) or not np.all(np.isfinite(u)):
        raise ConfigError(f"the prestress state must be a finite displacement of shape ({model.n_dofs},), "
                          f"got shape {u.shape}", key="prestress")

    return _assemble(model, lambda block: block_geometric_stiffness(block, u))


def static_state(model) -> np.ndarray:
    """The preloaded static state of a model without a contact solve [m], shape (n_dofs,): the linear response to
    the full pressure loads with every displacement motion at its final ``amplitude`` (an imposed stretch, a moved
    clamp) and all other constrained dofs (clamps, velocity motions) at rest
    (:func:`fivid.fe.loads.static_response`). For a contact preload use :func:`fivid.fe.static.preload_state`."""
    imposed = np.zeros(model.n_dofs)
    for m in model.motions:
        if m.kind == "displacement":
            imposed[m.dofs] = m.amplitude
    return static_response(model, imposed=imposed)


def prestress_state(model, normal_load: float | None = None) -> np.ndarray:
    """The static state [m] (n_dofs,) whose stress the prestress stiffness takes, the same for the explicit
    solver, modes and CEA: the contact preload (:func:`fivid.fe.static.preload_state` under ``normal_load`` [N],
    or under the model's own loading -- pressure loads, expanding rigid circles -- when it is None) for a model
    with contacts that something presses, else :func:`static_state`."""
    if model.contacts and (normal_load is not None or pressed_by_itself(model)):
        return preload_state(model, normal_load).u
    return static_state(model)


def preload_ramp_end(model) -> float:
    """End [s] of the preload's ramps (pressure loads, expanding rigid circles, the loading clamp's motion): the
    explicit solver ramps the prestress term's reference state ``r(t) u_0`` over ``[0, preload_ramp_end]``
    with the solver's smooth ramp (0: a step at t = 0)."""
    ends = [float(ld.start + ld.ramp_time) for ld in model.loads]
    ends += [float(c.rigid.expansion_start + c.rigid.expansion_ramp_time) for c in model.contacts
             if c.rigid is not None and c.rigid.kind == "circle" and c.rigid.expansion != 0.0]
    ends += [float(m.ramp_time) for m in model.motions if m.kind == "displacement"]
    return max(ends, default=0.0)


def buckling_load_factors(model, u: np.ndarray, n: int = 1) -> np.ndarray:
    """The ``n`` smallest positive load factors ``lambda`` at which ``K + lambda K_sigma(u)`` turns singular on
    the free dofs (linearised buckling of the load that produced ``u``; springs included in ``K``).

    Solved as ``K_sigma phi = mu K phi`` with ``K`` positive definite on the free dofs (a model held against
    rigid-body motion) and ``lambda = -1/mu`` for the most negative ``mu`` (ARPACK, ``scipy.sparse.linalg.eigsh``
    in the ``K``-inner product; dense ``scipy.linalg.eigh`` below 600 free dofs).

    Parameters
    ----------
    model : Model
    u : ndarray, shape (n_dofs,)
        The static state under the reference load [m].
    n : int
        Number of load factors.

    Returns
    -------
    ndarray, shape (<= n,)
        Ascending positive load factors [-] (the critical load is ``lambda`` x the reference load); fewer
        than ``n`` if the stress state has fewer compressive modes.
    """
    import scipy.linalg
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    free = model.free_dofs
    K = stiffness_matrix(model).tocsr()[free][:, free]
    Ks = geometric_stiffness_matrix(model, u)[free][:, free]
    k = int(min(n, free.size - 1))
    if k < 1:
        raise ConfigError(f"n must be >= 1 and the model must have free dofs, got n={n}", key="n")
    if free.size <= 600:
        mu = scipy.linalg.eigh(-Ks.toarray(), K.toarray(), eigvals_only=True)[::-1][:k]
    else:
        mu = spla.eigsh(sp.csc_matrix(-Ks), k=k, M=sp.csc_matrix(K), which="LA", return_eigenvectors=False)
        mu = np.sort(mu)[::-1]
    mu = mu[mu > 0]
    return 1.0 / mu
