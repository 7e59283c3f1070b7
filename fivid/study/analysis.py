"""What a transient did: growth rate, onset, limit cycle, stick share, and the regime it falls in (seed 002).

Regimes (decided in this order, from the record's contact states and its envelope):

``stick_slip``
    the record's second half has stick phases: samples where the contact sticks as a whole (at least
    ``GROSS_STICK`` of it), in at least ``STICK_SHARE`` of them;
``mode_coupling``
    otherwise, if in sliding the envelope grows exponentially (a fitted growth phase with rate > 3 standard
    errors) and then saturates (limit cycle; its vibration speed may exceed a slow sliding speed, so parts of
    the contact stick within each cycle: seed 002's 10 rpm ring);
``stable``
    otherwise: the disturbance decays or no growth is found.

The growth rate is fitted on the last factor 30 of the envelope's rise (:func:`fivid.signal.transient.growth_phase`)
from the first continuously sliding sample (a contact may stick while the drive winds it up) and before the
contact first leaves continuous sliding after it: beyond it the system is not the linear one a CEA
describes. ``onset_time`` is the end of that window: when the instability has grown to where the
nonlinearity takes over. The limit cycle is the last quarter of the record: its dominant frequency (Welch PSD
peak) and RMS.
"""

from __future__ import annotations

import numpy as np

from fivid.signal.spectral import welch_density
from fivid.signal.transient import envelope, envelope_growth_rate, growth_phase

__all__ = ["GROSS_STICK", "STICK_SHARE", "analyse_transient"]

#: share of stick-phase samples (second half of the record) from which a run is called stick-slip
STICK_SHARE = 0.01
#: share of the contact that sticks at once for a sample to be in a stick phase (the contact as a whole sticks;
#: a limit cycle whose vibration speed exceeds a slow sliding speed sticks locally within each cycle)
GROSS_STICK = 0.9


def _peak_frequency(x, fs: float) -> float:
    n = min(x.size, 4096)
    f, p = welch_density(x - x.mean(), fs, nperseg=n)
    return float(f[1:][np.argmax(p[1:])])


def analyse_transient(t, x, *, sliding=None, stick=None) -> dict:
    """Growth, onset, limit cycle and regime of a response record.

    Parameters
    ----------
    t : array_like
        Sample times [s], uniform.
    x : array_like
        Response (displacement, velocity or acceleration; any units).
    sliding : array_like of bool, optional
        Per sample: the contact slides (the system is the CEA's linearised one). The growth fit runs from the
        first True to the first False after it.
    stick : array_like of float, optional
        Per sample: share of the contact sticking (0..1).

    Returns
    -------
    dict
        ``regime``; ``growth_rate`` [s-1] and ``growth_rate_stderr`` (NaN without a growth phase);
        ``onset_time`` [s] (NaN unless mode coupling); ``frequency`` [Hz] and ``amplitude`` (RMS, units of x) of
        the last quarter; ``stick_fraction`` [-] over the second half.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    fs = 1.0 / float(np.median(np.diff(t)))
    n = t.size
    tail = x[3 * n // 4:]
    f_lc = _peak_frequency(tail, fs) if tail.size >= 16 else float("nan")
    f_all = _peak_frequency(x, fs)
    second = np.asarray(stick, dtype=float)[n // 2:] if stick is not None else np.zeros(0)
    stick_fraction = float(np.mean(second)) if second.size else 0.0
    stick_phases = float(np.mean(second >= GROSS_STICK)) if second.size else 0.0
    out = {"frequency": f_lc, "amplitude": float(np.sqrt(np.mean((tail - tail.mean()) ** 2))),
           "stick_fraction": stick_fraction, "growth_rate": float("nan"), "growth_rate_stderr": float("nan"),
           "onset_time": float("nan")}
    band = (f_all / 1.5, min(f_all * 1.5, 0.45 * fs)) if f_all > 0 else None
    linear_until = None
    t_slide = t[0]
    if sliding is not None:
        sl = np.asarray(sliding, dtype=bool)
        # the linear (CEA) system is the one in continuous sliding: from the first sliding sample (a contact that
        # sticks while the drive winds it up, like a held ring on a slow shaft, slides only later) to the first
        # stick or opening after it
        first = np.flatnonzero(sl)
        if first.size:
            t_slide = float(t[first[0]])
            off = np.flatnonzero(~sl[first[0]:])
            linear_until = float(t[first[0] + off[0]]) if off.size else None
        else:
            linear_until = float(t[0])
    growing = False
    if band is not None and band[0] < band[1]:
        env = envelope(x, fs, band)
        edge = 10.0 / (band[1] - band[0])  # the zero-phase band-pass's start/end transients (signal.transient)
        usable = (t <= t[-1] - edge) & (t >= t_slide)  # the window's start is the envelope's 1 %: the start edge
        # is harmless
        window = growth_phase(t[usable], env[usable], linear_until=linear_until) if usable.sum() > 16 else None
        if window is not None and window[1] - window[0] > 2.0 / f_all:
            fit = envelope_growth_rate(t, x, band=band, window=window)
            growing = fit.rate > 3.0 * fit.stderr
            if growing:
                out["onset_time"] = window[1]
        else:
            # no full growth phase in the record: fit the interior (before the first stick or opening); a
            # significant positive rate is a growth that has not saturated yet (no onset time)
            stop = t[-1] - edge if linear_until is None else min(t[-1] - edge, linear_until)
            start = max(t[0] + edge, t_slide)
            fit = envelope_growth_rate(t, x, band=band, window=(start, stop)) if stop > start + edge else None
            growing = fit is not None and fit.rate > 3.0 * fit.stderr
        if fit is not None:
            out.update(growth_rate=fit.rate, growth_rate_stderr=fit.stderr)
    if stick_phases >= STICK_SHARE:
        out["regime"] = "stick_slip"
    elif growing:
        out["regime"] = "mode_coupling"
    else:
        out["regime"] = "stable"
    return out
