"""The identification's defaults do not bias the amplitude A (SYNTHETIC runs and the SYNTHETIC twin data).

At 51.2 kHz and a ~0.4 s steady window the former default Welch segment (1024 samples, 50 Hz bins) made
every bin "near a mains harmonic": broadband power next to a steep spectral feature was taken for hum and
interpolated away, and A came out 4–13 % low on the twin data. The default now resolves the lines
(bins <= mains/4, :func:`fivid.signal.welch.default_nperseg`).
"""

import glob
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats
from tests.helpers.synthetic_friction_runs import band_amplitude, edge_law, synthetic_run

from fivid.identify import identify_friction_law
from fivid.identify.runs import DEFAULT_BAND_HIGH, DEFAULT_BAND_LOW, mains_lines_resolved
from fivid.signal.welch import default_nperseg

FS = 51200.0  # [Hz] the twin's DAQ rate
GRID = [(v, ra) for ra in (0.4e-6, 1.6e-6) for v in (0.005, 0.01, 0.02)]


def test_default_segment_resolves_mains_within_the_record():
    # 0.4 s at 51.2 kHz: the averages rule alone gives 1024 (50 Hz bins); mains/4 needs 4096 (12.5 Hz)
    assert default_nperseg(FS, 20000) == 1024
    assert default_nperseg(FS, 20000, 50.0) == 4096 and mains_lines_resolved(FS / 4096, 50.0)
    assert default_nperseg(FS, 20000, 60.0) == 4096 and mains_lines_resolved(FS / 4096, 60.0)  # 12.5 <= 15
    # too short for 12.5 Hz bins with >= 7 segments: the averages rule stands, lines are left in
    assert default_nperseg(FS, 10000, 50.0) == 2048 and not mains_lines_resolved(FS / 2048, 50.0)
    # long records already had fine bins: unchanged
    assert default_nperseg(25600.0, 60000, 50.0) == default_nperseg(25600.0, 60000) == 2048


def _edge_runs(hum, offsets):
    law = edge_law()
    return law, [synthetic_run(law, velocity=v, roughness=ra, normal_load=5.0, seed=4100 + i, run_id=f"E{i}", fs=FS,
                               duration=0.8, unloaded=0.05, hum=hum, mains=50.02, offsets=offsets)
                 for i, (v, ra) in enumerate(GRID)]


@pytest.mark.parametrize("hum, offsets, tare", [
    ((2e-3, 1e-3), (0.02, -0.05), (0.0, 0.04)),  # weak hum (not a line at this A), offsets and a tare
    ((0.02, 0.01), (0.0, 0.0), None),  # strong hum: lines removed (without: A up to 40 % high)
], ids=["weak-hum-tare", "strong-hum"])
def test_default_identification_recovers_a(hum, offsets, tare):
    law, runs = _edge_runs(hum, offsets)
    res = identify_friction_law(runs, tare=tare)  # the band, nperseg and mains removal at their defaults
    band = (DEFAULT_BAND_LOW, DEFAULT_BAND_HIGH)
    assert res.band == band and res.settings["welch"]["frequency_resolution"] <= 50.0 / 4
    used = res.used_runs
    assert len(used) == len(GRID) and all(r.mains_removal == "on" for r in used)
    if hum[0] > 0.01:
        assert all(r.mains_bins_removed >= 5 for r in used)  # at least the fundamental's main lobe
    truth = np.array([band_amplitude(law, r.sliding_velocity, r.roughness_ra, r.normal_load, band) for r in used])
    a = np.array([r.mu_rms for r in used])
    se = np.array([r.mu_rms_stderr for r in used])
    z = (a - truth) / se
    print("A / A_true:", np.round(a / truth, 4), "z:", np.round(z, 2))
    # Each run's A is a band power estimate, ~normal with its se (Bendat & Piersol §8.2): two-sided 99.9 %,
    # Bonferroni over the 6 runs -> |z| < 3.76. A bias shows in the mean z: for independent runs it has
    # sd 1/sqrt(6); two-sided 99.9 % -> |mean z| < 3.29/sqrt(6) = 1.34. The old default (50 Hz bins) gave
    # mean z -3.9 with the weak hum (broadband taken for lines) and +3.6 with the strong hum (the lines,
    # not resolved from the broadband, were not found; A up to 40 % high).
    assert np.all(np.abs(z) < stats.norm.ppf(1 - 0.001 / (2 * len(z))))
    assert abs(z.mean()) < stats.norm.ppf(0.9995) / np.sqrt(len(z))


def _twin_truth(root):
    sys.path.insert(0, str(root / "sample_data"))
    try:
        import generate
    finally:
        sys.path.pop(0)
    return generate.load_truth(root / "sample_data" / "ground_truth.yaml"), generate


def test_twin_data_at_defaults_inside_the_pipeline_intervals(root, tmp_path):
    """``fivid identify`` with defaults on the ingested twin: the truth inside the law's 95 % intervals.

    The same comparison as the pipeline's slow test (tests/pipeline/test_pipeline_sample.py), at the defaults
    (band 20 Hz–2 kHz, no tare): the true band RMS over the part of the band where the truth has power
    (it has none below 100 Hz).
    """
    from fivid.io import read_rig_csv
    from fivid.report import amplitude_interval

    truth, generate = _twin_truth(Path(root))
    runs = [read_rig_csv(p) for p in sorted(glob.glob(str(Path(root) / "sample_data" / "twin" / "*.csv")))]
    res = identify_friction_law(runs, categorical=True)
    # the generating form (one line per roughness level) is asked for and its intervals checked: the
    # question here is the bias of A at the defaults. At 6 runs AICc does not support it (n - k - 1 = 0:
    # no AICc) nor any 3-coefficient law (correction +40): the chosen form is the constant, whose
    # cross-validation error says how poor a predictor it is (see docs/identification.md).
    lines = next(f for f in res.form_fits if f.form == "linear_velocity")
    true_law = generate.truth_law(truth)
    fc, (t1, t2) = truth["corner"], truth["band"]
    b1, b2 = max(res.band[0], t1), min(res.band[1], t2)
    in_band = np.sqrt((np.arctan(b2 / fc) - np.arctan(b1 / fc)) / (np.arctan(t2 / fc) - np.arctan(t1 / fc)))
    ratios = []
    for run in generate.conditions(truth):
        v, ra = np.array([run["sliding_velocity"]]), np.array([run["roughness_ra"]])
        a_true = float(true_law.amplitude(v, ra)[0]) * in_band
        a, lo, hi = (float(x[0]) for x in amplitude_interval(lines.model, v, ra,
                                                             np.array([truth["normal_load"]])))
        ratios.append(a / a_true)
        assert lo <= a_true <= hi, (run["run_id"], a_true, a, lo, hi)
    print("twin at defaults, A / A_true:", np.round(ratios, 4), "chosen form", res.law.amplitude_model.form)
    # without a tare mu0 carries the sensor offsets (0.012 N, -0.02 N at 5 N: +0.0036); the result says so
    # and suggests a tare inside the 20 ms unloaded pre-trigger
    hint = [m for m in res.messages if m.startswith("no tare given")]
    assert len(hint) == 1 and "tare=(0, 0.0151) s" in hint[0] and "up to 0.0036" in hint[0], res.messages
    assert not any(m.startswith("no tare") for m in identify_friction_law(runs, tare=(0.0, 0.015)).messages)

    # the engineer's command, `fivid identify *.nc -o law.nc`, gives the same law and records its settings
    import xarray as xr

    from fivid.cli import main
    from fivid.io import write_run

    paths = [str(write_run(ds, tmp_path / f"{ds.attrs['run_id']}.nc")) for ds in runs]
    assert main(["identify", *paths, "-o", str(tmp_path / "law.nc")]) == 0
    with xr.open_dataset(tmp_path / "law.nc") as law:
        np.testing.assert_array_equal(law["run_mu_rms"].values, [r.mu_rms for r in res.runs])
        assert list(law["run_nperseg"].values) == [4096] * len(runs)
        assert list(law["run_mains_removal"].values) == ["on"] * len(runs)
        assert law.attrs["setting_welch_frequency_resolution"] == 12.5 and law.attrs["setting_nperseg"] == "auto"
        assert law.attrs["setting_nperseg_rule"].startswith("largest power of two")


@pytest.mark.parametrize("tare, match", [
    ((0.0, 0.5), "overlaps the steady-sliding window"),  # reaches into the loaded, sliding part
    ((0.0, 5.0), "inside the record"),  # runs past the end of the record
    ((0.03, 0.01), "increasing interval"),
])
def test_tare_must_be_an_unloaded_interval_of_the_record(tare, match):
    """A tare that holds the load (or lies outside the record) is refused with the run and the allowed range named,
    not applied: subtracting the loaded forces would leave "contact lost" runs and no error (docs helper, issue 20)."""
    from fivid.errors import FividError

    _, runs = _edge_runs((0.0, 0.0), (0.0, 0.0))
    with pytest.raises(FividError, match=match) as err:
        identify_friction_law(runs[:2], tare=tare)
    assert "run 'E0'" in str(err.value)


def test_glitch_repair_is_for_measured_runs_only():
    """A spike in the force channel is repaired in a measured run and kept in a simulated one (attribute
    transient_end: no DAQ; a rough contact's asperity impacts are physics), unless asked for."""
    from fivid.identify.runs import RunAnalysisSettings, analyse_run

    _, runs = _edge_runs((0.0, 0.0), (0.0, 0.0))
    ds = runs[0].copy(deep=True)
    ds["friction_force"].values[30000] += 50.0  # a 50 N spike on a ~1.5 N signal
    band = (DEFAULT_BAND_LOW, DEFAULT_BAND_HIGH)
    measured = analyse_run(ds, RunAnalysisSettings(), band=band)
    sim = ds.assign_attrs(transient_end=0.05)
    simulated = analyse_run(sim, RunAnalysisSettings(), band=band)
    forced = analyse_run(sim, RunAnalysisSettings(glitch_repair=True), band=band)
    assert measured.glitches_replaced >= 1 and forced.glitches_replaced == measured.glitches_replaced
    assert simulated.glitches_replaced == 0 and simulated.mu_rms > measured.mu_rms
