"""Steady-sliding window: the part of a run where the sliding velocity sits on its plateau.

A rig run ramps the base up, slides steadily, and ramps down; the friction law and the PSD scores
use only the steady part (DESIGN §3: "the part where the encoder velocity is within a tolerance of
its plateau"). A run recorded without an encoder (no ``velocity`` nor ``position``) gets its window
from the forces instead (:func:`steady_force_window`: loaded, and Ft/Fn on its plateau). A simulated
run says itself where its transient ends (attribute ``transient_end`` [s]).
:func:`steady_part` is the one place that picks the steady part of any run, measured or simulated.
"""

from __future__ import annotations

import logging

import numpy as np

from fivid.errors import ConfigError, DataQualityError
from fivid.signal.sampling import check_finite, run_label, sample_rate_of

__all__ = ["sliding_velocity_signal", "steady_sliding_window", "steady_force_window", "measured_window", "steady_part", "NO_ENCODER_HINT"]

log = logging.getLogger("fivid")

NO_ENCODER_HINT = ("without an encoder signal the window is found from the forces (loaded, Ft/Fn on its plateau), or "
                   "give it yourself: fivid identify --window T0 T1 (e.g. --window '0.05 s' '0.4 s')")
"""What a person can do when a run has neither ``velocity`` nor ``position`` (quoted in the messages)."""


def sliding_velocity_signal(ds) -> tuple[np.ndarray, np.ndarray, str]:
    """Time [s], encoder sliding velocity [m s-1] and its origin, from ``velocity`` or ``position``.

    ``velocity`` is used when present; otherwise ``position`` [m] is differentiated (second-order
    central differences, :func:`numpy.gradient`).
    """
    label = run_label(ds, default="dataset")
    if "time" not in ds.coords:
        raise DataQualityError(f"{label}: no 'time' coordinate")
    t = np.asarray(ds["time"].values, dtype=np.float64)
    if "velocity" in ds.variables:
        name = "velocity"
    elif "position" in ds.variables:
        name = "position"
    else:
        raise DataQualityError(
            f"{label}: neither 'velocity' nor 'position' is recorded, so the steady-sliding window cannot be "
            f"found from the encoder; variables present: {', '.join(sorted(map(str, ds.data_vars)))}; "
            f"{NO_ENCODER_HINT}"
        )
    values = np.asarray(ds[name].values, dtype=np.float64)
    if values.ndim != 1:
        raise DataQualityError(f"{label}: {name!r} has dims {ds[name].dims}; expected ('time',)")
    check_finite(values, label=label, variable=name, time=t)
    if name == "position":
        sample_rate_of(t, label=label)
        values = np.gradient(values, t)
    return t, values, name


def steady_sliding_window(ds, *, tolerance=0.05, smoothing=0.05, central_fraction=0.5, min_duration=None):
    """The longest interval where the smoothed sliding velocity is within a tolerance of its plateau.

    Parameters
    ----------
    ds : xarray.Dataset
        A RunDataset with ``velocity`` [m s-1] or ``position`` [m] on a uniform ``time`` [s].
    tolerance : float, default 0.05
        Allowed relative deviation from the plateau [-]: ``|v_s - v_p| <= tolerance * |v_p|``.
    smoothing : float, default 0.05
        Length of the centred moving average applied to the velocity [s] (encoder quantisation of a
        differentiated position is averaged out; a ramp's crossing time moves by at most half of it).
    central_fraction : float, default 0.5
        The plateau ``v_p`` is the median of the smoothed velocity over this central part of the record.
    min_duration : float, optional
        Shortest acceptable window [s]; default 20 % of the record.

    Returns
    -------
    (t_start, t_stop) : tuple of float [s]
        Times of the first and last sample of the window.

    Raises
    ------
    DataQualityError
        No velocity/position, NaN, non-uniform time, a zero plateau (no sliding), or no interval of
        at least ``min_duration`` within the tolerance; the message names the run and the values.
    """
    from scipy.ndimage import uniform_filter1d

    label = run_label(ds, default="dataset")
    if not (0 < tolerance < 1):
        raise ConfigError(f"tolerance must be in (0, 1), got {tolerance!r}", key="tolerance")
    if not (0 < central_fraction <= 1):
        raise ConfigError(f"central_fraction must be in (0, 1], got {central_fraction!r}", key="central_fraction")
    if not (np.isfinite(smoothing) and smoothing >= 0):
        raise ConfigError(f"smoothing must be a duration >= 0 [s], got {smoothing!r}", key="smoothing")
    t, v, origin = sliding_velocity_signal(ds)
    fs = sample_rate_of(t, label=label)
    duration = t[-1] - t[0]
    width = max(1, int(round(smoothing * fs)))
    if width > t.size // 2:
        raise ConfigError(f"{label}: smoothing {smoothing!r} s exceeds half the record ({duration!r} s)",
                          key="smoothing")
    vs = uniform_filter1d(v, size=width, mode="nearest")
    n = t.size
    lo = int(n * (1 - central_fraction) / 2)
    hi = max(lo + 1, n - lo)
    plateau = float(np.median(vs[lo:hi]))
    if plateau == 0.0 or not np.isfinite(plateau):
        raise DataQualityError(f"{label}: the plateau of the sliding velocity (from {origin!r}) is {plateau!r} m s-1: "
                               "no steady sliding in this run")
    inside = np.abs(vs - plateau) <= tolerance * abs(plateau)
    edges = np.diff(np.concatenate(([0], inside.astype(np.int8), [0])))
    starts = np.nonzero(edges == 1)[0]
    stops = np.nonzero(edges == -1)[0]  # exclusive
    min_duration = 0.2 * duration if min_duration is None else float(min_duration)
    if starts.size:
        j = int(np.argmax(stops - starts))
        i0, i1 = int(starts[j]), int(stops[j]) - 1
        if t[i1] - t[i0] >= min_duration:
            return float(t[i0]), float(t[i1])
        longest = t[i1] - t[i0]
    else:
        longest = 0.0
    raise DataQualityError(
        f"{label}: no steady sliding: the {smoothing:g} s-smoothed velocity (from {origin!r}) stays within "
        f"{tolerance:.1%} of its plateau {plateau:.6g} m s-1 for at most {longest:.6g} s "
        f"({np.mean(inside):.1%} of samples in all); at least {min_duration:.6g} s is required "
        "(raise tolerance= or lower min_duration= if this run is usable)"
    )


def measured_window(ds, *, tolerance=0.05):
    """Steady window [s] of a measured run: from the encoder (:func:`steady_sliding_window`) when it has
    ``velocity`` or ``position``, else from the forces (:func:`steady_force_window`)."""
    if "velocity" in ds.variables or "position" in ds.variables:
        return steady_sliding_window(ds, tolerance=tolerance)
    return steady_force_window(ds, tolerance=tolerance)


def steady_force_window(ds, *, tolerance=0.05, load_tolerance=0.25, smoothing=0.05, central_fraction=0.5,
                        min_duration=None):
    """The steady-sliding window of a run without an encoder signal, from its normal and friction force.

    Sliding is steady where the rig is loaded and the friction coefficient sits on its plateau: the
    longest interval where the smoothed normal force is within ``load_tolerance`` of its plateau and the
    smoothed ratio Ft/Fn within ``tolerance`` of its own. The plateaus are medians over the central
    part of the record, as in :func:`steady_sliding_window`; a dead load holds the normal force within
    a few per cent, a displacement-loaded clamp lets it drift (the contact moves), hence the wider
    load tolerance. The preload ramp, an unloaded pre-trigger interval and a stick phase before
    gross sliding (Ft/Fn below its plateau) fall outside.

    Parameters
    ----------
    ds : xarray.Dataset
        A RunDataset with ``friction_force`` [N] and ``normal_force`` [N] on a uniform ``time`` [s].
    tolerance : float, default 0.05
        Allowed relative deviation of the smoothed Ft/Fn from its plateau [-].
    load_tolerance : float, default 0.25
        Allowed relative deviation of the smoothed normal force from its plateau [-].
    smoothing : float, default 0.05
        Length of the centred moving average [s]; at most a tenth of the record is used.
    central_fraction : float, default 0.5
        The plateaus are medians over this central part of the record.
    min_duration : float, optional
        Shortest acceptable window [s]; default 20 % of the record.

    Returns
    -------
    (t_start, t_stop) : tuple of float [s]

    Raises
    ------
    DataQualityError
        Forces missing or not finite, no load (plateau normal force <= 0), or no interval of at least
        ``min_duration``; the message names the run, the values and the ``--window`` way out.
    """
    from scipy.ndimage import uniform_filter1d

    label = run_label(ds, default="dataset")
    for name, value in (("tolerance", tolerance), ("load_tolerance", load_tolerance)):
        if not (0 < value < 1):
            raise ConfigError(f"{name} must be in (0, 1), got {value!r}", key=name)
    missing = [v for v in ("friction_force", "normal_force") if v not in ds.variables]
    if missing or "time" not in ds.coords:
        raise DataQualityError(f"{label}: no {', '.join(missing) or 'time'} to find the steady window from (and "
                               "neither 'velocity' nor 'position' for the encoder window); give it with --window T0 T1")
    t = np.asarray(ds["time"].values, dtype=np.float64)
    fs = sample_rate_of(t, label=label)
    ft, fn = (np.asarray(ds[v].values, dtype=np.float64) for v in ("friction_force", "normal_force"))
    for name, values in (("friction_force", ft), ("normal_force", fn)):
        check_finite(values, label=label, variable=name, time=t)
    duration = t[-1] - t[0]
    width = max(1, int(round(min(smoothing, duration / 10) * fs)))
    fn_s = uniform_filter1d(fn, size=width, mode="nearest")
    ft_s = uniform_filter1d(ft, size=width, mode="nearest")
    lo = int(t.size * (1 - central_fraction) / 2)
    hi = max(lo + 1, t.size - lo)
    fn_p = float(np.median(fn_s[lo:hi]))
    if not fn_p > 0:
        raise DataQualityError(f"{label}: the normal force's plateau is {fn_p:.4g} N: the run is not loaded, so no "
                               "steady-sliding window can be found from the forces; give it with --window T0 T1")
    loaded = np.abs(fn_s - fn_p) <= load_tolerance * fn_p
    mu_s = np.abs(ft_s) / np.where(loaded, fn_s, fn_p)
    mu_p = float(np.median(mu_s[lo:hi]))
    inside = loaded & (np.abs(mu_s - mu_p) <= tolerance * mu_p)
    edges = np.diff(np.concatenate(([0], inside.astype(np.int8), [0])))
    starts, stops = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]
    min_duration = 0.2 * duration if min_duration is None else float(min_duration)
    longest = 0.0
    if starts.size:
        j = int(np.argmax(stops - starts))
        i0, i1 = int(starts[j]), int(stops[j]) - 1
        if t[i1] - t[i0] >= min_duration:
            log.info("%s: steady window %.6g-%.6g s from the forces (no encoder signal)", label, t[i0], t[i1])
            return float(t[i0]), float(t[i1])
        longest = t[i1] - t[i0]
    raise DataQualityError(
        f"{label}: no steady sliding found from the forces: the normal force stays within {load_tolerance:.0%} of "
        f"its plateau {fn_p:.4g} N and Ft/Fn within {tolerance:.0%} of its plateau {mu_p:.4g} for at most "
        f"{longest:.4g} s; at least {min_duration:.4g} s is required: give the window with --window T0 T1, "
        "or record 'velocity' or 'position'"
    )


def steady_part(ds, *, settle=0.0, tolerance=0.05, label=None, whole_record_if_none=False):
    """The steady-sliding part of a run, measured or simulated, less ``settle`` [s] at its start.

    - A simulated run (attribute ``transient_end`` [s]: preload, settling and base ramp end there) is
      kept from ``transient_end`` to its end; its encoder signal is not consulted (the driver knows
      where its transient ends, and a run whose base slides from the start would otherwise keep the
      preload).
    - A measured run is cropped to :func:`steady_sliding_window` (encoder velocity within
      ``tolerance`` of its plateau), or without an encoder signal to :func:`steady_force_window`.

    Parameters
    ----------
    ds : xarray.Dataset
        A RunDataset on a ``time`` [s] coordinate.
    settle : float, default 0
        Time skipped after the start of the steady part [s], so that the ringing of lightly damped modes
        excited by the start of sliding has decayed; skip the same in runs that are compared.
    tolerance : float, default 0.05
        Relative velocity tolerance of the measured window [-] (:func:`steady_sliding_window`).
    label : str, optional
        How to name the run in messages (default: its ``run_id``).
    whole_record_if_none : bool, default False
        When a measured run has no steady-sliding window (or no encoder signal), use the whole record
        (logged) instead of raising.

    Returns
    -------
    xarray.Dataset
        ``ds`` selected on ``time`` in ``[t_start + settle, t_stop]``.

    Raises
    ------
    DataQualityError
        No steady window (unless ``whole_record_if_none``), or nothing left after ``settle``.
    ConfigError
        ``settle`` negative or not finite.
    """
    label = label or run_label(ds, default="run")
    settle = float(settle)
    if not (np.isfinite(settle) and settle >= 0):
        raise ConfigError(f"{label}: settle must be a duration >= 0 [s], got {settle!r}", key="settle")
    if "transient_end" in ds.attrs:
        t0, t1 = float(ds.attrs["transient_end"]), None
    else:
        try:
            t0, t1 = measured_window(ds, tolerance=tolerance)
        except DataQualityError as exc:
            if not whole_record_if_none:
                raise DataQualityError(exc.message if exc.message.startswith(label) else f"{label}: {exc.message}") \
                    from None
            log.info("%s: no steady-sliding window found (%s); the whole record is used", label, exc.message)
            t0, t1 = float(ds["time"].values[0]), None
    part = ds.sel(time=slice(t0 + settle, t1))
    if part.sizes.get("time", 0) == 0:
        end = float(ds["time"].values[-1]) if t1 is None else t1
        raise DataQualityError(f"{label}: nothing is left of the steady part {t0:.6g}-{end:.6g} s after a settle time "
                               f"of {settle:.6g} s; lower the settle time or record longer")
    return part
