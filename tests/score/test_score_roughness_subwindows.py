"""Lv per sub-window (fivid.score.roughness.subwindow_levels) against closed forms.

Synthetic records (labelled synthetic; generators below): (1) ``_stepped``: each sub-window carries sinusoids
of whole cycles per sub-window, amplitude ``A_k`` in sub-window ``k`` -- its mean square is exactly
``sum A**2 / 2`` (and, with the periodic Hann taper, a line of whole cycles puts its power in three bins, so a
band's share is that of the lines inside it, to round-off); (2) stationary white Gaussian noise, whose window mean
square over ``N`` samples has relative variance ``2 / N`` (chi-square), the oracle of the standard error."""

import numpy as np
import pytest
import xarray as xr

from fivid.errors import ConfigError
from fivid.score.roughness import LV_BAND, subwindow_levels, vibration_level

FS = 2.0e6
SUB = 0.5e-3  # sub-window [s]: 1 000 samples, bins of 2 kHz


def _stepped(amplitudes, lines=((4, 1.0),), n_sensors=2, start=0.2e-3):
    """Synthetic back-face velocity: in sub-window ``k``, ``A_k * a_i * sin(2 pi c_i t / SUB + phase_i)`` summed
    over ``lines`` = ((c_i whole cycles per sub-window, a_i relative amplitude), ...), sensor ``s`` scaled by
    ``1 + s``, plus a constant offset per sensor; ``SUB`` per sub-window at ``FS``."""
    n = int(round(SUB * FS))
    t = start + np.arange(n * len(amplitudes)) / FS
    tau = np.arange(n) / FS
    rng = np.random.default_rng(3)
    v = np.concatenate([amp * sum(a * np.sin(2 * np.pi * c * tau / SUB + rng.uniform(0, 2 * np.pi))
                                  for c, a in lines) for amp in amplitudes])
    scale = 1.0 + np.arange(n_sensors)
    vs = np.outer(v, scale) + 1e-3 * np.arange(n_sensors)
    return xr.Dataset({"sensor_velocity": (("time", "sensor"), vs)}, coords={"time": t}), scale


def test_each_subwindow_reads_its_own_amplitude_and_their_mean_is_the_window_level():
    amps = np.array([1e-4, 1e-3, 3e-3, 2e-3])
    ds, scale = _stepped(amps)
    r = subwindow_levels(ds, SUB, start=0.2e-3)
    ms = amps ** 2 / 2 * np.mean(scale ** 2)
    assert r["count"] == 4
    np.testing.assert_allclose(r["level"], 10 * np.log10(ms / 1e-18), atol=1e-9)
    np.testing.assert_allclose(r["start"], 0.2e-3 + SUB * np.arange(4), atol=1e-12)
    assert r["level_of_mean"] == pytest.approx(10 * np.log10(ms.mean() / 1e-18), abs=1e-9)
    # whole cycles in every sub-window: the per-sub-window mean removal is the whole window's, so the mean of the
    # sub-windows' mean squares is seed 003's Lv of the whole window
    assert r["level_of_mean"] == pytest.approx(vibration_level(ds, start=0.2e-3)[0], abs=1e-9)
    se = 10 / np.log(10) * np.std(ms, ddof=1) / (2 * ms.mean())
    assert r["standard_error_db"] == pytest.approx(se, rel=1e-9)


def test_a_settled_record_has_equal_subwindows_and_zero_standard_error():
    ds, _ = _stepped([2e-3] * 5)
    r = subwindow_levels(ds, SUB, start=0.2e-3)
    assert np.ptp(r["level"]) < 1e-9
    assert r["standard_error_db"] < 1e-9


def test_the_band_level_per_subwindow_keeps_only_the_lines_inside_the_band():
    # per sub-window: a 8 kHz line (4 cycles) in 1-20 kHz and a 300 kHz line (150 cycles) of 10x the amplitude
    amps = np.array([1e-3, 4e-3, 2e-3])
    ds, scale = _stepped(amps, lines=((4, 1.0), (150, 10.0)))
    r = subwindow_levels(ds, SUB, band=LV_BAND, start=0.2e-3)
    np.testing.assert_allclose(r["level"], 10 * np.log10(amps ** 2 / 2 * np.mean(scale ** 2) / 1e-18), atol=1e-8)
    full = subwindow_levels(ds, SUB, start=0.2e-3)
    np.testing.assert_allclose(full["level"] - r["level"], 10 * np.log10(101.0), atol=1e-8)


def test_a_trailing_partial_subwindow_is_dropped():
    ds, _ = _stepped([1e-3, 2e-3, 3e-3])
    r = subwindow_levels(ds, 0.7e-3, start=0.2e-3)  # 1.5 ms: two sub-windows of 0.7 ms
    assert r["count"] == 2
    assert r["stop"][-1] == pytest.approx(0.2e-3 + 1.4e-3, abs=1e-12)


def test_standard_error_matches_the_chi_square_closed_form_on_white_noise():
    """Stationary white Gaussian noise (synthetic, seed 11), K sub-windows of n samples: the window level's
    standard deviation over M realisations is (10 / ln 10) sqrt(2 / (K (n - 1))) (chi-square with K (n - 1)
    degrees of freedom, each sub-window's mean removed), to the sampling error of an SD over M realisations; the
    estimate's mean is that times c4(K) (the sample SD's bias), to its own sampling error over M."""
    k, n, m = 8, 250, 300
    rng = np.random.default_rng(11)
    t = np.arange(k * n) / FS
    lv, se = np.empty(m), np.empty(m)
    for i in range(m):
        ds = xr.Dataset({"sensor_velocity": (("time",), 1e-3 * rng.standard_normal(k * n))}, coords={"time": t})
        r = subwindow_levels(ds, n / FS, start=0.0)
        lv[i], se[i] = r["level_of_mean"], r["standard_error_db"]
    closed = 10 / np.log(10) * np.sqrt(2 / (k * (n - 1)))
    assert np.std(lv, ddof=1) == pytest.approx(closed, rel=4 / np.sqrt(2 * (m - 1)))
    from math import exp, lgamma, sqrt
    c4 = sqrt(2 / (k - 1)) * exp(lgamma(k / 2) - lgamma((k - 1) / 2))
    sd_of_se = closed * sqrt(1 - c4 ** 2)
    assert np.mean(se) == pytest.approx(c4 * closed, abs=4 * sd_of_se / np.sqrt(m))


def test_a_subwindow_longer_than_the_record_or_too_short_for_the_band_is_refused():
    ds, _ = _stepped([1e-3, 1e-3])
    with pytest.raises(ConfigError, match="sub-window length"):
        subwindow_levels(ds, 2e-3, start=0.2e-3)
    with pytest.raises(ConfigError, match="sub-window length"):
        subwindow_levels(ds, 0.0, start=0.2e-3)
    with pytest.raises(ConfigError, match="1/\\(2T\\)"):
        subwindow_levels(ds, 0.25e-3, band=LV_BAND, start=0.2e-3)


def _cosine_profile(amplitude, wavelength, step, length=2e-3, phase=0.0):
    """Synthetic profile ``A cos(2 pi x / lambda + phase)`` sampled every ``step`` [m] (generator of the test
    below): its tips are its crests, of curvature ``A k^2`` exactly."""
    x = np.arange(0.0, length, step)
    return xr.DataArray(amplitude * np.cos(2 * np.pi * x / wavelength + phase), coords={"x": x}, dims="x")


def test_tip_following_speed_is_the_closed_form_of_two_cosine_profiles():
    """Two cosines (synthetic): crest curvatures A1 k1^2 + A2 k2^2, so V* = sqrt((F / m) / kappa); the central
    second difference reads A k^2 * 2 (1 - cos(k h)) / (k h)^2, within (k h)^2 / 12 of it."""
    from fivid.score.roughness import tip_following_speed
    a1, l1, a2, l2, h = 20e-6, 400e-6, 10e-6, 250e-6, 400e-6 / 24
    lower = _cosine_profile(a1, l1, h)
    upper = _cosine_profile(a2, l2, h, phase=0.3)
    r = tip_following_speed(lower, upper, 1.0, 0.0749)
    k1, k2 = 2 * np.pi / l1, 2 * np.pi / l2
    assert r["tip_curvature"][0] == pytest.approx(a1 * k1 ** 2, rel=(k1 * h) ** 2 / 12)
    # the phase-shifted cosine's sampled crests sit up to h / 2 off its true crest: cos(k h / 2) more
    assert r["tip_curvature"][1] == pytest.approx(a2 * k2 ** 2, rel=(k2 * h) ** 2 / 12 + (k2 * h) ** 2 / 8)
    assert r["rms_curvature"][0] == pytest.approx(a1 * k1 ** 2 / np.sqrt(2), rel=(k1 * h) ** 2 / 12 + 0.02)
    kappa = a1 * k1 ** 2 + a2 * k2 ** 2
    assert r["load_acceleration"] == pytest.approx(1.0 / 0.0749, rel=1e-12)
    assert r["following_speed"] == pytest.approx(np.sqrt(1.0 / 0.0749 / kappa), rel=(k2 * h) ** 2 / 8)
    with pytest.raises(ConfigError, match="tip_quantile"):
        tip_following_speed(lower, upper, 1.0, 0.0749, tip_quantile=1.0)
