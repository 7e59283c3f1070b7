"""Vectorised checks of a run's samples: finite values, a strictly increasing, uniformly sampled time.

Each check returns ``None`` when the data pass, or a :class:`Finding` with the 0-based index of the
first (or worst) offending sample and a message, so a reader can name the file's line. The checks
touch each array once or twice with numpy and never copy a column.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Finding", "first_non_finite", "time_without_resolution", "time_not_increasing", "sampling_deviation",
           "nominal_sample_rate", "time_finding", "column_extremes"]


@dataclass(frozen=True)
class Finding:
    """A problem found in the samples.

    Attributes
    ----------
    index : int
        0-based sample index where it is (the first or the worst occurrence).
    message : str
        What is wrong (without the location).
    previous : int or None
        A second sample index the message refers to (the sample before, for time steps).
    severity : {"error", "warning"}
        An error rejects the run; a warning goes into its ``quality_report`` (:mod:`fivid.io.plausibility`).
    subject : str or None
        The variable or metadata key concerned, when the finding does not come with its column.
    overridable : bool
        An error that ``allow_implausible`` (``fivid ingest --allow-implausible``) turns into a
        recorded warning: the data are implausible for a friction rig, not impossible.
    """

    index: int
    message: str
    previous: int | None = None
    severity: str = "error"
    subject: str | None = None
    overridable: bool = False


def first_non_finite(values: np.ndarray) -> Finding | None:
    """The first NaN or infinite value of ``values``, and how many there are."""
    finite = np.isfinite(values)
    if finite.all():
        return None
    i = int(np.argmin(finite))
    n = int(values.size - np.count_nonzero(finite))
    return Finding(i, f"value {float(values[i])!r} is not a finite number ({n} non-finite value(s) in this column)")


def time_without_resolution(time: np.ndarray, tolerance: float) -> Finding | None:
    """A time column that cannot give a sample rate: all values equal, or stamps too coarse for the rate.

    Stamps written with too few decimals for the rate (``'%.4f'`` at 51.2 kHz: a resolution of 100 µs
    for a 19.5 µs step) repeat: several consecutive samples carry the same time. That is told apart
    from a duplicated row by the smallest non-zero step (the resolution the times were written with)
    being longer than the nominal step ``(t[-1] - t[0]) / (n - 1)`` by more than half. The decimals
    asked for are those whose rounding error stays within ``tolerance`` of a step:
    ``ceil(-log10(tolerance * dt))`` (7 at 51.2 kHz and 1 %).

    Parameters
    ----------
    time : ndarray
        Times [s], at least 2.
    tolerance : float
        The profile's ``checks.sampling_tolerance`` [-].
    """
    if time.size < 2:
        return None
    if time[-1] == time[0] and np.ptp(time) == 0:
        return Finding(0, f"all {time.size} time values are {float(time[0]):.9g} s: the time column holds no time "
                          "(a constant column mapped to time?); map the sample time to the time column")
    steps = np.diff(time)
    repeated = steps == 0
    positive = steps[steps > 0]
    if not repeated.any() or positive.size == 0:
        return None
    resolution = float(positive.min())
    dt = float((time[-1] - time[0]) / (time.size - 1))
    if not 0 < dt < resolution / 1.5:
        return None  # isolated duplicates: time_not_increasing names them
    i = int(np.argmax(repeated)) + 1
    decimals = int(np.ceil(-np.log10(tolerance * dt)))
    return Finding(
        i,
        f"time stamps repeat ({int(np.count_nonzero(repeated))} of {steps.size} steps are zero): the times are "
        f"written with resolution {resolution:.3g} s, coarser than the sampling step {dt:.4g} s "
        f"({1 / dt:.6g} Hz from the first and last time); write the time with at least {decimals} decimals "
        f"(e.g. '%.{decimals}f') or export the sample index",
        previous=i - 1,
    )


def time_not_increasing(time: np.ndarray) -> Finding | None:
    """The first sample whose time is not strictly greater than the previous one's [s]."""
    if time.size < 2:
        return None
    steps = np.diff(time)
    ok = steps > 0
    if ok.all():
        return None
    i = int(np.argmin(ok)) + 1
    n = int(steps.size - np.count_nonzero(ok))
    what = "is duplicated" if time[i] == time[i - 1] else "goes backwards"
    return Finding(
        i,
        f"time is not strictly increasing: {float(time[i])!r} s {what} after {float(time[i - 1])!r} s "
        f"({n} such step(s) in the file)",
        previous=i - 1,
    )


def nominal_sample_rate(time: np.ndarray) -> float:
    """Sample rate from the first and last time [Hz]: ``(n - 1) / (t[-1] - t[0])``.

    With times written to a resolution r, its relative error is at most ``2 r / (t[-1] - t[0])``,
    far below that of any single step.
    """
    return float((time.size - 1) / (time[-1] - time[0]))


def sampling_deviation(time: np.ndarray, tolerance: float) -> Finding | None:
    """The worst departure of a time step from the nominal step, if it exceeds ``tolerance``.

    Parameters
    ----------
    time : ndarray
        Strictly increasing times [s].
    tolerance : float
        Allowed ``|dt_i - dt| / dt`` [-], where the nominal step ``dt`` is the median step (of at most
        65 536 evenly spread steps), so that a few gaps do not shift it. Times printed with d
        decimals have steps off by up to ``10**-d``: at 51.2 kHz and 7 decimals that is 0.5 %, so the
        default tolerance of a profile is 1 %. A dropped sample shows as a 100 % deviation.
    """
    if time.size < 3:
        return None
    deviation = np.diff(time)
    dt = float(np.median(deviation[:: max(1, deviation.size // 65536)]))
    deviation -= dt
    np.abs(deviation, out=deviation)  # in place: one temporary array of n - 1 floats
    worst = int(np.argmax(deviation))
    relative = float(deviation[worst] / dt)
    if relative <= tolerance:
        return None
    n_bad = int(np.count_nonzero(deviation > tolerance * dt))
    step = float(time[worst + 1] - time[worst])
    return Finding(
        worst + 1,
        f"sampling is not uniform: the time step here is {step:.9g} s, {100 * relative:.3g} % off the nominal "
        f"(median) step {dt:.9g} s ({1 / dt:.9g} Hz); tolerance {100 * tolerance:.3g} % "
        f"(checks.sampling_tolerance); {n_bad} step(s) exceed it",
        previous=worst,
    )


def time_finding(time: np.ndarray, tolerance: float) -> Finding | None:
    """Every check of a time column in one pass over its steps; the first problem found, or None.

    The same findings, in the same order, as :func:`time_without_resolution`, :func:`time_not_increasing`
    and :func:`sampling_deviation` (each assumes the previous passed), but the steps are computed once
    and a good column costs one ``diff``, its minimum and maximum and a median of at most 65 536 steps:
    the largest ``|dt_i - dt|`` is ``max(max_i dt_i - dt, dt - min_i dt_i)``, no temporary needed. Only a
    column that fails is searched again, by the individual checks, for the message.

    Parameters
    ----------
    time : ndarray
        Times [s], at least 2.
    tolerance : float
        Relative tolerance on the step (the profile's ``checks.sampling_tolerance``) [-].
    """
    if time.size < 3:
        return time_without_resolution(time, tolerance) or time_not_increasing(time)
    steps = np.diff(time)
    smallest, largest = float(steps.min()), float(steps.max())
    if smallest > 0:
        dt = float(np.median(steps[:: max(1, steps.size // 65536)]))
        if max(largest - dt, dt - smallest) <= tolerance * dt:
            return None
    del steps
    for check in (lambda: time_without_resolution(time, tolerance), lambda: time_not_increasing(time),
                  lambda: sampling_deviation(time, tolerance)):
        finding = check()
        if finding is not None:
            return finding
    return None


def column_extremes(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-column minimum and maximum of a 1-D or 2-D ``(time, sensor)`` array (1-D results).

    NaN propagates through both, so ``isfinite`` of the two tells whether the whole column is finite:
    the finiteness, bounds and clipping checks of a column share these two reductions.
    """
    columns = values if values.ndim == 2 else values[:, None]
    return columns.min(axis=0), columns.max(axis=0)
