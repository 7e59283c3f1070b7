"""A rigid circle that expands radially (seed 002's preload, issue 31 item 1): the static preload solves the radial
displacement for a target mean contact pressure, the explicit solver follows the same radius history.

Oracle: Lamé's thick-walled ring (plane stress) under a radial bore displacement ``delta`` and a free outer edge,
``p = E delta / (a [(1 - nu) a^2 + (1 + nu) b^2] / (b^2 - a^2))`` and the hoop stress
``s_tt(r) = p a^2 / (b^2 - a^2) (1 + b^2 / r^2)`` (tensile). The ring is axisymmetric, so the tangential
supports carry nothing and friction plays no part. Synthetic geometry (the placeholder radii of
configs/models/ring.yaml)."""

import json

import numpy as np
import pytest
import yaml

from fivid.cli import main
from fivid.errors import ConfigError
from fivid.fe import load_model
from fivid.fe.assembly import GAUSS_POINTS_2X2
from fivid.fe.prestress import block_gauss_point_stress
from fivid.fe.static import preload_state

A, B, E, NU, P = 0.03, 0.05, 2.3e9, 0.37, 40e6  # bore, outer radius [m], modulus [Pa], Poisson, pressure [Pa]
DELTA_LAME = P * A / E * ((1 - NU) * A * A + (1 + NU) * B * B) / (B * B - A * A)


def ring(n_around, n_wall, expansion=None):
    """A polycarbonate ring on a rigid circle expanding to 40 MPa mean contact pressure (mapping for load_model)."""
    return {"name": "ring", "plane": "stress", "materials": {"pc": {"E": E, "nu": NU, "rho": 1200.0}},
            "bodies": {"ring": {"annulus": {"center": [0, 0], "inner_radius": A, "outer_radius": B},
                                "divisions": [n_around, n_wall], "material": "pc", "thickness": 0.01}},
            "damping": {"alpha": "40 s^-1", "beta": "4.5e-7 s"},
            "contacts": [{"name": "bore", "slave": {"body": "ring", "edge": "inner"}, "mu": 0.3,
                          "rigid": {"circle": {"center": [0, 0], "radius": A, "side": "outside"},
                                    "expansion": expansion or {"mean_pressure": P, "ramp_time": 1e-3},
                                    "speed": "10 rpm", "start": "1.5 ms", "ramp_time": "1 ms"}}],
            "springs": [{"name": f"s{i}", "a": {"body": "ring", "at": [0, y]}, "b": "ground", "component": "x",
                         "stiffness": 1e8} for i, y in enumerate((B, -B))],
            "sensors": [{"name": "acc", "body": "ring", "at": [B, 0], "direction": "x"}]}


def _bore_hoop_stress(model, u):
    """Hoop stress [Pa] at the Gauss points of the bore's element row and their radius [m]."""
    block = model.blocks[0]
    s = block_gauss_point_stress(block, u)[0]  # (n_around, 4, 3): the row at the inner edge
    xy = block.element_corners()[0]
    out, rad = [], []
    for g, (xi, eta) in enumerate(GAUSS_POINTS_2X2):
        shape = 0.25 * np.array([(1 - xi) * (1 - eta), (1 + xi) * (1 - eta), (1 + xi) * (1 + eta),
                                 (1 - xi) * (1 + eta)])
        x, y = np.einsum("a,...ai->i...", shape, xy)
        th = np.arctan2(y, x)
        c, sn = np.cos(th), np.sin(th)
        out.append(s[:, g, 0] * sn ** 2 + s[:, g, 1] * c ** 2 - 2 * s[:, g, 2] * sn * c)
        rad.append(np.hypot(x, y))
    return np.concatenate(out), np.concatenate(rad)


def test_the_expansion_for_40_mpa_converges_to_lames_and_stretches_the_bore():
    """The solved radial displacement converges to Lamé's with the Q4's observed order 2 (meshes h, h/2, h/4);
    Richardson's limit removes the h^2 term, so what is left is of higher order: below a tenth of the finest
    mesh's error. The preload's mean pressure is the target to the secant's tolerance (1e-9), and the bore's
    hoop stress is tensile and converges to Lamé's too."""
    deltas, hoop_err = [], []
    for n in (1, 2, 4):
        model = load_model(ring(24 * n, 2 * n))
        rigid = model.contacts[0].rigid
        deltas.append(rigid.expansion)
        state = preload_state(model, None)
        (summary,) = state.summary(model)
        assert summary["mean_pressure_pa"] == pytest.approx(P, rel=1e-8)
        assert summary["closed_nodes"] == 24 * n
        hoop, r = _bore_hoop_stress(model, state.u)
        lame = P * A * A / (B * B - A * A) * (1 + B * B / r ** 2)
        assert np.all(hoop > 0.0)  # tensile: the expanding cylinder stretches the bore (seed 002)
        hoop_err.append(float(np.abs(hoop / lame - 1).max()))
    e = np.array(deltas) / DELTA_LAME - 1
    order = np.log2(e[:-1] / e[1:])
    assert np.all(order > 1.8), order  # 1.91, 1.97
    limit = deltas[2] + (deltas[2] - deltas[1]) / (2 ** order[-1] - 1)
    assert abs(limit / DELTA_LAME - 1) < 0.1 * abs(e[-1])
    assert hoop_err[2] < hoop_err[1] < hoop_err[0]


def test_a_given_expansion_is_taken_as_is_and_a_line_cannot_expand():
    """``displacement`` instead of ``mean_pressure``: no solve, the preload reports the pressure it gives (Lamé's
    40 MPa for Lamé's displacement, to the mesh's error of the convergence test above); a rigid line, or both keys,
    is a config error naming the key."""
    model = load_model(ring(48, 4, {"displacement": DELTA_LAME, "ramp_time": 1e-3}))
    assert model.contacts[0].rigid.expansion == DELTA_LAME
    (summary,) = preload_state(model, None).summary(model)
    assert summary["mean_pressure_pa"] == pytest.approx(P, rel=5e-3)  # the 48 x 4 mesh's delta error is 3.3e-3
    with pytest.raises(ConfigError, match="either 'mean_pressure'"):
        load_model(ring(24, 2, {"displacement": 1e-3, "mean_pressure": P}))
    cfg = ring(24, 2)
    cfg["contacts"][0]["rigid"] = {"line": {"point": [0, 0], "normal": [0, 1]}, "expansion": {"displacement": 1e-3}}
    with pytest.raises(ConfigError, match="only a rigid circle expands") as exc:
        load_model(cfg)
    assert "contacts[0].rigid.expansion" in str(exc.value)


@pytest.mark.parametrize("prestress", [False, True])
def test_the_explicit_run_follows_the_expansion_to_40_mpa(tmp_path, capsys, prestress):
    """The explicit solver grows the circle's radius over its ramp (the same radius history): after the ramp the
    ring's contact normal force is the static preload's, 40 MPa x 2 pi a t, within the acceptance's 2 % (the
    breathing vibration the 1 ms ramp leaves is ~1e-3 of it); before the expansion starts there is no force. With
    the prestress term (``prestress: true``) too: it vanishes at the static state, so the preload is the same."""
    path = tmp_path / "ring.yaml"
    path.write_text(yaml.safe_dump({**ring(48, 4), "prestress": prestress}))
    out = tmp_path / "ring.nc"
    assert main(["simulate", str(path), "--duration", "0.5 ms", "--sample-rate", "20 kHz", "-o", str(out),
                 "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    import xarray as xr

    with xr.open_dataset(out) as ds:
        t = ds["time"].values
        force = ds["contact_normal_force"].values.ravel()
    nominal = P * 2 * np.pi * A * 0.01
    after = (t > 1.2e-3) & (t < 1.5e-3)  # expansion done, cylinder not yet turning
    assert after.any()
    assert np.abs(force[after] / nominal - 1).max() < 0.02
    assert force[0] < 0.01 * nominal
    assert abs(summary["max_energy_balance_error_j"]) < 1e-9
