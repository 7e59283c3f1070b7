"""Contact-law definitions: closed forms of the laws, the Greenwood-Williamson fit, the Stribeck curve in the
solver, and config errors (issue 13)."""

import math

import numpy as np
import pytest

from tests.helpers.contact_models import block_on_belt, block_on_line
from fivid.contact import GreenwoodWilliamson, NormalLaw
from fivid.friction import FrictionCurve
from fivid.errors import ConfigError
from fivid.fe import load_model
from fivid.solver import OutputOptions, RunSchedule, simulate


def test_gw_f32_closed_form_against_quadrature_and_gamma():
    """F_3/2 by the parabolic cylinder function vs adaptive quadrature (rel 1e-10) and, at 0, the Gamma-function
    value 2^(1/4) Gamma(5/4) / sqrt(2 pi)."""
    from scipy.integrate import quad

    x = np.array([-6.0, -1.0, 0.0, 0.7, 3.0, 5.5])
    phi = lambda s: math.exp(-0.5 * s * s) / math.sqrt(2 * math.pi)  # noqa: E731
    ref = [quad(lambda s, a=a: (s - a) ** 1.5 * phi(s), a, max(a, 0.0) + 12.0, epsabs=0.0, epsrel=1e-11,
                limit=200)[0] for a in x]
    np.testing.assert_allclose(GreenwoodWilliamson.f32(x), ref, rtol=1e-8)
    assert GreenwoodWilliamson.f32(0.0)[0] == pytest.approx(2 ** 0.25 * math.gamma(1.25) / math.sqrt(2 * math.pi),
                                                            rel=1e-12)


def test_gw_table_law_follows_the_closed_form():
    """The tabulated law (what every analysis uses) against the GW pressure at arbitrary (off-grid)
    penetrations: linear interpolation of a smooth curve on 2048 segments, the error it reports (<= 1e-4)."""
    gw = GreenwoodWilliamson(sigma=0.5e-6, radius=50e-6, density=1.5e9, e_star=115e9)
    law = gw.table_law(1e8)
    err = float(law.source.split("interpolation error <= ")[1].split(" %")[0]) / 100
    assert err < 1e-4
    h0 = gw.separation_at(1.0)  # the origin: where the GW pressure is 1 Pa
    p0 = 1.0
    assert law.pressure(np.array([0.0]))[0] == 0.0
    for p in (1e3, 1e5, 1e7):
        d = law.penetration(p)
        # the table's interpolation error, plus the 1 Pa origin subtracted from the law (1e-3 of 1 kPa)
        assert float(gw.pressure_at_separation(h0 - d)[0]) - p0 == pytest.approx(p, rel=2 * err + 1e-3)


def test_gw_power_fit_reports_its_deviation_and_stays_within_it():
    gw = GreenwoodWilliamson(sigma=0.5e-6, radius=50e-6, density=5e9, e_star=115e9)
    law = gw.power_fit((1e3, 1e6))
    assert law.kind == "power" and law.exponent > 1.0
    dev = float(law.source.split("largest deviation ")[1].split(" %")[0]) / 100
    h0 = float(law.source.split("separation h0 = ")[1].split(" sigma")[0]) * gw.sigma
    for p in np.geomspace(1e3, 1e6, 7):
        d = h0 - gw.separation_at(p)
        assert law.pressure(d) == pytest.approx(p, rel=1.05 * dev + 1e-9)  # 1.05: h0 printed to 4 digits
    with pytest.raises(ConfigError, match="out of its reach"):
        gw.power_fit((1e3, 1e30))


_GW_TABLE = GreenwoodWilliamson(sigma=0.5e-6, radius=50e-6, density=1.5e9, e_star=115e9).table_law(1e8)


@pytest.mark.parametrize("law", [NormalLaw("linear", 1e13), NormalLaw("power", 2e13, 1.5), NormalLaw("power", 1e9, 2.3),
                                 _GW_TABLE])
def test_tangent_and_energy_are_derivative_and_integral_of_the_pressure(law):
    """Central differences (h = 1e-6 d: truncation ~1e-12, round-off ~1e-10; off the table's grid points, where
    its tangent jumps) and the inverse."""
    d = np.array([1e-7, 3e-6, 2e-5]) if law.kind != "table" else law.coefficient * np.array([100.37, 901.5, 2040.2])
    h = 1e-6 * d
    np.testing.assert_allclose(law.tangent(d), (law.pressure(d + h) - law.pressure(d - h)) / (2 * h), rtol=1e-7)
    np.testing.assert_allclose(law.pressure(d), (law.energy(d + h) - law.energy(d - h)) / (2 * h), rtol=1e-7)
    np.testing.assert_allclose(law.penetration(law.pressure(d)), d, rtol=1e-12)
    assert law.pressure(np.array([-1e-6, 0.0])).tolist() == [0.0, 0.0]


def test_stribeck_curve_values():
    f = FrictionCurve(mu_static_excess=0.2, stribeck_velocity=0.01, viscous=1.0)
    assert f.coefficient(0.3, 0.0) == pytest.approx(0.5)
    assert f.coefficient(0.3, -0.05) == pytest.approx(0.3 + 0.2 * math.exp(-5) + 0.05)


def test_solver_slides_on_the_stribeck_and_viscous_curve():
    """Steady sliding (belt at V, block at rest on a stiff holder, heavy mass damping): the friction/normal
    ratio is mu(V) = mu_k + (mu_s - mu_k) exp(-V/v_s) + c_v V, to the Gauss-Seidel tolerance."""
    mu, mu_s, vs, cv, V = 0.3, 0.5, 0.01, 1.0, 0.05
    model = load_model(block_on_belt(mu=mu, mu_static=mu_s, belt=V, spring=1e6, stribeck=f"{vs} m/s",
                                     viscous=f"{cv} s/m", alpha="3000 s-1"))
    ds = simulate(model, schedule=RunSchedule(duration=0.01, sample_rate=100e3, settle_time=0.0),
                  output=OutputOptions(oversample=1, progress=False))
    belt = ds.sel(contact="belt")
    late = ds.time.values > 0.008
    assert belt.slip_fraction.values[late].min() == 1.0
    ratio = np.abs(belt.contact_tangential_force.values[late]) / belt.contact_normal_force.values[late]
    assert np.median(ratio) == pytest.approx(mu + (mu_s - mu) * math.exp(-V / vs) + cv * V, rel=1e-6)


@pytest.mark.parametrize("edit, key", [
    (lambda c: c["contacts"][0].update(mu_static=0.1, mu=0.3), "contacts[0].mu_static"),
    (lambda c: c["contacts"][0].update(master={"body": "block", "edge": "top"}), "contacts[0]"),
    (lambda c: c["contacts"][0]["rigid"].update(velocity=["0 m/s", "1 m/s"]), "contacts[0].rigid.velocity"),
    (lambda c: c["contacts"][0].update(normal={"law": "power", "coefficient": 1e13}), "contacts[0].normal.exponent"),
    (lambda c: c["contacts"][0].update(normal={"law": "linear", "stiffness": "1e13 N/m^3", "exponent": 2}),
     "contacts[0].normal.exponent"),
    (lambda c: c["contacts"][0].update(normal={"law": "hertz"}), "contacts[0].normal.law"),
    (lambda c: c["contacts"][0].update(stribeck_velocity="1 cm/s"), "contacts[0].stribeck_velocity"),
    (lambda c: c["contacts"][0]["rigid"].update(speed="10 rpm"), "contacts[0].rigid.speed"),
])
def test_contact_config_errors_name_the_key(edit, key):
    cfg = block_on_line(law={"law": "linear", "stiffness": "1e13 N/m^3"})
    edit(cfg)
    with pytest.raises(ConfigError) as exc:
        load_model(cfg)
    assert key in str(exc.value)


def test_rigid_circle_speed_in_rpm():
    cfg = block_on_line(law="rigid")
    cfg["contacts"][0]["rigid"] = {"circle": {"center": ["5 mm", "-20 mm"], "radius": "20 mm"}, "speed": "60 rpm"}
    pair = load_model(cfg).contacts[0]
    assert pair.rigid.angular_velocity == pytest.approx(2 * math.pi)
    g, n, t, vt = pair.rigid.geometry(np.array([[5e-3, 0.0]]))
    assert g[0] == pytest.approx(0.0, abs=1e-15) and n[0].tolist() == pytest.approx([0.0, 1.0])
    assert vt[0] == pytest.approx(2 * math.pi * 0.02)  # counter-clockwise: the top moves along t = (-1, 0)


def test_the_pair_record_is_written_and_read_by_its_named_columns():
    """kernel_row puts every law at its named column of the one layout module (not at positions known elsewhere)."""
    from fivid.contact import RigidSurface, kernel_row
    from fivid.contact import _layout_kernels as L

    curve = FrictionCurve(mu_static_excess=0.15, stribeck_velocity=2e-3, viscous=0.5)
    law = NormalLaw("power", 3e9, 1.5, "given")
    circle = RigidSurface("circle", np.array([0.1, -0.2]), radius=0.05, side="inside", angular_velocity=3.0,
                          start=0.01, ramp_time=0.02, expansion=-1e-4, expansion_start=1e-3, expansion_ramp_time=4e-3)
    row = kernel_row(law, curve, circle)
    assert row.shape == (L.NPAR,)
    expected = {L.LAW: L.LAW_POWER, L.LAW_COEFFICIENT: 3e9, L.LAW_EXPONENT: 1.5, L.MU_STATIC_EXCESS: 0.15,
                L.STRIBECK_VELOCITY: 2e-3, L.VISCOUS: 0.5, L.MASTER: L.MASTER_CIRCLE, L.SURFACE_X: 0.1,
                L.SURFACE_Y: -0.2, L.SURFACE_A: 0.05, L.SURFACE_B: -1.0, L.SURFACE_SX: 3.0, L.SURFACE_SY: 0.0,
                L.SURFACE_START: 0.01, L.SURFACE_RAMP: 0.02, L.EXPANSION: -1e-4, L.EXPANSION_START: 1e-3,
                L.EXPANSION_RAMP: 4e-3}
    assert sorted(expected) == list(range(L.NPAR))  # every column named once
    assert {c: row[c] for c in expected} == expected
    edge = kernel_row(NormalLaw(), FrictionCurve(), None)
    assert edge[L.MASTER] == L.MASTER_EDGE and edge[L.LAW] == L.LAW_RIGID


def test_no_bare_column_index_of_a_pair_record_outside_the_layout_module():
    """``pair_par[p, 13]`` or ``par_p[3]`` anywhere in fivid would bypass the one layout (issue 29 item 5)."""
    import re
    from pathlib import Path

    pkg = Path(__file__).resolve().parents[2] / "fivid"
    bare = re.compile(r"\b(pair_par\[[^\]\[]*,\s*\d+\s*\]|par_p\[\s*\d+\s*\]|row\[\s*\d+\s*(:\s*\d+\s*)?\])")
    hits = [f"{p.relative_to(pkg)}:{i}: {ln.strip()}" for p in pkg.rglob("*.py") if p.name != "_layout_kernels.py"
            for i, ln in enumerate(p.read_text(encoding="utf-8").splitlines(), 1) if bare.search(ln)]
    assert not hits, "\n".join(hits)
