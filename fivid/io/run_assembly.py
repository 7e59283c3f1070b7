"""From converted columns to a validated RunDataset: the checks and the assembly every reader shares.

A reader (the rig CSV, or a DAQ file: TDMS, UFF58, MAT, LVM, MDF4) finds its columns through a
rig profile (:class:`~fivid.io.rig_header.RigHead`), converts each to SI and hands them here as
``variable -> (values, [ColumnSpec, ...])``. Here the time column is checked (resolution, strictly
increasing, uniform sampling, the stated sample rate), the values for plausibility, and the Dataset
is built with CF attributes and provenance. Where a finding is reported is the reader's business:
``locate(row)`` gives the file's line of a 0-based sample, or None for a file without lines (the
message then names the sample).
"""

from __future__ import annotations

import logging

import numpy as np

from fivid.errors import DataQualityError, SchemaError
from fivid.io.data_checks import column_extremes, first_non_finite, nominal_sample_rate, time_finding
from fivid.io.plausibility import plausibility_findings, quality_report, sample_rate_error, time_unit_hint
from fivid.io.rig_header import RigHead
from fivid.schema import apply_cf_attrs, new_history, registry, validate_run, with_condition_coords

__all__ = ["assemble_run", "finding_error", "by_variable"]

log = logging.getLogger("fivid")


def _where(locate, row: int) -> tuple[int | None, str]:
    """``(line, text)`` of a 0-based sample: the file's line, or no line and ``"sample N"``."""
    line = locate(row)
    return line, (f"line {line}" if line is not None else f"sample {row + 1}")


def finding_error(head: RigHead, locate, finding, column: str | None = None) -> DataQualityError:
    """A :class:`~fivid.io.data_checks.Finding` as an error naming the file, line (or sample) and column."""
    line, _ = _where(locate, finding.index)
    message = finding.message
    if line is None:
        message += f" (at sample {finding.index + 1})"
    if finding.previous is not None:
        message += f" (previous sample at {_where(locate, finding.previous)[1]})"
    return DataQualityError(message, file=head.path, line=line, column=column)


def by_variable(head: RigHead) -> dict:
    """``variable -> [(field index, ColumnSpec), ...]`` in header order (several for sensors)."""
    groups: dict = {}
    for index, spec in head.columns:
        groups.setdefault(spec.variable, []).append((index, spec))
    return groups


def _time_spec(head: RigHead):
    return next(spec for _, spec in head.columns if spec.variable == "time")


def _stated_line(head: RigHead, key: str) -> int | None:
    origin = head.attr_origin.get(key, "")
    return int(origin.split()[1]) if origin.startswith("line ") else None


def _sample_rate(head: RigHead, locate, time: np.ndarray) -> float:
    if time.size < 2:
        raise SchemaError(
            "no data rows after the header" if time.size == 0 else
            "only one data row; a run needs at least two samples", file=head.path, line=head.header_line,
        )
    stated = head.attrs.get("sample_rate")
    problem = None if stated is None else sample_rate_error(stated)
    if problem is not None:  # before any division by it
        raise DataQualityError(problem, file=head.path, line=_stated_line(head, "sample_rate"), key="sample_rate")
    finding = time_finding(time, head.profile.sampling_tolerance)
    if finding is not None:
        raise finding_error(head, locate, finding, column=_time_spec(head).name)
    measured = nominal_sample_rate(time)
    if stated is None:
        return measured
    tolerance = head.profile.sampling_tolerance
    if abs(stated - measured) > tolerance * measured:
        hint = ""
        for factor in (1e-3, 1e3, 1e-6, 1e6):
            if abs(measured - stated * factor) <= tolerance * stated * factor:  # no division: stated may be tiny
                hint = "; " + time_unit_hint(factor, _time_spec(head).units)
        raise DataQualityError(
            f"the stated sample rate {stated:.9g} Hz ({head.attr_origin['sample_rate']}) does not match the time "
            f"column, which gives {measured:.9g} Hz; tolerance {100 * tolerance:.3g} %{hint}",
            file=head.path, line=_stated_line(head, "sample_rate"), key="sample_rate",
        )
    return float(stated)


def _extremes(head: RigHead, locate, arrays: dict) -> dict:
    """``variable -> (minimum, maximum)`` per column, one pass each; raises at the first non-finite value."""
    out = {}
    for name, (values, specs) in arrays.items():
        lowest, highest = column_extremes(values)
        for k in np.flatnonzero(~(np.isfinite(lowest) & np.isfinite(highest))):  # NaN/inf reach min or max
            finding = first_non_finite(values if values.ndim == 1 else values[:, k])
            raise finding_error(head, locate, finding, column=specs[k].name)
        out[name] = (lowest, highest)
    return out


def _check_plausibility(head: RigHead, locate, time: np.ndarray, arrays: dict, extremes: dict,
                        allow_implausible: bool) -> str:
    """Raise the first plausibility error (file, line, column or key); log the warnings; return the report.

    With ``allow_implausible`` the overridable errors are logged and kept in the report instead.
    """
    findings = plausibility_findings(head.attrs, {"time": time, **{n: v for n, (v, _) in arrays.items()}},
                                     extremes=extremes, time_units=_time_spec(head).units)
    allowed = []
    for finding in findings:
        if finding.severity == "error" and finding.overridable and allow_implausible:
            log.warning("%s: %s: allowed (--allow-implausible): %s", head.path, finding.subject, finding.message)
            allowed.append(finding)
        elif finding.severity == "error" and finding.subject == "time":
            raise finding_error(head, locate, finding, column=_time_spec(head).name)
        elif finding.severity == "error" and finding.subject in arrays:
            column = ", ".join(spec.name for spec in arrays[finding.subject][1])
            raise finding_error(head, locate, finding, column=column)
        elif finding.severity == "error":
            raise DataQualityError(finding.message, file=head.path, line=_stated_line(head, finding.subject),
                                   key=finding.subject)
        else:
            log.warning("%s: %s: %s", head.path, finding.subject, finding.message)
    return quality_report(findings, allowed=allowed)


def _history(head: RigHead, digest: str, what: str) -> str:
    cols = []
    for _, spec in head.columns:
        how = f"{spec.name!r} [{spec.units}]"
        if spec.sensitivity:
            how += f" at {spec.sensitivity}"
        if spec.scale != 1.0:
            how += f" x {spec.scale:g}"
        target = spec.variable if spec.sensor is None else f"{spec.variable}[{spec.sensor}]"
        cols.append(f"{target} <- {how}")
    origin = ", ".join(f"{k} ({v})" for k, v in head.attr_origin.items())
    return new_history(
        f"ingest {head.path.name}{what} (sha256 {digest}) with {head.profile.describe()}; columns: {'; '.join(cols)}; "
        f"metadata: {origin}", timestamp=False)  # same recording, same bytes: see new_history


def assemble_run(head: RigHead, locate, arrays: dict, digest: str, *, file_format: str | None = None,
                 allow_implausible: bool = False):
    """Check the converted columns and build the RunDataset.

    Parameters
    ----------
    head : RigHead
        The file's head: path, profile, mapped columns, metadata and where each came from.
    locate : callable
        ``locate(row)``: the file's 1-based line of 0-based sample ``row``, or None when the file has
        no lines (a binary DAQ file); messages then name the sample.
    arrays : dict
        ``variable -> (values, [ColumnSpec, ...])`` in SI, ``time`` included (finite); ``values`` is
        1-D, or 2-D ``(time, sensor)`` with one spec per sensor. Their finiteness is checked here,
        in the same pass as the plausibility bounds.
    digest : str
        sha256 of the file (hex), recorded in ``source`` and ``history``.
    file_format : str, optional
        Name of the file format when it is not a CSV (``"tdms"``); recorded in ``source_format``
        and ``history``.
    allow_implausible : bool, default False
        Keep a run whose data fail an overridable plausibility check (:mod:`fivid.io.plausibility`),
        recording each in ``quality_report`` and the attribute ``allow_implausible = "yes"``.

    Returns
    -------
    xarray.Dataset
        A valid RunDataset (see :func:`fivid.io.read_rig_csv`).

    Raises
    ------
    DataQualityError, SchemaError
        A value is not finite, the time column fails a check, the stated sample rate is not a
        positive number or disagrees with it, or a value is implausible.
    """
    import xarray as xr

    extremes = _extremes(head, locate, arrays)
    arrays = dict(arrays)
    time = arrays.pop("time")[0]
    sample_rate = _sample_rate(head, locate, time)
    report = _check_plausibility(head, locate, time, arrays, extremes, allow_implausible)
    attrs = dict(head.attrs)
    attrs["sample_rate"] = sample_rate
    attrs["quality_report"] = report
    if report.startswith("allowed"):
        attrs["allow_implausible"] = "yes"
    attrs["source"] = f"{head.path.name} sha256:{digest}"
    if file_format is not None:
        attrs["source_format"] = file_format
    attrs["history"] = _history(head, digest, "" if file_format is None else f" ({file_format})")
    data_vars, sensor_names = {}, None
    for name, (values, specs) in arrays.items():
        var_attrs = {"source_column": ", ".join(s.name for s in specs),
                     "source_units": ", ".join(s.units for s in specs)}
        if any(s.sensitivity for s in specs):
            var_attrs["sensitivity"] = ", ".join(s.sensitivity or "-" for s in specs)
        if any(s.scale != 1.0 for s in specs):
            var_attrs["scale"] = ", ".join(f"{s.scale:g}" for s in specs) if len(specs) > 1 else specs[0].scale
        if values.ndim == 2:
            names = [s.sensor for s in specs]
            if sensor_names is not None and names != sensor_names:
                raise SchemaError(f"{name!r} has sensors {names} but another variable has {sensor_names}; "
                                  "every variable with a sensor dimension must list the same sensors",
                                  file=head.path, line=head.header_line, column=specs[0].name)
            sensor_names = names
        data_vars[name] = xr.Variable(("time",) if values.ndim == 1 else ("time", "sensor"), values, var_attrs)
    time_spec = _time_spec(head)
    coords = {"time": xr.Variable(("time",), time, {"source_column": time_spec.name, "source_units": time_spec.units})}
    if sensor_names is not None:
        coords["sensor"] = xr.Variable(("sensor",), np.array(sensor_names, dtype=object))
    ds = apply_cf_attrs(with_condition_coords(xr.Dataset(data_vars, coords=coords, attrs=attrs)))
    known = registry().variables
    ds = ds[[n for n in known if n in ds.data_vars]]  # canonical order
    return validate_run(ds, name=str(head.path))
