"""Q4 element matrices and global assembly against closed forms, a published matrix and the patch test."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from hypothesis import given, settings
from hypothesis import strategies as st

from fivid.fe import (
    consistent_mass,
    element_mass_q4,
    element_stiffness_q4,
    load_model,
    lumped_mass,
    rayleigh_through_two_ratios,
    stiffness_matrix,
)
from fivid.fe.assembly import GAUSS_POINTS_2X2, shape_gradients_q4, strain_displacement_q4

EPS = np.finfo(float).eps
QUAD = np.array([[0.0, 0.0], [2.0, 0.3], [1.7, 1.4], [0.2, 1.1]])  # a general convex quadrilateral [m]


def test_unit_square_stiffness_equals_the_published_matrix():
    """Andreassen et al. (2011), '88-line topology optimization', KE of a unit square plane-stress Q4 (E=1, t=1)."""
    nu = 0.3
    k = np.array([1 / 2 - nu / 6, 1 / 8 + nu / 8, -1 / 4 - nu / 12, -1 / 8 + 3 * nu / 8,
                  -1 / 4 + nu / 12, -1 / 8 - nu / 8, nu / 6, 1 / 8 - 3 * nu / 8])
    idx = np.array([[1, 2, 3, 4, 5, 6, 7, 8], [2, 1, 8, 7, 6, 5, 4, 3], [3, 8, 1, 6, 7, 4, 5, 2],
                    [4, 7, 6, 1, 8, 3, 2, 5], [5, 6, 7, 8, 1, 2, 3, 4], [6, 5, 4, 3, 2, 1, 8, 7],
                    [7, 4, 5, 2, 3, 8, 1, 6], [8, 3, 2, 5, 4, 7, 6, 1]]) - 1
    KE = k[idx] / (1 - nu**2)
    K = element_stiffness_q4(np.array([[0, 0], [1, 0], [1, 1], [0, 1.0]]), 1.0, nu, 1.0, "stress")
    # entries are O(1) sums of 4 Gauss terms: a few ulps
    np.testing.assert_allclose(K, KE, rtol=0, atol=16 * EPS)


def test_element_stiffness_has_exactly_three_rigid_body_modes():
    K = element_stiffness_q4(QUAD, 210e9, 0.3, 0.01, "stress")
    assert np.abs(K - K.T).max() <= 16 * EPS * np.abs(K).max()
    w = np.linalg.eigvalsh(K)
    # zero eigenvalues up to eps*||K|| times the matrix size; the 4th (first elastic) is O(E t)
    zero = 8 * 8 * EPS * w[-1]
    assert np.all(np.abs(w[:3]) < zero) and w[3] > 1e-3 * w[-1]
    x, y = QUAD.T
    for rigid in (np.c_[np.ones(4), np.zeros(4)], np.c_[np.zeros(4), np.ones(4)], np.c_[-y, x]):
        assert np.abs(K @ rigid.ravel()).max() < zero


def test_plane_strain_equals_plane_stress_with_effective_constants():
    """Plane strain with (E, nu) is plane stress with E* = E/(1-nu^2), nu* = nu/(1-nu) (elasticity textbooks)."""
    E, nu = 70e9, 0.33
    a = element_stiffness_q4(QUAD, E, nu, 1.0, "strain")
    b = element_stiffness_q4(QUAD, E / (1 - nu**2), nu / (1 - nu), 1.0, "stress")
    np.testing.assert_allclose(a, b, rtol=0, atol=64 * EPS * np.abs(a).max())


def test_rectangle_consistent_mass_closed_form_and_lumped_rowsum():
    a, b, rho, t = 0.3, 0.2, 7850.0, 0.01
    M = element_mass_q4(np.array([[0, 0], [a, 0], [a, b], [0, b]]), rho, t)
    m = rho * t * a * b / 36 * np.array([[4, 2, 1, 2], [2, 4, 2, 1], [1, 2, 4, 2], [2, 1, 2, 4]])  # bilinear, exact
    np.testing.assert_allclose(M[0::2, 0::2], m, rtol=64 * EPS)
    np.testing.assert_allclose(M[1::2, 1::2], m, rtol=64 * EPS)
    assert np.all(M[0::2, 1::2] == 0)
    L = element_mass_q4(QUAD, rho, t, lumped=True)
    C = element_mass_q4(QUAD, rho, t)
    np.testing.assert_allclose(np.diag(L), C.sum(axis=1), rtol=64 * EPS)
    assert np.all(np.diag(L) > 0)


def _distorted_block(plane="stress"):
    cfg = {"plane": plane, "bodies": {"patch": {
        "corners": [[0, 0], [2.0, 0.3], [1.7, 1.4], [0.2, 1.1]], "divisions": [4, 3],
        "material": {"E": 1e3, "nu": 0.25, "rho": 1.0}, "thickness": 0.5}}}
    model = load_model(cfg)
    b = model.blocks[0]
    rng = np.random.default_rng(7)
    inner = b.coords[1:-1, 1:-1]
    inner += rng.uniform(-0.08, 0.08, inner.shape)  # perturb interior nodes: general, non-affine quads
    model.coords[:] = b.coords.reshape(-1, 2)
    return model


@pytest.mark.parametrize("plane", ["stress", "strain"])
def test_patch_test_reproduces_a_linear_field_exactly(plane):
    """Displacement patch test (Irons; Zienkiewicz & Taylor): boundary nodes follow u = a + G x, interior free,
    no load. A consistent element reproduces the linear field at interior nodes and a constant strain G_sym."""
    model = _distorted_block(plane)
    b = model.blocks[0]
    x = model.coords
    a0 = np.array([1e-3, -2e-3])
    G = np.array([[2e-3, -1e-3], [3e-3, 1.5e-3]])
    exact = (a0 + x @ G.T).ravel()
    K = stiffness_matrix(model)
    boundary = np.unique(np.concatenate([b.edge_nodes(e) for e in ("bottom", "right", "top", "left")]))
    fixed = np.sort(np.concatenate([2 * boundary, 2 * boundary + 1]))
    free = np.setdiff1d(np.arange(model.n_dofs), fixed)
    u = exact.copy()
    u[free] = spla.spsolve(K[free][:, free].tocsc(), -K[free][:, fixed] @ exact[fixed])
    # error ~ cond(K_ff) * eps * |u|; cond(K_ff) of a 4x3 patch is O(100): 1e-10 relative is a wide margin
    scale = np.abs(exact).max()
    assert np.abs(u - exact).max() < 1e-10 * scale
    strain = np.array([G[0, 0], G[1, 1], G[0, 1] + G[1, 0]])
    ue = u[b.element_dofs().reshape(-1, 8)]
    for xi, eta in GAUSS_POINTS_2X2:
        dN, det = shape_gradients_q4(b.element_corners().reshape(-1, 4, 2), xi, eta)
        assert np.all(det > 0)
        eps_g = np.einsum("eij,ej->ei", strain_displacement_q4(dN), ue)
        assert np.abs(eps_g - strain).max() < 1e-9 * np.abs(strain).max()


def test_global_matrices_rigid_motions_total_mass_and_point_masses():
    cfg = {"bodies": {
        "a": {"corners": [[0, 0], [0.1, 0], [0.1, 0.01], [0, 0.01]], "divisions": [10, 2],
              "material": {"E": 210e9, "nu": 0.3, "rho": 7850}, "thickness": 0.01},
        "b": {"corners": [[0, 0.02], [0.05, 0.02], [0.05, 0.03], [0, 0.035]], "divisions": [5, 2],
              "material": {"E": 70e9, "nu": 0.33, "rho": 2700}, "thickness": 0.02}},
        "point_masses": [{"name": "acc", "body": "a", "at": [0.05, 0.01], "mass": "5 g"}]}
    m = load_model(cfg)
    K = stiffness_matrix(m)
    assert K.shape == (m.n_dofs, m.n_dofs) and abs(K - K.T).max() <= 64 * EPS * abs(K).max()
    x, y = m.coords.T
    for rigid in (np.c_[np.ones_like(x), 0 * x], np.c_[0 * x, np.ones_like(x)], np.c_[-y, x]):
        assert np.abs(K @ rigid.ravel()).max() < 1e-9 * abs(K).max() * np.abs(rigid).max()
    area_b = 0.05 * 0.01 + 0.5 * 0.05 * 0.005  # trapezoid
    total = 7850 * 0.01 * 0.1 * 0.01 + 2700 * 0.02 * area_b + 0.005
    ml = lumped_mass(m)
    Mc = consistent_mass(m)
    ones_x = np.tile([1.0, 0.0], m.n_nodes)
    assert ml[0::2].sum() == pytest.approx(total, rel=1e-12) and ml[1::2].sum() == pytest.approx(total, rel=1e-12)
    assert ones_x @ (Mc @ ones_x) == pytest.approx(total, rel=1e-12)
    np.testing.assert_allclose(ml, np.asarray(Mc.sum(axis=1)).ravel(), rtol=1e-12)  # global row-sum lumping
    node = m.point_masses[0].node
    assert np.allclose(m.coords[node], [0.05, 0.01])


def test_springs_add_to_stiffness():
    base = {"bodies": {"a": {"corners": [[0, 0], [1, 0], [1, 1], [0, 1]], "divisions": [1, 1],
                             "material": {"E": 1.0, "nu": 0.3, "rho": 1.0}, "thickness": 1.0}}}
    cfg = dict(base, springs=[
        {"name": "g", "a": {"body": "a", "at": [0, 0]}, "b": "ground", "component": "y", "stiffness": 5.0},
        {"name": "ab", "a": {"body": "a", "at": [1, 0]}, "b": {"body": "a", "at": [1, 1]}, "component": "x",
         "stiffness": 2.0, "damping": 0.1}])
    d = (stiffness_matrix(load_model(cfg)) - stiffness_matrix(load_model(base))).toarray()
    expect = np.zeros((8, 8))
    expect[1, 1] = 5.0
    expect[np.ix_([2, 6], [2, 6])] = [[2.0, -2.0], [-2.0, 2.0]]  # x dofs of nodes 1 (1, 0) and 3 (1, 1)
    np.testing.assert_allclose(d, expect, atol=1e-14)


def test_rayleigh_coefficients_reproduce_the_target_damping_ratios():
    f1, z1, f2, z2 = 1e3, 0.005, 1e4, 0.01
    alpha, beta = rayleigh_through_two_ratios(f1, z1, f2, z2)
    for f, z in ((f1, z1), (f2, z2)):
        w = 2 * np.pi * f
        assert alpha / (2 * w) + beta * w / 2 == pytest.approx(z, rel=1e-12)
    with pytest.raises(ValueError):
        rayleigh_through_two_ratios(1e3, 0.01, 1e3, 0.02)

_square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-0.2, 0.2), min_size=8, max_size=8), st.floats(0.0, 2 * np.pi), st.floats(1e-3, 10.0))
def test_element_stiffness_is_objective_and_scale_free(offsets, angle, scale):
    """For any convex quad (a unit square with corners moved by < 0.2, always convex): rotating the element by R
    rotates its stiffness, K(R x) = T K(x) T^T with T = blockdiag(R, R, R, R); and in 2D the stiffness of a
    geometrically scaled element is unchanged (K ~ t E, integrand ~ 1/L^2 times area ~ L^2)."""
    xy = _square + np.reshape(offsets, (4, 2))
    K = element_stiffness_q4(xy, 1.0, 0.3, 1.0, "stress")
    c, s = np.cos(angle), np.sin(angle)
    R = np.array([[c, -s], [s, c]])
    T = np.kron(np.eye(4), R)
    Kr = element_stiffness_q4(scale * xy @ R.T, 1.0, 0.3, 1.0, "stress")
    # entries O(1), each a sum of a few products: rounding ~ 1e2 eps covers rotation and scaling round-off
    np.testing.assert_allclose(Kr, T @ K @ T.T, rtol=0, atol=1e-13)
    w = np.linalg.eigvalsh(K)
    assert np.all(np.abs(w[:3]) < 1e-13) and w[3] > 1e-3
