"""The real-data path (issue 16 item 6): SYNTHETIC runs carrying what measured records carry — thermal drift
of the force sensors, a 50 Hz mains line with harmonics, DAQ glitches (spikes of 2-10 N, dropouts to 0 N) —
still identify the law; glitches are replaced and counted per run, influential runs are reported by Cook's
distance (threshold 4/n), none silently dropped.
"""

import numpy as np
import pytest
from tests.helpers.synthetic_friction_runs import ANALYSIS_BAND, TWIN_MU0, band_amplitude, run_grid, synthetic_run, twin_law

from fivid.friction import predict_amplitude
from fivid.identify import identify_friction_law
from fivid.identify.glitches import glitch_mask

GRID = dict(velocities=(0.0025, 0.005, 0.01, 0.02), roughnesses=(0.5e-6, 2e-6), duration=2.4)
Z = 3.29  # two-sided 99.9 % normal quantile


@pytest.fixture(scope="module")
def measured_style():
    law = twin_law()
    dirty = run_grid(law, seed=19, drift=0.004, glitches=6, mains=50.0, **GRID)
    res = identify_friction_law(dirty, band=ANALYSIS_BAND, tare=(0.0, 0.5), nperseg=2048)
    return law, res


def test_identification_keeps_working(measured_style):
    law, res = measured_style
    assert all(r.used for r in res.runs), [r.reason for r in res.runs]  # dropouts are not lost contact
    assert all(r.glitches_replaced >= 6 for r in res.runs)  # each spike takes 3 samples, each dropout 1-3 + edges
    assert sum(m.count("replaced as DAQ glitches") for m in res.messages) == len(res.runs)
    assert abs(res.mu0 / TWIN_MU0 - 1) < 0.01  # the drift after the tare biases mu0 by ~0.4 % here
    pred = predict_amplitude(res.law.amplitude_model, 0.0075, 1e-6, 5.0, domain=res.domain)
    truth = band_amplitude(law, 0.0075, 1e-6, 5.0)
    print("measured-style: mu0", res.mu0, "A(7.5 mm/s, 1 um) / truth", pred.amplitude[0] / truth,
          "form", res.law.amplitude_model.form)
    assert abs(pred.amplitude[0] / truth - 1) < 0.15
    assert res.law.amplitude_model.form in ("power_law", "linear_velocity_power_law")


def test_outliers_reported_per_run_not_dropped(measured_style):
    _, res = measured_style
    report = res.to_json()
    n = len(res.used_runs)
    rows = [r for r in report["runs"] if r["used"]]
    assert len(rows) == n and all("cooks_distance" in r for r in rows)
    flagged = [r["run_id"] for r in rows if r["cooks_distance"] > 4 / n]
    assert report["outliers"]["influential"] == flagged
    assert "4/n" in report["outliers"]["rule"]
    assert all(any(f"run {k} is influential" in m for m in res.messages) for k in flagged)
    ds = res.to_dataset()
    np.testing.assert_allclose(ds["run_cooks_distance"].values, [r["cooks_distance"] for r in rows])
    assert ds["run_glitches_replaced"].values.tolist() == [r.glitches_replaced for r in res.runs]


def test_glitches_do_not_change_the_amplitude():
    """The same record with and without glitches: A agrees within the estimator's own error (the replaced
    samples are 0.05 % of the record); without the replacement one spike alone makes A several times larger."""
    law = twin_law()
    kw = dict(velocity=0.005, roughness=0.5e-6, normal_load=5.0, seed=21, duration=2.4)
    clean = identify_friction_law([synthetic_run(law, **kw)], band=ANALYSIS_BAND, tare=(0.0, 0.5), nperseg=2048)
    dirty_ds = synthetic_run(law, glitches=9, **kw)
    dirty = identify_friction_law([dirty_ds], band=ANALYSIS_BAND, tare=(0.0, 0.5), nperseg=2048)
    a0, a1 = clean.runs[0], dirty.runs[0]
    assert abs(a1.mu_rms - a0.mu_rms) < Z * a0.mu_rms_stderr, (a0.mu_rms, a1.mu_rms, a0.mu_rms_stderr)
    # every injected spike is found (|spike| >= 2 N against a ~mN residual scale)
    ft, fn = (dirty_ds[c].values - synthetic_run(law, **kw)[c].values for c in ("friction_force", "normal_force"))
    injected = (np.abs(ft) > 1.0) | (np.abs(fn) > 1.0)
    found = glitch_mask(dirty_ds["friction_force"].values) | glitch_mask(dirty_ds["normal_force"].values)
    assert np.all(found[injected])


def test_glitch_free_gaussian_noise_raises_few_false_alarms():
    """White Gaussian noise of 61 440 samples: the Bonferroni threshold makes a false alarm in a record
    a ~1 % event; over 20 records at most 2 (binomial(20, 0.01): P(>2) ~ 1e-3)."""
    rng = np.random.default_rng(3)
    alarms = sum(glitch_mask(rng.standard_normal(61440)).any() for _ in range(20))
    assert alarms <= 2
