"""Pressure loads: nodal-force resultants, Lame's thick-walled cylinder, and the explicit solver's load work."""

import copy

import numpy as np
import pytest

from fivid.errors import ConfigError
from fivid.fe import external_load_vector, load_model, pressure_forces, static_response
from tests.helpers.solver_models import cantilever
from tests.helpers.convergence import assert_order
from tests.helpers.config_errors import assert_config_error

EPS = np.finfo(float).eps
PC = {"E": "2.3 GPa", "nu": 0.3, "rho": "1200 kg/m^3"}


def loaded_cantilever(pressure="40 MPa", *, ramp="0.1 ms", x=None, alpha=0.0):
    cfg = cantilever(v0=0.0)
    load = {"name": "p", "body": "beam", "edge": "top", "pressure": pressure, "ramp_time": ramp}
    if x is not None:
        load["x"] = x
    cfg["loads"] = [load]
    cfg["damping"]["alpha"] = f"{alpha} s-1"
    return cfg


def quarter_ring(n, m, *, pressure="40 MPa", a=0.03, b=0.035):
    """A quarter of a thick-walled polycarbonate cylinder (plane strain) with symmetry supports, inner pressure."""
    return {
        "plane": "strain",
        "bodies": {"ring": {"annulus": {"center": [0, 0], "inner_radius": a, "outer_radius": b,
                                        "angles": ["0 deg", "90 deg"]},
                            "divisions": [n, m], "material": PC, "thickness": "10 mm"}},
        "motions": [{"name": "sym0", "body": "ring", "edge": "start", "component": "y", "kind": "displacement",
                     "amplitude": 0},
                    {"name": "sym90", "body": "ring", "edge": "end", "component": "x", "kind": "displacement",
                     "amplitude": 0}],
        "loads": [{"name": "p", "body": "ring", "edge": "inner", "pressure": pressure, "ramp_time": "1 ms"}],
    }


def test_resultant_is_pressure_times_area():
    """Sum of the nodal forces = -p L t n on a straight edge (exact up to round-off of the node coordinates)."""
    p, t = 40e6, 5e-3
    for x, length in ((None, 32e-3), (["10 mm", "20 mm"], 10e-3)):
        model = load_model(loaded_cantilever(x=x))
        F = external_load_vector(model).reshape(-1, 2)
        scale = p * t * 32e-3
        assert abs(F[:, 1].sum() + p * length * t) <= 64 * EPS * scale
        assert abs(F[:, 0].sum()) <= 64 * EPS * scale
        # consistent forces: interior nodes of the loaded edge take p t h, the two ends p t h / 2
        fy = -F[model.blocks[0].edge_nodes("top"), 1]
        loaded = fy[fy > 0]
        np.testing.assert_allclose(loaded[1:-1], p * t * 2e-3, rtol=1e-12)
        np.testing.assert_allclose(loaded[[0, -1]], p * t * 1e-3, rtol=1e-12)


def test_closed_ring_pressure_is_self_equilibrated():
    model = load_model({"bodies": {"ring": {"annulus": {"center": ["3 mm", 0], "inner_radius": "30 mm",
                                                        "outer_radius": "35 mm"},
                                            "divisions": [48, 2], "material": PC, "thickness": "10 mm"}},
                        "loads": [{"name": "p", "body": "ring", "edge": "outer", "pressure": "1 MPa"}]})
    F = pressure_forces(model, model.loads[0]).reshape(-1, 2)
    scale = 1e6 * 0.01 * 0.035
    assert np.abs(F.sum(axis=0)).max() <= 48 * 4 * EPS * scale
    r = model.coords - [3e-3, 0.0]
    assert abs(np.sum(r[:, 0] * F[:, 1] - r[:, 1] * F[:, 0])) <= 48 * 4 * EPS * scale * 0.035
    # inward on the outer surface; each segment's normal is pi/48 off the radius of its end nodes, so the
    # total radial force is p t x (perimeter of the 48-gon) x cos(pi/48)
    n = model.blocks[0].edge_nodes("outer")
    radial = np.sum(F[n] * r[n], axis=1) / np.hypot(*r[n].T)
    assert np.all(radial < 0)
    np.testing.assert_allclose(-radial.sum(), 1e6 * 0.01 * 48 * 2 * 0.035 * np.sin(np.pi / 48) * np.cos(np.pi / 48),
                               rtol=1e-12)


def test_pressurised_thick_cylinder_against_lame():
    """Plane-strain thick cylinder, inner pressure p: u_r(r) = (1+nu) p a^2 / (E (b^2-a^2)) ((1-2nu) r + b^2/r).

    Bilinear elements converge at order 2 in displacement: the order fitted over three meshes must be 2 within
    the fit's own 95 % interval (its residual: tests/helpers/convergence.py), and the hoop displacement must vanish
    (symmetry) to float resolution of the solve.
    """
    E, nu, p, a, b = 2.3e9, 0.3, 40e6, 0.03, 0.035
    err = []
    meshes = ((8, 2), (16, 4), (32, 8))
    for n, m in meshes:
        model = load_model(quarter_ring(n, m))
        u = static_response(model).reshape(-1, 2)
        r = np.hypot(*model.coords.T)
        ur = np.sum(u * model.coords, axis=1) / r
        ut = (u[:, 1] * model.coords[:, 0] - u[:, 0] * model.coords[:, 1]) / r
        exact = (1 + nu) * p * a * a / (E * (b * b - a * a)) * ((1 - 2 * nu) * r + b * b / r)
        err.append(np.abs(ur - exact).max() / exact.max())
        assert np.abs(ut).max() <= 1e-9 * exact.max()
    assert_order([1.0 / n for n, _ in meshes], err, 2.0)
    assert err[-1] < 1e-3


def test_explicit_run_with_pressure_closes_the_energy_balance_and_settles_to_the_static_response():
    """Energy: the load work enters the balance (external + load work = kinetic + strain + dissipated), closing to
    round-off. Statics: with mass damping alpha every mode decays like exp(-alpha t / 2) (no mode is
    overdamped: alpha/2 is below the first angular frequency), so after the ramp the displacement tends to
    K^-1 F; after 2 ms, exp(-alpha t/2) = exp(-20) bounds the relative remainder."""
    from fivid.solver import OutputOptions, RunSchedule, simulate

    alpha = 2e4
    model = load_model(loaded_cantilever("2 MPa", ramp="0.1 ms", alpha=alpha))
    ds = simulate(model, schedule=RunSchedule(duration=2e-3, sample_rate=51200.0, settle_time=0.0),
                  output=OutputOptions(record_state=True, progress=False))
    scale = float(ds.load_work.max())
    assert scale > 0
    assert np.abs(ds.energy_balance_error.values).max() <= 1e-9 * scale
    # the load work equals the final strain energy plus the damping loss (no kinetic energy left)
    np.testing.assert_allclose(ds.load_work[-1], ds.strain_energy[-1] + ds.damping_dissipation[-1], rtol=1e-9)
    u_static = static_response(model)
    u = np.asarray(ds.attrs["final_u"])
    assert np.abs(u - u_static).max() <= 1e-6 * np.abs(u_static).max()
    # the statics of a linear model: strain energy = half the load work of a dead load applied slowly
    np.testing.assert_allclose(ds.strain_energy[-1], 0.5 * external_load_vector(model) @ u_static, rtol=1e-6)


def test_pressure_enters_the_contact_preload(root):
    """The static preload (fe/static) includes the applied loads. With a frictionless contact, the upper beam's
    vertical equilibrium gives contact force = transducer force + pressure resultant, whatever the bending: a
    pressure of 0.1 MPa on 10 mm of its top face (P = 10 N) raises the contact force by exactly P at the same
    transducer force."""
    import yaml

    from fivid.fe.static import preload_state

    cfg = yaml.safe_load((root / "configs/models/triboair_coarse.yaml").read_text())
    base = preload_state(load_model(cfg), 5.0, mu=0.0)
    cfg["loads"] = [{"name": "p", "body": "upper", "edge": "top", "x": ["120 mm", "130 mm"], "pressure": "0.1 MPa"}]
    model = load_model(cfg)
    P = -external_load_vector(model)[1::2].sum()
    assert abs(P - 10.0) <= 1e-12 * 10.0
    loaded = preload_state(model, 5.0, mu=0.0)
    assert abs(np.sum(base.normal_force) - 5.0) <= 1e-8 * 5.0
    assert abs(np.sum(loaded.normal_force) - (5.0 + P)) <= 1e-8 * (5.0 + P)


@pytest.mark.parametrize("load, key, words", [
    ({"name": "p", "body": "beam", "edge": "inner", "pressure": "1 MPa"}, "loads[0].edge", ["inner"]),
    ({"name": "p", "body": "beam", "edge": "top", "pressure": "1 m"}, "loads[0].pressure", ["Pa"]),
    ({"name": "p", "body": "beam", "edge": "top"}, "loads[0].pressure", ["required"]),
])
def test_bad_load_is_a_config_error(load, key, words):
    cfg = copy.deepcopy(cantilever())
    cfg["loads"] = [load]
    assert_config_error(cfg, key, words)


def test_pressurised_free_ring_stays_axisymmetric_in_the_explicit_solver():
    """A free periodic ring under a uniform inner pressure responds axisymmetrically (breathing): the radial
    displacement is the same at every node of a radius, the hoop displacement and the mean displacement vanish.
    Any seam artefact (wrong neighbours across the seam columns) would break the symmetry at O(1). Discrete
    rotational symmetry is exact, so the asymmetry is round-off: ~ steps x eps x |u_r|."""
    from fivid.solver import OutputOptions, RunSchedule, simulate

    cfg = {"plane": "stress",
           "bodies": {"ring": {"annulus": {"center": [0, 0], "inner_radius": "30 mm", "outer_radius": "50 mm"},
                               "divisions": [24, 3], "material": PC, "thickness": "10 mm"}},
           "damping": {"alpha": "40 s^-1", "beta": "4.5e-7 s"},
           "loads": [{"name": "p", "body": "ring", "edge": "inner", "pressure": "40 MPa", "ramp_time": "0.1 ms"}],
           "sensors": [{"name": "top", "body": "ring", "at": ["0 mm", "50 mm"], "direction": "y"}]}
    model = load_model(cfg)
    ds = simulate(model, schedule=RunSchedule(duration=2e-4, sample_rate=51200.0, settle_time=0.0),
                  output=OutputOptions(record_state=True, progress=False))
    scale = float(ds.load_work.max())
    assert np.abs(ds.energy_balance_error.values).max() <= 1e-9 * scale
    u = np.asarray(ds.attrs["final_u"]).reshape(-1, 2)
    r = np.hypot(*model.coords.T)
    ur = np.sum(u * model.coords, axis=1) / r
    ut = (u[:, 1] * model.coords[:, 0] - u[:, 0] * model.coords[:, 1]) / r
    steps = 2e-4 / 1e-8  # at most this many steps (dt > 1e-8 s here)
    tol = steps * EPS * np.abs(ur).max()
    rows = model.blocks[0].node_numbers()
    for row in rows:
        assert np.ptp(ur[row]) <= tol
    assert np.abs(ut).max() <= tol
    assert np.abs(u.mean(axis=0)).max() <= tol
    assert ur[rows[0]].mean() > 0  # the inner pressure expands the ring


def test_pressure_on_part_of_a_ring_edge_across_the_seam():
    """An x-range of a full ring's outer edge that straddles the seam (angle 0) is loaded on exactly the segments
    between its nodes: resultant = -p t x (chord of the loaded arc) along +x for a symmetric arc about angle 0."""
    n, R, t, p = 36, 0.05, 0.01, 1e6
    model = load_model({"bodies": {"ring": {"annulus": {"center": [0, 0], "inner_radius": "30 mm",
                                                        "outer_radius": "50 mm"},
                                            "divisions": [n, 2], "material": PC, "thickness": "10 mm"}},
                        "loads": [{"name": "p", "body": "ring", "edge": "outer", "x": ["40 mm", "60 mm"],
                                   "pressure": "1 MPa"}]})
    seg = model.loads[0].segments
    ang = np.degrees(np.arctan2(model.coords[seg, 1], model.coords[seg, 0]))
    # x >= 40 mm at R = 50 mm keeps |angle| <= 36.9 deg: the outer nodes at 0, +-10, +-20, +-30 deg (6 segments)
    assert seg.shape == (6, 2) and np.all(np.abs(ang) <= 30.0 + 1e-9)
    F = pressure_forces(model, model.loads[0]).reshape(-1, 2).sum(axis=0)
    half = 30.0
    chord = 2 * R * np.sin(np.radians(half))
    np.testing.assert_allclose(F, [-p * t * chord, 0.0], rtol=0, atol=1e-12 * p * t * R)
