"""Two spectra on one frequency grid compared: log-spectral distance, level difference, band levels.

The one home of these measures: the PSD scores (:mod:`fivid.score`), the solver's time-step halving
(:mod:`fivid.solver.step_halving`), a study's mesh and time-step convergence (:mod:`fivid.study.convergence`)
and the pipeline's discretisation error (:mod:`fivid.pipeline.discretisation`) all call them, so a score and
the error that qualifies it are the same quantity on the same band grid.

A band's power is the PSD times the bin weights of :func:`fivid.signal.levels.bin_weights` (each bin's
rectangle ``[f - df/2, f + df/2]`` counted with the fraction inside the band); the log-spectral distance is over
the bins whose centre lies in the band.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import DataQualityError
from fivid.signal.levels import bin_weights
from fivid.signal.spectral import welch_density
from fivid.signal.steady import steady_part
from fivid.signal.welch import default_nperseg

__all__ = ["log_psd_db", "log_spectral_distance", "level_difference_db", "band_levels_db", "band_distance",
           "steady_psds"]


def log_psd_db(psd: np.ndarray, *, label: str = "PSD") -> np.ndarray:
    """``10 log10(P)`` [dB re 1 unit² Hz-1]; a zero or negative bin is a :class:`DataQualityError`."""
    p = np.asarray(psd, dtype=np.float64)
    if np.any(p <= 0):
        i = int(np.argmin(p > 0))
        raise DataQualityError(f"{label}: PSD bin {i} is {p[i]!r}; a log-spectral score needs positive values "
                               "(a constant or digitally silent signal in the band?)")
    return 10.0 * np.log10(p)


def log_spectral_distance(p_ref: np.ndarray, p: np.ndarray, *, labels=("measured", "simulated")) -> float:
    """RMS over frequency of ``10 log10(P / P_ref)`` [dB] (two PSDs on one grid, positive).

    ``labels`` name ``(p_ref, p)`` in the error raised on a non-positive bin.

    >>> round(log_spectral_distance(np.ones(4), np.full(4, 10.0)), 12)
    10.0
    """
    d = log_psd_db(p, label=labels[1]) - log_psd_db(p_ref, label=labels[0])
    return float(np.sqrt(np.mean(d**2)))


def level_difference_db(p_ref: np.ndarray, p: np.ndarray, weights: np.ndarray) -> float:
    """``10 log10(∫ P df / ∫ P_ref df)`` [dB] with the bin weights [Hz] of the band."""
    return float(10.0 * np.log10((p @ weights) / (p_ref @ weights)))


def band_levels_db(psd: np.ndarray, weights: np.ndarray, *, reference: float = 1.0) -> np.ndarray:
    """Band power levels ``10 log10(Σ_k w_kb P_k / reference)`` [dB re ``reference`` unit²] for a weight matrix
    (n_bins, n_bands) or vector (n_bins,) from :func:`fivid.signal.levels.bin_weights` /
    :func:`fivid.signal.levels.third_octave_weights`; ``-inf`` for a band without power."""
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10((np.asarray(psd, dtype=np.float64) @ weights) / reference)


def band_distance(f, p_ref, p, band) -> tuple[float, float]:
    """``(lsd_db, level_diff_db)`` of ``p`` against ``p_ref`` over ``band = (f_lo, f_hi)`` [Hz]: the
    :func:`log_spectral_distance` over the bins with ``f_lo <= f <= f_hi`` and the :func:`level_difference_db`
    of the band's powers (bin weights). Both NaN when no bin lies in the band."""
    f = np.asarray(f, dtype=np.float64)
    p_ref, p = np.asarray(p_ref, dtype=np.float64), np.asarray(p, dtype=np.float64)
    lo, hi = (float(b) for b in band)
    sel = (f >= lo) & (f <= hi)
    if not sel.any():
        return float("nan"), float("nan")
    lsd = log_spectral_distance(p_ref[sel], p[sel], labels=("reference PSD", "PSD"))
    return lsd, level_difference_db(p_ref, p, bin_weights(f, lo, hi))


def steady_psds(runs, *, variable: str = "acceleration", nperseg: int | None = None):
    """Welch PSDs of ``variable`` over the steady part of each run (:func:`fivid.signal.steady_part`; Hann, 50 %
    overlap, constant detrend, density; first sensor): ``(frequency [Hz], [psd, ...], nperseg)``.

    One ``nperseg`` for all runs: the one given (default :func:`fivid.signal.welch.default_nperseg` of the shortest
    steady part), capped at the shortest steady part."""
    signals = []
    for ds in runs:
        da = steady_part(ds)[variable]
        if "sensor" in da.dims:
            da = da.isel(sensor=0)
        signals.append((np.asarray(da.values), float(ds.attrs["sample_rate"])))
    shortest = min(x.size for x, _ in signals)
    n = default_nperseg(signals[0][1], shortest) if nperseg is None else int(nperseg)
    n = min(n, shortest)
    psds = []
    for x, fs in signals:
        f, p = welch_density(x, fs, nperseg=n)
        psds.append(p)
    return f, psds, n
