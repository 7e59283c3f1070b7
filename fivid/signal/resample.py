"""Resampling a run to another sampling rate: polyphase, anti-aliased (:func:`scipy.signal.resample_poly`).

Used when measured and simulated runs have different rates, so their PSDs share one frequency grid.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from fivid.errors import ConfigError, DataQualityError
from fivid.schema import append_history, apply_cf_attrs
from fivid.signal.sampling import check_finite, run_label, sample_rate_of

__all__ = ["rational_ratio", "resample_to"]

# Rates are known to ~1e-9 (DAQ crystals, float seconds); a ratio closer than that is the same ratio.
RATE_RTOL = 1e-9


def rational_ratio(sample_rate: float, target: float, *, max_denominator: int = 10_000) -> tuple[int, int]:
    """``(up, down)`` with ``sample_rate · up / down == target`` within :data:`RATE_RTOL`.

    Raises :class:`~fivid.errors.ConfigError` when no ratio with ``down <= max_denominator`` is that close.
    """
    if not (np.isfinite(target) and target > 0):
        raise ConfigError(f"target sampling rate must be a positive number of Hz, got {target!r}", key="sample_rate")
    ratio = Fraction(target / sample_rate).limit_denominator(max_denominator)
    up, down = ratio.numerator, ratio.denominator
    achieved = sample_rate * up / down
    if up == 0 or abs(achieved / target - 1) > RATE_RTOL:
        raise ConfigError(
            f"cannot resample {sample_rate!r} Hz to {target!r} Hz with a ratio up/down, down <= {max_denominator} "
            f"(best {up}/{down} gives {achieved!r} Hz); choose a target rate with a simpler ratio", key="sample_rate"
        )
    return up, down


def resample_to(ds, sample_rate: float, *, max_denominator: int = 10_000):
    """A copy of RunDataset ``ds`` resampled to ``sample_rate`` [Hz] by polyphase filtering.

    Every variable with a ``time`` dimension is filtered with :func:`scipy.signal.resample_poly`
    (Kaiser-windowed FIR low-pass at the lower of the two Nyquist frequencies, edges padded with the
    line through the end samples, ``padtype="line"``). Other variables and attributes are kept;
    ``time`` becomes ``t0 + k / sample_rate``; ``sample_rate`` and ``history`` are updated.

    Raises
    ------
    DataQualityError
        Non-uniform time or NaN (naming the run).
    ConfigError
        No rational ratio with a denominator up to ``max_denominator`` reaches the target rate.
    """
    import scipy.signal

    label = run_label(ds, default="dataset")
    t = np.asarray(ds["time"].values, dtype=np.float64)
    fs = sample_rate_of(t, label=label, declared=ds.attrs.get("sample_rate"))
    up, down = rational_ratio(fs, float(sample_rate), max_denominator=max_denominator)
    if up == down:
        return ds.copy()
    for name, var in ds.coords.items():
        if "time" in var.dims and name != "time":
            raise DataQualityError(f"{label}: cannot resample the time-dependent coordinate {name!r}")
    n_new = -(-t.size * up // down)
    new_t = t[0] + np.arange(n_new) / float(sample_rate)
    out = ds.drop_vars([name for name, v in ds.variables.items() if "time" in v.dims]).copy()
    out = out.assign_coords(time=("time", new_t, dict(ds["time"].attrs)))
    for name, var in ds.data_vars.items():
        if "time" not in var.dims:
            continue
        values = np.asarray(var.values, dtype=np.float64)
        check_finite(values, label=label, variable=str(name), time=t)
        axis = var.dims.index("time")
        if values.shape[axis] < 2:
            raise DataQualityError(f"{label}: variable {name!r} has too few samples to resample")
        y = scipy.signal.resample_poly(values, up, down, axis=axis, padtype="line")
        out[name] = (var.dims, y, dict(var.attrs))
    out.attrs = dict(ds.attrs)
    out.attrs["sample_rate"] = float(sample_rate)
    append_history(out, f"resampled from {fs:.10g} Hz to {float(sample_rate):.10g} Hz "
                        f"(scipy.signal.resample_poly, up={up}, down={down}, padtype='line')")
    return apply_cf_attrs(out)
