"""Q4 element matrices (2x2 Gauss) and global sparse assembly: stiffness, lumped/consistent mass, Rayleigh damping.

Element functions are vectorised: ``xy`` may be one element ``(4, 2)`` or a stack ``(..., 4, 2)``
(e.g. ``Block.element_corners()``, shape ``(ny, nx, 4, 2)``), and they return ``(..., 8, 8)``.
Element dofs are ordered ``x0, y0, x1, y1, x2, y2, x3, y3`` for nodes counter-clockwise from the
element's lower-left node, i.e. natural coordinates ``(-1,-1), (1,-1), (1,1), (-1,1)``.

A model with :class:`fivid.fe.model.Tie` rows (mesh transitions) is assembled on its independent dofs:
``T^T K T``, ``T^T M T`` and the lumped ``T^T m`` with ``u = T u`` (:func:`tie_matrix`), so the tied dofs'
rows and columns are zero (they are not in ``Model.free_dofs``).

The explicit solver builds its per-block stencils from :func:`element_stiffness_q4` (and
:func:`block_element_stiffness`); the sparse matrices here serve modal analysis, CEA and reference checks.
"""

from __future__ import annotations

import weakref

import numpy as np

from fivid.errors import ConfigError
from fivid.fe.model import Material

__all__ = [
    "GAUSS_POINTS_2X2",
    "shape_functions_q4",
    "shape_gradients_q4",
    "strain_displacement_q4",
    "element_stiffness_q4",
    "element_mass_q4",
    "block_element_stiffness",
    "block_element_mass",
    "stiffness_matrix",
    "consistent_mass",
    "lumped_mass",
    "damping_matrix",
    "tie_matrix",
]

_G = 1.0 / np.sqrt(3.0)
#: 2x2 Gauss points (xi, eta) in [-1, 1]^2, weights all 1.
GAUSS_POINTS_2X2 = np.array([[-_G, -_G], [_G, -_G], [_G, _G], [-_G, _G]])
_XI_NODES = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])


def shape_functions_q4(xi: float, eta: float) -> np.ndarray:
    """Bilinear shape functions ``N_a = (1 + xi_a xi)(1 + eta_a eta)/4`` at ``(xi, eta)``, shape (4,)."""
    return 0.25 * (1.0 + _XI_NODES[:, 0] * xi) * (1.0 + _XI_NODES[:, 1] * eta)


def _natural_gradients(xi: float, eta: float) -> np.ndarray:
    """dN_a/dxi, dN_a/deta, shape (4, 2)."""
    return 0.25 * np.stack(
        [_XI_NODES[:, 0] * (1.0 + _XI_NODES[:, 1] * eta), _XI_NODES[:, 1] * (1.0 + _XI_NODES[:, 0] * xi)], axis=-1
    )


def shape_gradients_q4(xy: np.ndarray, xi: float, eta: float) -> tuple[np.ndarray, np.ndarray]:
    """Cartesian shape-function gradients and Jacobian determinant at ``(xi, eta)``.

    Parameters
    ----------
    xy : ndarray, shape (..., 4, 2)
        Element node coordinates [m].

    Returns
    -------
    dN : ndarray, shape (..., 4, 2)
        dN_a/dx, dN_a/dy [m-1].
    detJ : ndarray, shape (...)
        Jacobian determinant [m2] (positive for counter-clockwise elements).
    """
    dn = _natural_gradients(xi, eta)  # (4, 2)
    J = np.einsum("ak,...ai->...ki", dn, xy)  # J[k, i] = d x_i / d xi_k
    det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    inv = np.stack(
        [np.stack([J[..., 1, 1], -J[..., 0, 1]], -1), np.stack([-J[..., 1, 0], J[..., 0, 0]], -1)], -2
    ) / det[..., None, None]  # inv[i, k] = d xi_k / d x_i
    dN = np.einsum("ak,...ik->...ai", dn, inv)
    return dN, det


def strain_displacement_q4(dN: np.ndarray) -> np.ndarray:
    """The 3x8 matrix B with ``(eps_xx, eps_yy, gamma_xy) = B u_e``, from gradients of shape (..., 4, 2)."""
    shape = dN.shape[:-2]
    B = np.zeros(shape + (3, 8))
    B[..., 0, 0::2] = dN[..., 0]
    B[..., 1, 1::2] = dN[..., 1]
    B[..., 2, 0::2] = dN[..., 1]
    B[..., 2, 1::2] = dN[..., 0]
    return B


def _elasticity(E: float, nu: float, plane: str) -> np.ndarray:
    return Material(E, nu, 1.0).elasticity_matrix(plane)


def element_stiffness_q4(xy: np.ndarray, E: float, nu: float, thickness: float, plane: str) -> np.ndarray:
    """Q4 element stiffness by 2x2 Gauss integration (full integration).

    ``K_e = t * sum_g B_g^T D B_g det J_g`` [N m-1].

    Parameters
    ----------
    xy : ndarray, shape (..., 4, 2)
        Node coordinates [m], counter-clockwise.
    E : float
        Young's modulus [Pa].
    nu : float
        Poisson's ratio [-].
    thickness : float
        Out-of-plane thickness [m].
    plane : {"stress", "strain"}

    Returns
    -------
    ndarray, shape (..., 8, 8)
        Symmetric positive semi-definite with 3 rigid-body zero modes [N m-1].
    """
    xy = np.asarray(xy, dtype=float)
    D = _elasticity(E, nu, plane)
    K = np.zeros(xy.shape[:-2] + (8, 8))
    for xi, eta in GAUSS_POINTS_2X2:
        dN, det = shape_gradients_q4(xy, xi, eta)
        B = strain_displacement_q4(dN)
        K += np.einsum("...ki,kl,...lj->...ij", B, D, B) * det[..., None, None]
    return thickness * K


def element_mass_q4(xy: np.ndarray, rho: float, thickness: float, *, lumped: bool = False) -> np.ndarray:
    """Q4 element mass, consistent (2x2 Gauss, exact for parallelograms) or lumped by row sums.

    ``M_e = rho t sum_g N_g^T N_g det J_g`` [kg]. Row-sum lumping keeps the element mass exactly and
    gives positive masses for any convex quadrilateral.

    Parameters
    ----------
    xy : ndarray, shape (..., 4, 2)
        Node coordinates [m].
    rho : float
        Density [kg m-3].
    thickness : float
        [m].
    lumped : bool
        Return the row-sum lumped (diagonal) matrix.

    Returns
    -------
    ndarray, shape (..., 8, 8) [kg]
    """
    xy = np.asarray(xy, dtype=float)
    m = np.zeros(xy.shape[:-2] + (4, 4))
    for xi, eta in GAUSS_POINTS_2X2:
        N = shape_functions_q4(xi, eta)
        _, det = shape_gradients_q4(xy, xi, eta)
        m += np.outer(N, N) * det[..., None, None]
    m *= rho * thickness
    if lumped:
        m = np.eye(4) * m.sum(axis=-1)[..., None, :]
    M = np.zeros(xy.shape[:-2] + (8, 8))
    M[..., 0::2, 0::2] = m
    M[..., 1::2, 1::2] = m
    return M


#: element stiffnesses per block, computed once per (frozen) block: a run asks for them three to four times (the
#: stencils, the preload's K, the reduced basis' K, the memory guard's step bound; 0.06 s per default-rig block)
_ELEMENT_STIFFNESS = weakref.WeakKeyDictionary()


def block_element_stiffness(block) -> np.ndarray:
    """Element stiffness of every element of a block, shape (ny, nx, 8, 8) [N m-1] (read-only: kept per block)."""
    ke = _ELEMENT_STIFFNESS.get(block)
    if ke is None:
        mat = block.material
        ke = element_stiffness_q4(block.element_corners(), mat.E, mat.nu, block.thickness, block.plane)
        ke.flags.writeable = False
        _ELEMENT_STIFFNESS[block] = ke
    return ke


def block_element_mass(block, *, lumped: bool = False) -> np.ndarray:
    """Element mass of every element of a block, shape (ny, nx, 8, 8) [kg] (the density times the block's
    ``mass_scale``, :mod:`fivid.fe.mass_scaling`)."""
    return element_mass_q4(block.element_corners(), block.material.rho * block.mass_scale, block.thickness,
                           lumped=lumped)


def _assemble(model, element_matrices) -> "scipy.sparse.csr_matrix":  # noqa: F821
    import scipy.sparse as sp

    rows, cols, vals = [], [], []
    for block in model.blocks:
        ke = element_matrices(block).reshape(-1, 8, 8)
        dofs = block.element_dofs().reshape(-1, 8)
        rows.append(np.repeat(dofs, 8, axis=1).ravel())
        cols.append(np.tile(dofs, (1, 8)).ravel())
        vals.append(ke.ravel())
    n = model.n_dofs
    A = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)).tocsr()
    if model.ties:
        T = tie_matrix(model)
        A = (T.T @ A @ T).tocsr()
    return A


def tie_matrix(model) -> "scipy.sparse.csr_matrix":  # noqa: F821
    """``T`` (n_dofs x n_dofs, scipy.sparse CSR) with ``u = T u`` for the model's ties: identity on untied dofs,
    a tied (slave) dof's row its interpolation weights on the masters' same component, its column zero."""
    import scipy.sparse as sp

    n = model.n_dofs
    keep = np.ones(n, dtype=bool)
    keep[model.tied_dofs] = False
    rows, cols, vals = [np.flatnonzero(keep)], [np.flatnonzero(keep)], [np.ones(int(keep.sum()))]
    for t in model.ties:
        for c in (0, 1):
            for i in (0, 1):
                rows.append(2 * np.asarray(t.slave_nodes) + c)
                cols.append(2 * np.asarray(t.master_nodes)[:, i] + c)
                vals.append(np.asarray(t.weights, float)[:, i])
    return sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)).tocsr()


def _springs_coo(model, attribute: str):
    rows, cols, vals = [], [], []
    for s in model.springs:
        k = float(getattr(s, attribute))
        if k == 0.0:
            continue
        a = 2 * s.node_a + s.component
        rows.append(a), cols.append(a), vals.append(k)
        if s.node_b >= 0:
            b = 2 * s.node_b + s.component
            rows += [b, a, b]
            cols += [b, b, a]
            vals += [k, -k, -k]
    return rows, cols, vals


def _discrete_matrix(model, attribute: str):
    import scipy.sparse as sp

    rows, cols, vals = _springs_coo(model, attribute)
    n = model.n_dofs
    return sp.coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()


def stiffness_matrix(model, *, include_springs: bool = True):
    """Global stiffness K [N m-1] (scipy.sparse CSR, ``n_dofs x n_dofs``), constraints not applied.

    Parameters
    ----------
    model : Model
    include_springs : bool
        Add the discrete springs (node-node and node-ground).
    """
    K = _assemble(model, block_element_stiffness)
    if include_springs and model.springs:
        K = (K + _discrete_matrix(model, "stiffness")).tocsr()
    return K


def consistent_mass(model):
    """Global consistent mass M [kg] (scipy.sparse CSR), point masses added on the diagonal."""
    import scipy.sparse as sp

    M = _assemble(model, block_element_mass)
    pm = _point_mass_vector(model)
    if pm.any():
        M = (M + sp.diags(pm)).tocsr()
    return M


def _point_mass_vector(model) -> np.ndarray:
    pm = np.zeros(model.n_dofs)
    for p in model.point_masses:
        pm[2 * p.node] += p.mass
        pm[2 * p.node + 1] += p.mass
    return pm


def lumped_mass(model) -> np.ndarray:
    """Row-sum lumped mass per dof [kg], shape (n_dofs,), point masses included (tied dofs: 0, their mass on
    their masters)."""
    m = np.zeros(model.n_dofs)
    for block in model.blocks:
        me = block_element_mass(block, lumped=True).reshape(-1, 8, 8)
        dofs = block.element_dofs().reshape(-1, 8)
        np.add.at(m, dofs.ravel(), np.diagonal(me, axis1=1, axis2=2).ravel())
    if model.ties:  # a tied node's mass goes to its masters by the interpolation weights (T^T m: mass kept)
        m = tie_matrix(model).T @ m
    return m + _point_mass_vector(model)


def damping_matrix(model, *, mass: str = "lumped", stiffness=None):
    """Viscous damping C = alpha M + beta K + dashpots [N s m-1] (scipy.sparse CSR).

    Parameters
    ----------
    model : Model
    mass : {"lumped", "consistent"}
        Which mass matrix the alpha term uses.
    stiffness : sparse matrix, optional
        K to reuse (assembled if not given).
    """
    import scipy.sparse as sp

    if mass not in ("lumped", "consistent"):
        raise ConfigError(f"mass must be 'lumped' or 'consistent', got {mass!r}", key="mass")
    M = sp.diags(lumped_mass(model)) if mass == "lumped" else consistent_mass(model)
    K = stiffness_matrix(model) if stiffness is None else stiffness
    C = model.rayleigh_alpha * M + model.rayleigh_beta * K
    if model.springs:
        C = C + _discrete_matrix(model, "damping")
    return sp.csr_matrix(C)
