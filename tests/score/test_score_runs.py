"""score_runs: closed-form cases (a run against itself, against itself scaled by 2), a detectable
difference, resampling, JSON keys, and the bad inputs of issue 3.

Runs are synthetic: white noise through a resonant IIR filter (scipy.signal.iirpeak) plus a white
floor, from numpy Generators with the seeds given."""

import numpy as np
import pytest
import scipy.signal
import xarray as xr

from fivid.errors import ConfigError, DataQualityError, SchemaError, UnitError
from fivid.score import score_runs, scores_to_json
from tests.helpers.resonance_runs import FS, resonance_run


def test_run_against_itself():
    m = resonance_run(1)
    sc = score_runs(m, m, nperseg=1024)
    assert float(sc.lsd_db) == 0.0
    assert float(sc.level_diff_db) == 0.0
    assert float(sc.band_level_rms_error_db) == 0.0
    assert float(sc.shape_correlation) == pytest.approx(1.0, abs=1e-12)
    for name in ("lsd_db", "level_diff_db", "band_level_rms_error_db", "shape_correlation"):
        assert not bool(sc[f"{name}_significant"])
    assert sc.peak.size >= 1
    assert abs(float(sc.peak_frequency_measured[0]) - 1200.0) < 2 * sc.attrs["frequency_resolution"]
    np.testing.assert_array_equal(sc.peak_frequency_error.values, 0.0)


def test_scaled_by_two_is_plus_6_02_db_everywhere():
    m = resonance_run(1)
    s = resonance_run(1, scale=2.0, run_id="S")
    sc = score_runs(m, s, nperseg=1024)
    six = 20 * np.log10(2.0)  # 6.0206 dB; PSD scales by 4 exactly, so only float round-off remains
    np.testing.assert_allclose(sc.log_psd_difference_db.values, six, atol=1e-12)
    np.testing.assert_allclose(sc.band_level_error_db.values, six, atol=1e-12)
    np.testing.assert_allclose(sc.peak_level_diff_db.values, six, atol=1e-12)
    for name in ("lsd_db", "level_diff_db", "band_level_rms_error_db"):
        assert float(sc[name]) == pytest.approx(six, abs=1e-12)
        assert bool(sc[f"{name}_significant"])
    assert float(sc.shape_correlation) == pytest.approx(1.0, abs=1e-12)
    assert not bool(sc.shape_correlation_significant)


def test_independent_realisations_are_within_uncertainty():
    sc = score_runs(resonance_run(10), resonance_run(11, run_id="S"), nperseg=1024)
    # one draw: each flag is false with probability ~0.95 (the slow calibration test measures the rates)
    assert float(sc.lsd_db) < 2 * float(sc.lsd_db_threshold)
    assert not bool(sc.lsd_db_significant)
    assert not bool(sc.level_diff_db_significant)


def test_moved_resonance_is_detected():
    sc = score_runs(resonance_run(1), resonance_run(2, peak=1380.0, run_id="S"), nperseg=1024)
    assert bool(sc.lsd_db_significant)
    assert bool(sc.shape_correlation_significant)
    # iirpeak puts the resonances exactly at 1200 and 1380 Hz: error 0.15. Each fitted vertex has a standard
    # error of a few Hz here (peak_frequency_error_threshold / 1.96 / sqrt 2 ~ 0.003 relative): 0.01 is ~3 sigma.
    assert float(sc.peak_frequency_error[0]) == pytest.approx(0.15, abs=0.01)
    assert bool(sc.peak_frequency_error_significant[0])
    j = scores_to_json(sc)
    assert j["significant"]["shape_correlation"] and j["peaks"][0]["frequency_significant"]


def test_json_has_the_issue_keys():
    j = scores_to_json(score_runs(resonance_run(1), resonance_run(2, run_id="S"), nperseg=1024, band=(100, 4000)))
    for key in ("lsd_db", "level_diff_db", "band_level_rms_error_db", "shape_correlation", "peaks"):
        assert key in j
    assert isinstance(j["lsd_db"], float) and isinstance(j["peaks"], list)
    assert j["band_hz"] == [100.0, 4000.0] and j["measured"] == "M" and j["simulated"] == "S"
    # 1/3-octave bands fully inside [100, 4000] Hz: IEC base-10 x = -9 (125.9 Hz, lower edge 112.2 Hz) ...
    # x = 5 (3162 Hz, upper edge 3548 Hz); the 100 Hz band starts at 89.1 Hz, the 3981 Hz band ends at 4467 Hz
    centres = [b["centre_hz"] for b in j["band_level_error_db"]]
    np.testing.assert_allclose(centres, 1000 * 10 ** (np.arange(-9, 6) / 10), rtol=1e-12)


def test_different_rates_are_resampled():
    m = resonance_run(3)
    up = scipy.signal.resample_poly(m["acceleration"].values, 2, 1)  # the same signal at 20 kHz
    n = up.size
    s = xr.Dataset({"acceleration": ("time", up, {"units": "m s-2"})},
                   coords={"time": ("time", np.arange(n) / (2 * FS), {"units": "s"})},
                   attrs={"run_id": "S", "sample_rate": 2 * FS})
    sc = score_runs(m, s, nperseg=1024, band=(100, 3000))
    assert sc.attrs["resampled"] == "simulated 20000 Hz -> 10000 Hz"
    # up then down by resample_poly: Kaiser(beta 5) passband ripple ~ 2e-3 each way, i.e. < 0.05 dB on power
    assert float(sc.lsd_db) < 0.05
    assert abs(float(sc.level_diff_db)) < 0.05


@pytest.mark.parametrize("which", ["measured", "simulated"])
def test_band_beyond_nyquist_names_the_run(which):
    m, s = resonance_run(1), resonance_run(2, fs=8000.0, run_id="S")
    if which == "measured":
        m, s = resonance_run(1, fs=8000.0), resonance_run(2, run_id="S")
    run = "'M'" if which == "measured" else "'S'"
    message = rf"4500.0 Hz is beyond the Nyquist frequency 4000.0 Hz of the {which} run {run}"
    with pytest.raises(ConfigError, match=message):
        score_runs(m, s, nperseg=1024, band=(100, 4500))


def test_different_units_are_named():
    with pytest.raises(UnitError, match=r"'m s-2' in the measured run 'M' but in 'g' in the simulated run 'S'"):
        score_runs(resonance_run(1), resonance_run(2, units="g", run_id="S"), nperseg=1024)


def test_missing_variable_is_named():
    s = resonance_run(2, run_id="S").drop_vars("acceleration")
    with pytest.raises(SchemaError, match=r"simulated run 'S' has no variable 'acceleration'; it has: friction_force"):
        score_runs(resonance_run(1), s, nperseg=1024)


def test_short_signal_names_the_run():
    with pytest.raises(DataQualityError, match=r"simulated run 'S'.* 500 samples .* nperseg = 1024"):
        score_runs(resonance_run(1), resonance_run(2, n=500, run_id="S"), nperseg=1024)


def test_nan_names_the_run_and_time():
    m = resonance_run(1)
    m["acceleration"][7000] = np.nan
    with pytest.raises(DataQualityError, match=r"measured run 'M'.*'acceleration' has 1 non-finite.*t = 0.7 s"):
        score_runs(m, resonance_run(2, run_id="S"), nperseg=1024)


def test_non_uniform_time_names_the_run():
    s = resonance_run(2, run_id="S")
    t = s["time"].values.copy()
    t[100:] += 0.5 / FS
    s = s.assign_coords(time=("time", t, {"units": "s"}))
    with pytest.raises(DataQualityError, match=r"simulated run 'S': non-uniform time: step 99"):
        score_runs(resonance_run(1), s, nperseg=1024)


def test_band_narrower_than_three_bins():
    with pytest.raises(ConfigError, match="fewer than 3 PSD bins"):
        score_runs(resonance_run(1), resonance_run(2, run_id="S"), nperseg=1024, band=(1000, 1010))


def test_significance_grows_with_record_length():
    # A true 0.5 dB level difference: with 2**13 samples (15 segments of 1024) the band-level threshold is
    # larger than 0.5 dB, with 2**19 samples (1023 segments) it is ~8x smaller (it scales as 1/sqrt(segments)).
    gain = 10 ** (0.5 / 20)
    short = score_runs(resonance_run(5, n=2**13), resonance_run(6, n=2**13, scale=gain, run_id="S"), nperseg=1024)
    long = score_runs(resonance_run(5, n=2**19), resonance_run(6, n=2**19, scale=gain, run_id="S"), nperseg=1024)
    assert not bool(short.level_diff_db_significant)
    assert bool(long.level_diff_db_significant)
    assert float(long.level_diff_db) == pytest.approx(0.5, abs=float(long.level_diff_db_threshold))
    ratio = float(short.level_diff_db_threshold) / float(long.level_diff_db_threshold)
    assert ratio == pytest.approx(np.sqrt(1023 / 15), rel=0.2)


def test_steady_option_crops_each_run():
    m = resonance_run(1, n=2**15)
    t = m["time"].values
    ramp = np.clip(t / 0.5, 0, 1) * np.clip((t[-1] - t) / 0.5, 0, 1)  # 0.5 s ramps, plateau 2.28 s
    m["velocity"] = ("time", 0.01 * ramp, {"units": "m s-1"})
    sc = score_runs(m, m, nperseg=1024, steady=True, band=(100, 4000))
    assert sc.attrs["steady_only"] == 1
    from fivid.signal import steady_sliding_window, welch_psd

    t0, t1 = steady_sliding_window(m)
    assert 0.45 < t0 < 0.5 and t[-1] - 0.5 < t1 < t[-1] - 0.45  # 5 % below the plateau: 0.475 s into each ramp
    crop = welch_psd(m["acceleration"].sel(time=slice(t0, t1)), nperseg=1024).sel(frequency=slice(100, 4000))
    np.testing.assert_array_equal(sc.psd_measured.values, crop.values)
    whole = welch_psd(m["acceleration"], nperseg=1024).sel(frequency=slice(100, 4000))
    assert not np.array_equal(sc.psd_measured.values, whole.values)
    no_encoder = resonance_run(2, run_id="S")
    with pytest.raises(DataQualityError, match=r"simulated run 'S'.*neither 'velocity' nor 'position'"):
        score_runs(m, no_encoder, nperseg=1024, steady=True)


def test_sensor_selection_survives_resampling():
    s = resonance_run(2, run_id="S")
    base = resonance_run(1, n=2**17, fs=2 * FS)["acceleration"].values
    t = np.arange(base.size) / (2 * FS)
    m = xr.Dataset({"acceleration": (("time", "sensor"), np.stack([base, 2 * base], axis=1), {"units": "m s-2"})},
                   coords={"time": ("time", t, {"units": "s"}), "sensor": ["a", "b"]},
                   attrs={"run_id": "M", "sample_rate": 2 * FS})
    with pytest.raises(ConfigError, match=r"sensors \['a', 'b'\]"):
        score_runs(m, s, nperseg=1024)
    a = score_runs(m, s, nperseg=1024, sensor="a", band=(100, 3000))
    b = score_runs(m, s, nperseg=1024, sensor="b", band=(100, 3000))
    assert a.attrs["resampled"].startswith("measured 20000 Hz")
    assert float(a.level_diff_db - b.level_diff_db) == pytest.approx(20 * np.log10(2), abs=1e-9)


def test_sensor_given_for_a_variable_without_sensors_is_named():
    # used to be ignored silently: a typo in --sensor scored the single channel without a word
    m, s = resonance_run(1, run_id="M"), resonance_run(2, run_id="S")
    with pytest.raises(ConfigError, match=r"sensor 'x' given, but 'acceleration' has no 'sensor' dimension"):
        score_runs(m, s, nperseg=1024, sensor="x")
