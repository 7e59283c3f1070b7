"""The PSD scores of DESIGN §6 on plain arrays: two one-sided PSDs on one frequency grid.

``P_m`` is the measured PSD, ``P_s`` the simulated one, both restricted to the scoring band. Pure
functions, no uncertainty (that is :mod:`fivid.score.uncertainty`) and no xarray.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import DataQualityError

__all__ = [
    "log_psd_db",
    "log_spectral_distance",
    "level_difference_db",
    "band_levels_db",
    "shape_correlation",
    "spectral_peaks",
    "match_peaks",
    "refine_peak",
]


def log_psd_db(psd: np.ndarray, *, label: str = "PSD") -> np.ndarray:
    """``10 log10(P)`` [dB re 1 unit² Hz-1]; a zero or negative bin is a :class:`DataQualityError`."""
    p = np.asarray(psd, dtype=np.float64)
    if np.any(p <= 0):
        i = int(np.argmin(p > 0))
        raise DataQualityError(f"{label}: PSD bin {i} is {p[i]!r}; a log-spectral score needs positive values "
                               "(a constant or digitally silent signal in the band?)")
    return 10.0 * np.log10(p)


def log_spectral_distance(p_m: np.ndarray, p_s: np.ndarray) -> float:
    """RMS over frequency of ``10 log10(P_s / P_m)`` [dB]."""
    d = log_psd_db(p_s, label="simulated") - log_psd_db(p_m, label="measured")
    return float(np.sqrt(np.mean(d**2)))


def level_difference_db(p_m: np.ndarray, p_s: np.ndarray, weights: np.ndarray) -> float:
    """``10 log10(∫ P_s df / ∫ P_m df)`` [dB] with bin weights [Hz] of the band."""
    return float(10.0 * np.log10((p_s @ weights) / (p_m @ weights)))


def band_levels_db(psd: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Band power levels ``10 log10(Σ_k w_kb P_k)`` [dB re 1 unit²] for a weight matrix (n_bins, n_bands)."""
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(psd @ weights)


def shape_correlation(p_m: np.ndarray, p_s: np.ndarray) -> float:
    """Pearson correlation of the two log-PSDs [-] (1: same shape, whatever the level)."""
    a = log_psd_db(p_m, label="measured")
    b = log_psd_db(p_s, label="simulated")
    a = a - a.mean()
    b = b - b.mean()
    den = np.sqrt(np.dot(a, a) * np.dot(b, b))
    if den == 0:
        return float("nan")
    return float(np.clip(np.dot(a, b) / den, -1.0, 1.0))


def spectral_peaks(log_psd: np.ndarray, *, prominence_db: float, max_peaks: int | None = None) -> np.ndarray:
    """Indices of peaks of a log-PSD [dB] with at least ``prominence_db`` prominence, most prominent first.

    :func:`scipy.signal.find_peaks` on the log-PSD (prominence measured against the higher of the
    two neighbouring minima).
    """
    from scipy.signal import find_peaks

    idx, props = find_peaks(np.asarray(log_psd, dtype=np.float64), prominence=prominence_db)
    order = np.argsort(-props["prominences"], kind="stable")
    idx = idx[order]
    return idx if max_peaks is None else idx[:max_peaks]


def match_peaks(frequency: np.ndarray, peaks_m: np.ndarray, peaks_s: np.ndarray, *, relative_tolerance: float):
    """Pair each measured peak with the nearest unused simulated peak within a relative distance.

    Measured peaks are taken in the given order (most prominent first); a measured peak with no
    simulated peak within ``relative_tolerance · f_m`` is paired with -1.

    Returns
    -------
    ndarray of shape (len(peaks_m), 2): index pairs (measured bin, simulated bin or -1).
    """
    f = np.asarray(frequency, dtype=np.float64)
    free = list(int(i) for i in peaks_s)
    pairs = []
    for i in peaks_m:
        fm = f[i]
        best = -1
        if free:
            dist = [abs(f[j] - fm) for j in free]
            k = int(np.argmin(dist))
            if dist[k] <= relative_tolerance * fm:
                best = free.pop(k)
        pairs.append((int(i), best))
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)



def refine_peak(frequency: np.ndarray, log_psd: np.ndarray, index: int, sigma_db: float,
                inflation: float = 1.0, drop_db: float = 3.0) -> tuple[float, float]:
    """Peak frequency [Hz] refined by a least-squares parabola through the peak's top, and its standard error.

    The top is the contiguous run of bins within ``max(drop_db, 4 sigma_db)`` of the maximum (at
    least 2 bins each side). With errors of ``sigma_db`` on the log-PSD (or the residual variance, if
    larger) the fit's covariance is ``σ² (XᵀX)⁻¹``, times ``inflation`` for correlated bins; the vertex
    ``f0 = f_k − b / (2c)`` has its variance by the delta method. When the top is not concave (a
    plateau, an edge, noise) it returns ``f_k`` with the standard error of a position spread uniformly
    over the top, ``width / sqrt(12)``.
    """
    f = np.asarray(frequency, dtype=np.float64)
    lp = np.asarray(log_psd, dtype=np.float64)
    floor = lp[index] - max(drop_db, 4.0 * sigma_db)
    lo, hi = index, index
    while lo > 0 and (lp[lo - 1] >= floor or index - lo < 2):
        lo -= 1
    while hi < lp.size - 1 and (lp[hi + 1] >= floor or hi - index < 2):
        hi += 1
    df = f[1] - f[0]
    uniform = (float(f[index]), (hi - lo + 1) * df / np.sqrt(12.0))
    if hi - lo < 2:
        return uniform
    x = (f[lo:hi + 1] - f[index]) / df
    design = np.stack([np.ones_like(x), x, x**2], axis=1)
    coef, *_ = np.linalg.lstsq(design, lp[lo:hi + 1], rcond=None)
    _, b, c = coef
    if not c < 0:
        return uniform
    vertex = -b / (2.0 * c)
    if not x[0] <= vertex <= x[-1]:
        return uniform
    # error variance: the known log-PSD noise, or the fit's residual variance when larger (the top of a
    # resonance is only approximately a parabola in dB; misfit then widens the interval rather than hiding)
    resid = lp[lo:hi + 1] - design @ coef
    dof = x.size - 3
    var = max(sigma_db**2, float(resid @ resid) / dof) if dof > 0 else sigma_db**2
    cov = var * inflation * np.linalg.inv(design.T @ design)
    grad = np.array([0.0, -1.0 / (2.0 * c), b / (2.0 * c * c)])
    return float(f[index] + vertex * df), float(np.sqrt(grad @ cov @ grad) * df)
