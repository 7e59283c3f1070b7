"""Transient analysis helpers (fivid.signal.transient) on signals with known answers."""

import numpy as np
import pytest

from fivid.errors import DataQualityError
from fivid.signal.transient import (dominant_frequency_track, envelope_growth_rate, growth_phase,
                                    narrowband_fraction)


@pytest.mark.parametrize("rate", [-300.0, 30.0])
def test_growth_rate_of_an_exponential_sine(rate):
    """exp(rate t) sin(2 pi f t): the band-passed Hilbert envelope is exactly exp(rate t) away from the ends;
    the default edge 10/B leaves the filter transients' error below 1e-3 relative (see the docstring)."""
    t = np.arange(40000) / 1e5
    x = np.exp(rate * t) * np.sin(2 * np.pi * 2e3 * t + 0.3)
    window = (0.004, 0.02) if rate < 0 else None
    fit = envelope_growth_rate(t, x, band=(1e3, 4e3), window=window)
    assert fit.rate == pytest.approx(rate, rel=2e-3)


def test_growth_phase_is_the_last_factor_before_saturation():
    """A logistic envelope: exponential at rate s early, saturating at 1; the phase ends at 30 % of the peak and
    starts a factor 30 lower, where the envelope is still exponential."""
    t = np.linspace(0, 1, 10001)
    s, t_half = 40.0, 0.6
    env = 1.0 / (1.0 + np.exp(-s * (t - t_half)))
    t0, t1 = growth_phase(t, env)
    assert env[np.searchsorted(t, t1)] == pytest.approx(0.3, abs=2e-3)
    assert env[np.searchsorted(t, t0)] == pytest.approx(0.01, abs=5e-4)
    assert growth_phase(t, np.exp(-5 * t)) is None  # decays: no growth phase
    assert growth_phase(t, env, linear_until=0.5)[1] == pytest.approx(0.5, abs=1e-4)


def test_dominant_frequency_follows_a_linear_chirp():
    """f(t) = f0 + k t: each segment's strongest bin is within one bin (fs/nperseg) of the chirp at its centre."""
    fs, f0, k = 50e3, 1e3, 2e4
    t = np.arange(int(0.5 * fs)) / fs
    x = np.sin(2 * np.pi * (f0 * t + 0.5 * k * t**2))
    tt, f, p = dominant_frequency_track(x, fs, nperseg=1024)
    assert np.abs(f - (f0 + k * tt)).max() <= fs / 1024
    with pytest.raises(DataQualityError):
        dominant_frequency_track(x[:100], fs, nperseg=1024)


def test_narrowband_fraction_of_a_tone_in_white_noise():
    """Tone of power A^2/2 in white noise of variance s^2: the tone's bins hold A^2/2 plus the noise in 7 bins
    (7 fs/N of s^2 over fs/2), so the fraction is (A^2/2 + 7 (2 s^2/N)) / (A^2/2 + s^2) within the Welch
    estimate's scatter (a few per cent of the noise part)."""
    from scipy.signal import welch

    rng = np.random.default_rng(1)
    fs, n = 10e3, 200_000
    t = np.arange(n) / fs
    A, s = 1.0, 1.0
    x = A * np.sin(2 * np.pi * 1234.0 * t) + s * rng.standard_normal(n)
    f, p = welch(x, fs=fs, nperseg=1024)
    expected = (A**2 / 2 + 7 * 2 * s**2 / 1024) / (A**2 / 2 + s**2)
    assert narrowband_fraction(f, p) == pytest.approx(expected, rel=0.02)
    assert narrowband_fraction(f, np.ones_like(f)) == 0.0  # flat: no peak
