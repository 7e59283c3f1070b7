"""The weak/strong kind (``kind: weak_strong``, seed 001): the contact's coupling over the normal load -- the
coupling indicator kappa of the preloaded modes per point (:mod:`fivid.study.coupling`), the load where it
crosses the weak/strong threshold, and the response's power law over load, velocity and roughness."""

from __future__ import annotations

import numpy as np

from fivid.study.axes import AXES
from fivid.study.coupling import WEAK_STRONG_THRESHOLD
from fivid.study.kinds.sweep import FeSweep

__all__ = ["WeakStrong", "KIND", "transitions"]


class WeakStrong(FeSweep):
    """Weak and strong contact over the normal load (:class:`fivid.study.kind.StudyKind`)."""

    name = "weak_strong"
    description = "weak and strong contact over the normal load (seed 001): coupling indicator, transition load"

    def guess(self, data: dict) -> bool:
        """An FE study computing modes (the coupling indicator comes from them)."""
        return "modes" in (data.get("points") or {})

    def check(self, cfg) -> list[tuple[str, str]]:
        """The coupling indicator comes from the preloaded modes."""
        return [] if cfg.points.modes is not None else [("points", "a weak/strong study needs points.modes "
                                                                   "(the coupling indicator of the preloaded modes)")]

    def summarise(self, study, ds, points: list[dict]) -> dict:
        """:func:`transitions` and the response's power law (``fits.rms``)."""
        return {**transitions(points), **super().summarise(study, ds, points)}

    def report(self, page, ds, summary: dict) -> None:
        """Nothing beyond the generic section, whose points table is followed by the transition load(s) of the
        summary (``transition_load``, ``transition_loads``)."""


def transitions(points) -> dict:
    """``transition_load`` (the first group's, see :func:`_transition_load`) and, when other conditions vary,
    ``transition_loads``: one per combination of them (the contact's compliance follows roughness, say)."""
    transition = _transition_load(points)
    if transition is None:
        return {}
    out = {"transition_load": transition}
    others = sorted({k for p in points for k in p if k in AXES and k not in ("normal_load", "seed")
                     and len({q.get(k) for q in points}) > 1})
    if others:
        groups = {}
        for p in points:
            groups.setdefault(tuple(p.get(k) for k in others), []).append(p)
        out["transition_loads"] = [{**dict(zip(others, key)), **(_transition_load(grp) or {})}
                                   for key, grp in groups.items()]
    return out


def _transition_load(points) -> dict | None:
    """Where the coupling indicator first crosses the weak/strong threshold along the normal load.

    ``{"value" [N], "bracket": [lo, hi] [N], "threshold"}``: kappa interpolated linearly in log load between the two
    swept loads that bracket the crossing (other axes: the first point of each load, in sweep order; the summary's
    ``transition_loads`` repeats this per combination of the other swept conditions). None without a load sweep
    or an indicator; ``value`` null when kappa stays on one side over the swept loads.
    """
    by_load = {}
    for p in points:
        if "normal_load" in p and "coupling_indicator" in p:
            by_load.setdefault(p["normal_load"], p["coupling_indicator"])
    if len(by_load) < 2:
        return None
    loads = np.array(sorted(by_load))
    kappa = np.array([by_load[f] for f in loads])
    above = kappa >= WEAK_STRONG_THRESHOLD
    k = np.flatnonzero(~above[:-1] & above[1:])
    if k.size == 0:
        return {"value": None, "bracket": None, "threshold": WEAK_STRONG_THRESHOLD,
                "note": "strong at every swept load" if above.all() else "weak at every swept load"
                if not above.any() else "kappa does not rise through the threshold"}
    i = int(k[0])
    w = (WEAK_STRONG_THRESHOLD - kappa[i]) / (kappa[i + 1] - kappa[i])
    value = float(np.exp(np.log(loads[i]) + w * (np.log(loads[i + 1]) - np.log(loads[i]))))
    return {"value": value, "bracket": [float(loads[i]), float(loads[i + 1])], "threshold": WEAK_STRONG_THRESHOLD}


#: the registered instance
KIND = WeakStrong()
