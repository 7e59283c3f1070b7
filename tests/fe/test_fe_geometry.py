"""Mapped block geometry: annular rings/arcs (periodic seam), profiled edges, graded divisions.

References: the thin-ring in-plane bending frequencies (closed form), exact node positions of the specified
geometry, and fivid's own rectangular blocks for the flat-profile limit (bit-for-bit).
"""

import copy

import numpy as np
import pytest

from fivid.errors import ConfigError
from fivid.fe import consistent_mass, load_model, lumped_mass, stiffness_matrix
from fivid.fe.geometry import graded_fractions
from fivid.solver.stencil import PATCH_MAPPED, PATCH_ROTATED, SAME_STENCIL_RTOL, apply_stencils, block_stencils
from tests.helpers.solver_models import STEEL, cantilever, stencil_bound
from tests.helpers.config_errors import assert_config_error

EPS = np.finfo(float).eps


def ring(n=64, m=2, *, radius=0.04, depth=0.002, seam_deg=None, angles=None, plane="stress", grading=None):
    """A steel ring of mean radius ``radius`` and radial depth ``depth`` [m], n x m elements."""
    ann = {"center": ["1 mm", "-2 mm"], "inner_radius": radius - depth / 2, "outer_radius": radius + depth / 2}
    if seam_deg is not None:
        ann["angles"] = [f"{seam_deg} deg", f"{seam_deg + 360} deg"]
    if angles is not None:
        ann["angles"] = angles
    body = {"annulus": ann, "divisions": [n, m], "material": STEEL, "thickness": "5 mm"}
    if grading:
        body["grading"] = grading
    return {"plane": plane, "bodies": {"ring": body}}


def profiled_cantilever(profile, *, grading=None, nx=16, ny=3):
    cfg = cantilever(nx=nx, ny=ny)
    cfg["bodies"]["beam"]["profile"] = profile
    if grading:
        cfg["bodies"]["beam"]["grading"] = grading
    return cfg


# ------------------------------------------------------------------------------------------------ rings


def test_periodic_ring_has_no_duplicate_nodes_and_closes():
    m = load_model(ring(n=12, m=2))
    b = m.blocks[0]
    assert b.periodic and b.n_cols == 12 and m.n_nodes == 12 * 3
    # every node distinct (the seam column is not repeated)
    xy = np.round(m.coords / 1e-9).astype(np.int64)
    assert len({tuple(p) for p in xy}) == m.n_nodes
    # the last element column joins the last node column back to column 0
    en = b.element_nodes()
    assert en[0, -1].tolist() == [b.node(11, 0), b.node(0, 0), b.node(0, 1), b.node(11, 1)]
    # counter-clockwise elements, inner edge closed with 12 segments
    assert set(b.edge_names) >= {"inner", "outer"} and "left" not in b.edge_names
    assert b.edge_segments("inner").shape == (12, 2)
    r = np.hypot(*(m.coords[b.edge_nodes("inner")] - [1e-3, -2e-3]).T)
    np.testing.assert_allclose(r, 0.039, rtol=1e-15)
    ke = stiffness_matrix(m)  # assembled: a positive element Jacobian everywhere, else K has negative pivots
    assert np.all(ke.diagonal() > 0)


def _ring_frequencies(n, m=4, **kw):
    import scipy.sparse.linalg as sla

    model = load_model(ring(n=n, m=m, **kw))
    K, M = stiffness_matrix(model), consistent_mass(model)
    w2 = sla.eigsh(K, 11, M, sigma=-1e3, return_eigenvectors=False)
    return np.sqrt(np.abs(np.sort(w2)[3:]))  # drop the 3 rigid-body modes; doublets n = 2, 3, 4, 5


def test_free_ring_in_plane_modes_against_thin_ring_closed_form():
    """omega_n = sqrt(EI/(rho A R^4)) n(n^2-1)/sqrt(n^2+1), n = 2, 3, 4.

    Q4 elements converge at order 2 in frequency (bending with full integration converges slowly, from
    above: shear locking at coarse meshes); the observed order from three meshes (n = 128, 256, 512 around,
    4 through the depth) must be 2 +- 0.3 and the Richardson extrapolation must match the thin-ring closed
    form within the thin-ring model error plus the extrapolation uncertainty. Thin-ring error: shear and
    rotary inertia lower a bending wave of wavenumber k = n/R by about (k r)^2 (1 + E/(kappa G))/2 with
    r^2 = I/A = h^2/12, kappa = 5/6 (Timoshenko); extrapolation uncertainty: the difference between the
    extrapolations from the coarse and the fine mesh pairs.
    """
    E, rho, nu, R, h = 210e9, 7850.0, 0.3, 0.04, 0.002
    f = np.array([_ring_frequencies(n) for n in (128, 256, 512)])  # (3 meshes, 8)
    pairs = f[:, 0::2], f[:, 1::2]
    # doublets: the periodic ring is symmetric under rotation by one element, so they coincide to solver precision:
    # shift-invert resolves an eigenvalue to about eps x cond(K - sigma M) ~ 1e-16 x 1e9 on the 512 x 4 ring
    # (observed 1e-8 .. 1.06e-7 between runs: ARPACK's random start vector), so 1e-6 on the frequencies
    np.testing.assert_allclose(pairs[0], pairs[1], rtol=1e-6)
    w = pairs[0][:, :3]
    order = np.log2((w[0] - w[1]) / (w[1] - w[2]))
    assert np.all(np.abs(order - 2.0) < 0.3), order
    rich_fine = w[2] + (w[2] - w[1]) / 3.0
    rich_coarse = w[1] + (w[1] - w[0]) / 3.0
    k = np.array([2.0, 3.0, 4.0])
    closed = np.sqrt(E * h ** 3 / 12 / (rho * h * R ** 4)) * k * (k * k - 1) / np.sqrt(k * k + 1)
    thin = 0.5 * (k * h / R) ** 2 / 12 * (1 + 2 * (1 + nu) / (5 / 6))
    tol = thin + np.abs(rich_fine - rich_coarse) / closed
    assert np.all(np.abs(rich_fine / closed - 1) <= tol), (rich_fine / closed - 1, tol)
    assert np.all(tol < 0.01)  # the check is sharp: at most 1 %


def test_rotating_the_seam_leaves_the_frequencies_unchanged():
    """The seam is no artefact: a ring whose seam sits 7.3 deg further has the same spectrum.

    Dense generalized eigenvalues (LAPACK) are backward stable: each eigenvalue is exact for matrices
    perturbed by ~ n eps ||K||, i.e. an absolute error ~ n eps lambda_max, far below any mesh effect."""
    import scipy.linalg as sla

    lam = []
    for seam in (None, 7.3):
        model = load_model(ring(n=64, m=2, seam_deg=seam))
        lam.append(sla.eigh(stiffness_matrix(model).toarray(), consistent_mass(model).toarray(), eigvals_only=True))
    a, b = lam
    tol = model.n_dofs * EPS * a[-1]
    np.testing.assert_allclose(a[3:], b[3:], rtol=0, atol=tol)
    assert np.all(np.abs(a[3:13:2] - a[4:13:2]) <= tol)  # exact doublets n = 2..6 (below the breathing mode)
    assert tol < 1e-6 * a[3]


def test_arc_block_and_radial_grading():
    m = load_model(ring(n=8, m=4, angles=["0 deg", "90 deg"], grading={"edge": "outer", "ratio": 2}))
    b = m.blocks[0]
    assert not b.periodic and b.n_cols == 9 and set(b.edge_names) >= {"start", "end", "inner", "outer"}
    c = np.array([1e-3, -2e-3])
    # i runs clockwise from 90 deg to 0 deg; "start" is the 0 deg side
    ang = np.degrees(np.arctan2(*(m.coords[b.edge_nodes("start")] - c).T[::-1]))
    np.testing.assert_allclose(ang, 0.0, atol=1e-12)
    r = np.hypot(*(b.coords[:, 0] - c).T)
    dr = np.diff(r)
    np.testing.assert_allclose(dr[:-1] / dr[1:], 2.0, rtol=1e-12)  # each layer twice the next toward the outer edge
    np.testing.assert_allclose([r[0], r[-1]], [0.039, 0.041], rtol=1e-14)


@pytest.mark.parametrize("config", [ring(n=24, m=3), ring(n=10, m=2, angles=["30 deg", "120 deg"]),
                                    ring(n=3, m=1),
                                    profiled_cantilever({"edge": "top", "sine": {"amplitude": "0.4 mm",
                                                                                   "wavelength": "5 mm"}},
                                                        grading={"ratio": 1.3})],
                         ids=["ring", "arc", "smallest-ring", "sine-profile"])
def test_stencil_equals_assembled_stiffness_on_mapped_blocks(config):
    """K u by the stencils of mapped blocks (and the seam's listed nodes) equals the assembled CSR K u to round-off.

    Per-node stencils: at most 4 elements x 8 terms = 32 products per entry in a different order, |diff| <= 32 eps
    sum |K_ij u_j|, plus their float32 rounding in difference form, 2^-24 sum |K_ij| |u_j - u_own|
    (:func:`tests.helpers.solver_models.stencil_bound`). Rotated rows (rings, arcs): one stencil per row in the column frames, accepted when every
    node's own agrees with it to ``SAME_STENCIL_RTOL`` x the block's largest coefficient; turned back into x, y
    that is at most twice as much per entry (a rotation keeps the Frobenius norm of a 2x2 block), over 9
    neighbours x 2 components: + 36 tol max|u|."""
    model = load_model(config)
    K = stiffness_matrix(model, include_springs=False)
    u = np.random.default_rng(3).standard_normal(model.n_dofs)
    for rotated in (True, False):
        st = block_stencils(model, rotated=rotated)
        f = apply_stencils(st, u)
        tol = SAME_STENCIL_RTOL * abs(K).max() if (st.blocks[:, 4] == PATCH_ROTATED).any() else 0.0
        assert np.all(np.abs(f - K @ u) <= stencil_bound(K, u) + 36 * tol * np.abs(u).max() + 1e-300)


def test_rings_and_arcs_have_one_stencil_per_row():
    """A ring's or an arc's rows are rotations of one stencil (radial layers, graded or not): rotated patches; a
    profiled block's are not (its heights vary along x): per-node coefficients."""
    for cfg in (ring(n=24, m=3), ring(n=10, m=2, angles=["30 deg", "120 deg"], grading={"edge": "inner", "ratio": 1.5})):
        st = block_stencils(load_model(cfg))
        assert st.blocks[:, 4].tolist() == [PATCH_ROTATED] and st.c_map.shape == (32, 0)
        assert st.c_uni.shape == (st.blocks[0, 2], 36)  # one stencil per row
    profiled = profiled_cantilever({"edge": "top", "sine": {"amplitude": "0.4 mm", "wavelength": "5 mm"}})
    assert block_stencils(load_model(profiled)).blocks[:, 4].tolist() == [PATCH_MAPPED]


def test_periodic_ring_stencil_layout():
    model = load_model(ring(n=12, m=2))
    st = block_stencils(model, rotated=False)
    # columns 1..10 as one per-node patch (row stride 12), the seam columns 0 and 11 listed with neighbours
    assert st.blocks.tolist() == [[st.pad + 1, 10, 3, 12, PATCH_MAPPED, 0, 0, 0]] and st.c_map.shape == (32, 30)
    assert sorted(st.lst_idx - st.pad) == [0, 11, 12, 23, 24, 35]
    k = int(np.flatnonzero(st.lst_idx == st.pad)[0])  # node (0, 0): its left neighbour is node (11, 0)
    assert st.lst_nbr[k, 3] == st.pad + 11 and st.lst_nbr[k, 5] == st.pad + 1 and st.lst_nbr[k, 4] == st.pad
    # rotated: the same patch and seam, one stencil per row, the angles of all 12 columns (the block from pad)
    rot = block_stencils(model)
    assert rot.blocks.tolist() == [[rot.pad + 1, 10, 3, 12, PATCH_ROTATED, 0, rot.pad, 0]]
    assert rot.c_uni.shape == (3, 36) and rot.rot.shape == (2, 12) and np.array_equal(rot.lst_idx, st.lst_idx)
    angle = -np.arange(12) * 2 * np.pi / 12  # clockwise, 30 deg apart
    np.testing.assert_allclose(rot.rot, [np.cos(angle), np.sin(angle)], atol=1e-12)


# --------------------------------------------------------------------------------------------- profiles


def test_graded_fractions_are_geometric():
    s = graded_fractions(5, 1.5)
    h = np.diff(s)
    np.testing.assert_allclose(h[:-1] / h[1:], 1.5, rtol=1e-13)
    assert s[0] == 0.0 and s[-1] == 1.0
    np.testing.assert_allclose(graded_fractions(4, 1.5, toward_end=False), 1 - graded_fractions(4, 1.5)[::-1],
                               atol=1e-15)
    np.testing.assert_array_equal(graded_fractions(4), [0, 0.25, 0.5, 0.75, 1.0])


def test_flat_profile_reproduces_the_rectangular_block_exactly():
    """A zero profile is today's rectangle: same nodes, matrices and simulated signals, bit for bit."""
    from fivid.solver import OutputOptions, RunSchedule, simulate

    rect = cantilever()
    flat = profiled_cantilever({"edge": "top", "x": [0.0, 0.016, 0.032], "z": [0.0, 0.0, 0.0]})
    a, b = load_model(rect), load_model(flat)
    assert b.blocks[0].shape == "profile"
    np.testing.assert_array_equal(a.coords, b.coords)
    assert (stiffness_matrix(a) != stiffness_matrix(b)).nnz == 0
    assert (consistent_mass(a) != consistent_mass(b)).nnz == 0
    np.testing.assert_array_equal(lumped_mass(a), lumped_mass(b))
    kw = dict(schedule=RunSchedule(duration=2e-4, sample_rate=51200.0, settle_time=0.0),
              output=OutputOptions(record_state=True, progress=False))
    ra, rb = simulate(a, **kw), simulate(b, **kw)
    np.testing.assert_array_equal(ra.acceleration.values, rb.acceleration.values)
    np.testing.assert_array_equal(ra.strain_energy.values, rb.strain_energy.values)


@pytest.mark.parametrize("edge", ["top", "bottom"])
def test_sine_profile_edge_nodes_follow_h(edge):
    amp, lam, phase = 0.3e-3, 6e-3, 0.4
    cfg = profiled_cantilever({"edge": edge, "sine": {"amplitude": "0.3 mm", "wavelength": "6 mm", "phase": phase}},
                              grading={"ratio": 1.25}, nx=40, ny=5)
    model = load_model(cfg)
    b = model.blocks[0]
    xy = model.coords[b.edge_nodes(edge)]
    y_edge = 6e-3 if edge == "top" else 0.0
    h = amp * np.sin(2 * np.pi * xy[:, 0] / lam + phase)
    np.testing.assert_allclose(xy[:, 1], y_edge + h, rtol=0, atol=4 * EPS * 6e-3)
    # the opposite edge stays straight; divisions graded toward the profile, ratio 1.25 in every column
    other = model.coords[b.edge_nodes("bottom" if edge == "top" else "top"), 1]
    np.testing.assert_allclose(other, 0.0 if edge == "top" else 6e-3, rtol=0, atol=4 * EPS * 6e-3)
    dy = np.diff(b.coords[:, :, 1], axis=0)
    ratio = dy[:-1] / dy[1:] if edge == "top" else dy[1:] / dy[:-1]
    np.testing.assert_allclose(ratio, 1.25, rtol=1e-9)


def test_profile_from_a_two_column_file_with_units(tmp_path):
    x = np.linspace(0.0, 32.0, 65)  # mm
    z = 0.5 * np.cos(x)  # um
    np.savetxt(tmp_path / "profile.csv", np.column_stack([x, z]), delimiter=",", header="x [mm], z [um]")
    cfg = profiled_cantilever({"edge": "top", "file": "profile.csv", "units": {"x": "mm", "z": "um"}}, nx=32)
    path = tmp_path / "model.yaml"
    import yaml

    path.write_text(yaml.safe_dump(cfg))
    model = load_model(path)
    xy = model.coords[model.blocks[0].edge_nodes("top")]
    np.testing.assert_allclose(xy[:, 1] - 6e-3, np.interp(xy[:, 0] * 1e3, x, z) * 1e-6, atol=1e-18)


@pytest.mark.parametrize("mutate, key, words", [
    (lambda b: b.update(annulus={"center": [0, 0], "inner_radius": 1, "outer_radius": 2}), "bodies.beam",
     ["exactly one of 'corners'"]),
    (lambda b: b.update(profile={"edge": "top", "x": [0.0, 0.01], "z": [0.0, 0.0]}), "bodies.beam.profile.x",
     ["whole edge"]),
    (lambda b: b.update(profile={"edge": "left", "sine": {"amplitude": 1e-4, "wavelength": 1e-3}}),
     "bodies.beam.profile.edge", ["'bottom' or 'top'"]),
    (lambda b: b.update(profile={"edge": "top", "sine": {"amplitude": "7 mm", "wavelength": "10 mm"}}),
     "bodies.beam.profile", ["fold"]),
    (lambda b: b.update(grading={"ratio": 1.2}), "bodies.beam.grading", ["missing 'edge'"]),
    (lambda b: b.update(grading={"edge": "middle", "ratio": 1.2}), "bodies.beam.grading.edge", ["middle"]),
])
def test_bad_geometry_is_a_config_error(mutate, key, words):
    cfg = copy.deepcopy(cantilever())
    mutate(cfg["bodies"]["beam"])
    assert_config_error(cfg, key, words)


def test_bad_annulus_is_a_config_error():
    with pytest.raises(ConfigError, match="must exceed the inner radius"):
        load_model(ring(radius=0.04, depth=-0.002))
    with pytest.raises(ConfigError, match="at most 90 deg"):
        load_model(ring(n=2, angles=["0 deg", "270 deg"]))
    with pytest.raises(ConfigError) as exc:
        cfg = ring(n=12)
        cfg["bodies"]["ring"]["clamp"] = ["left"]
        load_model(cfg)
    assert exc.value.key == "bodies.ring.clamp[0]" and "inner" in str(exc.value)


def test_rough_pair_profiles_are_reproduced_by_their_script_and_followed_by_the_mesh(root):
    """The committed profiles are what make_rough_profiles.py generates (to the file's 4 decimals: 5e-5 um), and
    the example's profiled edges sit on them (linear interpolation at the node x)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("make_rough", root / "configs/models/profiles/make_rough_profiles.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    model = load_model(root / "configs/models/rough_pair.yaml")
    for body, edge, seed, y0 in (("lower", "top", 3, 8e-3), ("upper", "bottom", 4, 8.0372498e-3)):
        x, z = mod.rough_profile(seed)
        table = np.loadtxt(root / f"configs/models/profiles/rough_{body}.csv", delimiter=",")
        np.testing.assert_allclose(table[:, 1] * 1e-6, z, rtol=0, atol=5.01e-11)
        np.testing.assert_allclose(table[:, 0] * 1e-3, x, rtol=0, atol=5.01e-8)
        xy = model.coords[model.block(body).edge_nodes(edge)]
        h = np.interp(xy[:, 0], table[:, 0] * 1e-3, table[:, 1] * 1e-6)
        np.testing.assert_allclose(xy[:, 1], y0 + h, rtol=0, atol=8 * EPS * 16e-3)
        assert 5e-6 < np.sqrt(np.mean(h * h)) < 15e-6  # Rq 10 um, as sampled by the mesh


def test_ungraded_quadrilaterals_keep_their_node_coordinates_bit_for_bit(root):
    """Ungraded blocks are still the bilinear map of the corners at numpy.linspace fractions: the default rig's
    nodes (hence its matrices and simulated signals) are unchanged to the last bit by the geometry options."""
    model = load_model(root / "configs/models/triboair_coarse.yaml")
    for b in model.blocks:
        s = np.linspace(0.0, 1.0, b.nx + 1)[None, :, None]
        t = np.linspace(0.0, 1.0, b.ny + 1)[:, None, None]
        c0, c1, c2, c3 = b.corners
        expected = (1 - s) * (1 - t) * c0 + s * (1 - t) * c1 + s * t * c2 + (1 - s) * t * c3
        np.testing.assert_array_equal(b.coords, expected)
