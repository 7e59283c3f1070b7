"""``fivid psd`` and ``fivid score`` end to end on synthetic RunDataset files (generator: test_score_runs)."""

import json

import numpy as np
import pytest
import xarray as xr
from tests.helpers.resonance_runs import resonance_run

from fivid.cli import main
from fivid.io import write_run


def run_file(path, seed, run_id, **kw):
    ds = resonance_run(seed, run_id=run_id, n=2**16, **kw)
    ds["normal_force"] = ("time", np.full(ds.sizes["time"], 5.0), {"units": "N"})
    ds.attrs.update(rig="synthetic", sliding_velocity=0.01, normal_load=5.0, roughness_ra=8e-7,
                    source="synthetic: tests/helpers/resonance_runs.py resonance_run", history="synthetic")
    write_run(ds, path, overwrite=True)
    return path


@pytest.fixture
def runs(tmp_path):
    return run_file(tmp_path / "M.nc", 1, "M"), run_file(tmp_path / "S.nc", 2, "S")


def test_psd_command_writes_psd_with_settings(runs, tmp_path, capsys):
    out = tmp_path / "psd.nc"
    assert main(["psd", str(runs[0]), "--nperseg", "2048", "-o", str(out)]) == 0
    with xr.open_dataset(out) as ds:
        p = ds["psd_acceleration"].load()
    assert p.attrs["units"] == "m2 s-4 Hz-1" and p.attrs["nperseg"] == 2048 and p.attrs["window"] == "hann"
    assert "psd_lower" in p.coords and p.attrs["equivalent_averages"] > 0
    assert "PSD of acceleration" in capsys.readouterr().out
    # the same PSD as the library gives for the run
    from fivid.io import read_run
    from fivid.signal import welch_psd

    ref = welch_psd(read_run(runs[0])["acceleration"], nperseg=2048)
    np.testing.assert_array_equal(p.values, ref.values)
    assert main(["psd", str(runs[0]), "-o", str(out)]) == 2  # exists, no --overwrite


def test_score_command_json_and_netcdf(runs, tmp_path, capsys):
    out = tmp_path / "scores.nc"
    status = main(["score", str(runs[0]), str(runs[1]), "--band", "100", "4000", "--nperseg", "1024",
                   "-o", str(out), "--json"])
    assert status == 0
    j = json.loads(capsys.readouterr().out)
    for key in ("lsd_db", "level_diff_db", "band_level_rms_error_db", "shape_correlation", "peaks", "significant"):
        assert key in j
    with xr.open_dataset(out) as sc:
        sc = sc.load()
    assert float(sc.lsd_db) == pytest.approx(j["lsd_db"], rel=1e-15)
    assert bool(sc.lsd_db_significant) == j["significant"]["lsd_db"]
    assert sc.attrs["measured_run_id"] == "M" and sc.attrs["band_upper"] == 4000.0


def test_score_command_bad_band_exits_2_naming_the_file(runs, capsys):
    assert main(["score", str(runs[0]), str(runs[1]), "--band", "100", "6000"]) == 2
    err = capsys.readouterr().err
    assert "6000.0 Hz is beyond the Nyquist frequency 5000.0 Hz of the measured run 'M'" in err
    assert "M.nc" in err


def test_score_command_variable_missing_in_one_run(tmp_path, capsys):
    m = run_file(tmp_path / "M.nc", 1, "M")
    s = resonance_run(2, run_id="S", n=2**16)
    s["normal_force"] = ("time", np.full(s.sizes["time"], 5.0), {"units": "N"})
    s["velocity"] = ("time", np.full(s.sizes["time"], 0.01), {"units": "m s-1"})
    s.attrs.update(rig="x", sliding_velocity=0.01, normal_load=5.0, roughness_ra=8e-7, source="synthetic", history="h")
    write_run(s, tmp_path / "S.nc")
    assert main(["score", str(m), str(tmp_path / "S.nc"), "--variable", "velocity"]) == 2
    err = capsys.readouterr().err
    assert "measured run 'M'" in err and "M.nc" in err and "has no variable 'velocity'" in err


def test_help_lists_both_commands(capsys):
    with pytest.raises(SystemExit):
        main(["--help"])
    out = capsys.readouterr().out
    assert "psd" in out and "score" in out


def test_psd_command_steady_window_and_missing_variable(tmp_path, capsys):
    ds = resonance_run(1, run_id="V", n=2**16)
    t = ds["time"].values
    ds["velocity"] = ("time", 0.01 * np.clip(t / 1.0, 0, 1) * np.clip((t[-1] - t) / 1.0, 0, 1), {"units": "m s-1"})
    ds["normal_force"] = ("time", np.full(t.size, 5.0), {"units": "N"})
    ds.attrs.update(rig="x", sliding_velocity=0.01, normal_load=5.0, roughness_ra=8e-7, source="synthetic", history="h")
    write_run(ds, tmp_path / "V.nc")
    out = tmp_path / "p.nc"
    assert main(["psd", str(tmp_path / "V.nc"), "--nperseg", "1024", "--steady", "-o", str(out)]) == 0
    with xr.open_dataset(out) as p:
        assert p.attrs["steady_only"] == 1 and "steady window" in p.attrs["history"]
        # 1 s ramps of a 6.55 s record, 5 % tolerance: the window is 6.55 - 2 * 0.95 = 4.65 s (+- smoothing)
        k = p["psd_acceleration"].attrs["n_segments"]
    assert abs(k - (4.65 * 10000 - 512) // 512) <= 0.05 * 10000 / 512 + 1
    assert main(["psd", str(tmp_path / "V.nc"), "--variable", "position", "-o", str(tmp_path / "q.nc")]) == 2
    err = capsys.readouterr().err
    assert "run 'V'" in err and "V.nc" in err and "no variable 'position'" in err
    assert err.count("V.nc") == 1  # the file is named once, not as a prefix and again in the run label


def test_summary_does_not_call_an_unjudged_score_within_uncertainty():
    from fivid.cli.commands.score import _summary

    names = ("lsd_db", "level_diff_db", "band_level_rms_error_db", "shape_correlation")
    j = {"simulated": "S", "measured": "M", "variable": "acceleration", "band_hz": [10.0, 100.0], "peaks": [],
         **{k: 0.5 for k in names}, "significant": {k: False for k in names},
         "thresholds": {**{k: 1.0 for k in names}, "shape_correlation": None}}
    lines = _summary(j).splitlines()
    assert "not judged" in lines[4] and "within uncertainty" in lines[1]
