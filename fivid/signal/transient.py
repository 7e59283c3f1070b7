"""Transient analysis of vibration records: growth rate, dominant frequency over time, narrowband share.

These helpers classify what a run does (DESIGN §11, seed 002: stable, mode coupling, stick-slip) and work on
measured and simulated records alike (plain arrays; the caller picks the steady or transient part).

- :func:`envelope_growth_rate`: the exponential rate ``sigma`` [s-1] of a signal's envelope, ``a(t) ~ exp(sigma
  t)``, by a straight-line fit of the log of the band-passed signal's peak amplitudes (an LTI filter maps each
  damped or growing exponential onto itself with the same rate, so band-passing around the mode leaves the
  rate intact away from the record's ends). Peaks, not the FFT-based Hilbert envelope: a growing record's
  large end leaks through the Hilbert transform's wrap-around into its small beginning (measured: 23 instead
  of 30 s-1 over a dynamic range of e^12); the peaks are local. Sampled peaks are low by at most
  ``1 - cos(pi f / fs)``, a constant factor that leaves the slope alone.
- :func:`dominant_frequency_track`: the frequency of the largest spectrogram bin per time slice [Hz].
- :func:`narrowband_fraction`: the share of a PSD's power within a few bins of its prominent peaks [-]
  (near 1: a tonal limit cycle; near 0: broadband roughness-type response).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.errors import DataQualityError
from fivid.signal.welch import default_nperseg

__all__ = ["GrowthFit", "envelope_growth_rate", "growth_phase", "envelope", "dominant_frequency_track",
           "narrowband_fraction"]


@dataclass(frozen=True)
class GrowthFit:
    """Exponential fit of an envelope.

    Attributes
    ----------
    rate : float
        ``sigma`` [s-1] (> 0 growth, < 0 decay).
    stderr : float
        Standard error of ``rate`` from the fit's residuals [s-1] (the residuals of a log-envelope are
        correlated over about one period, so it is a lower bound on the true uncertainty).
    t_start, t_stop : float
        The fitted window [s].
    """

    rate: float
    stderr: float
    t_start: float
    t_stop: float


def _band_passed(x, fs: float, band, order: int = 4) -> np.ndarray:
    from scipy.signal import butter, sosfiltfilt

    x = np.asarray(x, dtype=float)
    x = x - x.mean()
    if band is None:
        return x
    lo, hi = (float(b) for b in band)
    if not 0 < lo < hi < fs / 2:
        raise DataQualityError(f"band [{lo:g}, {hi:g}] Hz must satisfy 0 < lo < hi < fs/2 = {fs / 2:g} Hz")
    return sosfiltfilt(butter(order, [lo, hi], btype="bandpass", fs=fs, output="sos"), x)


def _peaks(z: np.ndarray):
    """Indices and values of the local maxima of ``|z|`` (two per period of an oscillation)."""
    from scipy.signal import find_peaks

    a = np.abs(z)
    k = find_peaks(a)[0]
    k = k[a[k] > 0]
    return k, a[k]


def envelope(x, fs: float, band: tuple[float, float] | None = None, *, order: int = 4) -> np.ndarray:
    """Peak envelope of ``x`` [its units], after a zero-phase Butterworth band-pass ``band`` [Hz] if given.

    The mean is removed first (a static offset is no vibration); the peaks of ``|x|`` are joined by
    interpolation in log amplitude (exact between the peaks of an exponential), held flat beyond the first and
    last peak.
    """
    z = _band_passed(x, fs, band, order)
    k, a = _peaks(z)
    if k.size < 2:
        return np.abs(z)
    return np.exp(np.interp(np.arange(z.size), k, np.log(a)))


def envelope_growth_rate(t, x, *, band: tuple[float, float] | None = None, window=None,
                         edge: float | None = None) -> GrowthFit:
    """Exponential growth (or decay) rate of the envelope of ``x(t)`` [s-1].

    Parameters
    ----------
    t : array_like
        Uniform sample times [s].
    x : array_like
        The record (any units).
    band : (float, float), optional
        Band-pass around the mode of interest [Hz]; the whole signal otherwise.
    window : (float, float), optional
        Times [s] between which to fit. By default the interior of the record: an ``edge`` at each end is left
        out (the zero-phase filter's start and end transients).
    edge : float, optional
        Left out at each end [s]; default ``10 / (hi - lo)`` with a band (the filter's impulse response has
        decayed by then: 0.04 % rate error on the example below, 1 % with ``2 / (hi - lo)``), else 5 % of the
        record.

    Returns
    -------
    GrowthFit

    Examples
    --------
    >>> t = np.arange(20000) / 1e5
    >>> x = np.exp(30.0 * t) * np.sin(2 * np.pi * 2e3 * t)
    >>> round(envelope_growth_rate(t, x, band=(1e3, 4e3)).rate, 1)
    30.0
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    if t.ndim != 1 or t.shape != x.shape or t.size < 16:
        raise DataQualityError(f"t and x must be 1-D of one length >= 16, got {t.shape} and {x.shape}")
    dt = np.diff(t)
    if not np.all(dt > 0):
        raise DataQualityError("the sample times must increase")
    fs = 1.0 / float(np.median(dt))
    k, amp = _peaks(_band_passed(x, fs, band))
    if window is None:
        if edge is None:
            edge = 10.0 / (band[1] - band[0]) if band is not None else 0.05 * (t[-1] - t[0])
        window = (t[0] + edge, t[-1] - edge)
    sel = (t[k] >= window[0]) & (t[k] <= window[1])
    if sel.sum() < 4:
        raise DataQualityError(f"fewer than 4 envelope peaks in the fit window [{window[0]:g}, {window[1]:g}] s")
    tt, ly = t[k[sel]], np.log(amp[sel])
    A = np.column_stack([tt - tt.mean(), np.ones_like(tt)])
    coef, *_ = np.linalg.lstsq(A, ly, rcond=None)
    n = tt.size
    resid = ly - A @ coef
    s2 = float(resid @ resid) / max(n - 2, 1)
    stderr = float(np.sqrt(s2 / float(((tt - tt.mean()) ** 2).sum())))
    return GrowthFit(float(coef[0]), stderr, float(tt[0]), float(tt[-1]))


def growth_phase(t, env, *, low: float = 0.01, high: float = 0.3, linear_until: float | None = None):
    """The window ``(t0, t1)`` [s] of the last factor ``high/low`` of an envelope's exponential growth.

    A self-excited run grows exponentially from its initial disturbance until a nonlinearity (loss of contact,
    stick) saturates it into a limit cycle. The last factor ``high/low`` of growth before ``t1`` is the cleanest
    stretch: other modes excited by the disturbance have decayed relative to the growing one, and the
    amplitude is still small against the saturation. ``t1`` is where the envelope first reaches ``high`` times
    its peak, or ``linear_until`` [s] if earlier (e.g. the first time the contact leaves continuous sliding:
    beyond it the system is no longer the linear one a CEA describes). Returns None when the envelope does not
    rise by ``high/low`` before ``t1`` (no growth to fit).
    """
    t = np.asarray(t, dtype=float)
    env = np.asarray(env, dtype=float)
    k_peak = int(np.argmax(env))
    above = np.flatnonzero(env[:k_peak + 1] >= high * env[k_peak])
    if above.size == 0:
        return None
    k1 = int(above[0])
    if linear_until is not None:
        k1 = min(k1, int(np.searchsorted(t, linear_until)))
    if k1 < 2:
        return None
    below = np.flatnonzero(env[:k1] <= env[k1] * low / high)
    if below.size == 0:
        return None
    return float(t[int(below[-1])]), float(t[k1])


def dominant_frequency_track(x, fs: float, *, nperseg: int | None = None, noverlap: int | None = None,
                             band: tuple[float, float] | None = None):
    """Frequency of the strongest spectrogram bin in each time slice.

    Parameters
    ----------
    x : array_like
        The record.
    fs : float
        Sample rate [Hz].
    nperseg, noverlap : int, optional
        Spectrogram segment and overlap [samples] (Hann window; default segment
        :func:`fivid.signal.welch.default_nperseg` of the record, default overlap half a segment).
    band : (float, float), optional
        Only bins within this band [Hz].

    Returns
    -------
    times : ndarray
        Segment centres [s] from the first sample.
    frequency : ndarray
        Dominant frequency per segment [Hz] (resolution ``fs / nperseg``).
    power : ndarray
        Its PSD value [units^2 Hz-1].
    """
    from scipy.signal import spectrogram

    x = np.asarray(x, dtype=float)
    nperseg = default_nperseg(fs, x.size) if nperseg is None else int(nperseg)
    if x.size < nperseg:
        raise DataQualityError(f"the record ({x.size} samples) is shorter than nperseg = {nperseg}")
    f, tt, S = spectrogram(x, fs=fs, window="hann", nperseg=nperseg,
                           noverlap=nperseg // 2 if noverlap is None else noverlap, detrend="constant",
                           scaling="density")
    sel = np.ones(f.size, bool) if band is None else (f >= band[0]) & (f <= band[1])
    if not sel.any():
        raise DataQualityError(f"no spectrogram bin in the band {band} Hz")
    fb, Sb = f[sel], S[sel]
    k = np.argmax(Sb, axis=0)
    return tt, fb[k], Sb[k, np.arange(tt.size)]


def narrowband_fraction(frequency, psd, *, prominence_db: float = 10.0, half_width_bins: int = 3) -> float:
    """Share of the power [-] within ``half_width_bins`` of the PSD's peaks at least ``prominence_db`` prominent.

    Prominence is measured on ``10 log10(psd)``; a Hann-window Welch peak of a pure tone spans about 4 bins,
    so 3 bins either side hold a tone's power. 1: all power in tones; 0: no prominent peak.
    """
    from scipy.signal import find_peaks

    f = np.asarray(frequency, dtype=float)
    p = np.asarray(psd, dtype=float)
    if f.shape != p.shape or f.ndim != 1 or f.size < 3:
        raise DataQualityError("frequency and psd must be 1-D of one length >= 3")
    total = float(np.trapezoid(p, f))
    if not total > 0:
        return 0.0
    with np.errstate(divide="ignore"):
        lp = 10.0 * np.log10(np.maximum(p, np.finfo(float).tiny))
    peaks, _ = find_peaks(lp, prominence=prominence_db)
    mask = np.zeros(p.size, bool)
    for k in peaks:
        mask[max(0, k - half_width_bins):k + half_width_bins + 1] = True
    return float(np.trapezoid(np.where(mask, p, 0.0), f) / total)
