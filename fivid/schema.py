"""The variable registry and the RunDataset schema.

The registry (``fivid/data/variables.yaml``) lists every canonical variable with its CF units,
long name and allowed dims, and the global attributes of a RunDataset. Readers map raw columns onto
it; everything downstream trusts it. Because xarray carries ``attrs`` through arithmetic even when
they became wrong, :func:`apply_cf_attrs` rewrites them from the registry on every output.

A RunDataset (measured or simulated) has dims ``time`` (and ``sensor`` for several accelerometers),
coordinate ``time`` [s], variables ``acceleration`` [m s-2], ``friction_force`` [N],
``normal_force`` [N], optional ``position`` [m] and ``velocity`` [m s-1], and the global attributes
``run_id, rig, sliding_velocity [m s-1], normal_load [N], roughness_ra [m], sample_rate [Hz], source,
fivid_version, schema_version, history``. Attribute units are given as ``<name>_units`` attributes.
"""

from __future__ import annotations

import datetime as _dt
import functools
from dataclasses import dataclass
from importlib import resources

import numpy as np

from fivid import __version__
from fivid.errors import SchemaError

__all__ = [
    "Variable",
    "Attribute",
    "SCHEMA_VERSION",
    "registry",
    "variable",
    "attribute",
    "check_run",
    "validate_run",
    "apply_cf_attrs",
    "with_condition_coords",
    "append_history",
    "new_history",
]


@dataclass(frozen=True)
class Variable:
    """A canonical variable: name, CF units, long name and allowed dimension tuples."""

    name: str
    units: str
    long_name: str
    dims: tuple[tuple[str, ...], ...]
    required: bool = False
    coordinate: bool = False


@dataclass(frozen=True)
class Attribute:
    """A global attribute of a RunDataset."""

    name: str
    type: str
    long_name: str
    required: bool = False
    units: str | None = None


@dataclass(frozen=True)
class Registry:
    schema_version: int
    variables: dict
    attributes: dict
    conditions: tuple[str, ...] = ()


def _registry_models():
    """The pydantic models of the registry file (built on first use: pydantic is not imported by ``import fivid``)."""
    from typing import Literal

    from pydantic import Field, model_validator

    from fivid.config_layer import ConfigModel, fail  # lazy: pulls pydantic

    class VariableSpec(ConfigModel):
        units: str
        long_name: str
        dims: list[list[str]] = Field(min_length=1)
        required: bool = False
        dtype: Literal["str"] | None = None

    class AttributeSpec(ConfigModel):
        type: Literal["str", "float", "int"]
        long_name: str
        required: bool = False
        units: str | None = None

    class RegistryConfig(ConfigModel):
        """The variable registry (``fivid/data/variables.yaml``)."""

        schema_version: int
        coordinates: dict[str, VariableSpec]
        variables: dict[str, VariableSpec]
        attributes: dict[str, AttributeSpec]
        condition_coordinates: list[str] = []

        @model_validator(mode="after")
        def _conditions_are_attributes(self):
            unknown = [c for c in self.condition_coordinates if c not in self.attributes]
            if unknown:
                raise fail(f"expected attributes of the registry, found {unknown}", at=("condition_coordinates",))
            return self

    return RegistryConfig


@functools.lru_cache(maxsize=None)
def registry() -> Registry:
    """The parsed registry (read once from the package data file, through :mod:`fivid.config_layer`)."""
    from fivid.config_layer import ConfigSource, parse_yaml_text, validate  # lazy: pulls pydantic

    text = resources.files("fivid").joinpath("data/variables.yaml").read_text(encoding="utf-8")
    name = "fivid/data/variables.yaml"
    data, lines = parse_yaml_text(text, name)
    raw = validate(_registry_models(), ConfigSource(data, name, lines))
    variables = {}
    for section, is_coord in (("coordinates", True), ("variables", False)):
        for var_name, spec in getattr(raw, section).items():
            variables[var_name] = Variable(name=var_name, units=str(spec.units), long_name=spec.long_name,
                                           dims=tuple(tuple(d) for d in spec.dims), required=spec.required,
                                           coordinate=is_coord)
    attributes = {attr: Attribute(name=attr, type=spec.type, long_name=spec.long_name, required=spec.required,
                                  units=spec.units)
                  for attr, spec in raw.attributes.items()}
    return Registry(raw.schema_version, variables, attributes, tuple(raw.condition_coordinates))


SCHEMA_VERSION = 1


def variable(name: str) -> Variable:
    """The registry entry of ``name``; :class:`SchemaError` naming the known ones if unknown."""
    reg = registry()
    try:
        return reg.variables[name]
    except KeyError:
        raise SchemaError(
            f"unknown variable {name!r}; known variables: {', '.join(sorted(reg.variables))}"
        ) from None


def attribute(name: str) -> Attribute:
    """The registry entry of global attribute ``name``."""
    reg = registry()
    try:
        return reg.attributes[name]
    except KeyError:
        raise SchemaError(
            f"unknown attribute {name!r}; known attributes: {', '.join(sorted(reg.attributes))}"
        ) from None


_TYPES = {"str": (str,), "float": (float, int, np.floating, np.integer), "int": (int, np.integer)}


def check_run(ds) -> list[str]:
    """Every way ``ds`` departs from the RunDataset schema, as a list of messages (empty when valid).

    Checks required variables and attributes, dims, units strings, attribute types, that ``time`` is
    strictly increasing and finite, and that data variables are finite.
    """
    reg = registry()
    problems: list[str] = []
    if "time" not in ds.coords:
        problems.append("coordinate 'time' is missing")
    else:
        t = np.asarray(ds["time"].values)
        if t.dtype.kind != "f":
            problems.append(f"coordinate 'time' must be float seconds, got dtype {t.dtype}")
        elif t.size and not np.all(np.isfinite(t)):
            problems.append("coordinate 'time' has NaN or infinite values")
        elif t.size > 1 and not np.all(np.diff(t) > 0):
            i = int(np.argmin(np.diff(t) > 0))
            problems.append(f"coordinate 'time' is not strictly increasing (at index {i + 1}: {t[i]!r} -> {t[i + 1]!r})")
        units = ds["time"].attrs.get("units")
        if units != "s":
            problems.append(f"coordinate 'time' has units {units!r}; expected 's'")
    for name, var in reg.variables.items():
        if var.coordinate:
            continue
        if name not in ds.data_vars:
            if var.required:
                problems.append(f"required variable {name!r} ({var.long_name}, {var.units}) is missing")
            continue
        da = ds[name]
        if tuple(da.dims) not in var.dims:
            allowed = " or ".join(str(d) for d in var.dims)
            problems.append(f"variable {name!r} has dims {tuple(da.dims)}; allowed: {allowed}")
        if da.attrs.get("units") != var.units:
            problems.append(f"variable {name!r} has units {da.attrs.get('units')!r}; expected {var.units!r}")
        values = np.asarray(da.values)
        if values.dtype.kind == "f" and values.size and not np.all(np.isfinite(values)):
            n = int(np.count_nonzero(~np.isfinite(values)))
            problems.append(f"variable {name!r} has {n} NaN or infinite values")
    for name, att in reg.attributes.items():
        if name not in ds.attrs:
            if att.required:
                problems.append(f"required attribute {name!r} ({att.long_name}) is missing")
            continue
        value = ds.attrs[name]
        if not isinstance(value, _TYPES[att.type]) or isinstance(value, bool):
            problems.append(f"attribute {name!r} = {value!r} should be of type {att.type}")
        elif att.type == "float" and not np.isfinite(value):
            problems.append(f"attribute {name!r} = {value!r} must be finite")
    return problems


def validate_run(ds, *, name: str | None = None):
    """Raise :class:`SchemaError` listing every problem of ``ds`` at once; return ``ds`` if valid.

    Parameters
    ----------
    ds : xarray.Dataset
        A RunDataset.
    name : str, optional
        How to name the dataset in the message (file name or run id).
    """
    problems = check_run(ds)
    if problems:
        label = name or ds.attrs.get("run_id", "dataset")
        raise SchemaError(
            f"{label} is not a valid RunDataset ({len(problems)} problem(s)): " + "; ".join(problems)
        )
    return ds


def apply_cf_attrs(ds):
    """Rewrite ``units``/``long_name`` of every registered variable and the attribute units from the registry.

    Returns a shallow copy of ``ds``; unregistered variables keep their attrs. Call on every output.
    """
    reg = registry()
    ds = ds.copy(deep=False)
    for name in list(ds.variables):
        var = reg.variables.get(name)
        if var is None:
            continue
        attrs = dict(ds[name].attrs)
        attrs["units"] = var.units
        attrs["long_name"] = var.long_name
        if name == "time":  # seconds without a reference date: no CF time coordinate (fivid/data/variables.yaml)
            attrs.pop("standard_name", None)
            attrs.pop("axis", None)
        ds[name].attrs = attrs
    for name in reg.conditions:
        if name in ds.coords and ds[name].ndim == 0:
            ds[name].attrs = _condition_attrs(reg.attributes[name])
    for name, att in reg.attributes.items():
        if att.units is not None and name in ds.attrs:
            ds.attrs[f"{name}_units"] = att.units
    ds.attrs["schema_version"] = reg.schema_version
    ds.attrs["fivid_version"] = __version__
    ds.attrs.setdefault("Conventions", "CF-1.8")
    return ds


def with_condition_coords(ds):
    """``ds`` (shallow copy) with its test conditions as scalar coordinates, rebuilt from the global attributes.

    The registry's ``condition_coordinates`` (``run_id``, ``sliding_velocity`` [m s-1], ``normal_load`` [N],
    ``roughness_ra`` [m]) present in ``ds.attrs`` become scalar coordinates with units and long_name, so runs
    stacked along a new dimension (``xr.open_mfdataset(paths, combine="nested", concat_dim="run")``) keep them
    as coordinates along it. The attributes are kept (readers use them) and stay the source of truth.
    """
    reg = registry()
    coords = {}
    for name in reg.conditions:
        if name in ds.attrs:
            value = ds.attrs[name]
            coords[name] = ((), str(value) if reg.attributes[name].type == "str" else float(value))
    ds = ds.assign_coords(coords)
    for name in coords:
        ds[name].attrs = _condition_attrs(reg.attributes[name])
    return ds


def _condition_attrs(att: Attribute) -> dict:
    """CF attrs of the scalar coordinate of a condition attribute (text has no units)."""
    return {"long_name": att.long_name, **({"units": att.units} if att.units else {})}


def _stamp() -> str:
    return _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def new_history(step: str, *, timestamp: bool = True) -> str:
    """A first ``history`` line: ISO timestamp, fivid version, what was done.

    With ``timestamp=False`` the line has no wall-clock time, so the same inputs give a byte-identical
    file (HDF5 itself writes no times): the run datasets of ``fivid ingest``, whose content the
    pipeline's cache hashes. The time of such a step is recorded outside the file (the pipeline's
    task manifests under ``.fivid-cache/``, ``fivid-run.log``; the file's mtime).
    """
    return f"{_stamp()} fivid {__version__}: {step}" if timestamp else f"fivid {__version__}: {step}"


def append_history(ds, step: str):
    """Append a line to ``ds.attrs['history']`` (in place) and return ``ds``."""
    line = new_history(step)
    old = ds.attrs.get("history", "")
    ds.attrs["history"] = f"{old}\n{line}" if old else line
    return ds
