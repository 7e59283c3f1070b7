"""Synthesis of μp(t): target PSD within its χ² bound (scipy.signal.welch as the estimator), target RMS."""

import numpy as np
import pytest
from scipy import signal, stats

from fivid.errors import FividError
from fivid.friction import synthesise_perturbation
from fivid.friction.synthesis import fft_frequencies, inverse_rfft

FS = 51200.0
DURATION = 4.0
A_TARGET = 0.01  # RMS of μp [-]
F_C = 2000.0  # roll-off corner [Hz]


def target_psd(f):
    """A second-order roll-off shape in 50 Hz - 20 kHz scaled to A_TARGET^2 (one-sided, [Hz-1])."""
    shape = np.where((f >= 50.0) & (f <= 20000.0), 1.0 / (1.0 + (f / F_C) ** 4), 0.0)
    fine = np.linspace(50.0, 20000.0, 200001)
    area = np.trapezoid(1.0 / (1.0 + (fine / F_C) ** 4), fine)
    return A_TARGET**2 * shape / area


def _welch_dof(n_segments: int) -> float:
    """Equivalent χ² degrees of freedom of Welch with a Hann window and 50 % overlap.

    Welch (1967): ν = 2K / (1 + 2 c(1/2)^2) with c(1/2) = 1/6 for the Hann window (the correlation
    of adjacent half-overlapped segments), up to end effects.
    """
    return 2.0 * n_segments / (1.0 + 2.0 * (1.0 / 6.0) ** 2)


def test_psd_within_chi2_bound_of_welch():
    x = synthesise_perturbation(target_psd, DURATION, FS, seed=11)[0]
    nperseg = 1024
    f, p = signal.welch(x, fs=FS, window="hann", nperseg=nperseg, noverlap=nperseg // 2, detrend="constant",
                        scaling="density")
    k = (len(x) - nperseg) // (nperseg // 2) + 1
    nu = _welch_dof(k)
    band = (f >= 200.0) & (f <= 15000.0)  # away from the band edges (leakage of the window)
    ratio = p[band] / target_psd(f[band])
    lo, hi = stats.chi2.ppf([0.025, 0.975], nu) / nu
    outside = np.count_nonzero((ratio < lo) | (ratio > hi))
    m = ratio.size
    # binomial count of bins outside the 95 % interval: mean 0.05 m; adjacent Hann bins are correlated
    # (|ρ|^2 = 4/9, 1/36 at lags 1, 2) so the count's variance is inflated by at most 1 + 2(4/9 + 1/36) < 2
    sd = np.sqrt(2.0 * 0.05 * 0.95 * m)
    assert outside <= 0.05 * m + 4 * sd, (outside, m)
    # the band mean of P/S: mean 1, variance (1/(ν/2)) (1 + 2 Σρ^2) / m per bin average; 4 σ
    sd_mean = np.sqrt(2.0 / nu * 2.0 / m)
    assert abs(ratio.mean() - 1.0) < 4 * sd_mean, (ratio.mean(), sd_mean)


def test_mean_square_matches_target_within_its_exact_spread():
    n = int(DURATION * FS)
    f = fft_frequencies(n, FS)
    s = target_psd(f)
    s[0] = s[-1] = 0.0
    df = FS / n
    x = synthesise_perturbation(target_psd, DURATION, FS, seed=5, n_signals=6)
    ms = np.mean(x**2, axis=1)
    expected = s.sum() * df
    # mean square = (2/n^2) Σ|X_k|^2, |X_k|^2 exponential with mean μ_k = S_k fs n / 2: sd = (2/n^2) sqrt(Σ μ_k^2)
    mu_k = s * FS * n / 2.0
    sd = 2.0 / n**2 * np.sqrt(np.sum(mu_k**2))
    assert np.all(np.abs(ms - expected) < 4 * sd), (ms, expected, sd)
    assert abs(ms.mean() - expected) < 4 * sd / np.sqrt(ms.size)
    # the discrete sum approximates the band integral A^2 (Riemann sum of a smooth shape, Δf = 0.25 Hz)
    assert expected == pytest.approx(A_TARGET**2, rel=1e-3)


def test_random_phase_has_exact_rms():
    n = int(DURATION * FS)
    f = fft_frequencies(n, FS)
    s = target_psd(f)
    s[0] = s[-1] = 0.0
    x = synthesise_perturbation(target_psd, DURATION, FS, seed=5, n_signals=3, method="random_phase")
    expected = s.sum() * FS / n
    # Parseval holds to float rounding: relative error ~ eps * log2(n) ≈ 4e-15; 1e-12 leaves margin
    np.testing.assert_allclose(np.mean(x**2, axis=1), expected, rtol=1e-12)
    np.testing.assert_allclose(x.mean(axis=1), 0.0, atol=1e-15)


def test_reproducible_and_independent():
    a = synthesise_perturbation(target_psd, 0.5, FS, seed=7, n_signals=2)
    b = synthesise_perturbation(target_psd, 0.5, FS, seed=7, n_signals=2)
    c = synthesise_perturbation(target_psd, 0.5, FS, seed=8, n_signals=2)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    # two signals of one call are independent: sample correlation ~ N(0, 1/n_eff); n_eff >> 100
    r = np.corrcoef(a[0], a[1])[0, 1]
    assert abs(r) < 0.1


def test_pyfftw_and_numpy_give_the_same_numbers():
    pytest.importorskip("pyfftw")
    rng = np.random.default_rng(0)
    n = 2**15
    coeff = rng.standard_normal(n // 2 + 1) + 1j * rng.standard_normal(n // 2 + 1)
    coeff[0] = coeff[-1] = 0
    x1 = inverse_rfft(coeff, n, backend="pyfftw")
    x2 = inverse_rfft(coeff, n, backend="numpy")
    # FFT round-off: ~ eps * log2(n) relative to the RMS; 10x margin
    tol = 10 * np.finfo(float).eps * np.log2(n) * np.sqrt(np.mean(x2**2))
    assert np.max(np.abs(x1 - x2)) < tol
    y1 = synthesise_perturbation(target_psd, 0.25, FS, seed=3, backend="pyfftw")
    y2 = synthesise_perturbation(target_psd, 0.25, FS, seed=3, backend="numpy")
    assert np.max(np.abs(y1 - y2)) < 10 * np.finfo(float).eps * np.log2(y1.size) * A_TARGET


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"duration": -1.0}, "duration"),
        ({"sample_rate": 0.0}, "sample_rate"),
        ({"n_signals": 0}, "n_signals"),
        ({"method": "pink"}, "synthesis method"),
    ],
)
def test_bad_arguments_are_named(kwargs, match):
    args = {"duration": 1.0, "sample_rate": 1000.0, "seed": 0}
    args.update(kwargs)
    with pytest.raises(FividError, match=match):
        synthesise_perturbation(target_psd, **args)


def test_negative_psd_rejected():
    with pytest.raises(FividError, match="negative or non-finite"):
        synthesise_perturbation(lambda f: -np.ones_like(f), 1.0, 1000.0, seed=0)
