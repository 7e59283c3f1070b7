"""Welch PSD: equality with scipy.signal.welch/csd, Parseval, white-noise level and variance, a sine's
power, χ² bounds, both FFT backends, and the bad inputs of issue 3.

All signals are synthetic (numpy Generator with the seed given in each test)."""

import numpy as np
import pytest
import scipy.signal
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from fivid.errors import ConfigError, DataQualityError, UnitError
from fivid.signal import csd, power_units, welch_psd
from fivid.signal.spectral import SpectralSettings, averaged_spectra, equivalent_degrees_of_freedom
from fivid.verify import evaluate_case, select_cases
from fivid.verify.cases.signal_welch import EPS, roundoff_atol
from fivid.verify.cases.signal_welch import time_signal as signal

BACKENDS = ["pyfftw", "numpy"]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(
    "nperseg, noverlap, window, detrend",
    [(1024, 512, "hann", "constant"), (1000, 250, "hamming", "linear"), (777, 0, ("tukey", 0.25), False),
     (4096, 3072, "blackman", "constant")],
)
def test_equals_scipy_welch(backend, nperseg, noverlap, window, detrend):
    rng = np.random.default_rng(1)
    fs = 51200.0
    x = np.cumsum(rng.standard_normal(200_003)) * 1e-3 + 0.3  # red noise with an offset: detrending matters
    p = welch_psd(signal(x, fs), nperseg=nperseg, noverlap=noverlap, window=window, detrend=detrend, backend=backend)
    f_ref, p_ref = scipy.signal.welch(x, fs=fs, window=window, nperseg=nperseg, noverlap=noverlap,
                                      detrend=detrend, scaling="density", average="mean")
    np.testing.assert_allclose(p["frequency"].values, f_ref, rtol=4 * EPS)
    np.testing.assert_allclose(p.values, p_ref, rtol=0, atol=roundoff_atol(p_ref, nperseg))
    assert p.attrs["units"] == "m2 s-4 Hz-1"
    assert p.attrs["n_segments"] == (x.size - noverlap) // (nperseg - noverlap)
    for key in ("window", "nperseg", "noverlap", "detrend", "scaling", "equivalent_averages", "sample_rate"):
        assert key in p.attrs


@pytest.mark.parametrize("backend", BACKENDS)
def test_csd_equals_scipy_csd(backend):
    rng = np.random.default_rng(2)
    fs = 1000.0
    x = rng.standard_normal(50_000)
    y = np.convolve(x, [0.5, -0.3, 0.2], mode="same") + 0.1 * rng.standard_normal(x.size)
    out = csd(signal(x, fs, "normal_force", "N"), signal(y, fs), nperseg=500, noverlap=200, detrend="linear",
              backend=backend)
    _, ref = scipy.signal.csd(x, y, fs=fs, nperseg=500, noverlap=200, detrend="linear", window="hann")
    np.testing.assert_allclose(out["pxy"].values, ref, rtol=0, atol=roundoff_atol(np.abs(ref), 500))
    assert out["pxy"].attrs["units"] == "N m s-2 Hz-1"


def test_backends_agree_to_roundoff():
    rng = np.random.default_rng(3)
    x = rng.standard_normal(300_000)
    a, b = (welch_psd(signal(x, 2048.0), nperseg=2048, backend=be) for be in BACKENDS)
    np.testing.assert_allclose(a.values, b.values, rtol=0, atol=roundoff_atol(b.values, 2048))
    assert a.attrs["fft_backend"] == "pyfftw" and b.attrs["fft_backend"] == "numpy"


@pytest.mark.parametrize("name", ["welch_parseval", "welch_vs_scipy", "welch_white_noise_level"])
def test_verification_cases(name):
    """Parseval exact for a boxcar window (sum(P) df = mean(x^2) to summation round-off), equality with
    scipy.signal.welch for one more setting, the white-noise level 2 s2 / fs: the verification cases (their
    tolerances and bases are there)."""
    (case,) = select_cases([name])
    result = evaluate_case(case, False, None)
    assert result.status == "passed", result


@pytest.mark.parametrize("backend", BACKENDS)
def test_sine_power(backend):
    # A sine on a bin centre with a Hann window puts exactly A^2/2 into bins k-1, k, k+1 (weights 1/6, 2/3, 1/6
    # of the power, since the periodic Hann window's DFT has only 3 non-zero lines).
    fs, nperseg, amp, k = 51200.0, 8192, 3.7, 1234
    t = np.arange(nperseg * 16) / fs
    x = amp * np.sin(2 * np.pi * k * fs / nperseg * t + 0.3)
    p = welch_psd(signal(x, fs), nperseg=nperseg, backend=backend)
    df = p.attrs["frequency_resolution"]
    band = p.values[k - 1:k + 2] * df
    np.testing.assert_allclose(band, amp**2 / 2 * np.array([1 / 6, 2 / 3, 1 / 6]), rtol=1e-9)
    assert float(p.sum()) * df == pytest.approx(amp**2 / 2, rel=1e-9)
    assert int(np.argmax(p.values)) == k


def test_white_noise_level_and_equivalent_degrees_of_freedom():
    # Gaussian white noise of variance s2 has one-sided density 2 s2 / fs. Each interior-bin estimate is
    # S chi2_nu / nu: mean S, variance 2 S^2 / nu with nu from Percival & Walden eq. 292b (nu = 18.93 for
    # Hann, 50 %, K = 10, against 2K = 20 without the overlap correlation: a 5.7 % difference in variance).
    rng = np.random.default_rng(5)
    fs, s2, nperseg, k, records = 4096.0, 0.49, 16384, 10, 10
    n = nperseg // 2 * (k + 1)
    ratios = []
    for _ in range(records):
        p = welch_psd(signal(rng.normal(0.0, np.sqrt(s2), n), fs), nperseg=nperseg)
        ratios.append(p.values[1:-1] / (2 * s2 / fs))
    assert p.attrs["n_segments"] == k
    nu = p.attrs["equivalent_degrees_of_freedom"]
    # Hann at 50 %: rho(N/2) = 1/6 -> nu = 2K / (1 + 2 (1 - 1/K) / 36)
    assert nu == pytest.approx(2 * k / (1 + 2 * (1 - 1 / k) / 36), rel=1e-3)
    r = np.concatenate(ratios)
    m = r.size
    # Bin correlation of Hann periodograms: 4/9 (adjacent), 1/36 (next) -> the mean of m ratios has variance
    # (2/nu)(1 + 2(4/9 + 1/36)) / m; squares of deviations correlate as rho^4: (1 + 2((4/9)^2 + (1/36)^2)).
    sd_mean = np.sqrt(2 / nu * (1 + 2 * (4 / 9 + 1 / 36)) / m)
    assert abs(r.mean() - 1) < 5 * sd_mean
    # Sample variance of a chi2_nu/nu variable: var(s^2) = (2/nu)^2 (2 + 12/nu) / m_eff (excess kurtosis 12/nu).
    m_eff = m / (1 + 2 * ((4 / 9) ** 2 + (1 / 36) ** 2))
    sd_var = (2 / nu) * np.sqrt((2 + 12 / nu) / m_eff)
    assert abs(r.var() - 2 / nu) < 5 * sd_var
    assert abs(r.var() - 2 / (2 * k)) > 5 * sd_var  # the uncorrected 2K is rejected by the same data


def test_chi2_bounds_cover_the_true_level():
    rng = np.random.default_rng(6)
    fs, s2 = 1000.0, 2.0
    p = welch_psd(signal(rng.normal(0, np.sqrt(s2), 64 * 1024), fs), nperseg=1024, confidence=0.9)
    true = 2 * s2 / fs
    lo, hi = p["psd_lower"].values[1:-1], p["psd_upper"].values[1:-1]
    assert np.all(lo < p.values[1:-1]) and np.all(p.values[1:-1] < hi)
    covered = np.mean((lo <= true) & (true <= hi))
    m = lo.size
    # binomial standard error inflated by the bin correlation (1 + 2(4/9 + 1/36)) of Hann periodograms
    sd = np.sqrt(0.9 * 0.1 / m * (1 + 2 * (4 / 9 + 1 / 36)))
    assert abs(covered - 0.9) < 5 * sd
    assert p["psd_lower"].attrs["units"] == "m2 s-4 Hz-1"


def test_equivalent_dof_without_overlap_is_2k():
    w = scipy.signal.get_window("hann", 256)
    assert equivalent_degrees_of_freedom(w, 12, 256) == 24.0


@pytest.mark.parametrize("units, expected", [("m s-2", "m2 s-4 Hz-1"), ("N", "N2 Hz-1"), ("1", "Hz-1"),
                                             ("m/s", "(m/s)2 Hz-1"), ("Hz", "Hz")])
def test_power_units(units, expected):
    assert power_units(units) == expected


def test_keeps_sensor_dimension():
    rng = np.random.default_rng(7)
    fs = 1000.0
    x = rng.standard_normal((5000, 2))
    da = xr.DataArray(x, dims=("time", "sensor"), coords={"time": np.arange(5000) / fs, "sensor": ["a", "b"]},
                      name="acceleration", attrs={"units": "m s-2"})
    p = welch_psd(da, nperseg=256)
    assert p.dims == ("sensor", "frequency")
    _, ref = scipy.signal.welch(x[:, 1], fs=fs, nperseg=256, noverlap=128)
    np.testing.assert_allclose(p.sel(sensor="b").values, ref, rtol=0, atol=roundoff_atol(ref, 256))


def test_shorter_than_one_segment_names_lengths():
    with pytest.raises(DataQualityError, match=r"1000 samples .* nperseg = 4096"):
        welch_psd(signal(np.zeros(1000), 1000.0), nperseg=4096)


def test_nan_is_named_with_its_time():
    x = np.zeros(5000)
    x[1234] = np.nan
    with pytest.raises(DataQualityError, match=r"'acceleration' has 1 non-finite .* index 1234, t = 1.234 s"):
        welch_psd(signal(x, 1000.0), nperseg=256)


def test_non_uniform_time_is_named():
    da = signal(np.zeros(5000), 1000.0)
    t = da["time"].values.copy()
    t[3000:] += 0.001  # a dropped sample
    da = da.assign_coords(time=t)
    with pytest.raises(DataQualityError, match=r"non-uniform time: step 2999"):
        welch_psd(da, nperseg=256)


def test_bad_settings():
    da = signal(np.zeros(5000), 1000.0)
    with pytest.raises(ConfigError, match="noverlap"):
        welch_psd(da, nperseg=256, noverlap=256)
    with pytest.raises(ConfigError, match="detrend"):
        welch_psd(da, nperseg=256, detrend="quadratic")
    with pytest.raises(ConfigError, match="window"):
        welch_psd(da, nperseg=256, window="nonesuch")
    with pytest.raises(ConfigError, match="backend"):
        welch_psd(da, nperseg=256, backend="mkl")
    with pytest.raises(DataQualityError, match="declared sampling rate 2000"):
        welch_psd(da, nperseg=256, fs=2000.0)
    with pytest.raises(UnitError, match="no 'units'"):
        welch_psd(da.assign_attrs(units=None).drop_attrs(), nperseg=256)


def test_pure_layer_matches_wrapper():
    rng = np.random.default_rng(8)
    x = rng.standard_normal(10_000)
    f, pxx, _, _, k = averaged_spectra(x, SpectralSettings(fs=10.0, nperseg=512, noverlap=256, backend="numpy"))
    p = welch_psd(signal(x, 10.0), nperseg=512, backend="numpy")
    np.testing.assert_array_equal(pxx, p.values)
    assert k == p.attrs["n_segments"]


def test_docstring_examples_run():
    import doctest

    import fivid.signal.welch

    result = doctest.testmod(fivid.signal.welch, optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0 and result.failed == 0


@settings(max_examples=25, deadline=None)
@given(nperseg=st.integers(8, 600), overlap_fraction=st.floats(0, 0.9), extra=st.integers(0, 3000),
       detrend=st.sampled_from(["constant", "linear", False]), seed=st.integers(0, 2**32 - 1),
       backend=st.sampled_from(BACKENDS))
def test_any_segmentation_equals_scipy(nperseg, overlap_fraction, extra, detrend, seed, backend):
    noverlap = min(int(overlap_fraction * nperseg), nperseg - 1)
    x = np.random.default_rng(seed).standard_normal(nperseg + extra)
    p = welch_psd(signal(x, 100.0), nperseg=nperseg, noverlap=noverlap, detrend=detrend, backend=backend)
    _, ref = scipy.signal.welch(x, fs=100.0, nperseg=nperseg, noverlap=noverlap, detrend=detrend, window="hann")
    np.testing.assert_allclose(p.values, ref, rtol=0, atol=roundoff_atol(ref, nperseg))


def test_ar1_spectrum_inside_its_chi2_bounds():
    # AR(1) x_t = phi x_{t-1} + e_t, var(e) = s2: S(f) = (2 s2 / fs) / |1 - phi exp(-2 pi i f / fs)|^2 (one-sided).
    # The spectrum is smooth on the scale of the Hann main lobe (3 bins of 1/1024 of fs), so the leakage bias,
    # ~ (1/24) B_e^2 S''/S < 1e-3 here, is negligible beside the ~ +-25 % chi2 width at nu ~ 110.
    rng = np.random.default_rng(9)
    fs, phi, s2, nperseg = 2000.0, 0.9, 1.0, 1024
    e = rng.normal(0.0, np.sqrt(s2), 2**15 + 1000)
    x = scipy.signal.lfilter([1.0], [1.0, -phi], e)[1000:]  # drop the start-up transient (phi^1000 ~ 1e-46)
    p = welch_psd(signal(x, fs), nperseg=nperseg)
    f = p["frequency"].values[1:-1]
    true = (2 * s2 / fs) / np.abs(1 - phi * np.exp(-2j * np.pi * f / fs)) ** 2
    lo, hi = p["psd_lower"].values[1:-1], p["psd_upper"].values[1:-1]
    covered = np.mean((lo <= true) & (true <= hi))
    sd = np.sqrt(0.95 * 0.05 / f.size * (1 + 2 * (4 / 9 + 1 / 36)))
    assert abs(covered - 0.95) < 5 * sd
    # and the estimate averaged over 64-bin blocks follows the closed form to its statistical error
    ratio = (p.values[1:-1] / true)[: 64 * 7].reshape(7, 64).mean(axis=1)
    nu = p.attrs["equivalent_degrees_of_freedom"]
    assert np.all(np.abs(ratio - 1) < 5 * np.sqrt(2 / nu * (1 + 2 * (4 / 9 + 1 / 36)) / 64))


def test_two_fftw_threads_give_the_same_numbers():
    rng = np.random.default_rng(10)
    x = signal(rng.standard_normal(100_000), 1000.0)
    one = welch_psd(x, nperseg=2048, backend="pyfftw")
    two = welch_psd(x, nperseg=2048, backend="pyfftw", threads=2)
    np.testing.assert_allclose(one.values, two.values, rtol=0, atol=roundoff_atol(one.values, 2048))
    assert one.attrs["fft_threads"] == 1 and two.attrs["fft_threads"] == 2


def test_fftw_plan_is_made_once_and_reused():
    from fivid.signal import fft

    x = signal(np.random.default_rng(12).standard_normal(50_000), 1000.0)
    welch_psd(x, nperseg=1536, backend="pyfftw")
    plans = {k: v for k, v in fft._plans.items() if k[1] == 1536}
    assert len(plans) == 1
    welch_psd(x * 2, nperseg=1536, backend="pyfftw")
    assert {k: v for k, v in fft._plans.items() if k[1] == 1536} == plans  # same key, same plan object
