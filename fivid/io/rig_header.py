"""The head of a rig CSV: preamble metadata, the column header, where the data start.

Reads only the first lines of a file (never the data), so :func:`fivid.io.ingest_files` can learn
every file's ``run_id`` cheaply before converting anything. Line numbers are the file's own
(1-based, counting every line, metadata and blank lines included).
"""

from __future__ import annotations

import csv
import logging
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from fivid.errors import FividError, SchemaError, UnitError
from fivid.io.input_files import binary_content, stat_input
from fivid.io.rig_profile import RESERVED_ATTRIBUTES, ColumnSpec, RigProfile, has_sensor_dim
from fivid.io.rig_quantities import attribute_units, metadata_value
from fivid.schema import registry
from fivid.units import conversion

__all__ = ["RigHead", "read_rig_head", "MAX_HEAD_LINES", "MAGIC_KEY", "FORMAT_VERSION"]

log = logging.getLogger("fivid")

MAGIC_KEY = "fivid-rig-csv"
FORMAT_VERSION = "1"
#: How far the column header is looked for.
MAX_HEAD_LINES = 1000
_MAX_HEAD_BYTES = 4 << 20
_HEAD_FIELD = re.compile(r"^(?P<name>.*?)\s*\[(?P<units>[^\]]*)\]$")
_RIG_META = re.compile(r"^\s*(?P<key>[A-Za-z][A-Za-z0-9_-]*)\s*:\s*(?P<value>.*?)\s*$")
_REQUIRED = ("run_id", "rig", "sliding_velocity", "normal_load", "roughness_ra")


@dataclass
class RigHead:
    """What the head of a rig CSV says.

    Attributes
    ----------
    path : Path
        The file.
    profile : RigProfile
        The profile it was read with.
    columns : list of (int, ColumnSpec)
        Field index in the row and how to convert it, for every column that maps to a variable.
    n_fields : int
        Number of fields of the header row (every data row must have as many).
    header_line : int
        1-based line number of the column header.
    data_offset : int
        Byte offset of the first line after the header.
    attrs : dict
        Run attributes (SI floats for quantities, str otherwise).
    attr_origin : dict
        Where each attribute came from (``"line 3"``, ``"file name"``, ``"profile"``).
    ignored_columns : list of str
        Header fields that map to no variable.
    """

    path: Path
    profile: RigProfile
    columns: list
    n_fields: int
    header_line: int
    data_offset: int
    attrs: dict
    attr_origin: dict = field(default_factory=dict)
    ignored_columns: list = field(default_factory=list)


def _head_lines(path: Path, encoding: str):
    """Yield ``(line_number, byte_offset_after, text)`` for the first lines of ``path``.

    Raises SchemaError for an empty or binary file, or text not in ``encoding``.
    """
    with open(path, "rb") as f:
        head = f.read(_MAX_HEAD_BYTES)
    if not head.strip():
        raise SchemaError("the file is empty" if not head else "the file has only blank lines", file=path, line=1)
    problem = None if encoding.replace("_", "-").lower().startswith(("utf-16", "utf-32")) else binary_content(head[:65536])
    if problem is not None and "text" in problem:  # UTF-16 (Excel's 'Unicode text'): name it, say how to read it
        raise SchemaError(f"not 8-bit CSV text: the file is {problem}; save it as UTF-8 (Excel: 'CSV UTF-8'; or "
                          f"iconv -f {problem.split()[0]} -t UTF-8 {path.name} > new.csv)", file=path, line=1)
    if problem is not None:
        raise SchemaError(
            "not a CSV text file (it has binary content, NUL bytes); export the DAQ data as CSV text", file=path
        )
    offset = 0
    if encoding.replace("_", "-").startswith("utf-8") and head.startswith(b"\xef\xbb\xbf"):
        offset = 3  # UTF-8 byte-order mark (Excel, some DAQ exports): accepted
    number = 0
    while offset < len(head) and number < MAX_HEAD_LINES:
        end = head.find(b"\n", offset)
        stop = len(head) if end < 0 else end + 1
        number += 1
        raw = head[offset:stop].rstrip(b"\r\n")
        try:
            text = raw.decode(encoding)
        except UnicodeDecodeError as exc:
            raise SchemaError(
                f"not {encoding} text (byte 0x{raw[exc.start]:02x} at character {exc.start + 1}); "
                "if this is a CSV export in another encoding, give it in the rig profile (csv.encoding: latin-1)",
                file=path, line=number,
            ) from None
        yield number, stop, text
        offset = stop


def _delimiter_hint(header: str, delimiter: str) -> str:
    """A hint when a header line is separated by another character than the profile's delimiter ("" if not)."""
    counts = {d: header.count(d) for d in (";", "\t", "|") if d != delimiter}
    other, n = max(counts.items(), key=lambda item: item[1])
    if n == 0 or header.count(delimiter) >= n:
        return ""
    name = {";": "semicolons", "\t": "tabs", "|": "'|'"}[other]
    return (f"; the header is separated by {name}, not {delimiter!r}: a fivid-rig-csv file uses commas and decimal "
            f"points; for another layout (e.g. semicolons with decimal commas) give a rig profile with delimiter "
            f"{other!r} (--rig NAME; configs/rigs/labdaq.yaml is one, docs/ingest.md §3)")


def _split(text: str, delimiter: str, path=None, line=None) -> list[str]:
    try:
        row = next(csv.reader([text], delimiter=delimiter, quotechar='"', skipinitialspace=True), [])
    except csv.Error as exc:  # e.g. a lone carriage return inside a line (found by tests/io/test_io_fuzz.py)
        raise SchemaError(f"the header line cannot be split into fields ({exc}); a lone carriage return or a "
                          "broken quote? Save the file with one line ending per line", file=path, line=line) from None
    return [f.strip().strip("\ufeff").strip() for f in row]


def _variables() -> dict:
    return {n: v for n, v in registry().variables.items() if not v.coordinate or n == "time"}


def rig_csv_columns(path: Path, fields: list[str], line: int):
    """Columns of a fivid-rig-csv header ``name [unit]`` or ``name:sensor [unit]``."""
    variables = _variables()
    columns, ignored, seen = [], [], {}
    for index, text in enumerate(fields):
        m = _HEAD_FIELD.match(text)
        if m is None or not m.group("name"):
            raise SchemaError(
                f"column header {text!r} must be written 'name [unit]', e.g. 'acceleration [g]'",
                file=path, line=line, column=text or f"#{index + 1}",
            )
        label, units = m.group("name").strip(), m.group("units").strip()
        if label in seen:
            raise SchemaError(f"column {label!r} appears twice in the header (fields {seen[label]} and {index + 1})",
                              file=path, line=line, column=label)
        seen[label] = index + 1
        name, _, sensor = (part.strip() for part in label.partition(":"))
        if name not in variables:
            ignored.append(label)
            continue
        if sensor and not has_sensor_dim(name):
            raise SchemaError(f"{name!r} has no sensor dimension; write '{name} [unit]' (one column)",
                              file=path, line=line, column=label)
        if not units:
            raise UnitError(f"column {label!r} has an empty unit; write e.g. '{label} [{variables[name].units}]'",
                            file=path, line=line, column=label)
        try:
            factor, offset = conversion(units, variables[name].units)
        except UnitError as exc:
            raise exc.located(file=path, line=line, column=label) from None
        columns.append((index, ColumnSpec(name, label, units, None, 1.0, factor, offset, sensor or None)))
    for name in {spec.variable for _, spec in columns}:
        named = [spec.sensor is not None for _, spec in columns if spec.variable == name]
        if len(named) > 1 and not all(named):
            raise SchemaError(
                f"{name!r} has {len(named)} columns: name each one's sensor, e.g. '{name}:top [unit]', "
                f"'{name}:side [unit]'", file=path, line=line, column=name)
    return columns, ignored


def table_columns(path: Path, profile: RigProfile, fields: list[str], line: int | None, what: str = "column"):
    """Columns of a table-format header (or a DAQ file's channel names), located by the names in the profile."""
    columns, missing = [], []
    for spec in profile.columns:
        where = [i for i, f in enumerate(fields) if f == spec.name]
        if len(where) > 1:
            place = "the header" if what == "column" else "the file"
            raise SchemaError(f"{what} {spec.name!r} appears {len(where)} times in {place}",
                              file=path, line=line, column=spec.name)
        if not where:
            missing.append(spec)
            continue
        columns.append((where[0], spec))
    variables = registry().variables
    for spec in missing:
        if spec.variable == "time" or variables[spec.variable].required:
            has = "the header has" if what == "column" else f"the file's {what}s are"
            raise SchemaError(
                f"required {what} {spec.name!r} ({spec.variable}) is missing; {has} "
                f"{', '.join(repr(f) for f in fields)} ({profile.describe()})",
                file=path, line=line, column=spec.name,
            )
        log.warning("%s: optional %s %r (%s) of %s is not in the file", path, what, spec.name, spec.variable,
                    profile.name)
    mapped = {i for i, _ in columns}
    ignored = [f for i, f in enumerate(fields) if i not in mapped]
    return sorted(columns, key=lambda c: c[0]), ignored


def metadata_attribute(profile: RigProfile, raw_key: str) -> str | None:
    """The attribute a file's metadata key gives under a table ``profile`` (``metadata.in_file.keys``,
    matched case-insensitively, or an attribute's own name), or None when it gives none."""
    raw_key = raw_key.strip().strip('"').strip()
    attr = profile.metadata_keys.get(raw_key.casefold())
    if attr is None and raw_key in set(registry().attributes) - RESERVED_ATTRIBUTES:
        attr = raw_key
    return attr


def _file_metadata(path: Path, profile: RigProfile, lines: list[tuple[int, str]]) -> dict:
    """``attr -> (value, line)`` from the preamble lines."""
    found: dict = {}
    if profile.format == "fivid-rig-csv":
        for number, text in lines:
            if not text.strip():
                continue
            m = _RIG_META.match(text[len(profile.comment):])
            if m is None:
                continue  # a comment
            key = m.group("key").replace("-", "_") if m.group("key") != MAGIC_KEY else MAGIC_KEY
            if key in found:
                raise SchemaError(f"metadata {key!r} is given twice (lines {found[key][1]} and {number})",
                                  file=path, line=number, key=key)
            found[key] = (m.group("value"), number)
        return found
    pattern = re.compile(profile.metadata_pattern)
    for number, text in lines:
        m = pattern.match(text)
        if m is None:
            continue
        attr = metadata_attribute(profile, m.group("key"))
        if attr is None:
            continue
        value = m.group("value").strip().rstrip(profile.delimiter).strip().strip('"').strip()
        if attr in found:
            raise SchemaError(f"metadata {attr!r} is given twice (lines {found[attr][1]} and {number})",
                              file=path, line=number, key=attr)
        found[attr] = (value, number)
    return found


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=0.0)
    return a == b


def _from_file_name(path: Path, profile: RigProfile, attrs: dict, origin: dict) -> bool:
    """Add the attributes the profile's file-name pattern gives; False when the name does not match."""
    if not profile.file_name_pattern:
        return True
    m = re.search(profile.file_name_pattern, path.name)
    if m is None:
        return False
    for attr, raw in m.groupdict().items():
        if raw is None:
            continue
        try:
            value = metadata_value(attr, raw, default_units=profile.file_name_units.get(attr), decimal=profile.decimal)
        except FividError as exc:
            raise type(exc)(f"from the file name ({raw!r}): {exc.message}", file=path, key=attr) from None
        if attr in attrs and not _same(attrs[attr], value):
            unit = f" {attribute_units(attr)}" if attribute_units(attr) else ""
            raise SchemaError(
                f"the file says {attr} = {attrs[attr]!r}{unit} ({origin[attr]}) but its name says {value!r}{unit}; "
                "correct one of them",
                file=path, key=attr,
            )
        if attr not in attrs:
            attrs[attr] = value
            origin[attr] = "file name"
    return True


def resolve_metadata(path: Path, profile: RigProfile, found: dict):
    """Attributes from the file, then the file name, then the profile; file and name must agree.

    ``found`` maps an attribute to ``(raw value, where)``: ``where`` is the 1-based line of a text
    file, or a description (``"file property 'Run'"``) for a file without lines.
    """
    attrs, origin = {}, {}
    for attr, (raw, number) in found.items():
        line = number if isinstance(number, int) else None
        if attr == MAGIC_KEY:
            continue
        if attr in RESERVED_ATTRIBUTES or attr.endswith("_units"):
            raise SchemaError(f"metadata {attr!r} is written by fivid itself; remove it from the file",
                              file=path, line=line, key=attr)
        try:
            attrs[attr] = metadata_value(attr, raw, default_units=profile.metadata_units.get(attr),
                                         decimal=profile.decimal)
        except FividError as exc:
            raise exc.located(file=path, line=line, key=attr) from None
        origin[attr] = f"line {number}" if line is not None else str(number)
    unmatched_name = not _from_file_name(path, profile, attrs, origin)
    for attr, value in profile.values.items():
        if attr not in attrs:
            attrs[attr] = value
            origin[attr] = "profile"
    for attr in _REQUIRED:
        if attr not in attrs:
            att = registry().attributes[attr]
            value = f"<value> {att.units}" if att.units else "<value>"
            if profile.format == "fivid-rig-csv":
                how = f"add a line '# {attr}: {value}' before the header"
                if att.units:
                    how += " (any unit of that dimension)"
            else:
                how = (f"give it in the file's preamble, the file name (metadata.file_name.pattern) or "
                       f"metadata.values of {profile.describe()}")
            if unmatched_name:
                how += f"; note: the file name does not match metadata.file_name.pattern {profile.file_name_pattern!r}"
            raise SchemaError(f"missing metadata {attr!r} ({att.long_name}): {how}", file=path, key=attr)
    return attrs, origin


def read_rig_head(path, profile: RigProfile | None = None) -> RigHead:
    """Read the metadata and column header of a rig CSV (not its data).

    Parameters
    ----------
    path : str or path-like
        The rig CSV.
    profile : RigProfile, optional
        How to read it; default the built-in ``fivid-rig-csv`` format.

    Raises
    ------
    SchemaError, UnitError
        Empty or binary file, wrong format line, no header, missing or duplicated column or
        metadata, unknown or incompatible unit. The error names the file, line and column or key.
    """
    path = Path(path)
    profile = profile if profile is not None else RigProfile()
    stat_input(path)  # no such file, a link loop, a folder: named before the file is opened
    preamble: list[tuple[int, str]] = []
    target_line = profile.header_line
    time_spec = profile.column("time")
    for number, offset, text in _head_lines(path, profile.encoding):
        if profile.format == "fivid-rig-csv" and number == 1:
            m = _RIG_META.match(text[len(profile.comment):]) if text.startswith(profile.comment) else None
            if m is None or m.group("key") != MAGIC_KEY:
                used = "" if profile.path is None else f" (the format of {profile.describe()})"
                raise SchemaError(
                    f"not a fivid-rig-csv file{used}: the first line must be '# {MAGIC_KEY}: {FORMAT_VERSION}', "
                    f"got {text[:60]!r}; for another DAQ export give its rig profile (--rig NAME, configs/rigs/)",
                    file=path, line=1,
                )
            if m.group("value") != FORMAT_VERSION:
                raise SchemaError(f"unsupported fivid-rig-csv version {m.group('value')!r}; this fivid reads version "
                                  f"{FORMAT_VERSION}", file=path, line=1, key=MAGIC_KEY)
        if target_line is not None:
            is_header = number == target_line
        elif profile.format == "fivid-rig-csv":
            is_header = bool(text.strip()) and not text.startswith(profile.comment)
        else:
            is_header = time_spec.name in _split(text, profile.delimiter, path, number)
        if not is_header:
            preamble.append((number, text))
            continue
        fields = _split(text, profile.delimiter, path, number)
        if profile.format == "fivid-rig-csv":
            columns, ignored = rig_csv_columns(path, fields, number)
        else:
            columns, ignored = table_columns(path, profile, fields, number)
        found = _file_metadata(path, profile, preamble)
        attrs, origin = resolve_metadata(path, profile, found)
        variables = {spec.variable for _, spec in columns}
        missing = [n for n, v in registry().variables.items() if (v.required or n == "time") and n not in variables]
        if missing:
            raise SchemaError(
                f"required column(s) {', '.join(repr(m) for m in missing)} missing; the header has "
                f"{', '.join(repr(f) for f in fields)}{_delimiter_hint(text, profile.delimiter)}",
                file=path, line=number, column=missing[0],
            )
        if ignored:
            log.info("%s: columns not mapped to a variable (ignored): %s", path, ", ".join(ignored))
        return RigHead(path, profile, columns, len(fields), number, offset, attrs, origin, ignored)
    if target_line is not None:
        what = f"line {target_line} (csv.header_line)"
        raise SchemaError(f"the file ends before the column header at {what}", file=path)
    if profile.format == "fivid-rig-csv":
        raise SchemaError("no column header: the file has only '#' metadata lines", file=path)
    raise SchemaError(
        f"no column header with {time_spec.name!r} in the first {MAX_HEAD_LINES} lines; is this an export of the "
        f"kind {profile.describe()} reads (delimiter {profile.delimiter!r})?",
        file=path,
    )
