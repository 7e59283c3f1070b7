"""Plausibility of an ingested run: values a friction test rig in a laboratory can produce.

:mod:`fivid.io.data_checks` checks that the samples are well-formed (finite, uniformly sampled); this
module checks that they make physical sense for a friction rig. Each check returns
:class:`~fivid.io.data_checks.Finding` objects with a ``severity``: ``"error"`` where the data cannot
be right (the run is rejected), ``"warning"`` where they are suspicious but possible (recorded in the
dataset's ``quality_report`` attribute and logged). Every message names the variable (or metadata
key), the value found and the range allowed.

Thresholds, and why (also in docs/bad-input.md):

==========================  =========  ===================================================================
check                       severity   threshold and reason
==========================  =========  ===================================================================
roughness_ra <= 0           error      Ra is a mean absolute height: > 0 for any real surface
roughness_ra > 50 µm        warning    50 µm is ISO 1302 grade N12, the coarsest; beyond it mm for µm?
normal_load <= 0            error      a friction run is loaded (compressive normal force > 0)
sliding_velocity < 0        error      the header gives a speed (magnitude); the direction is in the data
``|force|`` > 1e5 N         error      :data:`MAX_FORCE`: 10 t-force, above the largest lab tribometers and
                                       brake dynamometers (~1e4 N); TRIBOAIR runs at 0.5-20 N
``|acceleration|`` > 1e6    error      :data:`MAX_ACCELERATION` m s-2 (~1e5 g), above the range of shock
                                       accelerometers; a unit or sensitivity error
normal force < 0            error      median of the loaded part below -10 % of a positive nominal load:
                                       the transducer's sign convention is reversed
load mismatch               warning    median normal force of the loaded part off the nominal load by more
                                       than :data:`LOAD_TOLERANCE` (20 %): dead weights and spring loading
                                       set it within a few %, stick-slip modulates it by ~10 %
velocity mismatch           warning    median ``|velocity|`` of the record off ``sliding_velocity`` by more
                                       than :data:`VELOCITY_TOLERANCE` (20 %; ramps are short)
mu outside [0, 2]           warning    median Ft/Fn of the loaded part: dry metal pairs in air give 0.1-1,
                                       rubber up to ~2; beyond, channels or units are likely swapped
clipping                    warning    the extreme value of acceleration or a force held by
                                       >= :data:`CLIP_RUN` consecutive samples: a flat top, the signature of
                                       a sensor or ADC over range (a band-limited signal does not dwell at
                                       its peak for 2 sample intervals)
sample rate < 1 kHz         warning    :data:`MIN_SAMPLE_RATE`: friction-induced vibration lies at 0.1-20 kHz;
                                       a lower rate is usually a time column in ms labelled s
==========================  =========  ===================================================================
"""

from __future__ import annotations

import numpy as np

from fivid.io.data_checks import Finding

__all__ = ["plausibility_findings", "quality_report", "MAX_FORCE", "MAX_ACCELERATION", "LOAD_TOLERANCE",
           "VELOCITY_TOLERANCE", "MU_RANGE", "CLIP_RUN", "MIN_SAMPLE_RATE", "MAX_ROUGHNESS", "LOADED_FRACTION"]

#: Largest plausible |force| of a laboratory friction rig [N] (see the module docstring).
MAX_FORCE = 1e5
#: Largest plausible |acceleration| [m s-2] (~1e5 g, beyond shock accelerometers).
MAX_ACCELERATION = 1e6
#: Relative difference between the nominal and the measured normal load that is reported [-].
LOAD_TOLERANCE = 0.2
#: Relative difference between the nominal and the measured sliding speed that is reported [-].
VELOCITY_TOLERANCE = 0.2
#: Plausible median friction coefficient of a dry contact in air [-].
MU_RANGE = (0.0, 2.0)
#: Consecutive samples at a column's extreme value that make a flat top (clipping).
CLIP_RUN = 3
#: Lowest plausible sample rate of a vibration record [Hz].
MIN_SAMPLE_RATE = 1000.0
#: Largest plausible Ra [m] (ISO 1302 roughness grade N12).
MAX_ROUGHNESS = 50e-6
#: Samples whose normal force exceeds this fraction of the nominal load are "loaded" (the same 5 % as
#: the unloaded start found by the identification).
LOADED_FRACTION = 0.05


def _error(subject: str, message: str, index: int = 0) -> Finding:
    return Finding(index, message, severity="error", subject=subject)


def _warning(subject: str, message: str, index: int = 0) -> Finding:
    return Finding(index, message, severity="warning", subject=subject)


def _metadata(attrs: dict) -> list:
    out = []
    ra = attrs.get("roughness_ra")
    if ra is not None and not ra > 0:
        out.append(_error("roughness_ra", f"roughness_ra = {ra:g} m: Ra is a mean absolute height, > 0 for any real "
                                          "surface; give the measured Ra (e.g. '0.8 um')"))
    elif ra is not None and ra > MAX_ROUGHNESS:
        out.append(_warning("roughness_ra", f"roughness_ra = {ra * 1e6:g} um is above {MAX_ROUGHNESS * 1e6:g} um "
                                            "(ISO 1302 grade N12, the coarsest); is the unit mm written for um?"))
    load = attrs.get("normal_load")
    if load is not None and not load > 0:
        out.append(_error("normal_load", f"normal_load = {load:g} N: a friction run needs a compressive load > 0 N; "
                                         "give the nominal load as a positive number"))
    speed = attrs.get("sliding_velocity")
    if speed is not None and speed < 0:
        out.append(_error("sliding_velocity", f"sliding_velocity = {speed:g} m s-1: it is the sliding speed (>= 0); "
                                              "the direction is in the position/velocity data"))
    rate = attrs.get("sample_rate")
    if rate is not None and 0 < rate < MIN_SAMPLE_RATE:
        out.append(_warning("sample_rate", f"sample rate {rate:.6g} Hz is below {MIN_SAMPLE_RATE:g} Hz: friction-"
                                           "induced vibration lies at 0.1-20 kHz; is the time column in ms but "
                                           "labelled s?"))
    return out


def _bounds(variable: str, values: np.ndarray, limit: float, units: str) -> list:
    worst = int(np.argmax(np.abs(values)))
    value = float(np.abs(values.flat[worst]))
    if value <= limit:
        return []
    return [_error(variable, f"|{variable}| = {value:.4g} {units} is beyond {limit:g} {units}, more than any "
                             "laboratory friction rig produces; check the unit, the sensitivity and the column",
                   worst // (values.shape[1] if values.ndim == 2 else 1))]


def _flat_top(variable: str, values: np.ndarray, units: str) -> list:
    out = []
    columns = values if values.ndim == 2 else values[:, None]
    for k in range(columns.shape[1]):
        x = columns[:, k]
        for name, extreme in (("maximum", x.max()), ("minimum", x.min())):
            at = x == extreme
            if np.count_nonzero(at) < CLIP_RUN:
                continue
            # lengths of the runs of consecutive samples at the extreme
            edges = np.diff(np.concatenate(([0], at.view(np.int8), [0])))
            starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
            flat = (stops - starts) >= CLIP_RUN
            if not flat.any():
                continue
            first = int(starts[np.argmax(flat)])
            out.append(_warning(variable, f"{variable} sits at its {name} {float(extreme):.6g} {units} for "
                                          f"{int((stops - starts)[flat].sum())} samples in {int(flat.sum())} flat "
                                          f"run(s) of >= {CLIP_RUN} samples: the sensor or the ADC was probably over "
                                          "range (clipped); use a larger range or a lower gain", first))
    return out


def _loaded(fn: np.ndarray, load: float) -> np.ndarray:
    return fn > LOADED_FRACTION * load


def _forces(attrs: dict, ft: np.ndarray, fn: np.ndarray) -> list:
    out = []
    load = attrs.get("normal_load")
    if load is None or not load > 0:
        return out
    median_fn = float(np.median(fn))
    if median_fn < -0.1 * load:
        return [_error("normal_force", f"normal force is negative (median {median_fn:.4g} N) but normal_load is "
                                       f"+{load:g} N: the transducer's sign convention is reversed; negate the "
                                       "column (a rig profile column with 'scale: -1')")]
    loaded = _loaded(fn, load)
    if not loaded.any():
        return [_warning("normal_force", f"normal force never exceeds {LOADED_FRACTION:.0%} of normal_load = "
                                         f"{load:g} N (maximum {float(fn.max()):.4g} N): was the run loaded?")]
    measured = float(np.median(fn[loaded]))
    if abs(measured - load) > LOAD_TOLERANCE * load:
        out.append(_warning("normal_force", f"measured normal load {measured:.4g} N (median of the loaded part) is "
                                            f"{100 * (measured / load - 1):+.0f} % off normal_load = {load:g} N "
                                            f"(tolerance {LOAD_TOLERANCE:.0%}); check the header or the sensitivity"))
    mu = float(np.median(ft[loaded] / fn[loaded]))
    if not MU_RANGE[0] <= mu <= MU_RANGE[1]:
        out.append(_warning("friction_force", f"friction coefficient Ft/Fn = {mu:.4g} (median of the loaded part) is "
                                              f"outside [{MU_RANGE[0]:g}, {MU_RANGE[1]:g}]: a swapped column, a unit or "
                                              "a sign convention (fivid's friction force is positive against the "
                                              "sliding)?"))
    return out


def _velocity(attrs: dict, velocity: np.ndarray) -> list:
    speed = attrs.get("sliding_velocity")
    if speed is None or not speed > 0:
        return []
    measured = float(np.median(np.abs(velocity)))
    if abs(measured - speed) <= VELOCITY_TOLERANCE * speed:
        return []
    return [_warning("velocity", f"measured sliding speed {measured:.4g} m s-1 (median |velocity|) is "
                                 f"{100 * (measured / speed - 1):+.0f} % off sliding_velocity = {speed:g} m s-1 "
                                 f"(tolerance {VELOCITY_TOLERANCE:.0%}); check the header or the column's unit")]


def plausibility_findings(attrs: dict, data: dict) -> list:
    """Everything implausible in a run, errors first.

    Parameters
    ----------
    attrs : dict
        Run attributes in SI (``normal_load`` [N], ``sliding_velocity`` [m s-1], ``roughness_ra`` [m],
        ``sample_rate`` [Hz]).
    data : dict
        ``variable -> ndarray`` in SI units, 1-D over time or 2-D (time, sensor).

    Returns
    -------
    list of Finding
        With ``severity`` ``"error"`` or ``"warning"`` and ``subject`` the variable or metadata key;
        ``index`` is the 0-based sample where it is seen (0 for metadata and whole-record findings).
    """
    found = _metadata(attrs)
    for name in ("friction_force", "normal_force"):
        if name in data:
            found += _bounds(name, data[name], MAX_FORCE, "N")
    if "acceleration" in data:
        found += _bounds("acceleration", data["acceleration"], MAX_ACCELERATION, "m s-2")
    if not any(f.severity == "error" for f in found):
        if "friction_force" in data and "normal_force" in data:
            found += _forces(attrs, data["friction_force"], data["normal_force"])
        if "velocity" in data:
            found += _velocity(attrs, data["velocity"])
        for name, units in (("acceleration", "m s-2"), ("friction_force", "N"), ("normal_force", "N")):
            if name in data:
                found += _flat_top(name, data[name], units)
    return sorted(found, key=lambda f: f.severity != "error")


def quality_report(findings) -> str:
    """The ``quality_report`` attribute: one line per warning, or that every check passed."""
    warnings = [f for f in findings if f.severity == "warning"]
    if not warnings:
        return "plausibility (fivid.io.plausibility): every check passed"
    return "\n".join(f"warning: {f.subject}: {f.message}" for f in warnings)
