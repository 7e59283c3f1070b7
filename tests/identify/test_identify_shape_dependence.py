"""Does the spectrum's shape depend on the condition? (issue 16 item 4; SYNTHETIC runs)

Runs synthesised from a convected law (a spatial field frozen on the surface: the temporal spectrum's
corner moves with V) and identified as uniform: the shape test (F-tests on the log-frequency centroid
and spread, Bonferroni) must find the dependence, the law file stores a shape per condition and the law
interpolates between them. From a law whose shape does not change it finds none (p >= 0.01, a 1 %
false-alarm rate by construction).
"""

import numpy as np
import pytest
from tests.helpers.synthetic_friction_runs import ANALYSIS_BAND, band_fraction, run_grid, twin_law

from fivid.friction import load_law
from fivid.identify import identify_friction_law
from fivid.identify.shape import shape_dependence

GRID = dict(velocities=(0.0025, 0.005, 0.01, 0.02), roughnesses=(0.5e-6, 2e-6), duration=2.4)


@pytest.fixture(scope="module")
def convected():
    law = twin_law("convected")
    runs = run_grid(law, seed=17, **GRID)
    return law, identify_friction_law(runs, band=ANALYSIS_BAND, tare=(0.0, 0.5), nperseg=2048)


def test_velocity_dependent_shape_is_found_and_stored(convected, tmp_path):
    law, res = convected
    test = res.shape_test
    assert test["depends"] and test["p_value"] < 0.01, test
    assert any("spectral shape depends" in m for m in res.messages)
    points, shapes = res.law.condition_shapes
    assert points.shape == (8, 3) and shapes.shape == (8, res.law.shape_frequency.size)
    np.testing.assert_allclose(np.trapezoid(shapes, res.law.shape_frequency, axis=1), 1.0, rtol=1e-9)
    # at an identified condition the law's shape is the true one (smoothed estimate: 15 % where s is large)
    f = np.array([500.0, 1000.0, 1500.0])
    for v in (0.005, 0.02):
        truth = law.normalised_shape(f, v) / band_fraction(law, velocity=v)
        np.testing.assert_allclose(res.law.normalised_shape(f, v, 2e-6, 5.0), truth, rtol=0.15)
    # between conditions the shape lies between its neighbours' (interpolation in ln V)
    lo, mid, hi = (res.law.normalised_shape(np.array([2000.0]), v, 1e-6, 5.0)[0] for v in (0.005, 0.0075, 0.01))
    assert lo < mid < hi
    path = res.write(tmp_path / "law.nc")
    back = load_law(path)
    assert back.sha256 == res.law.sha256
    np.testing.assert_array_equal(back.condition_shapes[1], shapes)


def test_constant_shape_is_not_split(convected):
    law = twin_law()
    res = identify_friction_law(run_grid(law, seed=18, **GRID), band=ANALYSIS_BAND, tare=(0.0, 0.5), nperseg=2048)
    assert res.shape_test["depends"] is False and res.shape_test["p_value"] >= 0.01
    assert res.law.condition_shapes is None
    # the same runs' statistics, tested directly, say the same
    out, shapes = shape_dependence(res.used_runs, res.band)
    assert out["p_value"] == pytest.approx(res.shape_test["p_value"]) and shapes is None


def test_too_few_runs_are_not_tested(convected):
    _, res = convected
    out, shapes = shape_dependence(res.used_runs[:3], res.band)  # one variable (V), 3 runs
    assert out["depends"] is None and "not tested" in out["reason"] and shapes is None
