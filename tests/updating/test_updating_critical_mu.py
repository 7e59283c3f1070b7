"""``critical_mu`` targets of ``fivid update``: the CEA critical friction coefficient of a mode pair as a fit target.

Synthetic (known-parameter recovery): a small polycarbonate ring on a rigid core (the seed-002 layout on a coarse
mesh, generated below). The "truth" is the same config at a known interface normal stiffness; its critical μ
(and a doublet frequency) computed by :func:`fivid.fe.cea.complex_eigenvalue_analysis` are the targets; the update
starts from another stiffness and must come back to the truth within its own 95 % interval.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from fivid.fe.cea import complex_eigenvalue_analysis
from fivid.fe.build import load_model
from fivid.updating import load_targets, update_model
from fivid.fe.config import read_config
from fivid.fe.modal import modal_analysis
from fivid.updating.predict import RIGID_INTERFACE_SCALE, FEModes, pair_critical_mu

RING = """\
# synthetic test model: a coarse polycarbonate ring squeezed on a rigid core turning at 10 rpm
name: ring_test
plane: stress
materials:
  pc: {{E: 2.3 GPa, nu: 0.37, rho: 1200 kg/m^3}}
bodies:
  ring:
    annulus: {{center: [0 mm, 0 mm], inner_radius: 30 mm, outer_radius: 50 mm}}
    divisions: [48, 3]
    material: pc
    thickness: 10 mm
damping: {{alpha: 40 s^-1, beta: 4.5e-7 s}}
loads:
  - {{name: squeeze, body: ring, edge: outer, pressure: 30 MPa, ramp_time: 1 ms}}
contacts:
  - name: bore
    slave: {{body: ring, edge: inner}}
    rigid:
      circle: {{center: [0 mm, 0 mm], radius: 30 mm, side: outside}}
      speed: 10 rpm
    mu: 0.3
    normal_stiffness: {kn}
springs:
  - {{name: s1, a: {{body: ring, at: [0 mm, 50 mm]}}, b: ground, component: x, stiffness: 1e8 N/m}}
  - {{name: s2, a: {{body: ring, at: [0 mm, -50 mm]}}, b: ground, component: x, stiffness: 1e8 N/m}}
"""
MU = np.linspace(0.0, 1.0, 11)


def _ring(tmp_path, kn, name):
    p = tmp_path / name
    p.write_text(RING.format(kn=kn))
    return p


def _lowest_pair(ds):
    crit = ds["critical_mu"].values
    mode = int(np.nanargmin(np.where(np.isfinite(crit), crit, np.inf))) + 1
    return mode, pair_critical_mu(ds, mode)[0]


@pytest.mark.slow  # ~1 min: a least-squares fit of CEA sweeps
def test_critical_mu_and_stiffness_recovered(tmp_path):
    truth = load_model(str(_ring(tmp_path, "3e11 N/m^3", "truth.yaml")))
    ds = complex_eigenvalue_analysis(truth, MU, n_modes=20)
    mode, mu_c = _lowest_pair(ds)
    assert 0 < mu_c < 1
    targets = tmp_path / "targets.yaml"
    targets.write_text(
        "parameters:\n  - {path: 'contacts[0].normal_stiffness', bounds: [1e11 N/m^3, 1e12 N/m^3]}\n"
        f"modes:\n  - {{frequency: {float(ds['frequency'].values[0, mode - 1])!r} Hz, tolerance: 0.01 %, "
        f"mode: {mode}}}\n"
        f"critical_mu:\n  - {{value: {mu_c!r}, tolerance: 0.001, mode: {mode}, mu: [0, 1, 11]}}\n"
        "contact: true\n")
    result, text = update_model(_ring(tmp_path, "5e11 N/m^3", "start.yaml"), load_targets(targets))
    assert result.converged
    k, ci = result.values[0], result.ci95[0]
    # the targets are the truth's own values: the fit comes back to 3e11 within its 95 % interval (the
    # interval is set by the 0.01 % / 0.001 tolerances, so it is narrow; the remaining error is the solver's)
    assert ci is not None and abs(k - 3e11) <= max(ci, 1e-6 * 3e11)
    row = [r for r in result.residuals if r.get("quantity") == "critical_mu"][0]
    assert abs(row["model"] - mu_c) < 1e-3 and row["partner_mode"] is not None
    assert "critical mu" not in text or "critical_mu[0]" in text  # the provenance names the target


def test_pair_critical_mu_takes_the_pair_minimum_and_extrapolates_a_stable_pair():
    mu = np.array([0.0, 0.5, 1.0])
    freq = np.tile([1000.0, 1001.0, 3000.0], (3, 1))
    re = np.array([[-1.0, -6.0, -5.0], [-0.5, -7.0, -4.0], [0.5, -8.0, -3.0]])
    ds = xr.Dataset({"frequency": (("mu", "mode"), freq), "real_part": (("mu", "mode"), re),
                     "critical_mu": ("mode", [0.75, np.nan, np.nan]), "partner": ("mode", [2, 1, -1])},
                    coords={"mu": mu, "mode": [1, 2, 3]})
    assert pair_critical_mu(ds, 2) == (0.75, {"mode": 2, "partner": 1, "frequency_hz": 1001.0,
                                              "extrapolated": False})
    value, detail = pair_critical_mu(ds, 3)  # stable; its nearest mode in frequency is mode 2 (falling)
    assert detail["extrapolated"]
    # max(Re3, Re2) = Re3 grows 1 s-1 per 0.5 of mu from -3 at mu 1: zero at mu 2.5 (linear extrapolation)
    assert value == pytest.approx(2.5)
    ds["real_part"][:, 2] = [-3.0, -4.0, -5.0]  # a pair that only gets more stable: 10 x the last mu
    assert pair_critical_mu(ds, 3)[0] == 10.0


@pytest.mark.parametrize("entry, key, words", [
    ("{value: 0.15, tolerance: 0.05, mode: 6}", "critical_mu[0]", "mu [start, stop, steps]"),
    ("{value: 1.5, tolerance: 0.05, mode: 6, mu: [0, 1, 21]}", "critical_mu[0].value", "outside the sweep"),
    ("{value: 0.15, tolerance: 0, mode: 6, mu: [0, 1, 21]}", "critical_mu[0].tolerance", "> 0"),
    ("{value: 0.15, tolerance: 0.05, mode: 0, mu: [0, 1, 21]}", "critical_mu[0].mode", ">= 1"),
    ("{value: 0.15, tolerance: 0.05, mode: 6, mu: [1, 0, 21]}", "critical_mu[0].mu", "start < stop"),
])
def test_critical_mu_target_errors_name_the_key(tmp_path, entry, key, words):
    from fivid.errors import ConfigError

    p = tmp_path / "targets.yaml"
    p.write_text("parameters:\n  - {path: materials.pc.E, bounds: [2 GPa, 2.6 GPa]}\n"
                 "modes:\n  - {frequency: 10 kHz, tolerance: 1 %}\n"
                 f"critical_mu:\n  - {entry}\n")
    with pytest.raises(ConfigError) as err:
        load_targets(p)
    assert err.value.key == key and words in err.value.message and err.value.line == 6


def test_rigid_interface_target_is_the_rigid_limit(tmp_path):
    """``interface: rigid`` mode targets: the contact springs scaled by RIGID_INTERFACE_SCALE. Oracle: the springs
    are in series with the ring, so a frequency's deficit from the rigid limit falls as 1 / scale once the
    interface is far stiffer than the wall (3e13 N/m^3 and up here, ~25 x the wall's 10 E / D): the decade
    differences shrink tenfold, to the next order (1 / scale^2: ~4 % at the first decade, hence 9-11)."""
    path = _ring(tmp_path, "3e11 N/m^3", "ring.yaml")
    model = load_model(str(path))
    f = {s: modal_analysis(model, 12, include_contact=True, interface_scale=s)["frequency"].values
         for s in (1.0, 1e2, 1e3, 1e4)}
    d1, d2 = f[1e3] - f[1e2], f[1e4] - f[1e3]
    sel = d1 > 1e-5 * f[1e2]  # modes that feel the interface (the others' differences are eigen-solver noise)
    assert sel.sum() >= 4
    assert np.all((d1[sel] / d2[sel] > 9.0) & (d1[sel] / d2[sel] < 11.0))
    targets = tmp_path / "targets.yaml"
    targets.write_text("parameters:\n  - {path: 'contacts[0].normal_stiffness', bounds: [1e11 N/m^3, 1e12 N/m^3]}\n"
                       "modes:\n  - {frequency: 5 kHz, tolerance: 1 %, mode: 3}\n"
                       "  - {frequency: 5 kHz, tolerance: 1 %, mode: 3, interface: rigid}\n"
                       "contact: true\nn_modes: 12\n")
    pred = FEModes(load_targets(targets))(read_config(path)[0])
    elastic = np.flatnonzero(f[1.0] > 0)
    assert RIGID_INTERFACE_SCALE == 1e4
    assert pred.frequency[0] == pytest.approx(f[1.0][elastic[2]], rel=1e-9)
    assert pred.frequency[1] == pytest.approx(f[1e4][np.flatnonzero(f[1e4] > 0)[2]], rel=1e-9)


@pytest.mark.parametrize("extra, key, words", [
    ("interface: stiff", "modes[0].interface", "model, rigid"),
    ("interface: rigid", "modes[0].interface", "contact: true"),
])
def test_interface_target_errors_name_the_key(tmp_path, extra, key, words):
    from fivid.errors import ConfigError

    p = tmp_path / "targets.yaml"
    p.write_text("parameters:\n  - {path: materials.pc.E, bounds: [2 GPa, 2.6 GPa]}\n"
                 f"modes:\n  - {{frequency: 10 kHz, tolerance: 1 %, {extra}}}\n")
    with pytest.raises(ConfigError) as err:
        load_targets(p)
    assert err.value.key == key and words in err.value.message and err.value.line == 4
