"""Profile parameters of ISO 21920-2:2021 (ISO 4287:1997) and DIN 4768, on arrays.

Pure numpy functions of a roughness (or waviness) profile ``r`` [m], sampled every ``step`` [m],
whose mean line is zero. The driver :func:`fivid.surface.evaluate_profile` prepares ``r`` (window,
form removal, filter) and labels the results.

Definitions (``n`` samples over the evaluation length ``L``):

=========  ==============================================================  ======================
symbol     definition                                                      clause
=========  ==============================================================  ======================
Ra         mean of ``|r|``                                                 ISO 4287 4.2.1
Rq         root mean square of ``r``                                       ISO 4287 4.2.2
Rsk        ``mean(r³) / Rq³``                                              ISO 4287 4.2.3
Rku        ``mean(r⁴) / Rq⁴``                                              ISO 4287 4.2.4
Rp, Rv     highest peak ``max r``, deepest valley ``-min r``               ISO 4287 4.1.1, 4.1.2
Rt         ``max r - min r`` over the evaluation length                    ISO 4287 4.1.6
Rz         mean over the sampling lengths of their ``max r - min r``       ISO 4287 4.1.3
RzDIN      mean over 5 equal segments of L of their ``max r - min r``      DIN 4768:1990
Rsm        mean width of the profile elements                              ISO 4287 4.3.1
Rdq        RΔq, rms of the local slope ``dr/dx`` (7-point formula)         ISO 4287 4.4.1
=========  ==============================================================  ======================

``attack_angle`` is the mean of ``|atan(dr/dx)|`` [rad], the mean absolute angle at which the
asperity flanks meet a sliding counter-face (no ISO symbol).
"""

from __future__ import annotations

import numpy as np

__all__ = ["amplitude_parameters", "peak_to_valley_mean", "local_slope", "slope_parameters",
           "profile_element_widths", "mean_element_width"]


def amplitude_parameters(r) -> dict[str, float]:
    """Ra, Rq, Rp, Rv, Rt [m] and Rsk, Rku [1] of ``r`` [m] (Rsk, Rku NaN when Rq = 0)."""
    r = np.asarray(r, dtype=np.float64)
    rq = float(np.sqrt(np.mean(r**2)))
    out = {"Ra": float(np.mean(np.abs(r))), "Rq": rq, "Rp": float(r.max()), "Rv": float(-r.min()),
           "Rt": float(r.max() - r.min())}
    out["Rsk"] = float(np.mean(r**3) / rq**3) if rq > 0 else float("nan")
    out["Rku"] = float(np.mean(r**4) / rq**4) if rq > 0 else float("nan")
    return out


def peak_to_valley_mean(r, n_segments: int, *, segment_points: int | None = None) -> float:
    """Mean over ``n_segments`` consecutive segments of ``max - min`` [m].

    With ``segment_points`` the segments have that many samples each, from the start (Rz over
    sampling lengths; samples after ``n_segments * segment_points`` are not used); otherwise ``r``
    is split into ``n_segments`` parts of equal length (±1 sample; RzDIN).
    """
    r = np.asarray(r, dtype=np.float64)
    if segment_points is not None:
        parts = np.split(r[: n_segments * segment_points], n_segments)
    else:
        parts = np.array_split(r, n_segments)
    return float(np.mean([p.max() - p.min() for p in parts]))


def local_slope(r, step: float) -> np.ndarray:
    """dr/dx [1] at the interior samples (3 dropped at each end), by the 7-point formula of ISO 4287 4.4::

        dr/dx_i = (r[i+3] - 9 r[i+2] + 45 r[i+1] - 45 r[i-1] + 9 r[i-2] - r[i-3]) / (60 Δx)

    Exact for polynomials of degree 6; error O(Δx⁶) for smooth profiles.
    """
    r = np.asarray(r, dtype=np.float64)
    n = r.size
    return (r[6:] - 9 * r[5:n - 1] + 45 * r[4:n - 2] - 45 * r[2:n - 4] + 9 * r[1:n - 5] - r[: n - 6]) / (60 * step)


def slope_parameters(r, step: float) -> dict[str, float]:
    """Rdq (RΔq, rms slope [rad for small slopes]) and attack_angle (mean ``|atan(slope)|`` [rad])."""
    s = local_slope(r, step)
    return {"Rdq": float(np.sqrt(np.mean(s**2))), "attack_angle": float(np.mean(np.abs(np.arctan(s))))}


def _zero_crossings(r, step: float) -> np.ndarray:
    """Positions [m from the first sample] where r changes sign (linear interpolation; 0 counts as +)."""
    positive = r >= 0
    i = np.flatnonzero(positive[1:] != positive[:-1])
    return (i + r[i] / (r[i] - r[i + 1])) * step


def profile_element_widths(r, step: float, *, height_threshold: float, width_threshold: float) -> np.ndarray:
    """Widths Xs [m] of the profile elements of ``r`` (ISO 4287 3.2.4, 4.3.1; ISO 21920-2 3.3.3).

    The profile is cut at its crossings of the mean line into parts above (peaks) and below
    (valleys). A part whose height (max ``|r|``) is below ``height_threshold`` or whose width is
    below ``width_threshold`` does not count: it joins its neighbours (smallest first, repeated until
    every part passes), so an element is a peak that passes the thresholds and the valley that
    follows it. Parts cut by the ends of the record are not used. Each returned width is the width
    of one peak + adjacent valley; an odd last part is left out.
    """
    r = np.asarray(r, dtype=np.float64)
    crossings = _zero_crossings(r, step)
    if crossings.size < 3:
        return np.empty(0)
    widths = list(np.diff(crossings))
    edges = np.round(crossings / step).astype(int)
    heights = [float(np.max(np.abs(r[a:b + 1]))) for a, b in zip(edges[:-1], edges[1:])]
    while len(widths) > 1:
        fails = [k for k in range(len(widths)) if heights[k] < height_threshold or widths[k] < width_threshold]
        if not fails:
            break
        k = min(fails, key=lambda j: heights[j])
        lo, hi = max(k - 1, 0), min(k + 1, len(widths) - 1)
        merged_width = sum(widths[lo:hi + 1])
        merged_height = max(heights[j] for j in range(lo, hi + 1) if j != k)
        widths[lo:hi + 1] = [merged_width]
        heights[lo:hi + 1] = [merged_height]
    pairs = len(widths) // 2
    w = np.asarray(widths[: 2 * pairs])
    return w[0::2] + w[1::2]


def mean_element_width(r, step: float, *, height_threshold: float, width_threshold: float) -> float:
    """Rsm [m]: mean of :func:`profile_element_widths` (NaN when there is no complete element)."""
    w = profile_element_widths(r, step, height_threshold=height_threshold, width_threshold=width_threshold)
    return float(w.mean()) if w.size else float("nan")
