"""One config layer: every YAML file fivid reads is loaded, typed and checked here, with one error format.

* :func:`read_yaml` is the one YAML loader. It parses a file once (PyYAML's ``SafeLoader``), keeps the
  1-based line of every key path (``simulate.duration``, ``stages[1]``) and the file's sha256.
* Configs are pydantic v2 models (:class:`ConfigModel`: unknown keys are errors, no silent type coercion).
  :func:`Quantity` is the field type of a physical quantity: ``"10 mm/s"`` is parsed by :mod:`fivid.units`
  into an SI float after a dimension check.
* :func:`validate` turns pydantic's ``ValidationError`` into fivid's :class:`~fivid.errors.ConfigError`;
  :class:`Problems` collects the checks a schema cannot express (cross-field rules, files that must exist).
  Both give one format::

      configs/runs/x.yaml:12: key 'simulate.duration': expected a positive quantity in 's', found '2 kg' ...

  the file, the line of the key (or of its nearest parent when the key is missing), the key path, what
  was expected (the allowed values) and what was found. With several problems the first one leads and
  the others follow as ``(and N more: key (line L): message; ...)``.
* :func:`json_schema` is the JSON Schema of a model, as published in ``docs/schema/`` (editors use it to
  complete and check configs).

pydantic is imported on first use of a model module, not at ``import fivid``.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import re
import typing
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Annotated, Any, Mapping

from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, WithJsonSchema, model_validator
from pydantic_core import PydanticCustomError

from fivid.errors import ConfigError, UnitError
from fivid.units import parse_quantity

__all__ = [
    "ConfigSource",
    "ConfigModel",
    "Problems",
    "Quantity",
    "Number",
    "Name",
    "none_as",
    "quantity_parser",
    "quantity_schema",
    "quantity_at",
    "QuantityText",
    "Vector",
    "either",
    "fail",
    "read_yaml",
    "parse_yaml_text",
    "from_mapping",
    "validate",
    "load_config",
    "json_schema",
    "key_path",
    "key_loc",
    "unknown_key_message",
    "MISSING",
]


# ---------------------------------------------------------------------------------------------- the loader


@dataclass
class ConfigSource:
    """A parsed config: its data, where it came from and the line of every key path.

    Attributes
    ----------
    data : Any
        What the YAML holds (usually a dict).
    file : str or None
        The file (None for a mapping given in code).
    lines : dict
        Key path (``bodies.upper.material.E``, ``stages[1]``) -> 1-based line of the key in ``file``.
    sha256 : str
        Of the file's bytes (of the canonical JSON of a mapping).
    """

    data: Any
    file: str | None = None
    lines: dict = field(default_factory=dict)
    sha256: str = ""

    @property
    def origin(self) -> str:
        """``"<file> sha256:<hex>"`` (``"<mapping> sha256:<hex>"``) for provenance."""
        return f"{self.file if self.file is not None else '<mapping>'} sha256:{self.sha256}"

    def line(self, key: str) -> int | None:
        """The line of ``key``, or of its nearest parent present in the file (a required key left out)."""
        while key:
            if key in self.lines:
                return self.lines[key]
            key = re.sub(r"(\[\d+\]|\.?[^.\[]*)$", "", key, count=1)
        return self.lines.get("")

    def error(self, key: str, message: str) -> ConfigError:
        """A :class:`ConfigError` at ``key`` (file, line and key path filled in)."""
        return ConfigError(message, file=self.file, line=self.line(key) if key else None, key=key or None)


def _record_lines(node, path: str, lines: dict) -> None:
    import yaml

    lines.setdefault(path, node.start_mark.line + 1)
    if isinstance(node, yaml.MappingNode):
        for k, v in node.value:
            sub = f"{path}.{k.value}" if path else str(k.value)
            lines[sub] = k.start_mark.line + 1
            _record_lines(v, sub, lines)
    elif isinstance(node, yaml.SequenceNode):
        for i, v in enumerate(node.value):
            _record_lines(v, f"{path}[{i}]", lines)


def parse_yaml_text(text: str, file: str | None = None) -> tuple[Any, dict]:
    """Parse YAML ``text`` once: ``(data, key path -> line)``; a syntax error is a one-line ConfigError."""
    import yaml

    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        data = None if node is None else loader.construct_document(node)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        # one line: the parser's problem and its column, not its multi-line excerpt of the file
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        where = "" if mark is None else f" at column {mark.column + 1}"
        raise ConfigError(f"not valid YAML: {problem}{where}", file=file,
                          line=None if mark is None else mark.line + 1) from None
    finally:
        loader.dispose()
    lines: dict = {}
    if node is not None:
        _record_lines(node, "", lines)
    return data, lines


def read_yaml(path: str | PathLike, what: str = "config", *, mapping: bool = True) -> ConfigSource:
    """Read a YAML config file: the one loader of fivid (see the module docstring).

    Parameters
    ----------
    path : path-like
        The file.
    what : str
        What the file is (``"run configuration"``), for messages.
    mapping : bool
        Require the document to be a mapping (an empty file is then an error too).

    Raises
    ------
    ConfigError
        The file does not exist, is not UTF-8 text, is not YAML, or (``mapping``) is empty or not a mapping.
    """
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"{what} {str(path)!r} is a folder; give a YAML file", file=path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise ConfigError(f"cannot read the {what} {str(path)!r}: it does not exist", file=path) from None
    except OSError as exc:
        raise ConfigError(f"cannot read the {what}: {exc.strerror}", file=path) from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise ConfigError(f"{what} is not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start}); save it "
                          "as UTF-8", file=path, line=line) from None
    data, lines = parse_yaml_text(text, str(path))
    if mapping and data is None:
        raise ConfigError(f"the {what} is empty; expected a mapping of keys", file=path)
    if mapping and not isinstance(data, dict):
        raise ConfigError(f"{what} must be a YAML mapping of keys, found {_kind(data)}", file=path, line=1)
    return ConfigSource(data, str(path), lines, hashlib.sha256(raw).hexdigest())


def from_mapping(data: Mapping) -> ConfigSource:
    """A config given in code (no file, no lines); its sha256 is that of its canonical JSON."""
    text = json.dumps(data, sort_keys=True, default=str)
    return ConfigSource(dict(data), None, {}, hashlib.sha256(text.encode()).hexdigest())


def _kind(value) -> str:
    if value is None:
        return "nothing (null)"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, (list, tuple)):
        return f"a list {value!r}"
    return f"{type(value).__name__} {value!r}"


# ---------------------------------------------------------------------------------------------- field types


def fail(message: str, *, at: tuple = ()) -> PydanticCustomError:
    """The error a validator raises: ``message`` in fivid's words (``expected ..., found ...``).

    ``at`` extends the key path below the field being validated (a model validator names the key it blames).
    """
    return PydanticCustomError("fivid", "{message}", {"message": message, "at": at})


def quantity_parser(units: str, positive: bool = False, nonnegative: bool = False, bare: str | None = None):
    """The function :func:`Quantity` validates with: value -> SI float, or a :func:`fail` error."""
    kind = "a positive quantity" if positive else "a non-negative quantity" if nonnegative else "a quantity"

    def parse(value):
        if isinstance(value, (dict, list, tuple)) or value is None:
            raise fail(f"expected {kind} in {units!r} (e.g. '1 {units}'), found {_kind(value)}")
        try:
            q = parse_quantity(value, units, default_units=bare)
        except UnitError as exc:
            raise fail(f"expected {kind} in {units!r}, found {value!r}: {exc.message}") from None
        if q != q or q in (float("inf"), float("-inf")):
            raise fail(f"expected a finite quantity in {units!r}, found {value!r}")
        if positive and not q > 0:
            raise fail(f"expected {kind} (> 0) in {units!r}, found {value!r}")
        if nonnegative and not q >= 0:
            raise fail(f"expected {kind} (>= 0) in {units!r}, found {value!r}")
        return float(q)

    return parse


def quantity_schema(units: str, *, positive: bool = False, nonnegative: bool = False, bare_is_si: bool = False,
                    also: tuple = ()) -> dict:
    """The JSON Schema of a quantity: a number, or a string with a unit; ``also``: other accepted constants."""
    number = {"type": "number"} | ({"exclusiveMinimum": 0} if positive else {"minimum": 0} if nonnegative else {})
    text = {"type": "string", "pattern": r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*\S.*$"}
    return {
        "anyOf": [number, text] + [{"const": c} for c in also],
        "description": f"a quantity with units compatible with {units!r}, e.g. '1 {units}'"
                       + ("; a bare number is in these units" if bare_is_si else ""),
        "x-fivid-units": units,
    }


def Quantity(units: str, *, positive: bool = False, nonnegative: bool = False, bare_is_si: bool = False):
    """Field type of a physical quantity: ``"10 mm/s"`` -> SI float (units checked, dimension compatible).

    Parameters
    ----------
    units : str
        The SI unit the value is converted to (``"m s-1"``, ``"Hz"``, ``"1"`` for dimensionless).
    positive, nonnegative : bool
        Range of the value.
    bare_is_si : bool
        A bare number is taken in ``units`` (model configs); otherwise a bare number needs a unit unless
        the quantity is dimensionless.
    """
    schema = quantity_schema(units, positive=positive, nonnegative=nonnegative, bare_is_si=bare_is_si)
    return Annotated[float, BeforeValidator(quantity_parser(units, positive, nonnegative,
                                                             units if bare_is_si else None)),
                     WithJsonSchema(schema)]


def Vector(units: str, length: int = 2, *, positive: bool = False, bare_is_si: bool = True):
    """Field type of a list of ``length`` quantities in ``units`` (a point ``[x, y]`` [m]), as a list of SI floats."""
    return Annotated[list[Quantity(units, positive=positive, bare_is_si=bare_is_si)],
                     BeforeValidator(lambda v: list(v) if isinstance(v, tuple) else v),
                     Field(min_length=length, max_length=length)]


def quantity_at(source: "ConfigSource", value, key: str, units: str, *, positive: bool = False,
                nonnegative: bool = False) -> float:
    """``value`` in SI ``units`` (a bare number is in ``units``), checked like a :func:`Quantity` field.

    For a quantity whose units depend on another key (a motion's amplitude: m or m s-1), or one read outside
    a model. A problem is a :class:`~fivid.errors.ConfigError` at ``key`` of ``source`` (file, line, key path).

    Examples
    --------
    >>> quantity_at(from_mapping({}), "10 mm", "bodies.beam.thickness", "m")
    0.01
    """
    try:
        return quantity_parser(units, positive, nonnegative, bare=units)(value)
    except PydanticCustomError as exc:
        raise source.error(key, exc.context["message"]) from None


def _quantity_text(value):
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise fail(f"expected a quantity (a number, or a number with a unit), found {_kind(value)}")
    return value


#: A quantity whose units depend on another key: kept as written (number or text), converted by
#: :func:`quantity_at` once the units are known.
QuantityText = Annotated[Any, BeforeValidator(_quantity_text),
                         WithJsonSchema({"anyOf": [{"type": "number"}, {"type": "string"}],
                                         "description": "a quantity (a number, or a number with a unit); its units "
                                                        "depend on the other keys"})]

#: Prefix of the tags of :func:`either` (dropped from the key paths of errors).
_VARIANT = "variant:"


def either(text, model):
    """Field type of a value written either as text (``text``: a type such as :data:`Name` or a ``Literal``) or
    as a mapping (``model``): a material's name or its ``{E, nu, rho}``.

    The branch is chosen by the value's type (text, or anything else: the mapping), so an error speaks about
    the branch the user meant, not about both.
    """
    from pydantic import Discriminator, Tag

    def branch(value):
        return _VARIANT + ("text" if isinstance(value, str) else "mapping")

    return Annotated[typing.Union[Annotated[text, Tag(_VARIANT + "text")], Annotated[model, Tag(_VARIANT + "mapping")]],
                     Discriminator(branch)]


def _number(value):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise fail(f"expected a number, found {_kind(value)}")
    return float(value)


def _name(value):
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise fail(f"expected a name (text), found {_kind(value)}")
    return str(value)


#: A name or short text (a number written in YAML is taken as its text).
Name = Annotated[str, BeforeValidator(_name), WithJsonSchema({"type": "string"})]

#: A plain number (int or float, not a bool, not a string), as a float.
Number = Annotated[float, BeforeValidator(_number), WithJsonSchema({"type": "number"})]


def none_as(empty):
    """A validator reading an empty YAML value (``key:`` with nothing after it) as ``empty()`` ({} or [])."""
    return BeforeValidator(lambda value: empty() if value is None else value)


class ConfigModel(BaseModel):
    """Base of fivid's config models: unknown keys are errors; no silent coercion ("5" is no integer);
    an empty section (``csv:`` with nothing under it) is the section with its defaults."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True, populate_by_name=True,
                              arbitrary_types_allowed=True)

    @model_validator(mode="before")
    @classmethod
    def _empty_section(cls, data):
        return {} if data is None else data


# ---------------------------------------------------------------------------------------------- errors


def key_path(loc) -> str:
    """``("bodies", "upper", "E")`` -> ``bodies.upper.E``; ``("stages", 1)`` -> ``stages[1]``."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out


def key_loc(key: str) -> tuple:
    """``columns.acceleration[1]`` -> ``("columns", "acceleration", 1)`` (the inverse of :func:`key_path`)."""
    return tuple(int(part[1:-1]) if part.startswith("[") else part for part in re.findall(r"[^.\[\]]+|\[\d+\]", key))


def unknown_key_message(key, allowed) -> str:
    """The one message of an unknown key: the allowed keys, and the closest one when it looks like a typo."""
    allowed = sorted(str(a) for a in allowed)
    close = difflib.get_close_matches(str(key), allowed, n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    return f"unknown key; allowed: {', '.join(allowed)}{hint}"


MISSING = "is required (missing)"


def _unwrap(tp):
    """The model / container type behind Optional, Annotated and unions (the first model in a union)."""
    while True:
        origin = typing.get_origin(tp)
        if origin is Annotated:
            tp = typing.get_args(tp)[0]
            continue
        if origin in (typing.Union, getattr(__import__("types"), "UnionType", None)):
            args = [typing.get_args(a)[0] if typing.get_origin(a) is Annotated else a
                    for a in typing.get_args(tp) if a is not type(None)]
            models = [a for a in args if isinstance(a, type) and issubclass(a, BaseModel)]
            containers = [a for a in args if typing.get_origin(a) in (list, dict)]
            tp = (models or containers or args)[0]
            continue
        return tp


def _model_at(model, loc) -> type | None:
    """The model class whose keys sit at ``loc`` (to list the allowed keys of an unknown one)."""
    tp = model
    for part in loc:
        tp = _unwrap(tp)
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            fields = {(f.alias or n): f for n, f in tp.model_fields.items()} | tp.model_fields
            if part not in fields:
                return None
            tp = fields[part].annotation
        elif typing.get_origin(tp) in (list, dict):
            tp = typing.get_args(tp)[-1]
        else:
            return None
    tp = _unwrap(tp)
    return tp if isinstance(tp, type) and issubclass(tp, BaseModel) else None


def allowed_keys(model) -> list[str]:
    """The keys a config model takes (YAML spelling)."""
    return sorted((f.alias or n) for n, f in model.model_fields.items())


def _describe(err: dict, model) -> tuple[str, str]:
    """(key path, message) of one pydantic error, in fivid's words."""
    loc = tuple(p for p in err["loc"]
                if not (isinstance(p, str) and p.startswith(("function-", "tagged-union", _VARIANT))))
    kind, ctx, found = err["type"], err.get("ctx") or {}, err.get("input")
    if kind == "fivid":
        return key_path(loc + tuple(ctx.get("at", ()))), ctx["message"]
    if kind == "extra_forbidden":
        parent = _model_at(model, loc[:-1])
        return key_path(loc), unknown_key_message(loc[-1], allowed_keys(parent) if parent is not None else [])
    if kind == "missing":
        return key_path(loc), MISSING
    expected = {
        "int_type": "an integer", "int_from_float": "an integer", "float_type": "a number", "bool_type": "true or false",
        "string_type": "a string", "list_type": "a list", "dict_type": "a mapping", "model_type": "a mapping",
        "model_attributes_type": "a mapping", "tuple_type": "a list",
        "greater_than": f"a value > {ctx.get('gt')}", "greater_than_equal": f"a value >= {ctx.get('ge')}",
        "less_than": f"a value < {ctx.get('lt')}", "less_than_equal": f"a value <= {ctx.get('le')}",
        "literal_error": f"one of {ctx.get('expected')}",
        "too_short": f"at least {ctx.get('min_length')} item(s)", "too_long": f"at most {ctx.get('max_length')} item(s)",
    }.get(kind)
    if expected is None:
        return key_path(loc), f"{err['msg']}; found {_kind(found)}"
    return key_path(loc), f"expected {expected}, found {_kind(found)}"


class Problems:
    """Every problem of one config, each at its key path; raised together as one :class:`ConfigError`."""

    def __init__(self, source: ConfigSource):
        self.source = source
        self.items: list[tuple[str, str]] = []

    def add(self, key: str, message: str) -> None:
        """Record a problem at the dotted ``key`` path (its line is looked up when raised)."""
        self.items.append((key, message))

    def __bool__(self) -> bool:
        return bool(self.items)

    def raise_if_any(self) -> None:
        """Raise one ConfigError for every problem recorded (the first in full, the others summarised), if any."""
        if not self.items:
            return
        key, message = self.items[0]
        if len(self.items) > 1:
            def at(k):
                line = self.source.line(k)
                return f"key {k!r}" + ("" if line is None else f" (line {line})")

            message += (f" (and {len(self.items) - 1} more: "
                        + "; ".join(f"{at(k)}: {m}" for k, m in self.items[1:]) + ")")
        raise self.source.error(key, message)


def validate(model, source: ConfigSource, problems: Problems | None = None, *, data=None, prefix: tuple = ()):
    """``model`` validated from ``source.data`` (or ``data``); None with the problems added when invalid.

    Without ``problems`` the problems are raised at once (:class:`ConfigError`).
    """
    own = problems is None
    problems = Problems(source) if own else problems
    try:
        result = model.model_validate(source.data if data is None else data)
    except ValidationError as exc:
        # an unknown key first: a misspelt key is the likely cause of a "missing" one beside it
        for err in sorted(exc.errors(include_url=False), key=lambda e: e["type"] != "extra_forbidden"):
            err = dict(err, loc=tuple(prefix) + tuple(err["loc"]))
            key, message = _describe(err, _rooted(model, prefix))
            problems.add(key, message)
        result = None
    if own:
        problems.raise_if_any()
    return result


def _rooted(model, prefix: tuple):
    """A stand-in root type for :func:`_model_at` when ``model`` validates the sub-tree at ``prefix``."""
    for part in reversed(prefix):
        model = dict[str, model] if isinstance(part, str) else list[model]
    return model


def load_config(path: str | PathLike, model, what: str = "config"):
    """Read ``path`` (:func:`read_yaml`) and validate it as ``model``: ``(instance, source)``."""
    source = read_yaml(path, what)
    return validate(model, source), source


def _json_safe(obj):
    """JSON has no infinity: an infinite default is written as the config spelling ``"inf"``."""
    if isinstance(obj, dict):
        return {k: _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, float) and obj in (float("inf"), float("-inf")):
        return "inf" if obj > 0 else "-inf"
    return obj


def json_schema(model, title: str | None = None) -> dict:
    """The JSON Schema (draft 2020-12) of a config model, as published in ``docs/schema/``."""
    schema = _json_safe(model.model_json_schema(by_alias=True))
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    if title:
        schema["title"] = title
    return schema
