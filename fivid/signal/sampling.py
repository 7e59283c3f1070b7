"""Checks of sampled signals before spectral analysis: uniform time, finite values, enough samples.

Every failure is a :class:`~fivid.errors.DataQualityError` naming the run (``run_id`` and file when
known), the variable and the offending value, so a person can find the bad record.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import DataQualityError

__all__ = ["run_label", "sample_rate_of", "check_finite", "TIME_STEP_RTOL"]

# A dropped or duplicated sample changes one step by 100 %; DAQ clock jitter is ppm; the rig CSV
# writes time with 7 decimals, i.e. a rounding of up to 0.5e-7 s = 0.26 % of the step at 51.2 kHz.
# 1 % separates the two by a factor ~4 either side.
TIME_STEP_RTOL = 0.01


def run_label(obj, default: str = "signal") -> str:
    """``"run 'R012' (file 'a.nc')"`` from a Dataset/DataArray's ``run_id`` attr and source file."""
    attrs = getattr(obj, "attrs", {}) or {}
    run_id = attrs.get("run_id")
    source = (getattr(obj, "encoding", {}) or {}).get("source")
    parts = []
    if run_id is not None:
        parts.append(f"run {run_id!r}")
    if source:
        parts.append(f"(file {str(source)!r})")
    return " ".join(parts) if parts else default


def sample_rate_of(time: np.ndarray, *, label: str = "signal", declared: float | None = None) -> float:
    """Sampling rate [Hz] of a time coordinate [s], after checking that it is uniform.

    Parameters
    ----------
    time : ndarray [s]
        Sample times, strictly increasing.
    label : str
        How to name the signal in error messages.
    declared : float, optional
        A rate given by the caller or the ``sample_rate`` attribute [Hz]; it must agree with the
        time coordinate within :data:`TIME_STEP_RTOL`, and is returned (exact) when it does.

    Raises
    ------
    DataQualityError
        Fewer than 2 samples, non-finite or non-uniform time, or a declared rate that disagrees.
    """
    t = np.asarray(time, dtype=np.float64)
    if t.size < 2:
        raise DataQualityError(f"{label}: {t.size} time sample(s); need at least 2 to know the sampling rate")
    if not np.all(np.isfinite(t)):
        i = int(np.argmin(np.isfinite(t)))
        raise DataQualityError(f"{label}: time[{i}] = {t[i]!r} is not finite")
    dt = np.diff(t)
    mean_dt = (t[-1] - t[0]) / (t.size - 1)
    if not mean_dt > 0:
        raise DataQualityError(f"{label}: time does not increase (from {t[0]!r} s to {t[-1]!r} s)")
    dev = np.abs(dt - mean_dt)
    i = int(np.argmax(dev))
    if dev[i] > TIME_STEP_RTOL * mean_dt:
        raise DataQualityError(
            f"{label}: non-uniform time: step {i} (t = {t[i]!r} s -> {t[i + 1]!r} s) is {dt[i]!r} s, "
            f"the mean step is {mean_dt!r} s (allowed deviation {TIME_STEP_RTOL:.0%}); "
            "resample the record onto a uniform grid or cut it at the gap"
        )
    fs = 1.0 / mean_dt
    if declared is not None:
        if not abs(declared * mean_dt - 1.0) <= TIME_STEP_RTOL:
            raise DataQualityError(
                f"{label}: declared sampling rate {declared!r} Hz disagrees with the time coordinate "
                f"({fs!r} Hz from {t.size} samples over {t[-1] - t[0]!r} s)"
            )
        return float(declared)
    return float(fs)


def check_finite(values: np.ndarray, *, label: str, variable: str, time: np.ndarray | None = None) -> None:
    """Raise :class:`DataQualityError` when ``values`` hold NaN or infinities, naming the first one."""
    v = np.asarray(values)
    finite = np.isfinite(v)
    if finite.all():
        return
    bad = int(v.size - np.count_nonzero(finite))
    first = np.unravel_index(int(np.argmin(finite.ravel())), v.shape)
    where = f"index {first[0] if len(first) == 1 else first}"
    if time is not None:
        where += f", t = {float(time[first[0]])!r} s"
    raise DataQualityError(
        f"{label}: variable {variable!r} has {bad} non-finite value(s) (first {v[first]!r} at {where}); "
        "cut the record or repair it before spectral analysis",
        column=variable,
    )
