"""The one spectral home (issue 29 item 1): the array-level Welch estimator against scipy's, the comparison
measures against closed forms, and peak tracking through a refinement series.

Oracles: scipy.signal.welch with identical settings (agreement to float round-off: the sums differ in order
only, so a few ulp of the largest bin); a PSD scaled by c has LSD |10 log10 c| and level difference 10 log10 c
exactly; Gaussian peaks (parabolas in dB) come back at their centres.
"""

import numpy as np
import pytest
from scipy.signal import welch

from fivid.signal.compare import band_distance, band_levels_db, log_spectral_distance
from fivid.signal.levels import bin_weights
from fivid.signal.peaks import track_peaks
from fivid.signal.spectral import welch_density

EPS = np.finfo(float).eps


@pytest.mark.parametrize("detrend, window, noverlap", [("constant", "hann", None), ("linear", "hamming", 100),
                                                       ("none", ("tukey", 0.25), 0)])
def test_the_array_and_the_dataarray_welch_agree(detrend, window, noverlap):
    """welch_density (scipy's estimator, plain arrays) and welch_psd (fivid's engine, DataArrays) are one
    spectrum: equal to float round-off (the sums run in another order: ~log2(k) eps per bin)."""
    import xarray as xr

    from fivid.signal import welch_psd

    x = np.random.default_rng(3).standard_normal(10_000).cumsum()  # synthetic: a random walk (red spectrum)
    f, p = welch_density(x, 2000.0, nperseg=512, noverlap=noverlap, window=window, detrend=detrend)
    fr, pr = welch(x, fs=2000.0, window=window, nperseg=512, noverlap=512 // 2 if noverlap is None else noverlap,
                   detrend=False if detrend == "none" else detrend, scaling="density")
    np.testing.assert_array_equal(f, fr)
    np.testing.assert_array_equal(p, pr)
    t = np.arange(x.size) / 2000.0
    da = xr.DataArray(x, dims="time", coords={"time": t}, name="y", attrs={"units": "m"})
    q = welch_psd(da, nperseg=512, noverlap=noverlap, window=window, detrend=detrend)
    np.testing.assert_allclose(q["frequency"].values, f, rtol=4 * EPS)
    np.testing.assert_allclose(q.values, p, rtol=64 * EPS, atol=64 * EPS * p.max())


def test_distance_of_a_scaled_spectrum_is_its_scale():
    f = np.arange(0.0, 5000.0, 12.5)
    p_ref = 1e-3 / (1.0 + (f / 800.0) ** 2)
    lsd, level = band_distance(f, p_ref, 2.0 * p_ref, (100.0, 3000.0))
    assert lsd == pytest.approx(10 * np.log10(2.0), rel=1e-13) and level == pytest.approx(10 * np.log10(2.0), rel=1e-13)
    assert np.isnan(band_distance(f, p_ref, p_ref, (5001.0, 6000.0))).all()  # no bin in the band
    assert log_spectral_distance(p_ref, p_ref / 10.0) == pytest.approx(10.0, rel=1e-13)


def test_band_level_of_a_white_spectrum_counts_each_bin_rectangle_once():
    """Adjacent bands add up to the whole: the band powers of a split band sum to the band's power."""
    f = np.arange(0.0, 1000.0, 10.0)
    p = np.full(f.size, 3.0)
    whole = band_levels_db(p, bin_weights(f, 100.0, 900.0))
    parts = band_levels_db(p, np.column_stack([bin_weights(f, 100.0, 333.3), bin_weights(f, 333.3, 900.0)]))
    assert 10 * np.log10(np.sum(10 ** (parts / 10))) == pytest.approx(whole, abs=1e-12)
    assert whole == pytest.approx(10 * np.log10(3.0 * 800.0), abs=1e-12)


def test_peaks_are_tracked_through_a_series_and_a_lost_one_is_dropped():
    f = np.arange(0.0, 5000.0, 25.0)

    def psd(centres):
        return 1e-8 + sum(np.exp(-0.5 * ((f - c) / 40.0) ** 2) for c in centres)

    series = [psd([1000.0, 3000.0]), psd([1010.0, 3050.0]), psd([1040.0])]  # finest first; 3 kHz lost last
    (track,) = track_peaks(f, series, 0, prominence_db=20.0, match_prominence_db=6.0, window=0.1)
    assert track[0] == pytest.approx(1000.0, abs=1e-6)
    np.testing.assert_allclose(track[1], [1000.0, 1010.0, 1040.0], atol=1e-6)
