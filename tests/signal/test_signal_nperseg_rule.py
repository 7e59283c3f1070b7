"""One default Welch segment rule (issue 20 item 2): ``fivid.signal.welch.default_nperseg``, used wherever no
nperseg is given, and every output states the nperseg it used.

The rule's values are worked out by hand from its statement (NPERSEG_RULE): the largest power of two m with
m <= n/16 and fs/m >= 2 Hz, at least 256; with mains, raised until fs/m <= mains/4 while m <= n/4.
"""

import json

import numpy as np
import pytest
import xarray as xr

from fivid.signal import welch_psd
from fivid.signal.welch import NPERSEG_RULE, default_nperseg


def _noise(n, fs, run_id="R", seed=0):
    t = np.arange(n) / fs
    rng = np.random.default_rng(seed)
    return xr.Dataset({"acceleration": ("time", rng.standard_normal(n), {"units": "m s-2"})},
                      coords={"time": ("time", t, {"units": "s"})}, attrs={"run_id": run_id, "sample_rate": fs})


@pytest.mark.parametrize("fs, n, mains, expected", [
    (51200.0, 20000, None, 1024),   # 20000/16 = 1250 -> 1024
    (51200.0, 20000, 50.0, 4096),   # 12.5 Hz bins need 4096 <= 20000/4
    (51200.0, 10000, 50.0, 2048),   # averages 512; mains raises to 2048 (<= 2500), 4096 > 2500 stops
    (51200.0, 1000, None, 256),     # the floor
    (1000.0, 10**6, None, 256),     # fs/m >= 2 Hz: 1000/512 < 2 -> 256
    (51200.0, 2**22, None, 16384),  # 2**18 allowed by n/16, fs/m >= 2 Hz stops at 16384 (3.125 Hz)
])
def test_rule_values_by_hand(fs, n, mains, expected):
    assert default_nperseg(fs, n, mains) == expected


def test_welch_psd_without_nperseg_uses_the_rule_and_says_so():
    ds = _noise(20000, 51200.0)
    p = welch_psd(ds["acceleration"])
    assert p.attrs["nperseg"] == 1024 and p.attrs["nperseg_rule"] == NPERSEG_RULE
    given = welch_psd(ds["acceleration"], nperseg=1024)
    np.testing.assert_array_equal(p.values, given.values)  # the rule only picks the number
    assert given.attrs["nperseg_rule"] == "given"


def test_score_runs_without_nperseg_uses_the_rule_on_the_shorter_run_at_the_common_rate():
    from fivid.score import score_runs, scores_to_json

    m = _noise(2**16, 10000.0, "M", 1)  # 65536 -> 4096
    s = _noise(2**14, 10000.0, "S", 2)  # 16384 -> 1024: the shorter sets it
    sc = score_runs(m, s)
    assert sc.attrs["nperseg"] == 1024 and sc.attrs["nperseg_rule"] == NPERSEG_RULE
    j = scores_to_json(sc)
    assert j["settings"]["nperseg"] == 1024 and j["settings"]["nperseg_rule"] == NPERSEG_RULE
    fast = _noise(2**15, 20000.0, "F", 3)  # at the common 10 kHz: 16384 samples -> 1024
    assert score_runs(m, fast).attrs["nperseg"] == 1024
    assert score_runs(m, s, nperseg=512).attrs["nperseg_rule"] == "given"


def test_cli_psd_and_score_state_the_nperseg_they_used(tmp_path, capsys):
    from tests.helpers.synthetic_friction_runs import synthetic_run, true_law

    from fivid.cli import main
    from fivid.io import write_run

    law = true_law()
    m = write_run(synthetic_run(law, velocity=0.01, roughness=0.4e-6, normal_load=5.0, seed=0, run_id="M",
                                duration=1.28), tmp_path / "m.nc")  # 32768 samples at 25.6 kHz -> 2048
    s = write_run(synthetic_run(law, velocity=0.01, roughness=0.4e-6, normal_load=5.0, seed=1, run_id="S",
                                duration=0.64), tmp_path / "s.nc")  # 16384 samples -> 1024
    assert main(["psd", str(m), "-o", str(tmp_path / "p.nc"), "--json", "-q"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["settings"]["nperseg"] == 2048 and j["settings"]["nperseg_rule"] == NPERSEG_RULE
    assert j["n_frequencies"] == 1025
    assert main(["score", str(m), str(s), "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["settings"]["nperseg"] == 1024 and j["settings"]["nperseg_rule"] == NPERSEG_RULE
    assert main(["score", str(m), str(s)]) == 0
    assert "Welch nperseg 1024" in capsys.readouterr().out


def test_time_step_halving_psds_use_the_rule_on_the_shortest_steady_part():
    from fivid.signal.compare import steady_psds

    a = _noise(20000, 51200.0).assign_attrs(transient_end=0.0)
    b = _noise(30000, 51200.0).assign_attrs(transient_end=0.0)
    f, psds, n = steady_psds([a, b])
    assert n == 1024 and f.size == 513 and all(p.size == 513 for p in psds)


def test_dominant_frequency_track_default_segment_is_the_rule():
    from fivid.signal.transient import dominant_frequency_track

    fs = 51200.0
    t = np.arange(20000) / fs
    tt, f, _ = dominant_frequency_track(np.sin(2 * np.pi * 1000.0 * t), fs)
    assert abs(f[0] - 1000.0) <= fs / 1024 / 2  # 1024-sample segments: bins of 50 Hz
    assert np.allclose(np.diff(tt), 512 / fs)


def test_pipeline_config_default_is_the_rule_on_the_simulated_steady_part(tmp_path):
    from fivid.pipeline.config import load_run_config

    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "R1.csv").write_text("x\n")
    (tmp_path / "model.yaml").write_text("name: m\n")

    def config(analysis):
        path = tmp_path / "run.yaml"
        path.write_text("fivid-run: 1\ninputs: {folder: data}\nmodel: model.yaml\noutput: out\n"
                        f"analysis: {analysis}\nsimulate: {{duration: 0.5 s, sample_rate: 51.2 kHz, seeds: 1}}\n",
                        encoding="utf-8")
        return load_run_config(path)

    # (0.5 s - 0.1 s settle) * 51.2 kHz = 20480 samples: 20480/16 = 1280 -> 1024
    assert config("{band: [500 Hz, 20 kHz], settle: 0.1 s}").nperseg == 1024
    assert config("{band: [500 Hz, 20 kHz], nperseg: 2048}").nperseg == 2048
