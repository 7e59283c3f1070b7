"""Rig profiles: how a DAQ export maps onto a RunDataset.

A rig profile (``configs/rigs/<name>.yaml``) tells :func:`fivid.io.read_rig_csv` how to read what a
rig's data-acquisition software writes, so a lab engineer can import it without editing the file:
the delimiter and decimal mark, the text encoding, where the column header is, which raw column is
which canonical variable and in which unit (with a sensor sensitivity such as ``100 mV/g`` for a
channel recorded in volts), and where the run's metadata come from (lines of the file's preamble,
the file name through a regular expression, or fixed values in the profile).

Two formats:

``fivid-rig-csv``
    fivid's own format (DESIGN §2): first line ``# fivid-rig-csv: 1``, metadata lines
    ``# key: value``, a header ``name [unit]`` whose names are canonical variable names.
``table``
    any delimited table with a one-line header; ``columns`` maps canonical names onto the raw ones.

See ``docs/ingest.md`` for the YAML keys. Every problem of a profile is reported at once, each
with its key path (``columns.acceleration.sensitivity``).
"""

from __future__ import annotations

import codecs
import difflib
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from fivid.errors import ConfigError, FividError, UnitError
from fivid.io.rig_quantities import attribute_units, metadata_value, sensitivity_factor
from fivid.schema import registry
from fivid.units import conversion

__all__ = [
    "RigProfile",
    "ColumnSpec",
    "FORMATS",
    "PROFILE_VERSION",
    "load_rig_profile",
    "rig_profile_from_mapping",
    "profile_search_path",
    "RESERVED_ATTRIBUTES",
    "has_sensor_dim",
]

PROFILE_VERSION = 1
FORMATS = ("fivid-rig-csv", "table")
#: Attributes fivid writes itself; a file or profile may not set them.
RESERVED_ATTRIBUTES = frozenset({"source", "history", "fivid_version", "schema_version", "Conventions",
                                 "quality_report", "source_format"})
#: Preamble line ``key: value`` (also ``key;value``, ``key=value``, ``key<TAB>value``).
DEFAULT_METADATA_PATTERN = r"^\s*(?P<key>[^:;=\t]+?)\s*[:;=\t]\s*(?P<value>.*?)\s*$"
_ATTR_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


@dataclass(frozen=True)
class ColumnSpec:
    """How one raw column becomes a canonical variable.

    Attributes
    ----------
    variable : str
        Canonical name (``time``, ``acceleration``, ...), from the registry.
    name : str
        The column's name in the file's header, as written.
    units : str
        The unit the values are written in (``mV``, ``g``, ``mm``).
    sensitivity : str or None
        Sensor sensitivity ``"<number> <signal unit>/<measured unit>"`` (``"100 mV/g"``) when the
        column holds the transducer's signal rather than the quantity.
    scale : float
        Extra dimensionless factor (``-1`` flips the sign of a channel).
    factor : float
        Total factor to the canonical SI unit: ``si = factor * raw + offset``.
    offset : float
        Offset to the canonical unit (non-zero only for affine units such as degC).
    sensor : str or None
        Sensor name when the variable has several transducers (dimension ``sensor``).
    """

    variable: str
    name: str
    units: str
    sensitivity: str | None = None
    scale: float = 1.0
    factor: float = 1.0
    offset: float = 0.0
    sensor: str | None = None


@dataclass(frozen=True)
class RigProfile:
    """A parsed, validated rig profile (see the module docstring and ``docs/ingest.md``).

    ``RigProfile()`` is the built-in ``fivid-rig-csv`` format with no defaults, what
    :func:`fivid.io.read_rig_csv` uses when no profile is given.
    """

    name: str = "fivid-rig-csv"
    format: str = "fivid-rig-csv"
    description: str = "fivid's own rig CSV format, version 1 (DESIGN §2)"
    delimiter: str = ","
    decimal: str = "."
    encoding: str = "utf-8"
    header_line: int | None = None
    comment: str = "#"
    metadata_pattern: str = DEFAULT_METADATA_PATTERN
    metadata_keys: dict = field(default_factory=dict)
    metadata_units: dict = field(default_factory=dict)
    file_name_pattern: str | None = None
    file_name_units: dict = field(default_factory=dict)
    values: dict = field(default_factory=dict)
    columns: tuple = ()
    sampling_tolerance: float = 0.01
    path: str | None = None

    def column(self, variable: str) -> ColumnSpec | None:
        """The spec of canonical ``variable``, or None when the profile does not map it."""
        for spec in self.columns:
            if spec.variable == variable:
                return spec
        return None

    def describe(self) -> str:
        """One line naming the profile and where it came from (for ``history``)."""
        where = f" ({self.path})" if self.path else " (built-in)"
        return f"rig profile {self.name!r}{where}"


def profile_search_path() -> list[Path]:
    """Folders searched for ``<name>.yaml``: ``./configs/rigs``, then the built-in profiles
    (:func:`fivid.builtin.builtin_folders`: the checkout's ``configs/rigs``, the installed copy in a wheel)."""
    from fivid.builtin import builtin_folders

    here = Path.cwd() / "configs" / "rigs"
    builtin = [f for f in builtin_folders("rigs") if f.resolve() != here.resolve()]
    return [here] + builtin


def load_rig_profile(name_or_path) -> RigProfile:
    """Load and validate a rig profile by name (``configs/rigs/<name>.yaml``) or path.

    Parameters
    ----------
    name_or_path : str or path-like
        A profile name such as ``"triboair"`` (looked up in :func:`profile_search_path`) or the
        path of a YAML file.

    Raises
    ------
    ConfigError
        The profile is not found, is not YAML, or is invalid; the message lists every problem
        with its key path.
    """
    import yaml

    text = str(name_or_path)
    looks_like_path = isinstance(name_or_path, os.PathLike) or any(c in text for c in "/\\") or text.endswith(
        (".yaml", ".yml")
    )
    if looks_like_path:
        path = Path(name_or_path)
        if path.is_dir():
            raise ConfigError(f"rig profile {text!r} is a folder; give a YAML file in it or a profile name")
        if not path.is_file():
            raise ConfigError(f"rig profile file {text!r} does not exist")
    else:
        candidates = [folder / f"{text}.yaml" for folder in profile_search_path()]
        path = next((p for p in candidates if p.is_file()), None)
        if path is None:
            known = sorted({p.stem for folder in profile_search_path() if folder.is_dir() for p in folder.glob("*.yaml")})
            raise ConfigError(
                f"no rig profile named {text!r}; known profiles: {', '.join(known) or '(none)'} "
                f"(searched {', '.join(str(f) for f in profile_search_path())}); or give the path of a YAML file"
            )
    try:
        raw = yaml.safe_load(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:
        raise ConfigError(f"rig profile is not UTF-8 text ({exc.reason} at byte {exc.start})", file=path) from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = None if mark is None else mark.line + 1
        raise ConfigError(f"rig profile is not valid YAML: {getattr(exc, 'problem', exc)}", file=path, line=line) from None
    return rig_profile_from_mapping(raw, path=path)


class _Problems:
    """Collects ``(key path, message)`` pairs; raises one ConfigError listing them all."""

    def __init__(self, path):
        self.path = None if path is None else str(path)
        self.items: list[tuple[str, str]] = []

    def add(self, key: str, message: str) -> None:
        self.items.append((key, message))

    def raise_if_any(self) -> None:
        if not self.items:
            return
        if len(self.items) == 1:
            key, message = self.items[0]
            raise ConfigError(f"invalid rig profile: {message}", file=self.path, key=key)
        listed = "; ".join(f"key {k!r}: {m}" for k, m in self.items)
        raise ConfigError(f"invalid rig profile ({len(self.items)} problems): {listed}", file=self.path)


def _mapping(raw, key: str, problems: _Problems, allowed: tuple[str, ...] | None = None) -> dict:
    if raw is None:
        return {}
    if not isinstance(raw, dict):
        problems.add(key, f"must be a mapping, got {type(raw).__name__} {raw!r}")
        return {}
    if allowed is not None:
        for k in raw:
            if k not in allowed:
                close = difflib.get_close_matches(str(k), allowed, n=1)
                hint = f"did you mean {close[0]!r}? " if close else ""
                problems.add(f"{key}.{k}" if key else str(k), f"unknown key; {hint}allowed: {', '.join(allowed)}")
    return raw


def _string(raw: dict, name: str, key: str, problems: _Problems, default=None):
    value = raw.get(name, default)
    if value is not None and not isinstance(value, str):
        problems.add(key, f"must be a string, got {value!r}")
        return default
    return value


def _regex(text: str | None, key: str, problems: _Problems, groups: tuple[str, ...] = ()):
    if text is None:
        return None
    try:
        compiled = re.compile(text)
    except re.error as exc:
        problems.add(key, f"not a valid regular expression ({exc}): {text!r}")
        return None
    missing = [g for g in groups if g not in compiled.groupindex]
    if missing:
        problems.add(key, f"the regular expression needs named groups {', '.join(f'(?P<{g}>...)' for g in missing)}")
        return None
    return compiled


def _check_attribute_name(name, key: str, problems: _Problems) -> bool:
    if not isinstance(name, str) or not _ATTR_NAME.match(name):
        problems.add(key, f"{name!r} is not a valid attribute name (letters, digits, _; starting with a letter)")
        return False
    if name in RESERVED_ATTRIBUTES or name.endswith("_units"):
        problems.add(key, f"attribute {name!r} is written by fivid itself and cannot come from metadata")
        return False
    return True


def _units_map(raw, key: str, problems: _Problems) -> dict:
    out = {}
    for name, units in _mapping(raw, key, problems).items():
        k = f"{key}.{name}"
        target = attribute_units(name)
        if target is None:
            problems.add(k, f"{name!r} is not a quantity attribute; units apply to "
                         f"{', '.join(n for n, a in registry().attributes.items() if a.units)}")
            continue
        try:
            conversion(str(units), target)
        except UnitError as exc:
            problems.add(k, exc.message)
            continue
        out[name] = str(units)
    return out


def has_sensor_dim(variable: str) -> bool:
    """Whether canonical ``variable`` may have a ``sensor`` dimension (several transducers)."""
    return ("time", "sensor") in registry().variables[variable].dims


_SENSOR_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.+-]*$")


def _column_spec(variable: str, spec, key: str, problems: _Problems, sensor_required: bool) -> ColumnSpec | None:
    """One column mapping ``{name, units, sensitivity, scale, sensor}`` (or just the name)."""
    if isinstance(spec, str):
        spec = {"name": spec}
    allowed = ("name", "units", "sensitivity", "scale", "sensor") if has_sensor_dim(variable) else (
        "name", "units", "sensitivity", "scale")
    spec = _mapping(spec, key, problems, allowed=allowed)
    name = _string(spec, "name", f"{key}.name", problems)
    units = _string(spec, "units", f"{key}.units", problems)
    sensitivity = spec.get("sensitivity")
    scale = spec.get("scale", 1.0)
    sensor = spec.get("sensor")
    target = registry().variables[variable].units
    if name is None or not name.strip():
        problems.add(f"{key}.name", "missing: the column's name as written in the file's header")
        return None
    if units is None:
        problems.add(f"{key}.units", f"missing: the unit the column is written in (canonical: {target!r})")
        return None
    if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not math.isfinite(scale) or scale == 0:
        problems.add(f"{key}.scale", f"must be a finite non-zero number (e.g. -1 to flip the sign), got {scale!r}")
        return None
    if sensor is None and sensor_required:
        problems.add(f"{key}.sensor", "missing: with several columns for one variable, name each one's sensor")
        return None
    if sensor is not None and not _SENSOR_NAME.match(str(sensor)):
        problems.add(f"{key}.sensor", f"{sensor!r} is not a sensor name (letters, digits, . _ + -)")
        return None
    try:
        if sensitivity is None:
            factor, offset = conversion(units, target)
        else:
            factor, offset = sensitivity_factor(units, str(sensitivity), target), 0.0
    except UnitError as exc:
        problems.add(f"{key}.{'units' if sensitivity is None else 'sensitivity'}", exc.message)
        return None
    return ColumnSpec(variable, name.strip(), units, None if sensitivity is None else str(sensitivity),
                      float(scale), factor * float(scale), offset * float(scale),
                      None if sensor is None else str(sensor))


def _column_specs(raw, fmt: str, problems: _Problems) -> tuple[ColumnSpec, ...]:
    reg = registry()
    columns = _mapping(raw, "columns", problems)
    if fmt == "fivid-rig-csv":
        if columns:
            problems.add("columns", "a fivid-rig-csv file names its columns and units in its header; "
                         "remove 'columns' or use format: table")
        return ()
    specs = []
    mappable = [n for n, v in reg.variables.items() if not v.coordinate or n == "time"]
    for variable, spec in columns.items():
        key = f"columns.{variable}"
        if variable not in mappable:
            problems.add(key, f"{variable!r} is not a canonical variable; known: {', '.join(mappable)}")
            continue
        if isinstance(spec, list):
            if not has_sensor_dim(variable):
                problems.add(key, f"{variable!r} has no sensor dimension: map it to one column")
                continue
            if not spec:
                problems.add(key, "an empty list: map it to at least one column")
                continue
            found = [_column_spec(variable, s, f"{key}[{i}]", problems, True) for i, s in enumerate(spec)]
            seen = set()
            for i, s in enumerate(found):
                if s is not None and s.sensor in seen:
                    problems.add(f"{key}[{i}].sensor", f"sensor {s.sensor!r} is already mapped to another column")
                seen.add(None if s is None else s.sensor)
            specs += [s for s in found if s is not None]
        else:
            found = _column_spec(variable, spec, key, problems, False)
            if found is not None:
                specs.append(found)
    names = [s.name for s in specs]
    for s in specs:
        if names.count(s.name) > 1:
            problems.add(f"columns.{s.variable}.name", f"column {s.name!r} is mapped more than once")
    required = [n for n, v in reg.variables.items() if v.required or n == "time"]
    given = {s.variable for s in specs} | set(columns)
    for n in required:
        if n not in given:
            problems.add(f"columns.{n}", f"required variable {n!r} ({reg.variables[n].units}) is not mapped to a column")
    return tuple(specs)


def rig_profile_from_mapping(raw, *, path=None) -> RigProfile:
    """Validate a profile given as a mapping (the parsed YAML) and build a :class:`RigProfile`.

    Raises :class:`ConfigError` listing every problem with its key path.
    """
    problems = _Problems(path)
    top = _mapping(raw, "", problems, allowed=(
        "fivid-rig-profile", "name", "description", "format", "csv", "metadata", "columns", "checks"))
    if raw is None:
        problems.add("fivid-rig-profile", "the profile is empty")
    problems.raise_if_any()
    version = top.get("fivid-rig-profile")
    if version != PROFILE_VERSION:
        problems.add("fivid-rig-profile", f"must be {PROFILE_VERSION} (the profile format version), got {version!r}")
    name = _string(top, "name", "name", problems)
    if name is None:
        name = Path(path).stem if path is not None else "unnamed"
    description = _string(top, "description", "description", problems, default="")
    fmt = top.get("format", "table")
    if fmt not in FORMATS:
        problems.add("format", f"must be one of {', '.join(FORMATS)}, got {fmt!r}")
        fmt = "table"

    csv = _mapping(top.get("csv"), "csv", problems, allowed=("delimiter", "decimal", "encoding", "header_line", "comment"))
    delimiter = _string(csv, "delimiter", "csv.delimiter", problems, default=",")
    if delimiter is not None and (len(delimiter) != 1 or delimiter in "\r\n\""):
        problems.add("csv.delimiter", f"must be one character (',', ';', '\\t', ...), got {delimiter!r}")
    decimal = _string(csv, "decimal", "csv.decimal", problems, default=".")
    if decimal not in (".", ","):
        problems.add("csv.decimal", f"must be '.' or ',', got {decimal!r}")
    elif decimal == delimiter:
        problems.add("csv.decimal", f"the decimal mark {decimal!r} cannot also be the delimiter")
    encoding = _string(csv, "encoding", "csv.encoding", problems, default="utf-8")
    try:
        encoding = codecs.lookup(encoding).name
        if "a;,.\n".encode(encoding) != b"a;,.\n":
            problems.add("csv.encoding", f"{encoding!r} is not ASCII-compatible; use utf-8, latin-1, cp1252, ...")
    except (LookupError, TypeError):
        problems.add("csv.encoding", f"unknown text encoding {encoding!r} (e.g. utf-8, latin-1, cp1252)")
    header_line = csv.get("header_line")
    if header_line is not None and (isinstance(header_line, bool) or not isinstance(header_line, int) or header_line < 1):
        problems.add("csv.header_line", f"must be a line number >= 1 (1 = first line), got {header_line!r}")
    comment = _string(csv, "comment", "csv.comment", problems, default="#")

    meta = _mapping(top.get("metadata"), "metadata", problems, allowed=("in_file", "file_name", "values"))
    in_file = _mapping(meta.get("in_file"), "metadata.in_file", problems, allowed=("pattern", "keys", "units"))
    if fmt == "fivid-rig-csv" and in_file:
        problems.add("metadata.in_file", "a fivid-rig-csv file gives its metadata as '# key: value' lines; remove in_file")
    pattern = _string(in_file, "pattern", "metadata.in_file.pattern", problems, default=DEFAULT_METADATA_PATTERN)
    _regex(pattern, "metadata.in_file.pattern", problems, groups=("key", "value"))
    keys = {}
    for raw_key, attr in _mapping(in_file.get("keys"), "metadata.in_file.keys", problems).items():
        if _check_attribute_name(attr, f"metadata.in_file.keys.{raw_key}", problems):
            keys[str(raw_key).strip().casefold()] = attr
    metadata_units = _units_map(in_file.get("units"), "metadata.in_file.units", problems)

    from_name = _mapping(meta.get("file_name"), "metadata.file_name", problems, allowed=("pattern", "units"))
    file_name_pattern = _string(from_name, "pattern", "metadata.file_name.pattern", problems)
    compiled = _regex(file_name_pattern, "metadata.file_name.pattern", problems)
    if compiled is not None:
        for group in compiled.groupindex:
            _check_attribute_name(group, f"metadata.file_name.pattern (group {group!r})", problems)
    file_name_units = _units_map(from_name.get("units"), "metadata.file_name.units", problems)

    values = {}
    for attr, value in _mapping(meta.get("values"), "metadata.values", problems).items():
        key = f"metadata.values.{attr}"
        if not _check_attribute_name(attr, key, problems):
            continue
        try:
            values[attr] = metadata_value(attr, value)
        except FividError as exc:
            problems.add(key, exc.message)

    columns = _column_specs(top.get("columns"), fmt, problems)

    checks = _mapping(top.get("checks"), "checks", problems, allowed=("sampling_tolerance",))
    tolerance = checks.get("sampling_tolerance", 0.01)
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float)) or not 0 < tolerance < 1:
        problems.add("checks.sampling_tolerance",
                     f"must be a fraction of the time step between 0 and 1 (0.01 = 1 %), got {tolerance!r}")
        tolerance = 0.01
    problems.raise_if_any()
    return RigProfile(
        name=name, format=fmt, description=description, delimiter=delimiter, decimal=decimal, encoding=encoding,
        header_line=header_line, comment=comment, metadata_pattern=pattern, metadata_keys=keys,
        metadata_units=metadata_units, file_name_pattern=file_name_pattern, file_name_units=file_name_units,
        values=values, columns=columns, sampling_tolerance=float(tolerance),
        path=None if path is None else str(path),
    )
