"""Readers for force-displacement hysteresis recordings (friction dampers, joints).

Two layouts:

* CSV with units in the header, optional ``# key: value`` metadata lines first (read with the rig CSV
  machinery: the head as :mod:`fivid.io.rig_header` reads it, the data parsed by pyarrow as in
  :mod:`fivid.io.rig_csv`, errors naming file, line and column)::

      # fivid-hysteresis-csv: 1
      # source: my rig
      time [s],displacement [mm],force [N]
      0.000,0.012,1.50

  Column names: ``time``, ``displacement``, ``force`` (``friction_force`` is accepted for ``force``).
* JSON as in the ARTS-Lab friction-damper dataset (``data``: rows of time, displacement, friction
  force, ...; units in ``"time units"``, ``"displacement units"``, ``"friction force units"``).

Both return SI arrays: time [s], displacement [m], force [N].
"""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fivid.errors import DataQualityError, FividError, SchemaError, UnitError
from fivid.io.input_files import check_text_input
from fivid.io.rig_csv import _first_null, _Lines, _parse_columns, _to_si
from fivid.io.rig_header import RigHead, _head_lines, _split
from fivid.io.rig_profile import ColumnSpec, RigProfile
from fivid.units import conversion

__all__ = ["HysteresisRecord", "read_hysteresis", "read_hysteresis_csv", "read_hysteresis_json", "read_units_csv",
           "numeric_columns"]

_HEADER = re.compile(r"^\s*([A-Za-z_][\w ]*?)\s*\[([^\]]*)\]\s*$")
_CANONICAL = {"time": ("time", "s"), "displacement": ("displacement", "m"), "force": ("force", "N"),
              "friction_force": ("force", "N")}


@dataclass(frozen=True)
class HysteresisRecord:
    """A force-displacement recording in SI units.

    Attributes
    ----------
    time : ndarray
        [s], strictly increasing.
    displacement : ndarray
        [m].
    force : ndarray
        [N].
    metadata : dict
        File metadata, the original units and ``source`` (file name and sha256).
    """

    time: np.ndarray
    displacement: np.ndarray
    force: np.ndarray
    metadata: dict = field(default_factory=dict)


def _read_text(path: Path) -> str:
    """The file as UTF-8 text, or a SchemaError saying where the first non-UTF-8 byte is."""
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise SchemaError(f"not UTF-8 text (byte 0x{exc.object[exc.start]:02x} at offset {exc.start}); "
                          "export the recording as UTF-8 CSV or JSON", file=path) from None


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _scale(units: str, to: str, *, file, column: str) -> float:
    try:
        scale, offset = conversion(units, to)
    except FividError as exc:
        raise UnitError(f"{exc.message} (expected units compatible with {to!r})", file=file, column=column) from None
    if offset != 0.0:
        raise UnitError(f"units {units!r} have an offset; use a plain unit of {to!r}", file=file, column=column)
    return scale


def _finish(path: Path, t, x, f, metadata: dict) -> HysteresisRecord:
    for name, arr in (("time", t), ("displacement", x), ("force", f)):
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            raise DataQualityError(f"{bad.size} non-finite {name} values (first at data row {bad[0] + 1})",
                                   file=path, column=name)
    if t.size < 3:
        raise DataQualityError(f"only {t.size} samples; a hysteresis loop needs at least a few cycles", file=path)
    if np.any(np.diff(t) <= 0):
        i = int(np.flatnonzero(np.diff(t) <= 0)[0])
        raise DataQualityError(f"time is not strictly increasing at data row {i + 2} ({t[i]} s then {t[i + 1]} s)",
                               file=path, column="time")
    metadata = dict(metadata, source=f"{path.name} sha256:{_sha256(path)}")
    return HysteresisRecord(time=t, displacement=x, force=f, metadata=metadata)


def read_hysteresis_json(path) -> HysteresisRecord:
    """Read the ARTS-Lab friction-damper JSON layout (see the module docstring)."""
    path = Path(path)
    try:
        doc = json.loads(_read_text(path))
    except json.JSONDecodeError as exc:
        raise SchemaError(f"not valid JSON: {exc.msg}", file=path, line=exc.lineno) from None
    if not isinstance(doc, dict) or "data" not in doc:
        raise SchemaError("expected a JSON object with a 'data' list of rows [time, displacement, force, ...]", file=path)
    units = {}
    for key, to in (("time units", "s"), ("displacement units", "m"), ("friction force units", "N")):
        if key not in doc:
            raise UnitError(f"missing {key!r}: the units must be stated (e.g. \"{key}\": \"{to}\")", file=path, key=key)
        units[key] = str(doc[key])
    try:
        rows = np.asarray(doc["data"], dtype=float)
    except (TypeError, ValueError):
        raise SchemaError("'data' must be a list of numeric rows", file=path, key="data") from None
    if rows.ndim != 2 or rows.shape[1] < 3:
        raise SchemaError(f"'data' rows need at least 3 columns (time, displacement, force), got shape {rows.shape}",
                          file=path, key="data")
    st = _scale(units["time units"], "s", file=path, column="time")
    sx = _scale(units["displacement units"], "m", file=path, column="displacement")
    sf = _scale(units["friction force units"], "N", file=path, column="force")
    meta = {k: v for k, v in doc.items() if k != "data"}
    meta["original_units"] = units
    return _finish(path, rows[:, 0] * st, rows[:, 1] * sx, rows[:, 2] * sf, meta)


def _units_head(path: Path, example_header: str):
    """The head of a units CSV, read as a rig CSV's head is (:func:`fivid.io.rig_header._head_lines`: BOM, binary
    and encoding checks; the header split by the csv module): ``(meta, header line, header, n_fields, data offset)``."""
    meta = {}
    for number, offset, text in _head_lines(path, "utf-8"):
        if text.startswith("#") or not text.strip():
            m = re.match(r"#\s*([^:]+):\s*(.*)$", text)
            if m:
                meta[m.group(1).strip()] = m.group(2).strip()
            continue
        fields = _split(text, ",", path, number)
        header = {}
        for j, cell in enumerate(fields):
            m = _HEADER.match(cell)
            if m is None:
                raise UnitError(f"header cell {cell!r} has no unit; write it as 'name [unit]'",
                                file=path, line=number, column=cell)
            name = m.group(1).strip()
            if name in header:
                raise SchemaError(f"column {name!r} appears twice in the header (cells {header[name][0] + 1} and "
                                  f"{j + 1})", file=path, line=number, column=name)
            header[name] = (j, m.group(2).strip())
        return meta, number, header, len(fields), offset
    raise SchemaError(f"no header line such as {example_header!r} found", file=path)


def read_units_csv(path, example_header: str):
    """Split a CSV with ``# key: value`` metadata lines and a ``name [unit]`` header.

    Returns
    -------
    meta : dict
        Metadata from the comment lines.
    header_line : int
        1-based line number of the header.
    header : dict
        ``name -> (column index, unit string)``.
    body : list of (int, str)
        ``(line number, text)`` of the data lines.
    """
    path = Path(path)
    lines = _read_text(path).splitlines()
    meta, header_line, header, _, _ = _units_head(path, example_header)
    body = [(k, line) for k, line in enumerate(lines[header_line:], start=header_line + 1) if line.strip()]
    return meta, header_line, header, body


def numeric_columns(path, body, indices) -> np.ndarray:
    """The given column indices of the data lines as floats, shape (n_rows, len(indices))."""
    data = []
    for k, line in body:
        cells = _split(line, ",", path, k)
        try:
            data.append([float(cells[j]) for j in indices])
        except (ValueError, IndexError):
            raise SchemaError(f"row is not numeric or too short: {line[:60]!r}", file=path, line=k) from None
    return np.asarray(data, dtype=float).reshape(-1, len(indices))


def _si_columns(path: Path, header_line: int, n_fields: int, data_offset: int, columns: list) -> list:
    """The data of ``columns`` (``(field index, ColumnSpec)``) in SI, parsed as a rig CSV's data are
    (:mod:`fivid.io.rig_csv`: pyarrow from a memory map; a bad value is named by line and column)."""
    import pyarrow as pa

    head = RigHead(path, RigProfile(), columns, n_fields, header_line, data_offset, attrs={})
    with pa.memory_map(str(path), "r") as mapped:
        buffer = mapped.read_buffer()
        lines = _Lines(buffer, head)
        parsed = _parse_columns(buffer, head, lines)
        out = []
        for index, spec in columns:
            column = parsed[index]
            if column.null_count:
                raise DataQualityError("empty value (a missing sample)", file=path, line=lines(_first_null(column)),
                                       column=spec.name)
            out.append(_to_si(column, spec.factor, spec.offset, np.empty(len(column))))
    return out


def read_hysteresis_csv(path) -> HysteresisRecord:
    """Read a hysteresis CSV with ``name [unit]`` headers (see the module docstring)."""
    path = Path(path)
    _read_text(path)  # the whole file is UTF-8 text (the data part is parsed as bytes)
    meta, header_line, header, n_fields, data_offset = _units_head(path, "time [s],displacement [m],force [N]")
    if "force" in header and "friction_force" in header:
        raise SchemaError("both 'force' and 'friction_force' columns: keep one (they name the same quantity)",
                          file=path, line=header_line, column="friction_force")
    specs = {}
    for name, (j, unit) in header.items():
        if name in _CANONICAL:
            canon, to = _CANONICAL[name]
            specs[canon] = (j, ColumnSpec(canon, name, unit, factor=_scale(unit, to, file=path, column=name)))
            meta.setdefault("original_units", {})[canon] = unit
    missing = [c for c in ("time", "displacement", "force") if c not in specs]
    if missing:
        raise SchemaError(f"missing columns {missing}; the header needs time, displacement and force (with units)",
                          file=path, line=header_line)
    t, x, f = _si_columns(path, header_line, n_fields, data_offset, [specs[c] for c in ("time", "displacement",
                                                                                        "force")])
    return _finish(path, t, x, f, meta)


def read_hysteresis(path) -> HysteresisRecord:
    """Read a hysteresis recording, choosing the layout by the file suffix (``.json`` or ``.csv``)."""
    path = check_text_input(path, what="hysteresis recording")  # size, link loops and encoding before reading
    suffix = path.suffix.lower()
    if suffix == ".json":
        return read_hysteresis_json(path)
    if suffix in (".csv", ".txt"):
        return read_hysteresis_csv(path)
    raise SchemaError(f"unknown hysteresis file type {suffix!r}; expected .json or .csv", file=path)
