"""Mesh and time-step convergence of a study (a ``mesh`` and/or ``time_step`` sweep; DESIGN §9).

Mesh: for a quantity ``q(h)`` computed on three meshes of element size ``h1 < h2 < h3`` the model
``q(h) = q_inf + C h^p`` has the observed order ``p`` solving ``(q3 - q2)/(q2 - q1) = (h3^p - h2^p)/(h2^p - h1^p)``
(``r^p`` for a constant refinement ratio ``r``) and the Richardson extrapolation
``q_inf = q1 - C h1^p``; the finest mesh's discretisation error is estimated as ``|q1 - q_inf|``. When the three
values do not converge monotonically the order is undefined (reported null) and the error is taken as
``|q1 - q2|``. Applied to the preloaded modal frequencies, the response level of the steady part and its
dominant frequency (the last is resolution-limited by the Welch bin, ``fs / nperseg``).

Time step: points that differ only in ``time_step`` (fractions of the critical step) are compared to the smallest
step: the log-spectral distance of their PSDs (dB) and their level difference (dB), as the solver's own
time-step study (:func:`fivid.solver.time_step_study`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["observed_order", "convergence_summary"]


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
        ``|q1 - q2|`` without an order), ``values`` and ``h`` (finest first).

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
    out = {"h": [h1, h2, h3], "values": [q1, q2, q3], "order": None, "extrapolated": None, "error": abs(q1 - q2)}
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
    out.update(order=float(p), extrapolated=float(q_inf), error=abs(q1 - q_inf))
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
            meshes.append(entry)
        if meshes:
            out["mesh"] = meshes
    if "time_step" in axes and "psd" in ds:
        steps = []
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
        if steps:
            out["time_step"] = steps
    return out or None
