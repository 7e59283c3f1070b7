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
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BeforeValidator, Field, WithJsonSchema, model_validator
from pydantic_core import PydanticCustomError

from fivid.builtin import builtin_folders
from fivid.config_layer import (ConfigModel, ConfigSource, Name, Number, Problems, fail, key_loc, read_yaml,
                                validate)
from fivid.errors import ConfigError, FividError, UnitError
from fivid.io.rig_quantities import attribute_units, metadata_value, sensitivity_factor
from fivid.schema import registry
from fivid.units import conversion

__all__ = [
    "RigProfile",
    "RigProfileConfig",
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
    source = read_yaml(path, "rig profile", mapping=False)
    if source.data is None:
        raise ConfigError("the rig profile is empty; expected a mapping starting 'fivid-rig-profile: 1'", file=path)
    return rig_profile_from_mapping(source.data, path=path, source=source)


def _attribute_name(name) -> str:
    """A metadata attribute a profile may set; otherwise a :func:`fail` error."""
    if not isinstance(name, str) or not _ATTR_NAME.match(name):
        raise fail(f"expected an attribute name (letters, digits, _; starting with a letter), found {name!r}: "
                   "not a valid attribute name")
    if name in RESERVED_ATTRIBUTES or name.endswith("_units"):
        raise fail(f"attribute {name!r} is written by fivid itself and cannot come from metadata")
    return name


def _regex(text: str | None, groups: tuple[str, ...] = ()):
    if text is None:
        return None
    try:
        compiled = re.compile(text)
    except re.error as exc:
        raise fail(f"expected a regular expression, found {text!r}: not a valid regular expression ({exc})") from None
    missing = [g for g in groups if g not in compiled.groupindex]
    if missing:
        raise fail(f"the regular expression needs named groups {', '.join(f'(?P<{g}>...)' for g in missing)}")
    return compiled


def _units_map(raw: dict) -> dict:
    out = {}
    for name, units in raw.items():
        target = attribute_units(name)
        if target is None:
            quantities = ", ".join(n for n, a in registry().attributes.items() if a.units)
            raise fail(f"{name!r} is not a quantity attribute; expected one of {quantities}", at=(name,))
        try:
            conversion(str(units), target)
        except UnitError as exc:
            raise fail(exc.message, at=(name,)) from None
        out[name] = str(units)
    return out


_UnitsMap = Annotated[dict[str, Name], AfterValidator(_units_map)]


def _delimiter(value: str) -> str:
    if len(value) != 1 or value in "\r\n\"":
        raise fail(f"expected one character (',', ';', '\\t', ...), found {value!r}")
    return value


def _encoding(value: str) -> str:
    try:
        name = codecs.lookup(value).name
    except LookupError:
        raise fail(f"unknown text encoding {value!r}; expected e.g. utf-8, latin-1, cp1252") from None
    if "a;,.\n".encode(name) != b"a;,.\n":
        raise fail(f"{name!r} is not ASCII-compatible; expected utf-8, latin-1, cp1252, ...")
    return name


class _Csv(ConfigModel):
    delimiter: Annotated[str, AfterValidator(_delimiter)] = ","
    decimal: Literal[".", ","] = "."
    encoding: Annotated[str, AfterValidator(_encoding)] = "utf-8"
    header_line: Annotated[int, Field(ge=1, description="1 = the first line")] | None = None
    comment: str = "#"

    @model_validator(mode="after")
    def _distinct(self):
        if self.decimal == self.delimiter:
            raise fail(f"the decimal mark {self.decimal!r} cannot also be the delimiter", at=("decimal",))
        return self


def _metadata_keys(raw: dict) -> dict:
    keys = {}
    for raw_key, attr in raw.items():
        try:
            keys[str(raw_key).strip().casefold()] = _attribute_name(attr)
        except PydanticCustomError as exc:
            raise fail(exc.context["message"], at=(raw_key,)) from None
    return keys


class _InFile(ConfigModel):
    pattern: Annotated[str, AfterValidator(lambda t: (_regex(t, ("key", "value")), t)[1])] = DEFAULT_METADATA_PATTERN
    keys: Annotated[dict[Name, Name], AfterValidator(_metadata_keys)] = {}
    units: _UnitsMap = {}


def _file_name_pattern(text):
    compiled = _regex(text)
    if compiled is not None:
        for group in compiled.groupindex:
            try:
                _attribute_name(group)
            except PydanticCustomError as exc:
                raise fail(f"group {group!r}: {exc.context['message']}") from None
    return text


class _FileName(ConfigModel):
    pattern: Annotated[str, AfterValidator(_file_name_pattern)] | None = None
    units: _UnitsMap = {}


def _metadata_values(raw: dict) -> dict:
    values = {}
    for attr, value in raw.items():
        try:
            values[_attribute_name(attr)] = metadata_value(attr, value)
        except PydanticCustomError as exc:
            raise fail(exc.context["message"], at=(attr,)) from None
        except FividError as exc:
            raise fail(exc.message, at=(attr,)) from None
    return values


class _Metadata(ConfigModel):
    in_file: _InFile | None = None
    file_name: _FileName = _FileName()
    values: Annotated[dict[Name, Any], AfterValidator(_metadata_values)] = {}


def _scale(value: float) -> float:
    if not math.isfinite(value) or value == 0:
        raise fail(f"expected a finite non-zero number (e.g. -1 to flip the sign), found {value!r}")
    return value


def _as_text(value):
    return None if value is None else str(value)


class _Column(ConfigModel):
    """One raw column: its name in the header, its unit, and (for a transducer signal) the sensitivity."""

    name: str | None = Field(None, description="the column's name as written in the file's header")
    units: str | None = Field(None, description="the unit the column is written in")
    sensitivity: Annotated[str | None, BeforeValidator(_as_text)] = Field(
        None, description="'<number> <signal unit>/<measured unit>', e.g. '100 mV/g'")
    scale: Annotated[Number, AfterValidator(_scale)] = 1.0
    sensor: Annotated[str | None, BeforeValidator(_as_text)] = Field(
        None, description="sensor name when a variable has several columns")


def _column_entry_schema() -> dict:
    column = _Column.model_json_schema()
    return {"anyOf": [{"type": "string", "description": "the column's name"}, column,
                      {"type": "array", "items": column, "minItems": 1}]}


class _Checks(ConfigModel):
    sampling_tolerance: Annotated[Number, Field(gt=0, lt=1, description="fraction of the time step (0.01 = 1 %)")
                                  ] = 0.01


def _version(value):
    if value != PROFILE_VERSION or isinstance(value, bool):
        raise fail(f"expected {PROFILE_VERSION} (the profile format version), found {value!r}")
    return value


class RigProfileConfig(ConfigModel):
    """A rig profile (``configs/rigs/*.yaml``, ``docs/ingest.md``)."""

    fivid_rig_profile: Annotated[int, BeforeValidator(_version), WithJsonSchema({"const": PROFILE_VERSION})] = Field(
        alias="fivid-rig-profile")
    name: Name | None = None
    description: str = ""
    format: Literal["fivid-rig-csv", "table"] = "table"
    csv: _Csv = _Csv()
    metadata: _Metadata = _Metadata()
    columns: Annotated[dict[str, Any], WithJsonSchema({"type": "object",
                                                       "additionalProperties": _column_entry_schema(),
                                                       "description": "canonical variable -> raw column(s)"})] = {}
    checks: _Checks = _Checks()

    @model_validator(mode="after")
    def _by_format(self):
        if self.format == "fivid-rig-csv":
            if self.columns:
                raise fail("a fivid-rig-csv file names its columns and units in its header; remove 'columns' or use "
                           "format: table", at=("columns",))
            if self.metadata.in_file is not None and self.metadata.in_file.model_fields_set:
                raise fail("a fivid-rig-csv file gives its metadata as '# key: value' lines; remove in_file",
                           at=("metadata", "in_file"))
        return self


def has_sensor_dim(variable: str) -> bool:
    """Whether canonical ``variable`` may have a ``sensor`` dimension (several transducers)."""
    return ("time", "sensor") in registry().variables[variable].dims


_SENSOR_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.+-]*$")


def _column_spec(variable: str, raw, key: str, source: ConfigSource, problems: Problems,
                 sensor_required: bool) -> ColumnSpec | None:
    """One column mapping ``{name, units, sensitivity, scale, sensor}`` (or just the name)."""
    if isinstance(raw, str):
        raw = {"name": raw}
    if isinstance(raw, dict) and "sensor" in raw and not has_sensor_dim(variable):
        problems.add(f"{key}.sensor", f"unknown key: {variable!r} has no sensor dimension; allowed: name, units, "
                                      "sensitivity, scale")
        return None
    spec = validate(_Column, source, problems, data=raw, prefix=key_loc(key))
    if spec is None:
        return None
    target = registry().variables[variable].units
    if spec.name is None or not spec.name.strip():
        problems.add(f"{key}.name", "is required (missing): the column's name as written in the file's header")
        return None
    if spec.units is None:
        problems.add(f"{key}.units", f"is required (missing): the unit the column is written in (canonical: {target!r})")
        return None
    if spec.sensor is None and sensor_required:
        problems.add(f"{key}.sensor", "is required (missing): with several columns for one variable, name each "
                                      "one's sensor")
        return None
    if spec.sensor is not None and not _SENSOR_NAME.match(spec.sensor):
        problems.add(f"{key}.sensor", f"expected a sensor name (letters, digits, . _ + -), found {spec.sensor!r}")
        return None
    try:
        if spec.sensitivity is None:
            factor, offset = conversion(spec.units, target)
        else:
            factor, offset = sensitivity_factor(spec.units, spec.sensitivity, target), 0.0
    except UnitError as exc:
        problems.add(f"{key}.{'units' if spec.sensitivity is None else 'sensitivity'}", exc.message)
        return None
    return ColumnSpec(variable, spec.name.strip(), spec.units, spec.sensitivity, spec.scale, factor * spec.scale,
                      offset * spec.scale, spec.sensor)


def _column_specs(columns: dict, source: ConfigSource, problems: Problems) -> tuple[ColumnSpec, ...]:
    reg = registry()
    specs = []
    mappable = [n for n, v in reg.variables.items() if not v.coordinate or n == "time"]
    for variable, spec in columns.items():
        key = f"columns.{variable}"
        if variable not in mappable:
            problems.add(key, f"{variable!r} is not a canonical variable; expected one of {', '.join(mappable)}")
            continue
        if isinstance(spec, list):
            if not has_sensor_dim(variable):
                problems.add(key, f"{variable!r} has no sensor dimension: expected one column, found a list")
                continue
            if not spec:
                problems.add(key, "expected at least one column, found an empty list")
                continue
            found = [_column_spec(variable, s, f"{key}[{i}]", source, problems, True) for i, s in enumerate(spec)]
            seen = set()
            for i, s in enumerate(found):
                if s is not None and s.sensor in seen:
                    problems.add(f"{key}[{i}].sensor", f"sensor {s.sensor!r} is already mapped to another column")
                seen.add(None if s is None else s.sensor)
            specs += [s for s in found if s is not None]
        else:
            found = _column_spec(variable, spec, key, source, problems, False)
            if found is not None:
                specs.append(found)
    names = [s.name for s in specs]
    for s in specs:
        if names.count(s.name) > 1:
            problems.add(f"columns.{s.variable}.name", f"column {s.name!r} is mapped more than once")
    required = [n for n, v in reg.variables.items() if v.required or n == "time"]
    for n in required:
        if n not in columns:
            problems.add(f"columns.{n}", f"required variable {n!r} ({reg.variables[n].units}) is not mapped to a "
                                         "column")
    return tuple(specs)


def rig_profile_from_mapping(raw, *, path=None, source: ConfigSource | None = None) -> RigProfile:
    """Validate a profile given as a mapping (the parsed YAML) and build a :class:`RigProfile`.

    Raises :class:`ConfigError` listing every problem with its key path (and line, from ``source``).
    """
    if source is None:
        source = ConfigSource(raw, None if path is None else str(path))
    problems = Problems(source)
    if raw is None:
        problems.add("fivid-rig-profile", "the profile is empty; expected a mapping starting 'fivid-rig-profile: 1'")
        problems.raise_if_any()
    cfg = validate(RigProfileConfig, source, problems, data=raw)
    columns = ()
    raw_columns = raw.get("columns") if isinstance(raw, dict) else None
    if isinstance(raw_columns, dict) and raw.get("format", "table") == "table":  # checked even when others fail
        columns = _column_specs(raw_columns, source, problems)
    problems.raise_if_any()
    in_file = cfg.metadata.in_file or _InFile()
    name = cfg.name if cfg.name is not None else (Path(path).stem if path is not None else "unnamed")
    return RigProfile(
        name=name, format=cfg.format, description=cfg.description, delimiter=cfg.csv.delimiter,
        decimal=cfg.csv.decimal, encoding=cfg.csv.encoding, header_line=cfg.csv.header_line, comment=cfg.csv.comment,
        metadata_pattern=in_file.pattern, metadata_keys=in_file.keys, metadata_units=in_file.units,
        file_name_pattern=cfg.metadata.file_name.pattern, file_name_units=cfg.metadata.file_name.units,
        values=cfg.metadata.values, columns=columns, sampling_tolerance=cfg.checks.sampling_tolerance,
        path=None if path is None else str(path),
    )
