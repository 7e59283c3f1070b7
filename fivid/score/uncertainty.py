"""How far apart two Welch PSD estimates of the *same* spectrum may lie: thresholds of the scores.

A Welch estimate of a locally flat spectrum S in an interior bin is ``P = S χ²_ν / ν`` (ν: equivalent
degrees of freedom, :func:`fivid.signal.spectral.equivalent_degrees_of_freedom`). Hence, exactly,

* ``10 log10 P`` has standard deviation ``σ(ν) = (10 / ln 10) · sqrt(ψ'(ν/2))`` dB and bias
  ``β(ν) = (10 / ln 10) · (ψ(ν/2) − ln(ν/2))`` dB (ψ digamma, ψ' trigamma: ``ln χ²_ν`` has mean
  ``ψ(ν/2) + ln 2`` and variance ``ψ'(ν/2)``);
* two independent estimates differ in dB by ``β_s − β_m ± sqrt(σ_m² + σ_s²)``;
* ordinates ``m`` bins apart correlate as ``r_m`` (:func:`fivid.signal.spectral.bin_correlation`;
  Hann: 4/9, 1/36), so sums over bins have fewer independent terms than bins.

Every threshold below is the value a score of two runs with identical true spectra stays under
with probability ``confidence``; a score above it is called *significant*.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "log_psd_std_db",
    "log_psd_bias_db",
    "relative_power_std",
    "rms_threshold_db",
    "correlation_ceiling",
]

_DB = 10.0 / np.log(10.0)


def log_psd_std_db(dof) -> np.ndarray:
    """Standard deviation [dB] of ``10 log10`` of a χ²_ν/ν-distributed PSD estimate."""
    from scipy.special import polygamma

    return _DB * np.sqrt(polygamma(1, np.asarray(dof, dtype=np.float64) / 2.0))


def log_psd_bias_db(dof) -> np.ndarray:
    """Mean [dB] of ``10 log10(χ²_ν / ν)`` (negative: the log of an average underestimates)."""
    from scipy.special import digamma

    half = np.asarray(dof, dtype=np.float64) / 2.0
    return _DB * (digamma(half) - np.log(half))


def _symmetric(r: np.ndarray) -> np.ndarray:
    return np.concatenate((r[:0:-1], r))


def relative_power_std(psd: np.ndarray, weights: np.ndarray, dof: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Relative standard deviation of band powers ``Σ_k w_k P_k`` estimated from a Welch PSD.

    ``var = Σ_k Σ_j w_k w_j P_k P_j sqrt(2/ν_k · 2/ν_j) r_|k−j|`` with the estimate ``P`` plugged in
    for the true spectrum.

    Parameters
    ----------
    psd : ndarray, shape (n,)
    weights : ndarray, shape (n,) or (n, b)
        Bin weights [Hz] of one band or of ``b`` bands (:func:`fivid.signal.levels.bin_weights`).
    dof : ndarray, shape (n,)
        Degrees of freedom per bin.
    r : ndarray
        Bin correlations ``r_0 = 1, r_1, …``.
    """
    w = np.asarray(weights, dtype=np.float64)
    single = w.ndim == 1
    w = w[:, None] if single else w
    a = w * (psd * np.sqrt(2.0 / np.asarray(dof, dtype=np.float64)))[:, None]
    kernel = _symmetric(np.asarray(r, dtype=np.float64))
    var = np.array([np.dot(col, np.convolve(col, kernel, mode="same")) for col in a.T])
    total = psd @ w
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.sqrt(var) / total
    return rel[0] if single else rel


def rms_threshold_db(sigma: np.ndarray, bias: np.ndarray, confidence: float, r: np.ndarray | None = None) -> float:
    """Threshold of ``sqrt(mean(e_k²))`` for errors ``e_k ~ N(bias_k, sigma_k²)`` [dB].

    ``Σ e_k²`` is approximated by ``Σ bias_k² + g χ²_h`` (Satterthwaite): ``g h = Σ σ²`` and
    ``2 g² h = 2 Σ σ⁴ (1 + 2 Σ_m r_m²)`` — squares of errors correlated ``r_m`` correlate ``r_m²``.
    ``r`` = None means independent terms.
    """
    from scipy.stats import chi2

    s2 = np.asarray(sigma, dtype=np.float64) ** 2
    n = s2.size
    inflation = 1.0 if r is None else 1.0 + 2.0 * float(np.sum(np.asarray(r)[1:] ** 2))
    total, total4 = s2.sum(), (s2**2).sum() * inflation
    g, h = total4 / total, total**2 / total4
    q = np.sum(np.asarray(bias, dtype=np.float64) ** 2) + g * chi2.ppf(confidence, h)
    return float(np.sqrt(q / n))


def correlation_ceiling(log_m: np.ndarray, log_s: np.ndarray, sigma_m: float, sigma_s: float,
                        confidence: float, n_eff: float) -> tuple[float, float]:
    """Expected and lowest-acceptable Pearson correlation of two noisy log-PSDs of the same shape.

    Noise of variance σ² on a log-PSD of spread ``V`` attenuates the correlation to at most
    ``sqrt(V_m/(V_m+σ_m²) · V_s/(V_s+σ_s²))`` (Spearman's attenuation), with ``V = var(log P̂) − σ²``.
    The lowest acceptable value is that ceiling lowered by the one-sided ``confidence`` quantile of
    Fisher's z, ``atanh(r) ~ N(atanh(ρ), 1/(n_eff − 3))``.

    Returns
    -------
    (expected, lowest) : floats; NaN when the log-PSDs have no spread above their noise.
    """
    from scipy.stats import norm

    rel = []
    for values, sigma in ((log_m, sigma_m), (log_s, sigma_s)):
        total = float(np.var(values))
        rel.append((total - sigma**2) / total if total > 0 else 0.0)
    if min(rel) <= 0 or n_eff <= 3:
        return float("nan"), float("nan")
    ceiling = float(np.sqrt(rel[0] * rel[1]))
    lowest = float(np.tanh(np.arctanh(min(ceiling, 1 - 1e-15)) - norm.ppf(confidence) / np.sqrt(n_eff - 3)))
    return ceiling, lowest
