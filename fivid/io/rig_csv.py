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
from fivid.io.rig_header import RigHead, read_rig_head
from fivid.io.rig_profile import RigProfile, load_rig_profile
from fivid.io.run_assembly import assemble_run, by_variable
from fivid.schema import registry

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


def read_rig_csv(path, profile=None, *, allow_implausible: bool = False):
    """Read a rig CSV file into a RunDataset in SI units.

    Parameters
    ----------
    path : str or path-like
        A ``fivid-rig-csv: 1`` file, or a DAQ export described by ``profile``.
    profile : RigProfile, str or path-like, optional
        How to read the file: a :class:`~fivid.io.RigProfile`, the name of a profile in
        ``configs/rigs/`` (``"triboair"``, ``"labdaq"``) or the path of one. Default: the built-in
        ``fivid-rig-csv`` format.
    allow_implausible : bool, default False
        Keep a run that fails an overridable plausibility check (:mod:`fivid.io.plausibility`: a
        rate outside the DAQ range, a measured load 10x off the nominal one, ...), recorded in its
        ``quality_report`` and the attribute ``allow_implausible``; by default it is an error.

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
        the profile's ``checks.sampling_tolerance``; a stated sample rate that is not > 0 or
        disagrees with the time column; implausible values (:mod:`fivid.io.plausibility`).
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
        for variable, members in by_variable(head).items():
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
            arrays[variable] = (values, [spec for _, spec in members])
        return assemble_run(head, lines, arrays, sha.hexdigest(), allow_implausible=allow_implausible)
