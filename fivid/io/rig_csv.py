"""Read a rig CSV into a validated RunDataset in SI units.

The head (metadata, header) is read by :mod:`fivid.io.rig_header`; the data are parsed by
``pyarrow.csv`` straight from a memory map, multi-threaded, as float64, and each column is converted
to its SI unit while it is copied out of Arrow (one pass, one copy). The checks are vectorised
(:mod:`fivid.io.data_checks`). Errors name the file's own line numbers: when something is wrong the
file is re-scanned (only then) to map data rows to lines, blank lines included.
"""

from __future__ import annotations

import difflib
import hashlib
import logging
import os
import re
import threading

import numpy as np

from fivid.errors import DataQualityError, FividError, SchemaError
from fivid.io.data_checks import (first_non_finite, nominal_sample_rate, sampling_deviation, time_not_increasing,
                                  time_without_resolution)
from fivid.io.plausibility import plausibility_findings, quality_report
from fivid.io.rig_header import RigHead, read_rig_head
from fivid.io.rig_profile import RigProfile, load_rig_profile
from fivid.schema import apply_cf_attrs, new_history, registry, validate_run

__all__ = ["read_rig_csv", "as_rig_profile"]

log = logging.getLogger("fivid")

_ROW = re.compile(r"Row #(\d+)")
_FIELDS = re.compile(r"Expected (\d+) columns, got (\d+): ?(.*)", re.S)
_VALUE = re.compile(r"column #(\d+).*invalid value '(.*)'", re.S)


def as_rig_profile(profile) -> RigProfile:
    """``None`` → the built-in fivid-rig-csv format; a name or path → :func:`load_rig_profile`."""
    if profile is None:
        return RigProfile()
    if isinstance(profile, RigProfile):
        return profile
    return load_rig_profile(profile)


class _Lines:
    """Maps 0-based data rows to the file's 1-based line numbers (pyarrow skips blank lines)."""

    def __init__(self, buffer, head: RigHead):
        self._buffer = buffer
        self._head = head
        self._rows = None

    def _nonempty(self) -> np.ndarray:
        if self._rows is None:
            data = np.frombuffer(self._buffer, dtype=np.uint8)[self._head.data_offset:]
            newlines = np.flatnonzero(data == 10)
            starts = np.concatenate(([0], newlines + 1))
            ends = np.concatenate((newlines, [data.size]))
            length = ends - starts
            if data.size:  # a line holding only "\r" is blank too (CRLF files)
                length -= (length > 0) & (data[np.maximum(ends - 1, 0)] == 13)
            self._rows = np.flatnonzero(length > 0)
        return self._rows

    def __call__(self, row: int) -> int:
        rows = self._nonempty()
        if rows.size == 0:
            return self._head.header_line + 1
        return self._head.header_line + 1 + int(rows[min(row, rows.size - 1)])

    def is_last(self, row: int) -> bool:
        return row == self._nonempty().size - 1


def _data_block(buffer, head: RigHead):
    """The data part of the file, without trailing lines made only of delimiters and blanks.

    Spreadsheet programs often save a table with trailing ``;;;;`` rows; they are not samples.
    Only the file's tail is read.
    """
    junk = b" \t\r\n" + head.profile.delimiter.encode()
    start = end = buffer.size
    last = None  # offset of the last byte that is not junk
    while start > head.data_offset and last is None:
        start = max(head.data_offset, start - (1 << 16))
        kept = buffer.slice(start, end - start).to_pybytes().rstrip(junk)
        if kept:
            last = start + len(kept) - 1
        end = start
    if last is None:
        return buffer.slice(head.data_offset, 0)
    rest = buffer.slice(last, buffer.size - last).to_pybytes()
    newline = rest.find(b"\n")
    stop = buffer.size if newline < 0 else last + newline + 1
    return buffer.slice(head.data_offset, stop - head.data_offset)


def _arrow_options(head: RigHead, *, use_threads: bool, names: list[str], include: list[str], handler=None):
    import pyarrow as pa
    import pyarrow.csv as pcsv

    profile = head.profile
    read = pcsv.ReadOptions(use_threads=use_threads, column_names=names, block_size=1 << 22)
    parse = pcsv.ParseOptions(delimiter=profile.delimiter, quote_char='"', ignore_empty_lines=True,
                              newlines_in_values=False, invalid_row_handler=handler)
    convert = pcsv.ConvertOptions(
        include_columns=include, column_types={n: pa.float64() for n in include}, null_values=[""],
        strings_can_be_null=False, quoted_strings_can_be_null=False, decimal_point=profile.decimal,
        check_utf8=False,
    )
    return read, parse, convert


def _locate_parse_error(buffer, head: RigHead, names, include, lines: _Lines, fallback: str) -> FividError:
    """Re-parse single-threaded to find the first bad row (pyarrow gives row numbers only then)."""
    import pyarrow as pa
    import pyarrow.csv as pcsv

    read, parse, convert = _arrow_options(head, use_threads=False, names=names, include=include)
    try:
        pcsv.read_csv(pa.BufferReader(_data_block(buffer, head)), read_options=read,
                      parse_options=parse, convert_options=convert)
    except pa.ArrowInvalid as exc:
        message = str(exc)
    else:  # not reproducible single-threaded: report what the first pass said
        return SchemaError(f"cannot parse the data ({fallback})", file=head.path)
    row = _ROW.search(message)
    line = None if row is None else lines(int(row.group(1)) - 1)
    fields = _FIELDS.search(message)
    if fields is not None:
        expected, got, text = fields.groups()
        hint = ""
        if row is not None and lines.is_last(int(row.group(1)) - 1) and int(got) < int(expected):
            hint = " (the last line is incomplete: was the file truncated?)"
        return SchemaError(
            f"the row has {got} field(s) but the header has {expected}{hint}: {text.strip()[:80]!r}",
            file=head.path, line=line,
        )
    value = _VALUE.search(message)
    if value is not None:
        index, text = int(value.group(1)), value.group(2)
        column = next((spec.name for i, spec in head.columns if i == index), f"#{index + 1}")
        mark = "decimal comma" if head.profile.decimal == "," else "decimal point"
        return SchemaError(
            f"cannot read {text!r} as a number (expected a number with a {mark}, or nan/inf)",
            file=head.path, line=line, column=column,
        )
    return SchemaError(f"cannot parse the data: {message}", file=head.path, line=line)


def _parse_columns(buffer, head: RigHead, lines: _Lines) -> dict:
    """Parse the data block with pyarrow; returns ``field index -> pyarrow.ChunkedArray`` (float64)."""
    import pyarrow as pa
    import pyarrow.csv as pcsv

    names = [f"f{i}" for i in range(head.n_fields)]
    include = [names[i] for i, _ in head.columns]
    read, parse, convert = _arrow_options(head, use_threads=True, names=names, include=include)
    try:
        table = pcsv.read_csv(pa.BufferReader(_data_block(buffer, head)), read_options=read,
                              parse_options=parse, convert_options=convert)
    except pa.ArrowInvalid as exc:
        if "Empty CSV file" in str(exc):
            raise SchemaError("no data rows after the header", file=head.path, line=head.header_line) from None
        raise _locate_parse_error(buffer, head, names, include, lines, str(exc)) from None
    return {i: table.column(names[i]) for i, _ in head.columns}


def _to_si(column, factor: float, offset: float, out: np.ndarray) -> np.ndarray:
    """Copy an Arrow float64 column into ``out`` (1-D, may be strided), scaled to SI in the same pass."""
    start = 0
    for chunk in column.chunks:
        raw = chunk.to_numpy(zero_copy_only=True)
        dst = out[start:start + raw.size]
        if factor == 1.0:
            np.copyto(dst, raw)
        else:
            np.multiply(raw, factor, out=dst)
        if offset:
            dst += offset
        start += raw.size
    return out


def _first_null(column) -> int:
    import pyarrow.compute as pc

    return int(pc.index(pc.is_null(column), True).as_py())


def _fail(head: RigHead, lines: _Lines, finding, column: str | None = None) -> DataQualityError:
    line = lines(finding.index)
    message = finding.message
    if finding.previous is not None:
        message += f" (previous sample at line {lines(finding.previous)})"
    return DataQualityError(message, file=head.path, line=line, column=column)


def _by_variable(head: RigHead) -> dict:
    """``variable -> [(field index, ColumnSpec), ...]`` in header order (several for sensors)."""
    groups: dict = {}
    for index, spec in head.columns:
        groups.setdefault(spec.variable, []).append((index, spec))
    return groups


def _time_spec(head: RigHead):
    return next(spec for _, spec in head.columns if spec.variable == "time")


def _sample_rate(head: RigHead, lines: _Lines, time: np.ndarray) -> float:
    if time.size < 2:
        raise SchemaError(
            "no data rows after the header" if time.size == 0 else
            "only one data row; a run needs at least two samples", file=head.path, line=head.header_line,
        )
    column = _time_spec(head).name
    tolerance = head.profile.sampling_tolerance
    checks = (lambda: time_without_resolution(time, tolerance), lambda: time_not_increasing(time),
              lambda: sampling_deviation(time, tolerance))  # in order: each assumes the previous passed
    for check in checks:
        finding = check()
        if finding is not None:
            raise _fail(head, lines, finding, column=column)
    measured = nominal_sample_rate(time)
    stated = head.attrs.get("sample_rate")
    if stated is None:
        return measured
    if abs(stated - measured) > head.profile.sampling_tolerance * measured:
        hint = ""
        for factor in (1e-3, 1e3, 1e-6, 1e6):
            if abs(measured / (stated * factor) - 1) <= head.profile.sampling_tolerance:
                hint = (f"; the ratio is {factor:g}: the time column's unit {_time_spec(head).units!r} looks wrong by "
                        "that factor (times in ms under a header in s give 0.001); correct the unit in the header")
        raise DataQualityError(
            f"the stated sample rate {stated:.9g} Hz ({head.attr_origin['sample_rate']}) does not match the time "
            f"column, which gives {measured:.9g} Hz; tolerance {100 * head.profile.sampling_tolerance:.3g} %{hint}",
            file=head.path, key="sample_rate",
        )
    return float(stated)


def _check_plausibility(head: RigHead, lines: _Lines, sample_rate: float, arrays: dict) -> str:
    """Raise the first plausibility error (file, line, column or key); log the warnings; return the report."""
    findings = plausibility_findings({**head.attrs, "sample_rate": sample_rate},
                                     {name: values for name, (values, _) in arrays.items()})
    for finding in findings:
        if finding.severity == "error" and finding.subject in arrays:
            column = ", ".join(spec.name for spec in arrays[finding.subject][1])
            raise _fail(head, lines, finding, column=column)
        if finding.severity == "error":
            origin = head.attr_origin.get(finding.subject, "")
            line = int(origin.split()[1]) if origin.startswith("line ") else None
            raise DataQualityError(finding.message, file=head.path, line=line, key=finding.subject)
        log.warning("%s: %s: %s", head.path, finding.subject, finding.message)
    return quality_report(findings)


def _history(head: RigHead, digest: str) -> str:
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
        f"ingest {head.path.name} (sha256 {digest}) with {head.profile.describe()}; columns: {'; '.join(cols)}; "
        f"metadata: {origin}", timestamp=False)  # same CSV, same bytes: see new_history


def _warn_misspelt_columns(head: RigHead) -> None:
    """Warn about fivid-rig-csv header names that are no variable but close to one ('positon').

    Such a column is ignored (it may be an extra channel), so a typo would drop data without a word.
    Done here, not in :func:`read_rig_head`, which an ingest calls twice per file.
    """
    if head.profile.format != "fivid-rig-csv":
        return
    variables = [n for n, v in registry().variables.items() if not v.coordinate or n == "time"]  # mappable
    for label in head.ignored_columns:
        close = difflib.get_close_matches(label.partition(":")[0].strip(), variables, n=1)
        if close:
            log.warning("%s:%d: column %r is not a variable and is ignored; did you mean %r?",
                        head.path, head.header_line, label, close[0])


def read_rig_csv(path, profile=None):
    """Read a rig CSV file into a RunDataset in SI units.

    Parameters
    ----------
    path : str or path-like
        A ``fivid-rig-csv: 1`` file, or a DAQ export described by ``profile``.
    profile : RigProfile, str or path-like, optional
        How to read the file: a :class:`~fivid.io.RigProfile`, the name of a profile in
        ``configs/rigs/`` (``"triboair"``, ``"labdaq"``) or the path of one. Default: the built-in
        ``fivid-rig-csv`` format.

    Returns
    -------
    xarray.Dataset
        A valid RunDataset (:func:`fivid.schema.validate_run`): coordinate ``time`` [s];
        ``acceleration`` [m s-2], ``friction_force`` [N], ``normal_force`` [N], and ``position`` [m]
        / ``velocity`` [m s-1] when present; attrs ``run_id``, ``rig``, ``sliding_velocity``
        [m s-1], ``normal_load`` [N], ``roughness_ra`` [m], ``sample_rate`` [Hz] (the stated one if
        the file gives it and it agrees with the time column, else ``(n - 1) / (t[-1] - t[0])``),
        ``source`` (file name and sha256), ``history`` and the other metadata found. Each variable
        records its ``source_column`` and ``source_units`` (and ``sensitivity``).

    Raises
    ------
    SchemaError
        Empty, binary or malformed file; missing column or metadata; a number that does not parse;
        a row with the wrong number of fields (e.g. a truncated last line).
    UnitError
        An unknown unit or one of the wrong dimension.
    DataQualityError
        NaN, infinite or missing values; time not strictly increasing; sampling not uniform within
        the profile's ``checks.sampling_tolerance``.
    ConfigError
        The profile is not found or invalid.

    Every error names the file and its line number (1-based, counting metadata lines), and the
    column or metadata key.

    Examples
    --------
    >>> ds = read_rig_csv("sample_data/R001_v10_ra08.csv")            # doctest: +SKIP
    >>> float(ds.attrs["sliding_velocity"])   # written '10 mm/s'     # doctest: +SKIP
    0.01
    """
    import pyarrow as pa
    import xarray as xr

    profile = as_rig_profile(profile)
    head = read_rig_head(path, profile)
    _warn_misspelt_columns(head)
    try:
        mapped = pa.memory_map(os.fspath(head.path), "r")
    except OSError as exc:
        raise FividError(f"cannot read the file ({exc.strerror or exc})", file=head.path) from None
    with mapped:
        buffer = mapped.read_buffer()
        sha = hashlib.sha256()
        hasher = threading.Thread(target=sha.update, args=(memoryview(buffer),), daemon=True)
        hasher.start()  # hashlib releases the GIL: the digest overlaps the parse
        lines = _Lines(buffer, head)
        try:
            arrow_columns = _parse_columns(buffer, head, lines)
        finally:
            hasher.join()
        arrays = {}
        for variable, members in _by_variable(head).items():
            n = len(arrow_columns[members[0][0]])
            sensors = [spec.sensor for _, spec in members]
            values = np.empty((n, len(members)) if sensors[0] is not None else n, dtype=np.float64)
            for k, (index, spec) in enumerate(members):
                column = arrow_columns.pop(index)
                if column.null_count:
                    raise DataQualityError("empty value (a missing sample)", file=head.path,
                                           line=lines(_first_null(column)), column=spec.name)
                target = values if values.ndim == 1 else values[:, k]
                _to_si(column, spec.factor, spec.offset, target)
                del column
                pa.default_memory_pool().release_unused()  # give the Arrow column back: one copy at a time
                finding = first_non_finite(target)
                if finding is not None:
                    raise _fail(head, lines, finding, column=spec.name)
            arrays[variable] = (values, [spec for _, spec in members])
        time = arrays.pop("time")[0]
        sample_rate = _sample_rate(head, lines, time)
        report = _check_plausibility(head, lines, sample_rate, arrays)
    digest = sha.hexdigest()
    attrs = dict(head.attrs)
    attrs["sample_rate"] = sample_rate
    attrs["quality_report"] = report
    attrs["source"] = f"{head.path.name} sha256:{digest}"
    attrs["history"] = _history(head, digest)
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
    ds = apply_cf_attrs(xr.Dataset(data_vars, coords=coords, attrs=attrs))
    known = registry().variables
    ds = ds[[n for n in known if n in ds.data_vars]]  # canonical order
    return validate_run(ds, name=str(head.path))
