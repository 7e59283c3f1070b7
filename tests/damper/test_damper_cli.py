"""fivid damper fit / frf from the command line."""

import json
from pathlib import Path

import numpy as np
import pytest

from fivid.cli import main
from fivid.friction.jenkins import jenkins_force

CONFIGS = Path(__file__).resolve().parents[2] / "configs" / "dampers"


def _loop_file(path, drift=0.0):
    """Synthetic (labelled): ramped 1 Hz sine on a Jenkins element (k 2e6 N/m, F_s 4 kN) + 5 N noise."""
    t = np.arange(0, 8, 1 / 512)
    x = 0.025 * np.clip(t, 0, 1) * np.clip(8 - t, 0, 1) * np.sin(2 * np.pi * t) + drift * t
    f = jenkins_force(x, 2e6, 4000.0) + 5.0 * np.random.default_rng(1).normal(size=t.size)
    doc = {"time units": "s", "displacement units": "mm", "friction force units": "kN",
           "data": np.column_stack([t, x * 1e3, f / 1e3]).tolist()}
    path.write_text(json.dumps(doc))
    return path


def test_fit_json(tmp_path, capsys):
    assert main(["damper", "fit", str(_loop_file(tmp_path / "l.json")), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["slip_force"] == pytest.approx(4000.0, rel=0.01)
    assert out["stiffness"] == pytest.approx(2e6, rel=0.05)
    for key in ("energy_per_cycle_measured", "energy_per_cycle_model"):
        assert out[key] > 0
    assert out["units"]["stiffness"] == "N m-1"


def test_fit_bad_input_exits_2(tmp_path, capsys):
    assert main(["damper", "fit", str(_loop_file(tmp_path / "d.json", drift=0.01))]) == 2
    err = capsys.readouterr().err
    assert "drifts" in err and "d.json" in err and "Traceback" not in err


def test_fit_real_loop_text(real_data, capsys):
    assert main(["damper", "fit", str(real_data / "friction_damper" / "1Hz35lbtension.json")]) == 0
    assert "slip_force" in capsys.readouterr().out


def test_frf_json(capsys):
    status = main(["damper", "frf", str(CONFIGS / "seed004_model1.yaml"), "--normal-load", "0.1", "80",
                   "--points", "116", "--json"])
    assert status == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["frequency"]) == 116
    peaks = [c["peak_frequency"] for c in out["curves"]]
    assert peaks[0] == pytest.approx(24, abs=1.0) and peaks[1] == pytest.approx(87, abs=1.0)  # 1 Hz grid


def test_frf_bad_load(capsys):
    assert main(["damper", "frf", str(CONFIGS / "seed004_model1.yaml"), "--normal-load", "-1"]) == 2
    assert "--normal-load: must be a positive force, got '-1'" in capsys.readouterr().err


def test_frf_arclength_json(capsys):
    status = main(["damper", "frf", str(CONFIGS / "seed004_model1.yaml"), "--normal-load", "2", "--arclength", "--json"])
    assert status == 0
    curve = json.loads(capsys.readouterr().out)["curves"][0]
    f = np.array(curve["frequency"])
    assert f[0] == pytest.approx(15) and f[-1] == pytest.approx(130)
    assert len(curve["stable"]) == len(curve["amplitude"]) == f.size
    assert all(curve["stable"])


def test_damper_without_action_shows_help(capsys):
    assert main(["damper"]) == 2
    assert "fit" in capsys.readouterr().err


@pytest.mark.parametrize("args, words", [(["--normal-load", "5", "-5"], "argument --normal-load: must be a positive"),
                                         (["--normal-load", "nan"], "argument --normal-load: 'nan' is not a force"),
                                         (["--normal-load", "5 kg"], "argument --normal-load: '5 kg' is not a force"),
                                         (["--normal-load", "5", "--points", "1"], "key '--points'")])
def test_frf_bad_arguments_name_the_option(args, words, capsys):
    assert main(["damper", "frf", str(CONFIGS / "seed004_model1.yaml"), *args]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err
