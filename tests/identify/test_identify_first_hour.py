"""A lab's own data (issue 32 items 1 and 3): runs without an encoder signal, and identify explaining its choice.

SYNTHETIC runs from tests/helpers/synthetic_friction_runs.py (known law; unloaded 0-0.6 s, load ramp 0.6-0.7 s, base ramp
0.7-0.8 s, steady sliding, ramp down over the last 0.15 s). Bounds as in test_identify_friction.py: two-sided
99.9 % (3.29 standard errors) on single-seed estimates.
"""

import numpy as np
import pytest
from scipy import stats
from tests.helpers.synthetic_friction_runs import ANALYSIS_BAND, MU0, band_amplitude, run_grid, synthetic_run, true_law

from fivid.cli import main
from fivid.errors import DataQualityError
from fivid.identify import identify_friction_law
from fivid.identify.amplitude_fit import CV_ERROR_WARN, FormFit, constant_law_warning
from fivid.signal import steady_force_window, steady_sliding_window

TARE = (0.0, 0.5)
NPERSEG = 2048
Z = stats.norm.ppf(0.9995)


def _without_encoder(ds):
    return ds.drop_vars(["velocity", "position"])


@pytest.fixture(scope="module")
def law():
    return true_law("linear_velocity")


@pytest.fixture(scope="module")
def encoderless(law):
    return [synthetic_run(law, velocity=v, roughness=0.4e-6, normal_load=5.0, seed=40 + i, run_id=f"F{i}")
            for i, v in enumerate((0.004, 0.016))]


def test_force_window_lies_in_the_steady_part_and_matches_the_encoder(encoderless):
    """Friction reaches its Coulomb value at ~0.75 s (base at 30 % of its plateau) and drops again in the last
    0.15 s: the force window must lie inside, and cover most of the encoder's window."""
    for ds in encoderless:
        duration = float(ds["time"][-1])
        t0, t1 = steady_force_window(_without_encoder(ds))
        e0, e1 = steady_sliding_window(ds)
        assert 0.7 < t0 < 0.85 and duration - 0.15 < t1 <= duration
        overlap = min(t1, e1) - max(t0, e0)
        assert overlap > 0.9 * (e1 - e0), ((t0, t1), (e0, e1))


def test_identify_without_encoder_recovers_the_law(law, encoderless):
    runs = [_without_encoder(ds) for ds in encoderless]
    res = identify_friction_law(runs, band=ANALYSIS_BAND, tare=TARE, nperseg=NPERSEG)
    assert all(r.used and r.window_source.startswith("forces") for r in res.runs)
    for r in res.runs:
        truth = band_amplitude(law, r.sliding_velocity, r.roughness_ra, r.normal_load)
        assert abs(r.mu_rms - truth) < Z * r.mu_rms_stderr, (r.run_id, r.mu_rms, truth)
        half = (r.mu_mean_ci[1] - r.mu_mean_ci[0]) / 2
        assert abs(r.mu_mean - MU0) < half * stats.t.ppf(0.9995, 19) / stats.t.ppf(0.975, 19)
    assert any("from the forces" in m for m in res.messages)


def test_window_given_by_hand(law, encoderless):
    runs = [_without_encoder(ds) for ds in encoderless]
    res = identify_friction_law(runs, band=ANALYSIS_BAND, tare=TARE, nperseg=NPERSEG, window=(1.0, 3.0))
    for r in res.runs:
        assert r.window_source.startswith("given")
        assert r.t_start == pytest.approx(1.0, abs=1 / 25600) and r.t_stop == pytest.approx(3.0, abs=1 / 25600)
        truth = band_amplitude(law, r.sliding_velocity, r.roughness_ra, r.normal_load)
        assert abs(r.mu_rms - truth) < Z * r.mu_rms_stderr
    assert res.settings["window"] == (1.0, 3.0)


def test_no_window_from_forces_says_both_ways(encoderless):
    ds = _without_encoder(encoderless[0]).copy(deep=True)
    t = ds["time"].values
    ds["friction_force"] = ds["friction_force"] * (1 + t)  # mu drifts with time: no plateau
    with pytest.raises(DataQualityError) as err:
        steady_force_window(ds)
    assert "--window T0 T1" in err.value.message and "'velocity' or 'position'" in err.value.message
    res = identify_friction_law([ds, _without_encoder(encoderless[1])], band=ANALYSIS_BAND, nperseg=NPERSEG)
    assert "--window T0 T1" in res.runs[0].reason


def test_cli_identify_without_encoder_and_with_window(encoderless, tmp_path, capsys):
    paths = []
    for ds in encoderless:
        p = tmp_path / f"{ds.attrs['run_id']}.nc"
        _without_encoder(ds).to_netcdf(p)
        paths.append(str(p))
    assert main(["identify", *paths, "-o", str(tmp_path / "a.nc"), "--band", "100", "5000"]) == 0
    assert "from the forces" in capsys.readouterr().out
    assert main(["identify", *paths, "-o", str(tmp_path / "b.nc"), "--band", "100", "5000",
                 "--window", "1000 ms", "3 s"]) == 0
    capsys.readouterr()
    assert main(["identify", *paths, "-o", str(tmp_path / "c.nc"), "--band", "100", "5000",
                 "--window", "1 s", "9 s"]) == 2
    assert "--window 1 s 9 s must be an increasing interval inside the record" in capsys.readouterr().err


def test_four_runs_constant_law_is_explained_and_flagged(law):
    """2 velocities x 2 roughnesses: the 3-coefficient forms have no AICc (k = 4 needs n >= 6), so the constant
    is the only form compared; the true amplitudes spread (0.002 + 0.25 V at 2 and 20 mm/s, 0.003 + 0.5 V)."""
    runs = run_grid(law, seed=5, velocities=(0.002, 0.02))
    res = identify_friction_law(runs, band=ANALYSIS_BAND, tare=TARE, nperseg=NPERSEG)
    assert res.law.amplitude_model.form == "constant"
    rows = {row["form"]: row for row in res.selection_table()}
    for form in ("power_law", "linear_velocity_power_law", "log_linear"):
        assert rows[form]["reason"] == "its AICc needs at least 6 runs for 3 coefficients, 4 given"
    text = res.summary()
    assert "power_law                  not compared: its AICc needs at least 6 runs" in text
    a = np.array([r.mu_rms for r in res.runs])
    assert a.max() / a.min() > 2
    assert len(res.warnings) == 1 and f"spread {a.max() / a.min():.2g}x" in res.warnings[0]
    assert "warning: a constant amplitude law was chosen" in text
    assert res.to_json()["warnings"] == res.warnings


def test_constant_law_warning_thresholds():
    fit = FormFit(form="constant", n_runs=4)
    fit.cv_error = CV_ERROR_WARN * 0.99
    assert constant_law_warning(fit, [1.0, 1.5, 1.9, 1.2]) == ""
    assert "spread 2.1x" in constant_law_warning(fit, [1.0, 2.1])
    fit.cv_error = CV_ERROR_WARN * 1.01
    assert "cross-validation error" in constant_law_warning(fit, [1.0, 1.1])
    other = FormFit(form="power_law", n_runs=4)
    assert constant_law_warning(other, [1.0, 5.0]) == ""


def test_pipeline_shows_identify_warnings(tmp_path, caplog):
    """`fivid run`: identify's warnings (e.g. the constant-law one) reach the console/log, not only law.json."""
    import json
    import logging
    from types import SimpleNamespace

    from fivid.pipeline.stages import Identify

    (tmp_path / "law.json").write_text(json.dumps({"warnings": ["constant law chosen although ... spread 3.0x"]}))
    task = SimpleNamespace(outputs={"json": str(tmp_path / "law.json"), "law": str(tmp_path / "law.nc")})
    ctx = SimpleNamespace(data={})
    with caplog.at_level(logging.WARNING, logger="fivid"):
        Identify().collect(ctx, [task])
    assert "identify: constant law chosen although ... spread 3.0x" in caplog.text
    assert ctx.data["law_summary"]["warnings"]
