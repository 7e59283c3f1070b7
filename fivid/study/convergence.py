"""Mesh and time-step convergence of a study (a ``mesh`` and/or ``time_step`` sweep; DESIGN §9).

Mesh: for a quantity ``q(h)`` computed on three meshes of element size ``h1 < h2 < h3`` the model
``q(h) = q_inf + C h^p`` has the observed order ``p`` solving ``(q3 - q2)/(q2 - q1) = (h3^p - h2^p)/(h2^p - h1^p)``
(``r^p`` for a constant refinement ratio ``r``) and the Richardson extrapolation
``q_inf = q1 - C h1^p``; the finest mesh's discretisation error is estimated as ``|q1 - q_inf|``. When the three
values do not converge monotonically the order is undefined (reported null) and the error is taken as
``|q1 - q2|``; ``deviation`` gives every mesh's signed distance from the extrapolated value (from the finest
value without an order), so the error of a coarser mesh used elsewhere (the calibration pipeline's 2 mm rig)
can be read off. Applied to the preloaded modal frequencies, the response level of the steady part and its
dominant frequency (the last is resolution-limited by the Welch bin, ``fs / nperseg``) and, with a ``psd``
task, to

- ``band_level_db``: the PSD's level [dB re 1e-6 of the response unit, i.e. re 1e-12 (unit)^2] in each
  one-third-octave band (base 2: centres 1000 * 2^(k/3) Hz, edges centre * 2^(-1/6) and centre * 2^(1/6), clipped
  to the PSD's frequency range, at least two bins) and, last, over the whole PSD range;
- ``psd_peak_frequency``: the frequency of each prominent peak of the finest mesh's PSD (prominence >= 20 dB:
  a single Welch bin of broadband noise is chi2 with 2 degrees of freedom, 20 dB above a neighbouring dip has
  probability below 1e-4 per bin pair), located to a fraction of a bin by a parabola through the log PSD at the
  peak bin and its neighbours (exact for a Gaussian peak), matched to the nearest peak of the same kind on the
  coarser meshes (within a quarter of the peak frequency).

Time step: points that differ only in ``time_step`` (fractions of the critical step) are compared to the smallest
step: the log-spectral distance of their PSDs (dB) and their level difference (dB), as the solver's own
time-step study (:func:`fivid.solver.time_step_study`); with three or more steps the same observed orders as
for the mesh (``order``, with ``time_step`` in the place of ``h``) for the band levels and the peak
frequencies.
"""

from __future__ import annotations

import numpy as np

__all__ = ["observed_order", "convergence_summary", "third_octave_bands", "band_levels_db", "psd_peaks"]

#: prominence [dB] of a PSD peak that is tracked (module docstring: a noise bin pair reaches it with p < 1e-4)
PEAK_PROMINENCE_DB = 20.0
#: prominence [dB] enough to find an already known peak again on a coarser mesh or a longer step
MATCH_PROMINENCE_DB = 6.0
#: largest relative distance of a matched peak from the finest one's frequency
MATCH_WINDOW = 0.1


def observed_order(h, q) -> dict:
    """Observed order, extrapolated value and the finest value's error from three (h, q) pairs.

    Parameters
    ----------
    h : sequence of 3 floats
        Element sizes [m], any order (sorted here).
    q : sequence of 3 floats
        The quantity on those meshes.

    Returns
    -------
    dict
        ``order`` (None if not monotone), ``extrapolated``, ``error`` (``|q_finest - extrapolated|``, or
        ``|q1 - q2|`` without an order), ``values`` and ``h`` (finest first), ``deviation`` (each value minus the
        extrapolated one, or minus the finest value without an order; finest first).

    Examples
    --------
    >>> r = observed_order([1.0, 0.5, 0.25], [1 + 0.3 * h**2 for h in (1.0, 0.5, 0.25)])
    >>> round(r["order"], 6), round(r["extrapolated"], 9)
    (2.0, 1.0)
    """
    from scipy.optimize import brentq

    order = np.argsort(h)
    h1, h2, h3 = (float(h[i]) for i in order)
    q1, q2, q3 = (float(q[i]) for i in order)
    out = {"h": [h1, h2, h3], "values": [q1, q2, q3], "order": None, "extrapolated": None, "error": abs(q1 - q2),
           "deviation": [0.0, q2 - q1, q3 - q1]}
    d21, d32 = q2 - q1, q3 - q2
    if not (h1 < h2 < h3) or d21 == 0 or d32 / d21 <= 0:
        return out
    ratio = d32 / d21

    def g(p):
        return (h3**p - h2**p) / (h2**p - h1**p) - ratio

    lo, hi = 0.05, 12.0
    if g(lo) * g(hi) > 0:
        return out
    p = brentq(g, lo, hi, xtol=1e-12)
    c = d21 / (h2**p - h1**p)
    q_inf = q1 - c * h1**p
    out.update(order=float(p), extrapolated=float(q_inf), error=abs(q1 - q_inf),
               deviation=[float(q - q_inf) for q in (q1, q2, q3)])
    return out


def third_octave_bands(f_lo: float, f_hi: float) -> list[tuple[float, float]]:
    """One-third-octave bands [Hz] (base 2: centres 1000 * 2^(k/3), edges centre * 2^(-+1/6)) overlapping
    ``[f_lo, f_hi]``, clipped to it.

    >>> [(round(a), round(b)) for a, b in third_octave_bands(800.0, 1500.0)]
    [(800, 891), (891, 1122), (1122, 1414), (1414, 1500)]
    """
    out = []
    for k in range(-36, 37):
        c = 1000.0 * 2.0 ** (k / 3.0)
        lo, hi = c * 2.0 ** (-1.0 / 6.0), c * 2.0 ** (1.0 / 6.0)
        if hi > f_lo and lo < f_hi:
            out.append((max(lo, f_lo), min(hi, f_hi)))
    return out


def band_levels_db(f, p, bands) -> list[float]:
    """Level [dB re 1e-12 (unit)^2, i.e. re 1e-6 of the PSD's amplitude unit] of the PSD ``p(f)`` in each band
    (sum of the bins whose centre is inside, times the bin width)."""
    f, p = np.asarray(f, float), np.asarray(p, float)
    df = float(np.median(np.diff(f)))
    out = []
    for lo, hi in bands:
        power = float(np.sum(p[(f >= lo) & (f <= hi)])) * df
        out.append(10.0 * np.log10(power / 1e-12) if power > 0 else float("-inf"))
    return out


def psd_peaks(f, p, prominence_db: float = PEAK_PROMINENCE_DB) -> np.ndarray:
    """Frequencies [Hz] of the peaks of ``p(f)`` with at least ``prominence_db`` of prominence, each refined by the
    parabola through the log PSD at the peak bin and its two neighbours.

    >>> f = np.arange(0.0, 2000.0, 25.0)
    >>> p = 1e-6 + np.exp(-0.5 * ((f - 1010.0) / 30.0) ** 2)  # a Gaussian peak between two bins
    >>> [round(float(x), 3) for x in psd_peaks(f, p)]
    [1010.0]
    """
    from scipy.signal import find_peaks

    f, p = np.asarray(f, float), np.asarray(p, float)
    ok = p > 0
    level = np.full(p.shape, -np.inf)
    level[ok] = 10.0 * np.log10(p[ok])
    level[~ok] = level[ok].min() if ok.any() else 0.0
    idx, _ = find_peaks(level, prominence=prominence_db)
    df = float(np.median(np.diff(f)))
    out = []
    for k in idx:
        a, b, c = level[k - 1], level[k], level[k + 1]
        den = a - 2.0 * b + c
        out.append(f[k] + (0.5 * (a - c) / den * df if den < 0 else 0.0))
    return np.array(out)


def _spectral_series(ds, idx, x) -> dict:
    """Observed orders of the band levels and the PSD peak frequencies over three points ``idx`` (positions in
    ``ds``) whose refinement parameter is ``x`` (element size or time step; any order)."""
    f = ds["frequency"].values
    psd = ds["psd"].values[idx]
    bands = [b for b in third_octave_bands(float(f[0]), float(f[-1])) if np.count_nonzero((f >= b[0]) & (f <= b[1])) >= 2]
    bands.append((float(f[0]), float(f[-1])))
    levels = np.array([band_levels_db(f, p, bands) for p in psd])  # (3, band)
    out = {"band_level_db": [dict(observed_order(x, levels[:, b]), band=list(bands[b])) for b in range(len(bands))]}
    finest = int(np.argmin(x))
    peaks = []
    for f_ref in psd_peaks(f, psd[finest]):
        found = []
        for k in range(len(idx)):
            cand = psd_peaks(f, psd[k], MATCH_PROMINENCE_DB) if k != finest else np.array([f_ref])
            near = cand[np.argmin(np.abs(cand - f_ref))] if cand.size else np.nan
            found.append(near if abs(near - f_ref) <= MATCH_WINDOW * f_ref else np.nan)
        if np.all(np.isfinite(found)):
            peaks.append(dict(observed_order(x, found), peak=float(f_ref)))
    out["psd_peak_frequency"] = peaks
    return out


def _groups(table, done, vary: str):
    """Points grouped by every condition except ``vary``: {other conditions: [(value of vary, point index)]}."""
    groups: dict = {}
    for i in done:
        cond = table[i]
        key = tuple(sorted((k, float(v)) for k, v in cond.items() if k != vary))
        groups.setdefault(key, []).append((float(cond[vary]), i))
    return groups


def convergence_summary(ds, table, done) -> dict | None:
    """The ``convergence`` block of a study summary (None without a mesh or time_step axis)."""
    axes = set(table[0]) if table else set()
    if not ({"mesh", "time_step"} & axes) or ds.sizes.get("point", 0) == 0:
        return None
    out = {}
    pts = {int(p): k for k, p in enumerate(ds["point"].values)}
    if "mesh" in axes and "element_size" in ds:
        meshes = []
        for key, members in _groups(table, done, "mesh").items():
            if len(members) < 3:
                continue
            members = sorted(members)[-3:]  # the three finest
            idx = [pts[i] for _, i in members]
            h = [float(ds["element_size"].values[k]) for k in idx]
            entry = {"conditions": dict(key), "element_size": sorted(h)}
            if "mode_frequency" in ds:
                f = ds["mode_frequency"].values[idx]  # (3, mode)
                entry["mode_frequency"] = [dict(observed_order(h, f[:, m]), mode=m + 1) for m in range(f.shape[1])]
            for name in ("level_db", "response_frequency"):
                if name in ds:
                    entry[name] = observed_order(h, ds[name].values[idx])
            if "psd" in ds:
                entry.update(_spectral_series(ds, idx, h))
            meshes.append(entry)
        if meshes:
            out["mesh"] = meshes
    if "time_step" in axes and "psd" in ds:
        steps, steps_order = [], []
        for key, members in _groups(table, done, "time_step").items():
            if len(members) < 2:
                continue
            members = sorted(members)
            ref = pts[members[0][1]]
            p_ref = ds["psd"].values[ref]
            for frac, i in members[1:]:
                p = ds["psd"].values[pts[i]]
                ok = (p > 0) & (p_ref > 0)
                d = 10 * np.log10(p[ok] / p_ref[ok])
                steps.append({"conditions": dict(key), "time_step": frac, "reference_time_step": members[0][0],
                              "lsd_db": float(np.sqrt(np.mean(d * d))),
                              "level_diff_db": float(10 * np.log10(p.sum() / p_ref.sum()))})
            if len(members) >= 3 and "psd" in ds:  # the three smallest steps: observed orders in the step
                three = members[:3]
                steps_order.append({"conditions": dict(key), "time_step": [m[0] for m in three],
                                    **_spectral_series(ds, [pts[i] for _, i in three], [m[0] for m in three])})
        if steps:
            out["time_step"] = steps
        if steps_order:
            out["time_step_order"] = steps_order
    return out or None
