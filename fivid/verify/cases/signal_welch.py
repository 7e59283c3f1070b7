"""Welch PSD: identical to scipy.signal.welch, Parseval exact, the white-noise level 2σ²/fs."""

from __future__ import annotations

import numpy as np
import xarray as xr

from fivid.signal import welch_psd
from fivid.verify.case import Case, Curve, Outcome, Plot

__all__ = ["CASES", "time_signal", "roundoff_atol", "EPS"]

EPS = float(np.finfo(float).eps)


def time_signal(values, fs, name="acceleration", units="m s-2", t0=0.0) -> xr.DataArray:
    """A uniformly sampled signal as fivid's spectral functions take it (``time`` coordinate, ``units``)."""
    t = t0 + np.arange(values.shape[0]) / fs
    return xr.DataArray(values, dims="time", coords={"time": t}, name=name, attrs={"units": units})


def roundoff_atol(p, nperseg) -> float:
    """Absolute round-off bound of a Welch PSD bin: an FFT of length N has a normwise relative error
    ~ eps log2(N) (Higham, Accuracy and Stability of Numerical Algorithms, §24.1); on |X|² that is an absolute
    error ≤ 2 eps log2(N) Σ|X|², every bin bounded by the total; a factor 8 covers the windowing, detrending
    and the averaging sum."""
    return 16 * EPS * np.log2(nperseg) * float(np.sum(p))


def _scipy(quick: bool, data) -> Outcome:
    import scipy.signal

    rng = np.random.default_rng(1)
    fs, nperseg, noverlap = 51200.0, 4096, 3072
    x = np.cumsum(rng.standard_normal(50_003 if quick else 200_003)) * 1e-3 + 0.3  # red noise with an offset
    p = welch_psd(time_signal(x, fs), nperseg=nperseg, noverlap=noverlap, window="blackman", detrend="constant")
    f_ref, p_ref = scipy.signal.welch(x, fs=fs, window="blackman", nperseg=nperseg, noverlap=noverlap,
                                      detrend="constant", scaling="density", average="mean")
    diff = float(np.abs(p.values - p_ref).max())
    plot = Plot("frequency [Hz]", "PSD [m² s⁻⁴ Hz⁻¹]",
                (Curve(f_ref[1:], p.values[1:], "fivid welch_psd"), Curve(f_ref[1:], p_ref[1:], "scipy.signal.welch",
                                                                           "dashed")), "log", "log")
    return Outcome(diff, 0.0, roundoff_atol(p_ref, nperseg), plot,
                   {"samples": int(x.size), "FFT backend": p.attrs.get("fft_backend", ""),
                    "largest relative frequency difference": float(np.abs(p["frequency"].values / np.where(
                        f_ref > 0, f_ref, 1) - np.where(f_ref > 0, 1, 0)).max())})


def _parseval(quick: bool, data) -> Outcome:
    rng = np.random.default_rng(4)
    fs, nperseg = 100.0, 256
    x = rng.standard_normal(nperseg * 40) + 0.5
    p = welch_psd(time_signal(x, fs), nperseg=nperseg, noverlap=0, window="boxcar", detrend="none")
    power = float(p.sum()) * fs / nperseg
    f = p["frequency"].values
    plot = Plot("frequency [Hz]", "cumulative ∫P df [m² s⁻⁴]",
                (Curve(f, np.cumsum(p.values) * fs / nperseg, "fivid: cumulative PSD"),
                 Curve(f[[0, -1]], np.full(2, np.mean(x ** 2)), "mean(x²)", "dashed")))
    return Outcome(power, float(np.mean(x ** 2)), 64 * EPS * np.log2(nperseg), plot, {"segments": 40})


def _white(quick: bool, data) -> Outcome:
    rng = np.random.default_rng(5)
    fs, s2, nperseg, k = 4096.0, 0.49, 16384, 10
    records = 4 if quick else 10
    n = nperseg // 2 * (k + 1)
    ratios = []
    for _ in range(records):
        p = welch_psd(time_signal(rng.normal(0.0, np.sqrt(s2), n), fs), nperseg=nperseg)
        ratios.append(p.values[1:-1] / (2 * s2 / fs))
    r = np.concatenate(ratios)
    nu = float(p.attrs["equivalent_degrees_of_freedom"])
    # Hann periodogram bins correlate 4/9 (adjacent) and 1/36 (next): the mean of m ratios has this variance
    sd_mean = np.sqrt(2 / nu * (1 + 2 * (4 / 9 + 1 / 36)) / r.size)
    f = p["frequency"].values[1:-1]
    plot = Plot("frequency [Hz]", "PSD / (2σ²/fs) [-]",
                (Curve(f, ratios[-1], "fivid, one record"), Curve(f[[0, -1]], np.ones(2), "1", "dashed")))
    return Outcome(float(r.mean()), 1.0, float(5 * sd_mean), plot,
                   {"records": records, "equivalent degrees of freedom ν": nu,
                    "variance of the ratio × ν/2 (1 expected)": float(r.var() * nu / 2)})


_SCIPY_SOURCE = ("reference implementation: scipy.signal.welch (P. Welch, IEEE Trans. Audio Electroacoust. 15 (1967) "
                 "70-73); P. Virtanen et al., SciPy 1.0, Nature Methods 17 (2020) 261-272")

CASES = (
    Case(name="welch_vs_scipy", title="Welch PSD against scipy.signal.welch",
         quantity="largest absolute difference of the PSD bins", unit="m2 s-4 Hz-1",
         reference="0: the same estimator with identical settings (Blackman, 4096, 75 % overlap, constant detrend)",
         source=_SCIPY_SOURCE,
         method="fivid.signal.welch_psd (pyFFTW plans) of 200 003 samples of red noise with an offset (--quick: "
                "50 003)",
         tolerance_basis="FFT round-off: 16 eps log2(N) Σ P (Higham §24.1, a factor 8 for windowing, detrending and "
                         "averaging)",
         compute=_scipy, error="absolute"),
    Case(name="welch_parseval", title="Parseval's theorem for the Welch PSD",
         quantity="∫P df of a boxcar-window, no-overlap, no-detrend PSD", unit="m2 s-4",
         reference="mean(x²) of the signal, exactly (Parseval per segment, one-sided doubling)",
         source="closed form (Parseval); J. S. Bendat, A. G. Piersol, Random Data, 4th ed., Wiley 2010, §5.2",
         method="fivid.signal.welch_psd of 40 segments of 256 samples of white noise plus 0.5; same for --quick",
         tolerance_basis="summation round-off 64 eps log2(N) relative", compute=_parseval),
    Case(name="welch_white_noise_level", title="White-noise level of the Welch PSD",
         quantity="mean over bins and records of P / (2σ²/fs)", unit="",
         reference="1: Gaussian white noise of variance σ² has the one-sided density 2σ²/fs",
         source="closed form; D. B. Percival, A. T. Walden, Spectral Analysis for Physical Applications, Cambridge "
                "1993, §6.17 (equivalent degrees of freedom, eq. 292b)",
         method="fivid.signal.welch_psd (Hann, 16384, 50 %, 10 segments) of 10 records of synthetic Gaussian noise "
                "(numpy seed 5; --quick: 4 records)",
         tolerance_basis="5 standard errors of the mean of χ²_ν/ν ratios, ν from Percival & Walden, inflated by the "
                         "Hann bin correlation (4/9, 1/36): a correct estimator fails with probability < 1e-6",
         compute=_white),
)
