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
sample rate <= 0            error      a rate is a number of samples per second (``sample_rate: 0 Hz``)
rate outside the DAQ range  error      the rate (stated, or from the time stamps' spacing) outside
                                       [:data:`MIN_SAMPLE_RATE`, :data:`MAX_SAMPLE_RATE`] = [1 kHz, 10 MHz],
                                       the range of vibration DAQs, while 1e3 or 1e6 times it is inside:
                                       the time column's unit is wrong by that factor (ms under [s])
sample rate < 1 kHz         warning    :data:`MIN_SAMPLE_RATE`: friction-induced vibration lies at 0.1-20 kHz
                                       (a rate that no factor 1e3/1e6 brings into the DAQ range)
load gap > 10x              error      measured normal load (median of the loaded part; below nominal: the
                                       largest normal force) and ``normal_load`` differ by
                                       :data:`LOAD_ERROR_FACTOR` (10) or more: a unit (kN for N), a
                                       sensitivity or a column mapping is wrong, not the rig
==========================  =========  ===================================================================

Errors marked *overridable* (the DAQ range, the bounds on forces and acceleration, the load gap, the
reversed normal force) are data that are implausible, not impossible: ``allow_implausible=True``
(``fivid ingest --allow-implausible``) keeps the run and records each as an ``allowed:`` line in its
``quality_report``. The others (a rate, load or Ra that is not positive) are never allowed.

Cost: the checks share one pass over each parsed column (its minimum and maximum,
:func:`~fivid.io.data_checks.column_extremes`: finiteness, bounds and the clipping candidates); the
medians (load, speed, mu) are taken over at most :data:`MEDIAN_SAMPLES` evenly spread samples, whose
relative error (~1/sqrt(65 536) = 0.4 % of the spread) is far below the 20 % tolerances.
"""

from __future__ import annotations

import numpy as np

import math

from fivid.io.data_checks import Finding, column_extremes, nominal_sample_rate

__all__ = ["plausibility_findings", "quality_report", "MAX_FORCE", "MAX_ACCELERATION", "LOAD_TOLERANCE",
           "VELOCITY_TOLERANCE", "MU_RANGE", "CLIP_RUN", "MIN_SAMPLE_RATE", "MAX_SAMPLE_RATE", "MAX_ROUGHNESS",
           "LOADED_FRACTION", "LOAD_ERROR_FACTOR", "MEDIAN_SAMPLES", "time_unit_hint", "daq_rate_factor",
           "sample_rate_error"]

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
#: Lowest plausible sample rate of a vibration record [Hz] (the lower end of the DAQ range).
MIN_SAMPLE_RATE = 1000.0
#: Highest plausible sample rate of a vibration DAQ [Hz] (fast digitisers for ultrasound reach 10 MHz).
MAX_SAMPLE_RATE = 1e7
#: A measured normal load more than this many times off the nominal one (either way) is an error [-].
LOAD_ERROR_FACTOR = 10.0
#: Most samples a plausibility median is taken over (evenly spread through the record).
MEDIAN_SAMPLES = 65536
#: Largest plausible Ra [m] (ISO 1302 roughness grade N12).
MAX_ROUGHNESS = 50e-6
#: Samples whose normal force exceeds this fraction of the nominal load are "loaded" (the same 5 % as
#: the unloaded start found by the identification).
LOADED_FRACTION = 0.05


def _error(subject: str, message: str, index: int = 0, *, overridable: bool = False) -> Finding:
    return Finding(index, message, severity="error", subject=subject, overridable=overridable)


def _spread(values: np.ndarray) -> np.ndarray:
    """At most :data:`MEDIAN_SAMPLES` evenly spread samples of ``values`` (a view, no copy)."""
    return values[:: max(1, values.shape[0] // MEDIAN_SAMPLES)]


def time_unit_hint(factor: float, units: str) -> str:
    """The advice when a sample rate is off by ``factor`` = 1e-3, 1e3, 1e-6 or 1e6 (the time unit is wrong)."""
    return (f"the ratio is {factor:g}: the time column's unit {units!r} looks wrong by that factor (times in ms "
            "under a header in s give 0.001); correct the unit in the header")


def daq_rate_factor(rate: float) -> float | None:
    """The factor 1e-3, 1e-6, 1e3 or 1e6 that ``rate`` [Hz] is off a rate in the DAQ range, or None.

    ``rate / factor`` lies in [:data:`MIN_SAMPLE_RATE`, :data:`MAX_SAMPLE_RATE`] while ``rate`` does not
    (by more than 1 %, so that float noise at the edge is no error). None when ``rate`` is in the range
    or no such factor exists.
    """
    if not math.isfinite(rate) or rate <= 0 or 0.99 * MIN_SAMPLE_RATE <= rate <= 1.01 * MAX_SAMPLE_RATE:
        return None
    for factor in (1e-3, 1e-6, 1e3, 1e6):
        if MIN_SAMPLE_RATE <= rate / factor <= MAX_SAMPLE_RATE:
            return factor
    return None


def sample_rate_error(rate: float) -> str | None:
    """Why a stated sample rate [Hz] cannot be one (not a finite number > 0), or None."""
    if math.isfinite(rate) and rate > 0:
        return None
    return (f"sample_rate = {rate:g} Hz: a sample rate is a finite number of samples per second, > 0; give the "
            "DAQ's rate (e.g. '51.2 kHz') or leave the line out (the time column gives it)")


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
    return out


def _sample_rate(attrs: dict, time: np.ndarray | None, time_units: str) -> list:
    """The rate against the DAQ range: stated (subject ``sample_rate``) or from the stamps (``time``)."""
    rate, subject, what = attrs.get("sample_rate"), "sample_rate", "the stated sample rate"
    if rate is None and time is not None and time.size >= 2:
        rate, subject = nominal_sample_rate(time), "time"
        what = "the time column's spacing gives a sample rate of"
    if rate is None:
        return []
    problem = sample_rate_error(rate)
    if problem is not None:
        return [_error(subject, problem)]
    factor = daq_rate_factor(rate)
    if factor is not None:
        return [_error(subject, f"{what} {rate:.6g} Hz, outside the range of vibration DAQs [{MIN_SAMPLE_RATE / 1e3:g} "
                                f"kHz, {MAX_SAMPLE_RATE / 1e6:g} MHz] (fivid.io.plausibility) while {rate / factor:.6g} "
                                f"Hz is in it; {time_unit_hint(factor, time_units)} (or pass --allow-implausible if "
                                "the rate is right)", overridable=True)]
    if rate < MIN_SAMPLE_RATE:
        return [_warning("sample_rate", f"sample rate {rate:.6g} Hz is below {MIN_SAMPLE_RATE:g} Hz: friction-"
                                        "induced vibration lies at 0.1-20 kHz; is the time column in ms but "
                                        "labelled s?")]
    return []


def _bounds(variable: str, values: np.ndarray, extremes, limit: float, units: str) -> list:
    lowest, highest = extremes
    largest = np.maximum(np.abs(lowest), np.abs(highest))
    if not (largest > limit).any():
        return []
    k = int(np.argmax(largest))  # the sensor column with the largest |value|; then its sample
    column = values if values.ndim == 1 else values[:, k]
    worst = int(np.argmax(np.abs(column)))
    value = float(abs(column[worst]))
    return [_error(variable, f"|{variable}| = {value:.4g} {units} is beyond {limit:g} {units}, more than any "
                             "laboratory friction rig produces; check the unit, the sensitivity and the column",
                   worst, overridable=True)]


def _flat_top(variable: str, values: np.ndarray, extremes, units: str) -> list:
    out = []
    columns = values if values.ndim == 2 else values[:, None]
    lowest, highest = extremes
    for k in range(columns.shape[1]):
        x = columns[:, k]
        for name, extreme in (("maximum", highest[k]), ("minimum", lowest[k])):
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


_GAP_ADVICE = (f"A gap of more than {LOAD_ERROR_FACTOR:g}x is a wrong unit (kN for N), sensitivity or column, not the "
               "rig: correct the header or the column (or pass --allow-implausible if the data are right)")


def _loaded_median(ft: np.ndarray, fn: np.ndarray, load: float):
    """Median Fn [N] and Ft/Fn [-] of the loaded samples (over :data:`MEDIAN_SAMPLES` spread samples, or
    all of them when the loaded part is too short to be met by the spread ones); some sample is loaded."""
    fts, fns = _spread(ft), _spread(fn)
    if not _loaded(fns, load).any():
        fts, fns = ft, fn
    loaded = _loaded(fns, load)
    fnl = fns[loaded]
    return float(np.median(fnl)), float(np.median(fts[loaded] / fnl))


def _forces(attrs: dict, ft: np.ndarray, fn: np.ndarray, fn_max: float) -> list:
    out = []
    load = attrs.get("normal_load")
    if load is None or not load > 0:
        return out
    median_fn = float(np.median(_spread(fn)))
    if median_fn < -0.1 * load:
        return [_error("normal_force", f"normal force is negative (median {median_fn:.4g} N) but normal_load is "
                                       f"+{load:g} N: the transducer's sign convention is reversed; negate the "
                                       "column (a rig profile column with 'scale: -1')", overridable=True)]
    if fn_max * LOAD_ERROR_FACTOR < load:
        return [_error("normal_force", f"normal force never exceeds {fn_max:.4g} N, less than 1/{LOAD_ERROR_FACTOR:g} "
                                       f"of normal_load = {load:g} N: was the run loaded? {_GAP_ADVICE}",
                       overridable=True)]
    measured, mu = _loaded_median(ft, fn, load)
    if measured > LOAD_ERROR_FACTOR * load:
        out.append(_error("normal_force", f"measured normal load {measured:.4g} N (median of the loaded part) is "
                                          f"{measured / load:.3g} times normal_load = {load:g} N. {_GAP_ADVICE}",
                                          overridable=True))
    elif abs(measured - load) > LOAD_TOLERANCE * load:
        out.append(_warning("normal_force", f"measured normal load {measured:.4g} N (median of the loaded part) is "
                                            f"{100 * (measured / load - 1):+.0f} % off normal_load = {load:g} N "
                                            f"(tolerance {LOAD_TOLERANCE:.0%}); check the header or the sensitivity"))
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
    measured = float(np.median(np.abs(_spread(velocity))))
    if abs(measured - speed) <= VELOCITY_TOLERANCE * speed:
        return []
    return [_warning("velocity", f"measured sliding speed {measured:.4g} m s-1 (median |velocity|) is "
                                 f"{100 * (measured / speed - 1):+.0f} % off sliding_velocity = {speed:g} m s-1 "
                                 f"(tolerance {VELOCITY_TOLERANCE:.0%}); check the header or the column's unit")]


def plausibility_findings(attrs: dict, data: dict, *, extremes: dict | None = None, time_units: str = "s") -> list:
    """Everything implausible in a run, errors first.

    Parameters
    ----------
    attrs : dict
        Run attributes in SI (``normal_load`` [N], ``sliding_velocity`` [m s-1], ``roughness_ra`` [m],
        ``sample_rate`` [Hz] when the file states it).
    data : dict
        ``variable -> ndarray`` in SI units, 1-D over time or 2-D (time, sensor); ``time`` [s] gives
        the sample rate when ``attrs`` has none.
    extremes : dict, optional
        ``variable -> (minimum, maximum)`` per column (:func:`~fivid.io.data_checks.column_extremes`),
        when the caller has them already; computed otherwise.
    time_units : str
        The time column's unit as written (named in the advice on a rate off by 1e3).

    Returns
    -------
    list of Finding
        With ``severity`` ``"error"`` or ``"warning"``, ``overridable`` for errors that
        ``allow_implausible`` may keep, and ``subject`` the variable or metadata key; ``index`` is
        the 0-based sample where it is seen (0 for metadata and whole-record findings).
    """
    extremes = dict(extremes or {})
    for name, values in data.items():
        if name != "time" and name not in extremes:
            extremes[name] = column_extremes(values)
    found = _metadata(attrs) + _sample_rate(attrs, data.get("time"), time_units)
    for name in ("friction_force", "normal_force"):
        if name in data:
            found += _bounds(name, data[name], extremes[name], MAX_FORCE, "N")
    if "acceleration" in data:
        found += _bounds("acceleration", data["acceleration"], extremes["acceleration"], MAX_ACCELERATION, "m s-2")
    if not any(f.severity == "error" and not f.overridable for f in found):
        if "friction_force" in data and "normal_force" in data:
            found += _forces(attrs, data["friction_force"], data["normal_force"],
                             float(np.max(extremes["normal_force"][1])))
        if "velocity" in data:
            found += _velocity(attrs, data["velocity"])
        for name, units in (("acceleration", "m s-2"), ("friction_force", "N"), ("normal_force", "N")):
            if name in data:
                found += _flat_top(name, data[name], extremes[name], units)
    return sorted(found, key=lambda f: f.severity != "error")


def quality_report(findings, *, allowed=()) -> str:
    """The ``quality_report`` attribute: one line per warning and per allowed error, or that every check passed.

    ``allowed`` are the overridable errors kept by ``allow_implausible``: each is an
    ``allowed (--allow-implausible): SUBJECT: MESSAGE`` line, so the file says it was let through.
    """
    lines = [f"allowed (--allow-implausible): {f.subject}: {f.message}" for f in allowed]
    lines += [f"warning: {f.subject}: {f.message}" for f in findings if f.severity == "warning"]
    if not lines:
        return "plausibility (fivid.io.plausibility): every check passed"
    return "\n".join(lines)
