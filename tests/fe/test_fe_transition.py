"""Meshes coarsening along x with depth (fivid.fe.transition): exactness across the tied transitions, the kernel
against assembly, modal convergence against a uniform mesh, and an explicit run's energy balance."""

from __future__ import annotations

import numpy as np
import pytest

from fivid.fe import load_model as build_model
from fivid.fe.assembly import lumped_mass, stiffness_matrix, tie_matrix
from fivid.fe.modal import constrained_matrices, lowest_modes
from fivid.fe.transition import transition_columns, transition_levels, transition_model
from fivid.solver.stencil import apply_stencils, block_stencils
from tests.helpers.convergence import assert_order
from tests.helpers.solver_models import stencil_bound

E, NU, RHO = 210e9, 0.3, 7800.0


def _block(nx, ny, *, length=0.12, depth=8e-3, amplitude=0.0, clamp=("left", "right"), grading=None):
    """A steel block profiled on its top edge (sine of ``amplitude`` [m], 1 mm wavelength), plane strain."""
    body = {"corners": [[0.0, 0.0], [length, 0.0], [length, depth], [0.0, depth]], "divisions": [nx, ny],
            "material": "steel", "thickness": 0.01, "clamp": list(clamp),
            "profile": {"edge": "top", "sine": {"amplitude": amplitude, "wavelength": 1e-3}}}
    if grading:
        body["grading"] = {"ratio": grading}
    return build_model({"name": "block", "plane": "strain",
                        "materials": {"steel": {"E": E, "nu": NU, "rho": RHO}}, "bodies": {"lower": body}})


def test_levels_fill_the_depth_and_halve_the_columns():
    lv = transition_levels(1920, 62.5e-6, 8e-3)
    assert sum(r * t for r, t in zip(lv.rows, lv.thickness)) == pytest.approx(8e-3, rel=1e-12)
    assert all(a == 2 * b for a, b in zip(lv.columns[:-1], lv.columns[1:]))
    nx = transition_columns(0.12, 64.5e-6, 8e-3)
    assert 0.12 / nx <= 64.5e-6 and nx % 2 ** (transition_levels(nx, 0.12 / nx, 8e-3).n_levels - 1) == 0


@pytest.fixture(scope="module")
def tied():
    """A 12 x 2 mm block with a 5 um sine profile, 96 columns at the surface, coarsened with depth (two ties)."""
    return transition_model(_block(96, 1, length=12e-3, depth=2e-3, amplitude=5e-6), ["lower"], max_width=1e-3)


def test_linear_fields_give_zero_interior_force_across_the_ties(tied):
    """Patch test: a linear displacement field (uniform strain) is exact on a conforming mesh, so the internal
    force vanishes at every node that is not on the outer boundary, the tied edges' masters included."""
    m = tied
    assert len(m.ties) >= 2
    xy = m.coords
    grad = np.array([[1.3e-4, -0.4e-4], [0.7e-4, -2.1e-4]])
    u = (xy @ grad.T + [1e-6, -2e-6]).ravel()
    f = apply_stencils(block_stencils(m), u)
    # the profiled surface level's float32 coefficients (difference form): per dof at most the rounding's bound,
    # moved onto the masters like the forces (|T|^T)
    T = tie_matrix(m)
    f32 = abs(T).T @ stencil_bound(stiffness_matrix(m), T @ u, n_terms=0)
    boundary = np.zeros(m.n_nodes, dtype=bool)
    x, y = xy.T
    tol = 1e-9 * 12e-3
    boundary |= (x < tol) | (x > 12e-3 - tol) | (y < tol)
    boundary[m.blocks[0].edge_nodes("top")] = True
    boundary[m.tied_dofs[::2] // 2] = True  # tied nodes carry no force of their own (moved to the masters)
    scale = np.abs(f).max()
    assert np.all(np.abs(f.reshape(-1, 2)[~boundary]) <= 1e-11 * scale + f32.reshape(-1, 2)[~boundary])
    # the forces on the boundary are the tractions of the uniform stress: they sum to zero (self-equilibrated)
    assert np.all(np.abs(f.reshape(-1, 2).sum(axis=0)) <= 1e-11 * scale + f32.reshape(-1, 2).sum(axis=0))


def test_kernel_equals_tied_assembly_and_mass_is_kept(tied):
    m = tied
    w = np.random.default_rng(1).standard_normal(m.n_dofs) * 1e-6
    T = tie_matrix(m)
    ref = stiffness_matrix(m) @ (T @ w)
    got = apply_stencils(block_stencils(m), w)
    # + the float32 rounding of the profiled level's coefficients (difference form), moved onto the masters
    f32 = abs(T).T @ stencil_bound(stiffness_matrix(m), T @ w, n_terms=0)
    assert np.all(np.abs(got - ref) <= 1e-12 * np.abs(ref).max() + f32)
    mass = lumped_mass(m)
    assert mass[m.tied_dofs].max() == 0.0
    assert mass.sum() == pytest.approx(2 * RHO * 12e-3 * 2e-3 * 0.01, rel=1e-12)


def _frequencies(model, n=4):
    K, M, _ = constrained_matrices(model, mass="consistent")
    return np.sqrt(lowest_modes(K, M, n)[0]) / (2 * np.pi)


@pytest.mark.slow
def test_modal_frequencies_converge_at_second_order_to_the_uniform_mesh():
    """Clamped-clamped 120 x 8 mm steel block (seed 003's): transition meshes whose every level halves together
    (surface step h, widest element 2 h) converge to the fine uniform mesh's Richardson-extrapolated frequencies
    at Q4's order 2; the default stack (widest element depth / 8 = 1 mm) is within 1 % below 20 kHz."""
    ref = [_frequencies(_block(n, n // 15), 6) for n in (480, 960)]  # uniform square elements 0.25, 0.125 mm
    exact = (4 * ref[1] - ref[0]) / 3  # Richardson, order 2
    assert exact[2] < 20e3 < exact[5]
    steps, errs = [], []
    for nx in (240, 480, 960):  # surface columns 0.5, 0.25, 0.125 mm
        m = transition_model(_block(nx, 1), ["lower"], max_width=2 * 0.12 / nx)
        assert len(m.ties) >= 1
        steps.append(0.12 / nx)
        errs.append(np.abs(_frequencies(m, 6) / exact - 1).max())
    assert_order(steps, errs, 2.0)
    default = transition_model(_block(240, 1), ["lower"])
    assert np.abs(_frequencies(default, 6) / exact - 1)[exact < 20e3].max() < 0.01
    # Euler-Bernoulli (plane strain E/(1-nu^2)) bounds the first clamped-clamped frequency from above: shear
    # and rotary inertia lower it (L/h = 15: a few %)
    eb = 4.7300407**2 / (2 * np.pi * 0.12**2) * np.sqrt(E / (1 - NU**2) * 8e-3**2 / 12 / RHO)
    assert 0.85 * eb < exact[0] < eb


def test_halving_joints_match_the_listed_ties(tied):
    """The row-wise halving joints (``tie_j``) against the listed ties they replace (the general gather/scatter
    path of ``block_forces``, fed the model's ties): bit-for-bit the same forces, tied rows included."""
    import dataclasses

    from fivid.solver._stencil_kernels import block_forces

    st = block_stencils(tied)
    assert st.tie_s.size == 0 and st.tie_j.shape[0] == len(tied.ties)
    listed = dataclasses.replace(
        st, tie_j=np.zeros((0, 3), dtype=np.int64),
        tie_s=st.pad + np.concatenate([t.slave_nodes for t in tied.ties]).astype(np.int64),
        tie_m=np.ascontiguousarray(st.pad + np.concatenate([t.master_nodes for t in tied.ties]), dtype=np.int64),
        tie_w=np.ascontiguousarray(np.concatenate([t.weights for t in tied.ties]), dtype=float))
    w = st.to_kernel(np.random.default_rng(2).standard_normal(tied.n_dofs) * 1e-6)
    f_joint, f_listed = np.zeros_like(w), np.zeros_like(w)
    block_forces(w.copy(), f_joint, st.kernel_args)
    block_forces(w.copy(), f_listed, listed.kernel_args)
    np.testing.assert_array_equal(f_joint, f_listed)


def test_a_long_rectangular_level_is_one_rectangular_stencil():
    """A 120 mm rectangle of 5 248 columns (the Ra 1 pair's level 1, 22.9 um elements): its coordinates' round-off
    spreads the element stiffnesses by more than SAME_STENCIL_RTOL, yet it is one uniform block (rectangular
    interior stencil, no per-node or rotated patch), and its forces are the assembled K's to 1e-12."""
    from fivid.fe.assembly import block_element_stiffness
    from fivid.solver.stencil import PATCH_MAPPED, PATCH_RECT, PATCH_ROTATED, SAME_STENCIL_RTOL

    m = _block(5248, 2, depth=2 * 0.12 / 5248)
    ke = block_element_stiffness(m.blocks[0])
    assert np.abs(ke - ke[0, 0]).max() > SAME_STENCIL_RTOL * np.abs(ke[0, 0]).max()  # the case at hand
    st = block_stencils(m)
    kinds = set(st.blocks[:, 4].tolist())
    assert PATCH_RECT in kinds and not kinds & {PATCH_MAPPED, PATCH_ROTATED}
    w = np.random.default_rng(3).standard_normal(m.n_dofs) * 1e-6
    ref = stiffness_matrix(m) @ w
    assert np.abs(apply_stencils(st, w) - ref).max() <= 1e-12 * np.abs(ref).max()
