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

Seed 002's own stick-slip (its p. 7, Fig. 8 right: a zone of sticking, the passage between stick and slip along
the contact, and a response with "peaks corresponding to all the system modes" instead of the mode-coupling's
"harmonic vibration at the unstable mode frequency") needs the contact's state node by node:
:func:`zone_stick_slip` (the ring kind, :mod:`fivid.study.kinds.ring`, decides its regimes with it).

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

__all__ = ["GROSS_STICK", "STICK_SHARE", "HARMONIC_SHARE", "analyse_transient", "harmonic_share", "sustained_sticks",
           "zone_stick_slip"]

#: share of stick-phase samples (second half of the record) from which a run is called stick-slip
STICK_SHARE = 0.01
#: share of the contact that sticks at once for a sample to be in a stick phase (the contact as a whole sticks;
#: a limit cycle whose vibration speed exceeds a slow sliding speed sticks locally within each cycle)
GROSS_STICK = 0.9
#: share of the response power at its dominant frequency and that frequency's harmonics below which the response is
#: not harmonic (seed 002's stick-slip "peaks corresponding to all the system modes", against mode coupling's
#: "harmonic vibration at the unstable mode frequency"): the majority of the power elsewhere
HARMONIC_SHARE = 0.5


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


def harmonic_share(x, fs: float, *, lo: float = 500.0, nperseg: int = 4096) -> tuple[float, float]:
    """Dominant frequency [Hz] of a record and the share [-] of its power (above ``lo`` [Hz]) at that frequency
    and its integer multiples.

    Welch PSD (Hann, ``nperseg`` samples or the record, half overlap; :func:`fivid.signal.spectral.welch_density`);
    the dominant frequency ``f0`` is the largest bin above ``lo``; the k-th harmonic's power is summed over
    ``2 + ceil(k / 2)`` bins either side of ``k f0`` (the Hann main lobe's half width, 2 bins, plus the k-fold
    growth of ``f0``'s half-bin quantisation). A periodic record of any wave shape gives 1 (to the window's
    sidelobe leakage, < 1e-3), n incommensurate tones of equal power 1/n.
    """
    x = np.asarray(x, dtype=float)
    f, p = welch_density(x - x.mean(), fs, nperseg=min(nperseg, x.size))
    df = float(f[1] - f[0])
    above = f >= lo
    total = float(np.sum(p[above]))
    if not total > 0:
        return float("nan"), float("nan")
    f0 = float(f[above][np.argmax(p[above])])
    comb = np.zeros(f.size, dtype=bool)
    for k in range(1, int(f[-1] / f0) + 1):
        comb |= np.abs(f - k * f0) <= (2 + np.ceil(k / 2)) * df
    return f0, float(np.sum(p[above & comb]) / total)


def sustained_sticks(stick, period: float) -> dict:
    """Stick phases of a contact that are not the stick within each cycle of a harmonic vibration.

    Parameters
    ----------
    stick : array_like of bool, shape (time, node)
        Per sample and contact node: the node sticks.
    period : float
        The dominant vibration's period [samples].

    Returns
    -------
    dict
        ``count``: runs of consecutive stick samples of one node longer than ``period`` that end inside the record
        (the node slips again: a stick -> slip passage); ``nodes``: how many nodes have one; ``longest``: the
        longest stick run of any node [periods].

    Notes
    -----
    A node of a harmonic limit cycle whose vibration speed exceeds the sliding speed sticks once in each cycle and
    must slip back within the same cycle to vibrate, so its stick lasts less than one period by construction; a
    stick longer than a period is a stick zone (seed 002, p. 7: "a zone of sticking between the two solids").
    """
    b = np.asarray(stick, dtype=bool)
    if b.ndim != 2:
        raise ValueError(f"stick must be (time, node), got shape {b.shape}")
    edges = np.diff(np.concatenate([np.zeros((1, b.shape[1]), np.int8), b.astype(np.int8),
                                    np.zeros((1, b.shape[1]), np.int8)]), axis=0)
    count, nodes, longest = 0, 0, 0
    for j in range(b.shape[1]):
        start, end = np.flatnonzero(edges[:, j] == 1), np.flatnonzero(edges[:, j] == -1)
        length = end - start
        if length.size:
            longest = max(longest, int(length.max()))
        n = int(np.sum((length > period) & (end < b.shape[0])))
        count += n
        nodes += n > 0
    return {"count": count, "nodes": nodes, "longest": longest / period}


def zone_stick_slip(x, fs: float, stick) -> dict:
    """Seed 002's stick-slip regime, by the paper's own marks (Massi et al., DINAME 2013, p. 7, Fig. 8 right: at
    mu 1 "the stress concentration in a localized zone of the contact ... brings to a zone of sticking between the
    two solids; the passage between stick and slip along the contact surface during the rotation of the inner disc
    excites the system dynamics; the PSD of the acceleration ... shows a complex dynamics with peaks corresponding to
    all the system modes. In this case the dynamic modal instability is replaced by a different unstable state
    characterized by stick-slip phenomena"; against mu 0.3: "a harmonic vibration at the unstable mode frequency").

    Both marks must hold: the contact has a stick zone that releases (:func:`sustained_sticks`: a node stuck
    longer than one period of the dominant vibration, then slipping), and the response is not harmonic
    (:func:`harmonic_share` below :data:`HARMONIC_SHARE`). The paper does not ask the contact to stick as a whole
    (:data:`GROSS_STICK`, :func:`analyse_transient`'s rule, made for small contacts).

    Parameters
    ----------
    x : array_like, shape (time,)
        Response record (acceleration [m s-2] or any), uniformly sampled.
    fs : float
        Sample rate [Hz].
    stick : array_like of bool, shape (time, node)
        Per sample and contact node: the node sticks.

    Returns
    -------
    dict
        ``stick_slip`` (bool), ``dominant_frequency`` [Hz], ``harmonic_share`` [-], ``sustained_sticks`` (count),
        ``sustained_stick_nodes``, ``longest_stick_periods`` [periods of the dominant frequency].
    """
    f0, share = harmonic_share(x, fs)
    runs = sustained_sticks(stick, fs / f0 if f0 > 0 else np.inf)
    return {"stick_slip": bool(share < HARMONIC_SHARE and runs["count"] > 0), "dominant_frequency": f0,
            "harmonic_share": share, "sustained_sticks": runs["count"], "sustained_stick_nodes": runs["nodes"],
            "longest_stick_periods": runs["longest"]}
