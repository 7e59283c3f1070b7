"""Run-time estimate of a prepared simulation from a short timed probe (``fivid simulate --dry-run``, issue 30 item 4).

The time loop costs the same per output interval throughout a run (the contact set changes, the work per step
hardly does), so two short probes of the prepared run -- ``k`` and ``2k`` intervals from the start, after a
compiling call -- give the per-interval cost as their difference (fixed costs cancel), and the run takes about
``set-up + n_intervals x that``. The probes integrate on fresh state and write nothing.
"""

from __future__ import annotations

import dataclasses
import math
import time

from fivid.solver.integrate import integrate
from fivid.solver.reduced import integrate_reduced

__all__ = ["estimate_run_time"]


def _integrate(prep, n_intervals: int) -> float:
    settings = dataclasses.replace(prep.settings, n_intervals=int(n_intervals))
    t0 = time.perf_counter()
    if prep.reduced is not None:
        integrate_reduced(prep.model, prep.reduced, prep.friction, settings, progress=False)
    else:
        integrate(prep.model, prep.stencils, prep.arrays, prep.friction, settings, progress=False)
    return time.perf_counter() - t0


def estimate_run_time(prep, *, setup_seconds: float = 0.0, probe_seconds: float = 0.5) -> dict:
    """Estimated wall time [s] of ``prep.run()`` (a :class:`fivid.solver.driver.PreparedRun`) on this machine now.

    Parameters
    ----------
    prep : PreparedRun
    setup_seconds : float
        Time already spent preparing the run [s] (model, stable step, reduced basis), added to the estimate.
    probe_seconds : float
        Rough wall time of the longer probe [s]; the probes grow from 8 intervals until one takes a tenth of it.

    Returns
    -------
    dict
        ``estimated_seconds`` (set-up + time loop), ``loop_seconds``, ``seconds_per_interval``,
        ``seconds_per_step``, ``probe_intervals``, ``n_intervals``, ``steps`` and ``setup_seconds``.
    """
    n_int = int(prep.settings.n_intervals)
    k = min(8, max(1, n_int // 2))
    _integrate(prep, min(2, n_int))  # compiles (or loads from numba's cache) outside the timing
    while True:
        t1 = _integrate(prep, k)
        if t1 >= probe_seconds / 10.0 or 2 * k >= n_int:
            break
        k *= 2
    k2 = min(2 * k, n_int)
    t2 = _integrate(prep, k2)
    per = (t2 - t1) / (k2 - k) if k2 > k else t1 / k
    if not (per > 0.0 and math.isfinite(per)):  # the machine's noise swamped the difference: the plain rate
        per = t2 / k2
    steps = n_int * int(prep.settings.steps_per_interval)
    loop = per * n_int
    return {"estimated_seconds": float(setup_seconds + loop), "loop_seconds": float(loop),
            "seconds_per_interval": float(per), "seconds_per_step": float(per / prep.settings.steps_per_interval),
            "probe_intervals": [int(k), int(k2)], "n_intervals": n_int, "steps": int(steps),
            "setup_seconds": float(setup_seconds)}
