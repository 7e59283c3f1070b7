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
  one-third-octave band of the PSD scores (IEC 61260-1 base-10 bands lying inside the PSD's frequency range, at
  least one bin wide, bins weighted by the fraction of their rectangle inside the band:
  :func:`fivid.signal.levels.third_octave_weights`) and, last, over the whole PSD range
  (:func:`fivid.signal.levels.bin_weights`) -- so the errors qualify the scores' own band levels;
- ``psd_peak_frequency``: the frequency of each prominent peak of the finest mesh's PSD (prominence >= 20 dB:
  a single Welch bin of broadband noise is chi2 with 2 degrees of freedom, 20 dB above a neighbouring dip has
  probability below 1e-4 per bin pair), located to a fraction of a bin by a parabola through the log PSD at the
  peak bin and its neighbours (exact for a Gaussian peak), matched to the nearest peak of the same kind on the
  coarser meshes (within a tenth of the peak frequency): :func:`fivid.signal.peaks.track_peaks`.

Time step: points that differ only in ``time_step`` (fractions of the critical step) are compared to the smallest
step: the log-spectral distance of their PSDs (dB) and their level difference (dB) over the PSD's range, as the
solver's own time-step halving (:func:`fivid.signal.compare.band_distance`); with three or more steps the same
observed orders as for the mesh (``order``, with ``time_step`` in the place of ``h``) for the band levels and the
peak frequencies.
"""

from __future__ import annotations

import numpy as np

from fivid.signal.compare import band_distance, band_levels_db
from fivid.signal.levels import bin_weights, third_octave_weights
from fivid.signal.peaks import track_peaks

__all__ = ["observed_order", "convergence_summary", "band_level_grid", "BAND_LEVEL_REFERENCE"]

#: reference power of the band levels [(unit)^2]: 1e-12, i.e. re 1e-6 of the response unit (ISO 1683's
#: acceleration reference for m s-2)
BAND_LEVEL_REFERENCE = 1e-12

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


def band_level_grid(f) -> tuple[list[tuple[float, float]], np.ndarray]:
    """The bands of ``band_level_db`` on the frequency grid ``f`` [Hz]: the scores' one-third-octave bands inside
    ``[f[0], f[-1]]`` (at least one bin wide) and, last, the whole range; ``(bands [Hz], weights (bin, band)
    [Hz])``."""
    f = np.asarray(f, float)
    lo, hi = float(f[0]), float(f[-1])
    thirds, weights = third_octave_weights(f, lo, hi, min_bins=1.0)
    bands = [(float(a), float(b)) for a, b in zip(thirds["lower"], thirds["upper"])] + [(lo, hi)]
    return bands, np.column_stack([weights, bin_weights(f, lo, hi)])


def _spectral_series(ds, idx, x) -> dict:
    """Observed orders of the band levels and the PSD peak frequencies over three points ``idx`` (positions in
    ``ds``) whose refinement parameter is ``x`` (element size or time step; any order)."""
    f = ds["frequency"].values
    psd = ds["psd"].values[idx]
    bands, weights = band_level_grid(f)
    levels = band_levels_db(psd, weights, reference=BAND_LEVEL_REFERENCE)  # (3, band)
    out = {"band_level_db": [dict(observed_order(x, levels[:, b]), band=list(bands[b])) for b in range(len(bands))]}
    tracks = track_peaks(f, psd, int(np.argmin(x)), prominence_db=PEAK_PROMINENCE_DB,
                         match_prominence_db=MATCH_PROMINENCE_DB, window=MATCH_WINDOW)
    out["psd_peak_frequency"] = [dict(observed_order(x, found), peak=f_ref) for f_ref, found in tracks]
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
            f = ds["frequency"].values
            p_ref = ds["psd"].values[pts[members[0][1]]]
            for frac, i in members[1:]:
                lsd, level = band_distance(f, p_ref, ds["psd"].values[pts[i]], (f[0], f[-1]))
                steps.append({"conditions": dict(key), "time_step": frac, "reference_time_step": members[0][0],
                              "lsd_db": lsd, "level_diff_db": level})
            if len(members) >= 3 and "psd" in ds:  # the three smallest steps: observed orders in the step
                three = members[:3]
                steps_order.append({"conditions": dict(key), "time_step": [m[0] for m in three],
                                    **_spectral_series(ds, [pts[i] for _, i in three], [m[0] for m in three])})
        if steps:
            out["time_step"] = steps
        if steps_order:
            out["time_step_order"] = steps_order
    return out or None
