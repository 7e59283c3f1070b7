"""Model updating (``fivid update``): known-parameter recovery, identifiability, error paths, the YAML rewrite.

Synthetic: the target modes of the recovery tests are the modes of the same model config with known
parameters (the "truth"), computed by ``fivid.fe.modal_analysis``; the update starts from perturbed values.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from fivid.cli import main
from fivid.fe.modal import modal_analysis
from fivid.fe.build import load_model
from fivid.updating import load_targets, update_model
from fivid.updating.paths import get_path, parse_path, replace_values

STRIP = """\
# synthetic test model: a clamped steel strip with a support spring at its free end
name: strip
plane: stress
materials:
  steel: {{E: {E}, nu: 0.3, rho: {rho}}}   # flow style kept by the rewrite
bodies:
  strip:
    corners: [[0 mm, 0 mm], [100 mm, 0 mm], [100 mm, 10 mm], [0 mm, 10 mm]]
    divisions: [20, 2]
    material: steel
    thickness: 10 mm
    clamp: [left]
springs:
  - {{name: support, a: {{body: strip, at: [100 mm, 10 mm]}}, b: ground, component: y, stiffness: {k}}}
sensors:
  - {{name: s1, body: strip, at: [25 mm, 10 mm], direction: y}}
  - {{name: s2, body: strip, at: [50 mm, 10 mm], direction: y}}
  - {{name: s3, body: strip, at: [75 mm, 10 mm], direction: y}}
  - {{name: s4, body: strip, at: [100 mm, 10 mm], direction: y}}
"""


def _strip(tmp_path, name="start.yaml", E="210 GPa", rho="7850 kg/m^3", k="2e5 N/m", spring=True) -> Path:
    p = tmp_path / name
    text = STRIP.format(E=E, rho=rho, k=k)
    if not spring:
        text = text.replace("springs:\n", "").replace(text.splitlines()[13] + "\n", "")
    p.write_text(text)
    return p


def _true_frequencies(path, n=4):
    ds = modal_analysis(load_model(str(path)), n)
    return ds["frequency"].values


def _targets(tmp_path, params, freqs, tol="0.01 %", extra="") -> Path:
    lines = ["parameters:"] + [f"  - {{path: '{p}', bounds: [{lo}, {hi}]}}" for p, lo, hi in params]
    lines += ["modes:"] + [f"  - {{frequency: {float(f)!r} Hz, tolerance: {tol}}}" for f in freqs]
    p = tmp_path / "targets.yaml"
    p.write_text("\n".join(lines) + "\n" + extra)
    return p


def test_modulus_and_spring_recovered_from_their_own_modes(tmp_path):
    truth = _strip(tmp_path, "truth.yaml", E="200 GPa", k="3e5 N/m")
    start = _strip(tmp_path)  # E +5 %, k -33 %
    f = _true_frequencies(truth)
    t = _targets(tmp_path, [("materials.steel.E", "150 GPa", "250 GPa"),
                            ("springs[0].stiffness", "1e4 N/m", "1e7 N/m")], f)
    result, text = update_model(start, load_targets(t))
    E, k = result.values
    assert abs(E / 200 - 1) < 0.01 and abs(k / 3e5 - 1) < 0.01
    assert result.converged and result.identifiable and not result.warnings
    assert all(ci is not None and ci > 0 for ci in result.ci95)
    assert max(abs(r["error_pct"]) for r in result.residuals) < 1e-3
    # the rewrite keeps comments and flow style, and the values land where they were
    assert "# flow style kept by the rewrite" in text and text.startswith("# Updated by fivid update")
    data = yaml.safe_load(text)
    assert data["materials"]["steel"]["E"].endswith("GPa") and data["springs"][0]["stiffness"].endswith("N/m")
    assert abs(float(data["materials"]["steel"]["E"].split()[0]) / 200 - 1) < 0.01


def test_mass_and_stiffness_scaled_together_is_reported_unidentifiable(tmp_path):
    """E and rho scaled by one factor leave every frequency unchanged: the pair must be named, not 'fitted'."""
    truth = _strip(tmp_path, "truth.yaml", E="220.5 GPa", rho="8242.5 kg/m^3", spring=False)  # both x1.05
    start = _strip(tmp_path, spring=False)
    assert "springs" not in start.read_text()
    f = _true_frequencies(truth)
    t = _targets(tmp_path, [("materials.steel.E", "150 GPa", "300 GPa"),
                            ("materials.steel.rho", "5000 kg/m^3", "11000 kg/m^3")], f)
    result, text = update_model(start, load_targets(t))
    assert not result.identifiable
    assert result.ci95 == [None, None]
    assert any("materials.steel.E" in w and "materials.steel.rho" in w and "apart" in w for w in result.warnings)
    assert abs(abs(result.correlation[0, 1]) - 1) < 1e-3
    assert "# warning: the targets cannot tell" in text


def test_shape_targets_pair_by_mac(tmp_path):
    """Targets listed out of order but with measured shapes pair with the right model modes."""
    import xarray as xr

    start = _strip(tmp_path)
    ds = modal_analysis(load_model(str(start)), 4)
    model = load_model(str(start))
    nodes = [s.node for s in model.sensors]
    shapes = ds["mode_shape"].values[:, nodes, 1]
    modes = xr.Dataset({"frequency": ("mode", ds["frequency"].values), "shape_real": (("mode", "dof"), shapes),
                        "shape_imag": (("mode", "dof"), np.zeros_like(shapes))})
    modes.to_netcdf(tmp_path / "modes.nc")
    text = ("parameters:\n  - {path: materials.steel.E, bounds: [150 GPa, 250 GPa]}\nmodes:\n"
            f"  - {{frequency: {float(ds['frequency'].values[1])!r} Hz, tolerance: 1 %, "
            "shape: {file: modes.nc, mode: 2, sensors: [s1, s2, s3, s4]}}\n"
            f"  - {{frequency: {float(ds['frequency'].values[0])!r} Hz, tolerance: 1 %, "
            "shape: {file: modes.nc, mode: 1, sensors: [s1, s2, s3, s4]}}\n")
    (tmp_path / "t.yaml").write_text(text)
    result, _ = update_model(start, load_targets(tmp_path / "t.yaml"))
    assert [r["model_mode"] for r in result.residuals] == [2, 1]
    assert all(r["mac"] > 0.999 for r in result.residuals)
    assert abs(result.values[0] / 210 - 1) < 1e-6


@pytest.mark.parametrize("targets, line, key, words", [
    ("parameters:\n  - {path: materials.steel.G, bounds: [1 GPa, 2 GPa]}\nmodes:\n  - {frequency: 1 kHz, "
     "tolerance: 1 %}\n", 2, "parameters[0].path", "unknown parameter path"),
    ("parameters:\n  - {path: materials.steel.E, bounds: [150, 250]}\nmodes:\n  - {frequency: 1 kHz, "
     "tolerance: 1 %}\n", 2, "parameters[0].bounds[0]", "has no unit"),
    ("parameters:\n  - {path: materials.steel.E, bounds: [150 GPa, 250 GPa]}\nmodes:\n  - {frequency: 1 kHz, "
     "tolerance: 1 %, mode: 40}\n", 4, "modes[0]", "cannot pair"),
    ("parameters:\n  - {path: materials.steel.E, bounds: [150 m, 250 m]}\nmodes:\n  - {frequency: 1 kHz, "
     "tolerance: 1 %}\n", 2, "parameters[0].bounds[0]", "not compatible"),
    ("parameters:\n  - {path: materials.steel.E, bounds: [150 GPa, 250 GPa]}\nmodes:\n  - {frequency: 1 kHz}\n",
     4, "modes[0]", "tolerance"),
    ("parameters:\n  - {path: materials.steel.E, bounds: [150 GPa, 250 GPa]}\nmode:\n  - {frequency: 1 kHz}\n",
     3, "mode", "unknown key"),
])
def test_error_paths_exit_2_naming_file_line_and_key(tmp_path, capsys, targets, line, key, words):
    start = _strip(tmp_path)
    t = tmp_path / "targets.yaml"
    t.write_text(targets)
    out = tmp_path / "updated.yaml"
    code = main(["update", str(start), "--targets", str(t), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert f"{t}:{line}" in err and f"key {key!r}" in err and words in err
    assert "Traceback" not in err and not out.exists()


def test_cli_json_keys(tmp_path, capsys):
    truth = _strip(tmp_path, "truth.yaml", E="205 GPa")
    start = _strip(tmp_path)
    t = _targets(tmp_path, [("materials.steel.E", "150 GPa", "250 GPa")], _true_frequencies(truth, 2), tol="0.5 %",
                 extra="count_below: {frequency: 6 kHz, count: 2}\nn_modes: 6\n")
    out = tmp_path / "updated.yaml"
    assert main(["update", str(start), "--targets", str(t), "-o", str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert {"parameters", "residuals", "cost", "iterations", "converged", "correlation"} <= set(s)
    p = s["parameters"][0]
    assert p["path"] == "materials.steel.E" and p["unit"] == "GPa" and abs(p["value"] / 205 - 1) < 1e-4
    assert p["ci95"] > 0
    assert {"target", "model", "error_pct"} <= set(s["residuals"][0])
    assert s["residuals"][0]["target"] == pytest.approx(_true_frequencies(truth, 2)[0])
    assert s["count_below"][0]["satisfied"] and s["count_below"][0]["model_count"] == 2
    assert out.read_text().startswith("# Updated by fivid update")


def test_paths_and_rewrite():
    assert parse_path("bodies.lower.corners[1][0]") == ["bodies", "lower", "corners", 1, 0]
    text = "a: {b: 1 mm, c: [2 N, 3 N]}  # note\nd:\n  - e: 4   # kept\n"
    new = replace_values(text, {"a.b": "1.5 mm", "a.c[1]": "3.25 N", "d[0].e": "5"})
    assert new == "a: {b: 1.5 mm, c: [2 N, 3.25 N]}  # note\nd:\n  - e: 5   # kept\n"
    assert get_path(yaml.safe_load(new), "a.c[1]") == "3.25 N"
    with pytest.raises(KeyError, match="does not exist"):
        get_path(yaml.safe_load(text), "a.x")


def test_lab_workflow_ema_then_update_with_mac_pairing(tmp_path, capsys):
    """Synthetic "measurement": receptance FRFs at the strip's four sensors (reference at s4) from the modes of
    the truth model (E = 200 GPa, 1 % modal damping), written as UFF58; 'fivid ema' identifies the modes, and
    'fivid update' pairs its shapes by MAC and recovers E from 210 GPa within 1 %."""
    import pyuff

    from fivid.io.export import uff58_set

    truth = _strip(tmp_path, "truth.yaml", E="200 GPa")
    model = load_model(str(truth))
    ds = modal_analysis(model, 3)
    fn = ds["frequency"].values
    phi = np.array([[ds["mode_shape"].values[r, s.node] @ s.direction for s in model.sensors] for r in range(3)])
    f = np.arange(1, 4097) * 4.0
    w, wn = 2 * np.pi * f, 2 * np.pi * fn
    h = sum(np.outer(phi[r] * phi[r, 3], 1 / (wn[r] ** 2 - w**2 + 2j * 0.01 * wn[r] * w)) for r in range(3))
    sets = []
    for k in range(4):
        s = uff58_set(f"s{k + 1}", f, h[k], ordinate_units="m/N", abscissa_units="Hz", node=k + 1, func_type=4,
                      abscissa="frequency")
        s.update(rsp_dir=2, ref_node=4, ref_dir=2)
        sets.append(s)
    pyuff.UFF(str(tmp_path / "frfs.uff")).write_sets(sets, mode="overwrite")
    assert main(["ema", str(tmp_path / "frfs.uff"), "--band", "500", "15000", "--modes", "3",
                 "-o", str(tmp_path / "modes.nc"), "--json"]) == 0
    measured = [m["frequency_hz"] for m in json.loads(capsys.readouterr().out)["modes"]]
    assert np.allclose(measured, fn, rtol=1e-3)
    shape = "shape: {file: modes.nc, mode: %d, sensors: [s1, s2, s3, s4]}"
    (tmp_path / "t.yaml").write_text(
        "parameters:\n  - {path: materials.steel.E, bounds: [150 GPa, 250 GPa]}\nmodes:\n"
        + "".join(f"  - {{frequency: {float(fk)!r} Hz, tolerance: 0.5 %, {shape % (3 - i)}}}\n"
                  for i, fk in enumerate(measured[::-1])))  # listed in reverse: MAC must pair them
    start = _strip(tmp_path)
    assert main(["update", str(start), "--targets", str(tmp_path / "t.yaml"), "-o", str(tmp_path / "u.yaml"),
                 "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert abs(s["parameters"][0]["value"] / 200 - 1) < 0.01
    assert [r["model_mode"] for r in s["residuals"]] == [3, 2, 1] and min(r["mac"] for r in s["residuals"]) > 0.99
