"""``fivid modes`` and ``fivid cea`` on the coarse rig config: JSON as the issue specifies, outputs, bad input -> 2."""

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from fivid.cli import main

ROOT = Path(__file__).resolve().parents[2]
COARSE = str(ROOT / "configs" / "models" / "triboair_coarse.yaml")


def test_modes_json_and_netcdf(tmp_path, capsys):
    out = tmp_path / "modes.nc"
    assert main(["modes", COARSE, "-n", "4", "--json", "-o", str(out)]) == 0
    j = json.loads(capsys.readouterr().out)
    assert len(j["frequencies_hz"]) == 4 and j["n_dofs"] == 984
    assert j["frequencies_hz"] == sorted(j["frequencies_hz"]) and 700 < j["frequencies_hz"][0] < 900
    with xr.open_dataset(out) as ds:
        assert ds["frequency"].values.tolist() == pytest.approx(j["frequencies_hz"])
        assert ds["mode_shape"].dims == ("mode", "node", "component")
    # the output exists now: refused without --overwrite (exit 2, one line), accepted with it
    assert main(["modes", COARSE, "-n", "2", "-o", str(out)]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["modes", COARSE, "-n", "2", "-o", str(out), "--overwrite"]) == 0


def test_modes_with_load_couple_the_bodies_at_the_closed_tip(capsys):
    """Under 5 N the bent upper beam touches with its tip corner only (static preload solve): one closed node
    carrying the whole load; the coupled first mode is well below the all-slave-nodes-bonded one (~2135 Hz)."""
    assert main(["modes", COARSE, "-n", "3", "--load", "5 N", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["include_contact"] and j["normal_load_n"] == 5.0 and len(j["closed_slave_nodes"]) == 1
    assert 1300 < j["frequencies_hz"][0] < 1600


def test_modes_table(capsys):
    assert main(["modes", COARSE, "-n", "3"]) == 0
    out = capsys.readouterr().out
    assert "frequency [Hz]" in out and len(out.strip().splitlines()) == 6  # model, damping, header, 3 modes


def test_modes_damping_ratios_and_curve(tmp_path, capsys):
    """Each mode's damping ratio is the scheme's exact ratio at its frequency; the curve is a PNG."""
    from fivid.fe import load_model
    from fivid.fe.damping import damping_ratio

    png = tmp_path / "damping.png"
    assert main(["modes", COARSE, "-n", "4", "--json", "--damping-curve", str(png)]) == 0
    j = json.loads(capsys.readouterr().out)
    model = load_model(COARSE)
    assert j["damping_scheme"] == "rayleigh" and j["damping_cutoff_hz"] is None
    np.testing.assert_allclose(j["damping_ratios"], damping_ratio(j["frequencies_hz"], model.rayleigh_alpha,
                                                                  model.rayleigh_beta), rtol=1e-12)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cea_json_per_mode(tmp_path, capsys):
    out = tmp_path / "cea.nc"
    assert main(["cea", COARSE, "--load", "5 N", "--mu", "0", "1.5", "16", "-n", "20", "--no-damping", "--json", "-o", str(out)]) == 0
    j = json.loads(capsys.readouterr().out)
    assert len(j["mu"]) == 16 and j["mu"][0] == 0 and j["mu"][-1] == 1.5
    assert len(j["modes"]) == 20
    for m in j["modes"]:
        assert len(m["frequency_hz"]) == 16 and len(m["real_part"]) == 16
        assert m["critical_mu"] is None or 0 <= m["critical_mu"] <= 1.5
    assert any(m["critical_mu"] is not None for m in j["modes"])
    with xr.open_dataset(out) as ds:
        assert ds.sizes == {"mu": 16, "mode": 20}


@pytest.mark.parametrize("argv, words", [
    (["cea", COARSE, "--load", "5 N", "--mu", "0", "1", "x"], "START STOP STEPS"),
    (["cea", COARSE, "--load", "5 N", "--mu", "1", "0", "5"], "START < STOP"),
    (["modes", "/nonexistent/model.yaml"], "cannot read"),
    (["modes", COARSE, "-n", "0"], ">= 1"),
    (["modes", COARSE, "--contact"], "--load"),
    (["modes", COARSE, "--load", "-5 N"], "positive"),
    (["cea", COARSE, "--load", "0 N", "--mu", "0", "1", "5"], "positive"),
    # a unit error names the option it came from
    (["modes", COARSE, "--load", "5 furlong"], "--load: '5 furlong' is not a force"),
    (["cea", COARSE, "--load", "5 kg", "--mu", "0", "1", "5"], "--load: '5 kg'"),
])
def test_bad_input_exits_2_with_one_line(argv, words, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and len(err.splitlines()) == 1


def test_config_error_names_key(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text(Path(COARSE).read_text().replace("divisions: [30, 5]", "divisions: [30, 0]"))
    assert main(["modes", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bodies.upper.divisions[1]" in err and f"{bad}:" in err
