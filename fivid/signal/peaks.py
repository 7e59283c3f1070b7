"""Peaks of a spectrum: found by prominence, refined between bins, matched between two spectra, tracked
across several (a mesh or time-step refinement).

All work on one-sided PSDs on a uniform frequency grid, as plain arrays.
"""

from __future__ import annotations

import numpy as np

__all__ = ["spectral_peaks", "match_peaks", "refine_peak", "parabolic_peaks", "track_peaks", "strongest_peaks",
           "near_frequencies"]


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

    For a peak of a noisy estimate (a measured or simulated Welch PSD with known log-PSD errors): the top is
    the contiguous run of bins within ``max(drop_db, 4 sigma_db)`` of the maximum (at least 2 bins each side).
    With errors of ``sigma_db`` on the log-PSD (or the residual variance, if larger) the fit's covariance is
    ``σ² (XᵀX)⁻¹``, times ``inflation`` for correlated bins; the vertex ``f0 = f_k − b / (2c)`` has its variance
    by the delta method. When the top is not concave (a plateau, an edge, noise) it returns ``f_k`` with the
    standard error of a position spread uniformly over the top, ``width / sqrt(12)``.
    (:func:`parabolic_peaks` is the three-point vertex, exact for a noise-free Gaussian peak.)
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


def parabolic_peaks(f, p, prominence_db: float) -> np.ndarray:
    """Frequencies [Hz], ascending, of the peaks of ``p(f)`` with at least ``prominence_db`` of prominence
    (:func:`spectral_peaks` on ``10 log10 p``; a non-positive bin takes the lowest positive level), each refined
    by the parabola through the log PSD at the peak bin and its two neighbours (exact for a Gaussian peak).

    >>> f = np.arange(0.0, 2000.0, 25.0)
    >>> p = 1e-6 + np.exp(-0.5 * ((f - 1010.0) / 30.0) ** 2)  # a Gaussian peak between two bins
    >>> [round(float(x), 3) for x in parabolic_peaks(f, p, 20.0)]
    [1010.0]
    """
    f, p = np.asarray(f, float), np.asarray(p, float)
    ok = p > 0
    level = np.full(p.shape, -np.inf)
    level[ok] = 10.0 * np.log10(p[ok])
    level[~ok] = level[ok].min() if ok.any() else 0.0
    idx = np.sort(spectral_peaks(level, prominence_db=prominence_db))
    df = float(np.median(np.diff(f)))
    out = []
    for k in idx:
        a, b, c = level[k - 1], level[k], level[k + 1]
        den = a - 2.0 * b + c
        out.append(f[k] + (0.5 * (a - c) / den * df if den < 0 else 0.0))
    return np.array(out)


def track_peaks(f, psds, reference: int, *, prominence_db: float, match_prominence_db: float,
                window: float) -> list[tuple[float, np.ndarray]]:
    """Each prominent peak of ``psds[reference]`` followed through the other spectra (a refinement series).

    Parameters
    ----------
    f : array_like
        Frequencies [Hz] of every spectrum.
    psds : sequence of array_like
        The spectra (one per mesh or time step).
    reference : int
        The spectrum whose peaks are tracked (the finest).
    prominence_db : float
        Prominence [dB] of a tracked peak in the reference (:func:`parabolic_peaks`).
    match_prominence_db : float
        Prominence [dB] enough to find a known peak again in another spectrum.
    window : float
        Largest relative distance ``|f - f_ref| / f_ref`` of the peak found again.

    Returns
    -------
    list of (f_ref, ndarray)
        Per reference peak found in every spectrum: its frequency [Hz] and the nearest peak's frequency in each
        spectrum (``f_ref`` itself for the reference); peaks lost in any spectrum are left out.
    """
    f = np.asarray(f, float)
    found = [parabolic_peaks(f, p, prominence_db if k == reference else match_prominence_db)
             for k, p in enumerate(psds)]
    out = []
    for f_ref in found[reference]:
        track = []
        for k, cand in enumerate(found):
            if k == reference:
                cand = np.array([f_ref])
            near = cand[np.argmin(np.abs(cand - f_ref))] if cand.size else np.nan
            track.append(near if abs(near - f_ref) <= window * f_ref else np.nan)
        if np.all(np.isfinite(track)):
            out.append((float(f_ref), np.array(track)))
    return out


def strongest_peaks(f, p, *, prominence_db: float, max_peaks: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``max_peaks`` highest peaks of a PSD ``p(f)`` with at least ``prominence_db`` prominence, strongest first.

    Returns ``(frequency [Hz], power)``: each frequency refined by the parabola through the log PSD at the peak bin
    and its neighbours (as :func:`parabolic_peaks`), the power the PSD integrated over the peak bin and two bins
    either side (a Hann-window Welch line spans about four bins); ordered by that power, descending.

    >>> f = np.arange(0.0, 4000.0, 25.0)
    >>> p = 1e-6 + np.exp(-0.5 * ((f - 1010.0) / 30.0) ** 2) + 4 * np.exp(-0.5 * ((f - 3000.0) / 30.0) ** 2)
    >>> [round(float(x), 3) for x in strongest_peaks(f, p, prominence_db=20.0, max_peaks=5)[0]]
    [3000.0, 1010.0]
    """
    f, p = np.asarray(f, float), np.asarray(p, float)
    ok = p > 0
    level = np.full(p.shape, -np.inf)
    level[ok] = 10.0 * np.log10(p[ok])
    level[~ok] = level[ok].min() if ok.any() else 0.0
    idx = spectral_peaks(level, prominence_db=prominence_db)
    df = float(np.median(np.diff(f)))
    freq, power = [], []
    for k in idx:
        if 0 < k < f.size - 1:
            a, b, c = level[k - 1], level[k], level[k + 1]
            den = a - 2.0 * b + c
            freq.append(f[k] + (0.5 * (a - c) / den * df if den < 0 else 0.0))
        else:
            freq.append(f[k])
        power.append(float(np.sum(p[max(0, k - 2):k + 3])) * df)
    order = np.argsort(-np.asarray(power), kind="stable")[:max_peaks]
    return np.asarray(freq)[order], np.asarray(power)[order]


def near_frequencies(f, centres, relative_width: float) -> np.ndarray:
    """Bool mask of the bins of ``f`` [Hz] within ``relative_width x centre`` of any of ``centres`` [Hz] (the band
    of a set of modes; a PSD's power splits into that band and the rest).

    >>> near_frequencies(np.array([90.0, 100.0, 104.0, 110.0]), [100.0], 0.05).tolist()
    [False, True, True, False]
    """
    f = np.asarray(f, float)[:, None]
    c = np.asarray(centres, float)[None, :]
    return np.any(np.abs(f - c) <= relative_width * c, axis=1)
