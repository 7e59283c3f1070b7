"""Steady-sliding window on synthetic rig runs with a known velocity profile (tests/helpers/steady_runs.py)."""

import numpy as np
import pytest
import xarray as xr

from fivid.errors import ConfigError, DataQualityError
from fivid.signal import steady_sliding_window
from tests.helpers.steady_runs import steady_sliding_run


@pytest.mark.parametrize("smoothing", [0.005, 0.02])
def test_window_of_a_trapezoid_profile(smoothing):
    # Within tolerance 5 %: v >= 0.95 v0 from t = 0.95 ramp = 0.19 s to duration - 0.19 = 1.81 s. A centred moving
    # average of width h equals a piecewise-linear profile except within h/2 of a kink, so each end moves by at
    # most h/2 (plus one sample).
    ds = steady_sliding_run()
    t0, t1 = steady_sliding_window(ds, tolerance=0.05, smoothing=smoothing)
    slack = smoothing / 2 + 1 / 5000.0
    assert abs(t0 - 0.19) <= slack
    assert abs(t1 - 1.81) <= slack


def test_window_from_quantised_position():
    # 1 um encoder at 10 mm/s: differentiated position has quantisation noise ~ 1e-6 m / (2 dt) per sample; a
    # 20 ms average brings it to ~ 1e-6 / 0.02 = 5e-5 m/s = 0.5 % of v0, below the 5 % tolerance.
    ds = steady_sliding_run(kind="position", encoder=1e-6)
    t0, t1 = steady_sliding_window(ds, tolerance=0.05, smoothing=0.02)
    # slack: h/2, plus the velocity error 1e-6 m / h divided by the ramp's slope v0 / ramp = 0.05 m s-2 (1 ms)
    slack = 0.02 / 2 + (1e-6 / 0.02) / (0.01 / 0.2)
    assert abs(t0 - 0.19) <= slack and abs(t1 - 1.81) <= slack


def test_noisy_velocity_is_smoothed():
    ds = steady_sliding_run(noise=0.002, seed=3)  # 20 % noise per sample, averaged over 250 samples -> 1.3 %
    t0, t1 = steady_sliding_window(ds, tolerance=0.05, smoothing=0.05)
    assert abs(t0 - 0.19) < 0.05 and abs(t1 - 1.81) < 0.05


def test_no_plateau_is_a_clear_error():
    ds = steady_sliding_run(ramp=1.0)  # a triangle: never steady
    with pytest.raises(DataQualityError, match=r"run 'SYN1'.*no steady sliding.*plateau"):
        steady_sliding_window(ds, tolerance=0.02, smoothing=0.01)


@pytest.mark.parametrize("smoothing", [-0.01, float("nan")])
def test_bad_smoothing_is_named(smoothing):
    # negative smoothing used to be silently replaced by one sample; NaN crashed in int(round(nan))
    with pytest.raises(ConfigError, match="smoothing must be a duration >= 0"):
        steady_sliding_window(steady_sliding_run(), smoothing=smoothing)


def test_standstill_is_a_clear_error():
    ds = steady_sliding_run(v=0.0)
    with pytest.raises(DataQualityError, match=r"run 'SYN1'.*plateau .* is 0.0"):
        steady_sliding_window(ds)


def test_missing_encoder_is_named():
    ds = steady_sliding_run().rename({"velocity": "acceleration"})
    with pytest.raises(DataQualityError, match="neither 'velocity' nor 'position'.*acceleration"):
        steady_sliding_window(ds)


def test_nan_in_velocity_is_named():
    ds = steady_sliding_run()
    ds["velocity"][100] = np.nan
    with pytest.raises(DataQualityError, match=r"'velocity' has 1 non-finite.*index 100"):
        steady_sliding_window(ds)
