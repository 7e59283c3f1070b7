"""Model configuration (YAML) -> validated :class:`~fivid.fe.model.Model`.

The format is documented in ``docs/model-config.md``. Quantities may carry units (``210 GPa``,
``10 mm``); a bare number is SI. Every problem raises :class:`~fivid.errors.ConfigError` with the
file, the line (when read from a file) and the key path, e.g. ``bodies.upper.material.nu``.
"""

from __future__ import annotations

import math
from os import PathLike
from pathlib import Path
from typing import Annotated, Any, Literal, Mapping

import numpy as np
from pydantic import BeforeValidator, Field, WithJsonSchema, model_validator
from pydantic_core import PydanticCustomError

import fivid.fe.model as fm
from fivid.config_layer import (MISSING, ConfigModel, ConfigSource, Name, Quantity, fail, from_mapping, key_loc,
                                none_as, quantity_parser, quantity_schema, read_yaml, unknown_key_message,
                                validate)
from fivid.errors import ConfigError

__all__ = ["build_model", "read_config", "ModelConfig"]

_BODY_KEYS = {"corners": "optional", "annulus": "optional", "profile": "optional", "grading": "optional",
              "divisions": "required", "material": "required", "thickness": "required",
              "clamp": "optional", "initial_velocity": "optional"}
_ANNULUS_KEYS = {"center": "required", "inner_radius": "required", "outer_radius": "required", "angles": "optional"}
_PROFILE_KEYS = {"edge": "required", "x": "optional", "z": "optional", "file": "optional", "units": "optional",
                 "sine": "optional", "gaussian": "optional"}
_GRADING_KEYS = {"edge": "optional", "ratio": "required"}
_PROFILE_UNITS_KEYS = {"x": "optional", "z": "optional"}
_SINE_KEYS = {"amplitude": "required", "wavelength": "required", "phase": "optional"}
_GAUSSIAN_KEYS = {"amplitude": "required", "width": "required", "center": "required"}
_EDGE_REF_KEYS = {"body": "required", "edge": "required", "x": "optional", "y": "optional"}
_POINT_REF_KEYS = {"body": "required", "at": "required"}
_MOTION_KEYS = {"name": "required", "component": "required", "kind": "required", "amplitude": "required",
                "ramp_time": "optional", "role": "optional"}
_POINT_MASS_KEYS = {"name": "required", "mass": "required"}
_SPRING_KEYS = {"name": "required", "a": "required", "b": "required", "component": "required",
                "stiffness": "required", "damping": "optional"}
_SENSOR_KEYS = {"name": "required", "direction": "required", "quantity": "optional"}
_REACTION_KEYS = {"name": "required", "tangential": "required", "normal": "required"}
_LOAD_KEYS = {"name": "required", "pressure": "required", "ramp_time": "optional", "start": "optional"}
_CONTACT_KEYS = {"name": "required", "slave": "required", "master": "optional", "rigid": "optional", "mu": "required",
                 "mu_static": "optional", "stribeck_velocity": "optional", "viscous": "optional",
                 "normal": "optional", "normal_stiffness": "optional"}
_NORMAL_LAW_KEYS = {"law": "required", "stiffness": "optional", "coefficient": "optional", "exponent": "optional",
                    "sigma": "optional", "asperity_radius": "optional", "asperity_density": "optional",
                    "e_star": "optional", "pressure_range": "optional", "max_pressure": "optional", "fit": "optional"}
_RIGID_KEYS = {"line": "optional", "circle": "optional", "velocity": "optional", "speed": "optional",
               "start": "optional", "ramp_time": "optional"}
_RIGID_LINE_KEYS = {"point": "required", "normal": "required"}
_RIGID_CIRCLE_KEYS = {"center": "required", "radius": "required", "side": "optional"}
_COMPONENTS = {"x": 0, "y": 1}


def read_config(source: str | PathLike | Mapping[str, Any]) -> tuple[dict, ConfigSource, str]:
    """Parse a config file (:func:`fivid.config_layer.read_yaml`) or take a mapping:
    ``(mapping, source with the key lines, provenance string with sha256)``."""
    if isinstance(source, Mapping):
        src = from_mapping(source)
    else:
        src = read_yaml(source, "model config")
    return src.data, src, src.origin


# ---------------------------------------------------------------------------------------------- typed sections


def _inf_or_frequency(value):
    if value in (None, "none", "inf"):
        return math.inf
    return quantity_parser("Hz", positive=True, bare="Hz")(value)


class _Material(ConfigModel):
    """Linear elastic isotropic material."""

    E: Quantity("Pa", positive=True, bare_is_si=True) = Field(description="Young's modulus")
    nu: Quantity("dimensionless", bare_is_si=True) = Field(description="Poisson's ratio, -1 < nu < 0.5")
    rho: Quantity("kg m-3", positive=True, bare_is_si=True) = Field(description="density")

    @model_validator(mode="after")
    def _poisson(self):
        if not -1.0 < self.nu < 0.5:
            raise fail(f"expected Poisson's ratio -1 < nu < 0.5 (nu >= 0.5 is incompressible: the elasticity matrix is "
                       f"singular), found {self.nu!r}", at=("nu",))
        return self


class _Ratio(ConfigModel):
    frequency: Quantity("Hz", positive=True, bare_is_si=True)
    ratio: Quantity("dimensionless", nonnegative=True, bare_is_si=True)


class _Damping(ConfigModel):
    """Rayleigh damping: ``alpha`` and ``beta`` given, or fitted through two modal damping ``ratios``."""

    alpha: Quantity("s-1", nonnegative=True, bare_is_si=True) = 0.0
    beta: Quantity("s", nonnegative=True, bare_is_si=True) = 0.0
    ratios: Annotated[list[_Ratio], Field(min_length=2, max_length=2)] | None = None
    cutoff: Annotated[float, BeforeValidator(_inf_or_frequency),
                      WithJsonSchema(quantity_schema("Hz", positive=True, bare_is_si=True, also=("inf", "none", None)))
                      ] = Field(math.inf, description="frequency above which beta stops acting ('inf' or 'none': "
                                                      "classic Rayleigh)")

    @model_validator(mode="before")
    @classmethod
    def _one_way(cls, data):
        if isinstance(data, Mapping) and "ratios" in data and ("alpha" in data or "beta" in data):
            raise fail("give either {alpha, beta} or ratios, not both")
        return data

    @model_validator(mode="after")
    def _distinct(self):
        if self.ratios is not None and self.ratios[0].frequency == self.ratios[1].frequency:
            raise fail("expected two different frequencies", at=("ratios",))
        return self


def _keys_schema(keys: dict[str, str], properties: dict | None = None, **more) -> dict:
    """The JSON Schema of a hand-checked mapping: its allowed and required keys (what :func:`_mapping` checks)."""
    properties = properties or {}
    schema = {"type": "object", "properties": {k: properties.get(k, {}) for k in keys},
              "additionalProperties": False, **more}
    required = [k for k, need in keys.items() if need == "required"]
    return schema | ({"required": required} if required else {})


def _item_schemas() -> dict:
    """JSON Schemas of the sections :func:`build_model` checks item by item (for editors; the checks are the code's)."""
    material = {"anyOf": [{"type": "string", "description": "an entry of 'materials'"},
                          _keys_schema({"E": "required", "nu": "required", "rho": "required"})]}
    edge_ref, point_ref = _keys_schema(_EDGE_REF_KEYS), _keys_schema(_POINT_REF_KEYS)
    profile = _keys_schema(_PROFILE_KEYS, {"units": _keys_schema(_PROFILE_UNITS_KEYS), "sine": _keys_schema(_SINE_KEYS),
                                           "gaussian": _keys_schema(_GAUSSIAN_KEYS)})
    body = _keys_schema(_BODY_KEYS, {"annulus": _keys_schema(_ANNULUS_KEYS), "profile": profile,
                                     "grading": _keys_schema(_GRADING_KEYS), "material": material,
                                     "divisions": {"type": "array", "items": {"type": "integer", "minimum": 1},
                                                   "minItems": 2, "maxItems": 2}})
    rigid = _keys_schema(_RIGID_KEYS, {"line": _keys_schema(_RIGID_LINE_KEYS),
                                       "circle": _keys_schema(_RIGID_CIRCLE_KEYS)})
    contact = _keys_schema(_CONTACT_KEYS, {"slave": edge_ref, "master": edge_ref, "rigid": rigid,
                                           "normal": {"anyOf": [{"type": "string"}, _keys_schema(_NORMAL_LAW_KEYS)]}})
    spring = _keys_schema(_SPRING_KEYS, {"a": point_ref, "b": {"anyOf": [{"const": "ground"}, point_ref]}})

    def items(schema):
        return {"type": "array", "items": schema}

    return {
        "bodies": {"type": "object", "minProperties": 1, "additionalProperties": body,
                   "description": "body name -> {corners | annulus, divisions, material, thickness, ...}"},
        "contacts": items(contact),
        "motions": items(_keys_schema({**_EDGE_REF_KEYS, **_MOTION_KEYS})),
        "point_masses": items(_keys_schema({**_POINT_REF_KEYS, **_POINT_MASS_KEYS})),
        "springs": items(spring),
        "sensors": items(_keys_schema({**_POINT_REF_KEYS, **_SENSOR_KEYS})),
        "reactions": items(_keys_schema({**_EDGE_REF_KEYS, **_REACTION_KEYS})),
        "loads": items(_keys_schema({**_EDGE_REF_KEYS, **_LOAD_KEYS})),
    }


_SCHEMAS = _item_schemas()


def _items_of(section: str):
    return Annotated[list[dict[str, Any]], none_as(list), WithJsonSchema(_SCHEMAS[section])]


class ModelConfig(ConfigModel):
    """A finite-element model config (``configs/models/*.yaml``, ``docs/model-config.md``).

    The top-level keys, materials and damping are typed here; bodies, contacts, motions, loads and the
    other item lists are checked item by item by :func:`build_model` (same error format).
    """

    name: Name = ""
    description: str = ""
    plane: Literal["stress", "strain"] = "stress"
    materials: Annotated[dict[str, _Material], none_as(dict)] = {}
    bodies: Annotated[dict[str, Any], Field(min_length=1), WithJsonSchema(_SCHEMAS["bodies"])]
    damping: _Damping | None = None
    contacts: _items_of("contacts") = []
    motions: _items_of("motions") = []
    point_masses: _items_of("point_masses") = []
    springs: _items_of("springs") = []
    sensors: _items_of("sensors") = []
    reactions: _items_of("reactions") = []
    loads: _items_of("loads") = []


# ---------------------------------------------------------------------------------------------- readers


def _mapping(ctx, value, key, allowed: dict[str, str]) -> dict:
    if not isinstance(value, Mapping):
        raise ctx.error(key, f"expected a mapping with keys {', '.join(sorted(allowed))}, found {type(value).__name__} "
                             f"{value!r}")
    unknown = [k for k in value if k not in allowed]
    if unknown:
        raise ctx.error(f"{key}.{unknown[0]}" if key else str(unknown[0]), unknown_key_message(unknown[0], allowed))
    missing = [k for k, need in allowed.items() if need == "required" and k not in value]
    if missing:
        raise ctx.error(f"{key}.{missing[0]}" if key else missing[0],
                        f"{MISSING}; required here: {', '.join(k for k, n in allowed.items() if n == 'required')}")
    return dict(value)


def _quantity(ctx, value, key, units: str, *, positive=False, nonnegative=False) -> float:
    """``value`` in SI ``units`` (a bare number is SI): the config layer's quantity check, at ``key``."""
    try:
        return quantity_parser(units, positive, nonnegative, bare=units)(value)
    except PydanticCustomError as exc:
        raise ctx.error(key, exc.context["message"]) from None


def _list(ctx, value, key, length=None) -> list:
    if not isinstance(value, (list, tuple)):
        raise ctx.error(key, f"expected a list, found {value!r}")
    if length is not None and len(value) != length:
        raise ctx.error(key, f"expected a list of {length} items, found {len(value)}: {value!r}")
    return list(value)


def _choice(ctx, value, key, choices):
    if value not in choices:
        raise ctx.error(key, f"expected one of {', '.join(map(str, choices))}, found {value!r}")
    return value


def _name(ctx, value, key) -> str:
    if not isinstance(value, str) or not value.strip():
        raise ctx.error(key, f"expected a non-empty name, found {value!r}")
    return value


def _material(ctx, value, key, materials: dict) -> fm.Material:
    if isinstance(value, str):
        if value not in materials:
            raise ctx.error(key, f"material {value!r} is not defined under 'materials' "
                                 f"(defined: {', '.join(materials) or 'none'})")
        return materials[value]
    if value is None:
        raise ctx.error(key, f"{MISSING}: give {{E, nu, rho}} or the name of an entry of 'materials'")
    m = validate(_Material, ctx, data=value, prefix=key_loc(key))
    return fm.Material(m.E, m.nu, m.rho)


def _check_corners(ctx, corners: np.ndarray, key: str) -> None:
    """Strictly convex and counter-clockwise: every turn c_{k-1} -> c_k -> c_{k+1} is to the left."""
    scale = float(np.ptp(corners, axis=0).max())
    for k in range(4):
        a = corners[k] - corners[k - 1]
        b = corners[(k + 1) % 4] - corners[k]
        cross = a[0] * b[1] - a[1] * b[0]
        if not cross > 1e-12 * scale * scale:
            area2 = sum(corners[i, 0] * corners[(i + 1) % 4, 1] - corners[(i + 1) % 4, 0] * corners[i, 1]
                        for i in range(4))
            why = "clockwise" if area2 < 0 else "not convex (or degenerate)"
            raise ctx.error(key, f"corners {corners.tolist()} are {why} at corner {k}; give 4 corners of a "
                                 "convex quadrilateral counter-clockwise from bottom-left")


def _grading(ctx, b, key, shape: str, profile_edge: str | None) -> tuple[str | None, float]:
    """``grading: {edge, ratio}`` -> (graded edge or None, ratio); a profile block grades toward its profile."""
    if "grading" not in b:
        return None, 1.0
    g = _mapping(ctx, b["grading"], f"{key}.grading", _GRADING_KEYS)
    ratio = _quantity(ctx, g["ratio"], f"{key}.grading.ratio", "dimensionless", positive=True)
    edges = fm.EDGES + (tuple(fm.ANNULUS_EDGES) if shape == "annulus" else ())
    if "edge" not in g and profile_edge is None:
        raise ctx.error(f"{key}.grading", "missing 'edge': the edge the mesh is refined toward "
                                          f"({', '.join(edges)}; a profile block defaults to its profiled edge)")
    edge = _choice(ctx, g.get("edge", profile_edge), f"{key}.grading.edge", edges)
    return fm.ANNULUS_EDGES.get(edge, edge), ratio


def _fractions(n: int, graded: str | None, ratio: float, axis: str) -> np.ndarray:
    """Node fractions along ``axis`` ("s": c0->c1, bottom-to-top "t") with the grading toward ``graded``."""
    from fivid.fe.geometry import graded_fractions

    ends = {"s": ("left", "right"), "t": ("bottom", "top")}[axis]
    if graded not in ends:
        return graded_fractions(n)
    return graded_fractions(n, ratio, toward_end=graded == ends[1])


def _annulus(ctx, spec, key, nx: int, t: np.ndarray) -> tuple[np.ndarray, bool]:
    from fivid.fe.geometry import annulus_coords

    a = _mapping(ctx, spec, key, _ANNULUS_KEYS)
    center = np.array([_quantity(ctx, v, f"{key}.center[{i}]", "m") for i, v in
                       enumerate(_list(ctx, a["center"], f"{key}.center", 2))])
    r_in = _quantity(ctx, a["inner_radius"], f"{key}.inner_radius", "m", positive=True)
    r_out = _quantity(ctx, a["outer_radius"], f"{key}.outer_radius", "m", positive=True)
    if not r_out > r_in:
        raise ctx.error(f"{key}.outer_radius", f"outer radius {r_out} m must exceed the inner radius {r_in} m")
    if "angles" in a:
        a0, a1 = (_quantity(ctx, v, f"{key}.angles[{i}]", "rad") for i, v in
                  enumerate(_list(ctx, a["angles"], f"{key}.angles", 2)))
    else:
        a0, a1 = 0.0, 2.0 * np.pi
    span = a1 - a0
    if not 0.0 < span <= 2.0 * np.pi * (1.0 + 1e-12):
        raise ctx.error(f"{key}.angles", f"expected start < end <= start + 360 deg (counter-clockwise), found "
                                         f"[{np.degrees(a0):.6g} deg, {np.degrees(a1):.6g} deg]")
    periodic = abs(span - 2.0 * np.pi) <= 1e-12 * 2.0 * np.pi
    if periodic and nx < 3:
        raise ctx.error(f"{key}", f"a full ring needs at least 3 divisions around, found {nx}")
    if not periodic and span / nx > np.pi / 2:
        raise ctx.error(f"{key}", f"{nx} divisions over {np.degrees(span):.6g} deg: an element may span at most 90 deg")
    return annulus_coords(center, r_in, r_out, a0, a0 + 2.0 * np.pi if periodic else a1, nx, t,
                          periodic=periodic), periodic


def _float_array(ctx, value, key) -> np.ndarray:
    if isinstance(value, np.ndarray):
        arr = np.asarray(value, dtype=float).ravel()
    else:
        items = _list(ctx, value, key)
        try:
            arr = np.array([float(v) for v in items])
        except (TypeError, ValueError):
            raise ctx.error(key, "expected a list of plain numbers (their unit is given by 'units')") from None
    if not np.all(np.isfinite(arr)):
        raise ctx.error(key, "contains values that are not finite")
    return arr


def _profile_table(ctx, p: dict, key) -> tuple[np.ndarray, np.ndarray]:
    """The (x, z) points of a measured profile [m], from arrays or a two-column file, with ``units: {x, z}``."""
    units = _mapping(ctx, p.get("units", {}), f"{key}.units", _PROFILE_UNITS_KEYS)
    scale = [_quantity(ctx, f"1 {units[c]}" if c in units else 1.0, f"{key}.units.{c}", "m") for c in ("x", "z")]
    if "file" in p:
        if "x" in p or "z" in p:
            raise ctx.error(f"{key}.file", "give the profile either as 'file' or as 'x' and 'z' arrays, not both")
        path = Path(str(p["file"]))
        if not path.is_absolute() and ctx.file is not None:
            path = Path(ctx.file).parent / path
        try:
            text = path.read_text().replace(",", " ").replace(";", " ")
            rows = [ln.split() for ln in text.splitlines()]
            rows = [r for r in rows if r and not r[0].startswith("#")]
            if rows and not _is_number(rows[0][0]):
                rows = rows[1:]  # a header line
            table = np.array([[float(v) for v in r[:2]] for r in rows])
        except OSError as exc:
            raise ctx.error(f"{key}.file", f"cannot read the profile file {str(path)!r}: {exc.strerror}") from None
        except (ValueError, IndexError):
            raise ctx.error(f"{key}.file", f"{str(path)!r} is not a two-column table of numbers (x, z)") from None
        if table.ndim != 2 or table.shape[0] < 2:
            raise ctx.error(f"{key}.file", f"{str(path)!r} needs at least 2 rows of (x, z)")
        x, z = table[:, 0], table[:, 1]
    else:
        if "x" not in p or "z" not in p:
            raise ctx.error(key, "a measured profile needs both 'x' and 'z' (or 'file', 'sine' or 'gaussian')")
        x, z = _float_array(ctx, p["x"], f"{key}.x"), _float_array(ctx, p["z"], f"{key}.z")
        if x.size != z.size or x.size < 2:
            raise ctx.error(f"{key}.z", f"expected x and z of the same length >= 2, found {x.size} and {z.size}")
    if not np.all(np.diff(x) > 0):
        raise ctx.error(f"{key}.x", "profile x must increase strictly")
    return x * scale[0], z * scale[1]


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _profile(ctx, spec, key, corners: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Coordinates of a rectangle whose bottom/top edge follows the profile ``spec`` (x from the left end)."""
    from fivid.fe.geometry import gaussian_profile, profile_coords, sine_profile

    p = _mapping(ctx, spec, key, _PROFILE_KEYS)
    edge = _choice(ctx, p["edge"], f"{key}.edge", ("bottom", "top"))
    c = corners
    if not (c[0, 1] == c[1, 1] and c[2, 1] == c[3, 1] and c[0, 0] == c[3, 0] and c[1, 0] == c[2, 0]):
        raise ctx.error(f"{key}", f"a profiled body needs axis-aligned rectangular corners, found {c.tolist()}")
    length = c[1, 0] - c[0, 0]
    xs = length * s  # node x measured from the left end
    kinds = [k for k in ("sine", "gaussian", "file", "x") if k in p]
    if len(kinds) != 1 and not (kinds == ["file", "x"]):
        raise ctx.error(key, "give exactly one profile: 'sine', 'gaussian', 'file', or 'x' and 'z' arrays")
    if "sine" in p:
        q = _mapping(ctx, p["sine"], f"{key}.sine", _SINE_KEYS)
        h = sine_profile(xs, _quantity(ctx, q["amplitude"], f"{key}.sine.amplitude", "m"),
                         _quantity(ctx, q["wavelength"], f"{key}.sine.wavelength", "m", positive=True),
                         _quantity(ctx, q.get("phase", 0.0), f"{key}.sine.phase", "rad"))
    elif "gaussian" in p:
        q = _mapping(ctx, p["gaussian"], f"{key}.gaussian", _GAUSSIAN_KEYS)
        h = gaussian_profile(xs, _quantity(ctx, q["amplitude"], f"{key}.gaussian.amplitude", "m"),
                             _quantity(ctx, q["width"], f"{key}.gaussian.width", "m", positive=True),
                             _quantity(ctx, q["center"], f"{key}.gaussian.center", "m"))
    else:
        x, z = _profile_table(ctx, p, key)
        tol = 1e-9 * length
        if x[0] > tol or x[-1] < length - tol:
            raise ctx.error(f"{key}.x", f"the profile covers x = [{x[0]:.6g}, {x[-1]:.6g}] m from the body's left "
                                        f"end; it must cover the whole edge [0, {length:.6g}] m")
        h = np.interp(xs, x, z)
    depth = c[3, 1] - c[0, 1]
    if (edge == "bottom" and h.max() >= depth) or (edge == "top" and -h.min() >= depth):
        raise ctx.error(key, f"profile heights [{h.min():.3g}, {h.max():.3g}] m fold the body (depth {depth:.3g} m)")
    return profile_coords(c, edge, h, s, t), edge


def _corners(ctx, b, key) -> np.ndarray:
    corners = np.array([[_quantity(ctx, v, f"{key}.corners[{i}][{j}]", "m") for j, v in
                         enumerate(_list(ctx, c, f"{key}.corners[{i}]", 2))]
                        for i, c in enumerate(_list(ctx, b["corners"], f"{key}.corners", 4))])
    _check_corners(ctx, corners, f"{key}.corners")
    return corners


def _block_geometry(ctx, b, key, nx: int, ny: int) -> tuple[np.ndarray, str, bool]:
    """(coords (ny+1, n_cols, 2), shape, periodic) of a body spec."""
    from fivid.fe.geometry import bilinear_coords

    if ("annulus" in b) == ("corners" in b):
        raise ctx.error(key, "give exactly one of 'corners' (a quadrilateral) or 'annulus' (a ring or arc)")
    if "annulus" in b:
        if "profile" in b:
            raise ctx.error(f"{key}.profile", "a profile edge is available on 'corners' bodies only")
        graded, ratio = _grading(ctx, b, key, "annulus", None)
        if graded in ("left", "right"):
            raise ctx.error(f"{key}.grading.edge", "an annulus grades radially only: edge inner or outer")
        xy, periodic = _annulus(ctx, b["annulus"], f"{key}.annulus", nx, _fractions(ny, graded, ratio, "t"))
        return xy, "annulus", periodic
    corners = _corners(ctx, b, key)
    pedge = None
    if "profile" in b:
        pedge = b["profile"].get("edge") if isinstance(b["profile"], Mapping) else None
    graded, ratio = _grading(ctx, b, key, "quad", pedge)
    s = _fractions(nx, graded, ratio, "s")
    t = _fractions(ny, graded, ratio, "t")
    if "profile" in b:
        xy, _ = _profile(ctx, b["profile"], f"{key}.profile", corners, s, t)
        return xy, "profile", False
    return bilinear_coords(corners, s, t), "quad", False


def _bodies(ctx, data, plane, materials) -> tuple[tuple, dict[str, tuple[str, ...]]]:
    bodies = data["bodies"]
    if not isinstance(bodies, Mapping) or not bodies:
        raise ctx.error("bodies", "expected a non-empty mapping of body name -> {corners, divisions, material, thickness}")
    blocks, clamps, offset = [], {}, 0
    for name, spec in bodies.items():
        key = f"bodies.{name}"
        b = _mapping(ctx, spec, key, _BODY_KEYS)
        div = _list(ctx, b["divisions"], f"{key}.divisions", 2)
        for i, d in enumerate(div):
            if isinstance(d, bool) or not isinstance(d, int) or d < 1:
                raise ctx.error(f"{key}.divisions[{i}]", f"expected divisions as integers >= 1, found {d!r}")
        nx, ny = div
        coords, shape, periodic = _block_geometry(ctx, b, key, nx, ny)
        material = _material(ctx, b["material"], f"{key}.material", materials)
        thickness = _quantity(ctx, b["thickness"], f"{key}.thickness", "m", positive=True)
        v0 = np.zeros(2)
        if "initial_velocity" in b:
            v0 = np.array([_quantity(ctx, v, f"{key}.initial_velocity[{i}]", "m s-1") for i, v in
                           enumerate(_list(ctx, b["initial_velocity"], f"{key}.initial_velocity", 2))])
        block = fm.Block(name=str(name), corners=coords[[0, 0, -1, -1], [0, -1, -1, 0]].copy(), nx=nx, ny=ny,
                         material=material, thickness=thickness, plane=plane, node_offset=offset, coords=coords,
                         initial_velocity=v0, shape=shape, periodic=periodic)
        clamp = b.get("clamp", [])
        clamp = [clamp] if isinstance(clamp, str) else _list(ctx, clamp, f"{key}.clamp")
        for i, e in enumerate(clamp):
            _choice(ctx, e, f"{key}.clamp[{i}]", block.edge_names)
        clamps[name] = tuple(clamp)
        blocks.append(block)
        offset += block.n_nodes
    return tuple(blocks), clamps


def _block_ref(ctx, blocks, value, key) -> fm.Block:
    for b in blocks:
        if b.name == value:
            return b
    raise ctx.error(key, f"body {value!r} does not exist; bodies are: {', '.join(b.name for b in blocks)}")


def _edge_ref(ctx, blocks, spec, key, extra: dict[str, str]) -> tuple[fm.Block, np.ndarray, dict]:
    """``{body, edge, x: [lo, hi] | y: [lo, hi]}`` -> (block, nodes in edge order, the other keys)."""
    allowed = {**_EDGE_REF_KEYS, **extra}
    m = _mapping(ctx, spec, key, allowed)
    block = _block_ref(ctx, blocks, m["body"], f"{key}.body")
    _choice(ctx, m["edge"], f"{key}.edge", block.edge_names)
    nodes = block.edge_nodes(m["edge"])
    coords = block.coords.reshape(-1, 2)[nodes - block.node_offset]
    for axis, c in (("x", 0), ("y", 1)):
        if axis in m:
            lo, hi = (_quantity(ctx, v, f"{key}.{axis}[{i}]", "m") for i, v in
                      enumerate(_list(ctx, m[axis], f"{key}.{axis}", 2)))
            tol = 1e-9 * float(np.ptp(block.coords.reshape(-1, 2), axis=0).max())
            keep = (coords[:, c] >= min(lo, hi) - tol) & (coords[:, c] <= max(lo, hi) + tol)
            nodes, coords = nodes[keep], coords[keep]
            if nodes.size == 0:
                raise ctx.error(f"{key}.{axis}", f"no node of edge {m['edge']!r} of body {block.name!r} has "
                                                 f"{axis} in [{lo}, {hi}] m")
    return block, nodes, m


def _point_ref(ctx, blocks, spec, key, extra: dict[str, str]) -> tuple[int, dict]:
    """``{body, at: [x, y]}`` -> the nearest node of the body (must lie within one element of the point)."""
    m = _mapping(ctx, spec, key, {**_POINT_REF_KEYS, **extra})
    block = _block_ref(ctx, blocks, m["body"], f"{key}.body")
    at = np.array([_quantity(ctx, v, f"{key}.at[{i}]", "m") for i, v in
                   enumerate(_list(ctx, m["at"], f"{key}.at", 2))])
    xy = block.coords.reshape(-1, 2)
    d = np.hypot(*(xy - at).T)
    k = int(np.argmin(d))
    size = max(float(np.hypot(*np.diff(block.coords, axis=a).reshape(-1, 2).T).max()) if block.coords.shape[a] > 1
               else 0.0 for a in (0, 1))  # the longest element side
    if d[k] > size:
        raise ctx.error(f"{key}.at", f"point {at.tolist()} m is not on body {block.name!r} (nearest node "
                                     f"{xy[k].tolist()} is {d[k]:.3g} m away)")
    return int(block.node_offset + k), m


def _point(ctx, value, key) -> np.ndarray:
    return np.array([_quantity(ctx, v, f"{key}[{j}]", "m") for j, v in enumerate(_list(ctx, value, key, 2))])


def _contact(ctx, spec, key, blocks):
    """One ``contacts`` item: slave edge against a master edge or a rigid surface, with its laws."""
    from fivid.contact import TangentialLaw

    m = _mapping(ctx, spec, key, _CONTACT_KEYS)
    sb, snodes, _ = _edge_ref(ctx, blocks, m["slave"], f"{key}.slave", {})
    if ("master" in m) == ("rigid" in m):
        raise ctx.error(key, "give either 'master' (an edge of another body) or 'rigid' (a rigid line or circle)")
    rigid = None
    mb = None
    if "master" in m:
        mb, mnodes, _ = _edge_ref(ctx, blocks, m["master"], f"{key}.master", {})
        if sb is mb:
            raise ctx.error(f"{key}.master", "slave and master must be edges of different bodies")
        if mnodes.size < 2:
            raise ctx.error(f"{key}.master", "the master edge needs at least 2 nodes (one segment)")
    else:
        rigid = _rigid_surface(ctx, m["rigid"], f"{key}.rigid")
        mnodes = np.zeros(0, dtype=np.int64)
    mu = _quantity(ctx, m["mu"], f"{key}.mu", "dimensionless", nonnegative=True)
    mu_s = _quantity(ctx, m.get("mu_static", mu), f"{key}.mu_static", "dimensionless", nonnegative=True)
    if mu_s < mu:
        raise ctx.error(f"{key}.mu_static", f"the static coefficient ({mu_s:g}) must be >= the kinetic mu ({mu:g})")
    friction = TangentialLaw(
        mu_static_excess=mu_s - mu,
        stribeck_velocity=_quantity(ctx, m.get("stribeck_velocity", 0.0), f"{key}.stribeck_velocity", "m s-1",
                                    nonnegative=True),
        viscous=_quantity(ctx, m.get("viscous", 0.0), f"{key}.viscous", "s m-1", nonnegative=True))
    if friction.stribeck_velocity > 0 and friction.mu_static_excess == 0:
        raise ctx.error(f"{key}.stribeck_velocity", "a Stribeck curve needs mu_static > mu (it decays from mu_static "
                                                    "to mu)")
    if "normal_stiffness" in m:
        kn = _quantity(ctx, m["normal_stiffness"], f"{key}.normal_stiffness", "N m-3", positive=True)
    else:  # 10 x the slave body's own normal stiffness per unit area E/D (D: its depth normal to the edge):
        # stiff against the body, and independent of the mesh (an element-size penalty is not)
        edge = m["slave"]["edge"]
        c = sb.corners
        if edge in ("bottom", "top"):
            depth = np.hypot(*(c[3] - c[0]))
        elif edge in ("left", "right"):
            depth = np.hypot(*(c[1] - c[0]))
        else:  # annulus: the wall
            depth = float(np.ptp(np.hypot(*(sb.coords.reshape(-1, 2) - sb.coords.reshape(-1, 2).mean(0)).T)))
        kn = 10.0 * sb.material.E / float(depth)
    law = _normal_law(ctx, m.get("normal"), f"{key}.normal", sb, mb)
    return fm.ContactPair(_name(ctx, m["name"], f"{key}.name"), sb.name, snodes, mb.name if mb else "", mnodes, mu,
                          kn, law=law, friction=friction, rigid=rigid)


def _normal_law(ctx, spec, key, slave_block, master_block):
    """``normal: {law: rigid | linear | power | greenwood-williamson, ...}`` -> NormalLaw."""
    from fivid.contact import GreenwoodWilliamson, NormalLaw, composite_modulus
    from fivid.errors import ConfigError

    if spec is None:
        return NormalLaw()
    if isinstance(spec, str):
        spec = {"law": spec}
    m = _mapping(ctx, spec, key, _NORMAL_LAW_KEYS)
    kind = _choice(ctx, m["law"], f"{key}.law", ("rigid", "linear", "power", "greenwood-williamson"))
    need = {"rigid": (), "linear": ("stiffness",), "power": ("coefficient", "exponent"),
            "greenwood-williamson": ("sigma", "asperity_radius", "asperity_density")}[kind]
    for k in need:
        if k not in m:
            raise ctx.error(f"{key}.{k}", f"the {kind} law needs '{k}' (see docs/model-config.md, contacts)")
    extra = set(m) - {"law", *need, *({"e_star", "pressure_range", "max_pressure", "fit"}
                                      if kind == "greenwood-williamson" else ())}
    if extra:
        raise ctx.error(f"{key}.{sorted(extra)[0]}", f"not a parameter of the {kind} law; it takes "
                                                     f"{', '.join(need) or 'no parameters'}")
    try:
        if kind == "rigid":
            return NormalLaw()
        if kind == "linear":
            return NormalLaw("linear", _quantity(ctx, m["stiffness"], f"{key}.stiffness", "N m-3", positive=True))
        if kind == "power":
            n = _quantity(ctx, m["exponent"], f"{key}.exponent", "dimensionless", positive=True)
            c = _quantity(ctx, m["coefficient"], f"{key}.coefficient", f"Pa / m**{n!r}", positive=True)
            return NormalLaw("power", c, n, "given")
        mats = [slave_block.material] + ([master_block.material] if master_block is not None else [])
        e_star = (_quantity(ctx, m["e_star"], f"{key}.e_star", "Pa", positive=True) if "e_star" in m
                  else composite_modulus(*mats))
        gw = GreenwoodWilliamson(
            sigma=_quantity(ctx, m["sigma"], f"{key}.sigma", "m", positive=True),
            radius=_quantity(ctx, m["asperity_radius"], f"{key}.asperity_radius", "m", positive=True),
            density=_quantity(ctx, m["asperity_density"], f"{key}.asperity_density", "m-2", positive=True),
            e_star=e_star)
        fit = _choice(ctx, m.get("fit", "none"), f"{key}.fit", ("none", "power"))
        if fit == "none":
            if "pressure_range" in m:
                raise ctx.error(f"{key}.pressure_range", "pressure_range is the range of 'fit: power'; the exact "
                                                         "(tabulated) law takes max_pressure")
            p_max = _quantity(ctx, m.get("max_pressure", 1e8), f"{key}.max_pressure", "Pa", positive=True)
            return gw.table_law(p_max)
        if "max_pressure" in m:
            raise ctx.error(f"{key}.max_pressure", "max_pressure bounds the exact (tabulated) law; 'fit: power' "
                                                   "takes pressure_range")
        rng = (1e3, 1e6)
        if "pressure_range" in m:
            rng = tuple(_quantity(ctx, v, f"{key}.pressure_range[{j}]", "Pa", positive=True)
                        for j, v in enumerate(_list(ctx, m["pressure_range"], f"{key}.pressure_range", 2)))
        return gw.power_fit(rng)
    except ConfigError as exc:
        if getattr(exc, "key", None):
            raise
        raise ctx.error(key, str(exc)) from None


def _rigid_surface(ctx, spec, key):
    """``rigid: {line: {point, normal} | circle: {center, radius, side}, velocity | speed, start, ramp_time}``."""
    from fivid.contact import RigidSurface

    m = _mapping(ctx, spec, key, _RIGID_KEYS)
    if ("line" in m) == ("circle" in m):
        raise ctx.error(key, "give either 'line: {point, normal}' or 'circle: {center, radius, side}'")
    start = _quantity(ctx, m.get("start", 0.0), f"{key}.start", "s", nonnegative=True)
    ramp = _quantity(ctx, m.get("ramp_time", 0.0), f"{key}.ramp_time", "s", nonnegative=True)
    if "line" in m:
        if "speed" in m:
            raise ctx.error(f"{key}.speed", "a rigid line moves with 'velocity: [vx, vy]' (along itself); 'speed' "
                                            "is a circle's rotation (e.g. 10 rpm)")
        q = _mapping(ctx, m["line"], f"{key}.line", _RIGID_LINE_KEYS)
        point = _point(ctx, q["point"], f"{key}.line.point")
        normal = np.array([_quantity(ctx, v, f"{key}.line.normal[{j}]", "dimensionless")
                           for j, v in enumerate(_list(ctx, q["normal"], f"{key}.line.normal", 2))])
        norm = float(np.hypot(*normal))
        if norm == 0.0:
            raise ctx.error(f"{key}.line.normal", "the normal is the zero vector")
        normal = normal / norm
        vel = np.zeros(2)
        if "velocity" in m:
            vel = np.array([_quantity(ctx, v, f"{key}.velocity[{j}]", "m s-1")
                            for j, v in enumerate(_list(ctx, m["velocity"], f"{key}.velocity", 2))])
            if abs(vel @ normal) > 1e-9 * max(float(np.hypot(*vel)), 1e-300):
                raise ctx.error(f"{key}.velocity", f"a rigid line can only slide along itself: velocity "
                                                   f"{vel.tolist()} m/s has a component along its normal "
                                                   f"{normal.tolist()}")
        return RigidSurface("line", point, normal=normal, velocity=vel, start=start, ramp_time=ramp)
    if "velocity" in m:
        raise ctx.error(f"{key}.velocity", "a rigid circle turns with 'speed' (e.g. 10 rpm or 1.05 rad/s, "
                                           "counter-clockwise positive)")
    q = _mapping(ctx, m["circle"], f"{key}.circle", _RIGID_CIRCLE_KEYS)
    side = _choice(ctx, q.get("side", "outside"), f"{key}.circle.side", ("outside", "inside"))
    omega = _quantity(ctx, m.get("speed", 0.0), f"{key}.speed", "rad s-1")
    return RigidSurface("circle", _point(ctx, q["center"], f"{key}.circle.center"),
                        radius=_quantity(ctx, q["radius"], f"{key}.circle.radius", "m", positive=True), side=side,
                        angular_velocity=omega, start=start, ramp_time=ramp)


def _items(ctx, data, section) -> list:
    value = data.get(section, []) or []
    return _list(ctx, value, section)


def build_model(source: str | PathLike | Mapping[str, Any]) -> fm.Model:
    """Validate a config (path or mapping) and build the :class:`Model` (see :func:`fivid.fe.load_model`)."""
    data, ctx, origin = read_config(source)
    top = validate(ModelConfig, ctx)
    plane = top.plane
    materials = {name: fm.Material(m.E, m.nu, m.rho) for name, m in top.materials.items()}
    blocks, clamps = _bodies(ctx, data, plane, materials)
    n_nodes = sum(b.n_nodes for b in blocks)
    coords = np.concatenate([b.coords.reshape(-1, 2) for b in blocks])

    fixed = []
    for b in blocks:
        for edge in clamps[b.name]:
            nodes = b.edge_nodes(edge)
            fixed += [2 * nodes, 2 * nodes + 1]

    motions = []
    for i, spec in enumerate(_items(ctx, data, "motions")):
        key = f"motions[{i}]"
        block, nodes, m = _edge_ref(ctx, blocks, spec, key, _MOTION_KEYS)
        kind = _choice(ctx, m["kind"], f"{key}.kind", ("velocity", "displacement"))
        comp = _COMPONENTS[_choice(ctx, m["component"], f"{key}.component", tuple(_COMPONENTS))]
        amp = _quantity(ctx, m["amplitude"], f"{key}.amplitude", "m s-1" if kind == "velocity" else "m")
        ramp = _quantity(ctx, m.get("ramp_time", 0.0), f"{key}.ramp_time", "s", nonnegative=True)
        role = m.get("role")
        if role is not None:
            _choice(ctx, role, f"{key}.role", ("base", "load"))
            if any(mo.role == role for mo in motions):
                raise ctx.error(f"{key}.role", f"a second motion with role {role!r}; only one is allowed")
        motions.append(fm.Motion(_name(ctx, m["name"], f"{key}.name"), nodes, comp, kind, amp, ramp, role))
        fixed.append(2 * nodes + comp)
    fixed_dofs = np.unique(np.concatenate(fixed)) if fixed else np.zeros(0, dtype=np.int64)

    point_masses = []
    for i, spec in enumerate(_items(ctx, data, "point_masses")):
        key = f"point_masses[{i}]"
        node, m = _point_ref(ctx, blocks, spec, key, _POINT_MASS_KEYS)
        point_masses.append(fm.PointMass(_name(ctx, m["name"], f"{key}.name"), node,
                                      _quantity(ctx, m["mass"], f"{key}.mass", "kg", positive=True)))

    springs = []
    for i, spec in enumerate(_items(ctx, data, "springs")):
        key = f"springs[{i}]"
        m = _mapping(ctx, spec, key, _SPRING_KEYS)
        a, _ = _point_ref(ctx, blocks, m["a"], f"{key}.a", {})
        b = -1 if m["b"] == "ground" else _point_ref(ctx, blocks, m["b"], f"{key}.b", {})[0]
        if a == b:
            raise ctx.error(f"{key}.b", "both ends of the spring are the same node")
        comp = _COMPONENTS[_choice(ctx, m["component"], f"{key}.component", tuple(_COMPONENTS))]
        springs.append(fm.Spring(_name(ctx, m["name"], f"{key}.name"), a, b, comp,
                              _quantity(ctx, m["stiffness"], f"{key}.stiffness", "N m-1", nonnegative=True),
                              _quantity(ctx, m.get("damping", 0.0), f"{key}.damping", "N s m-1", nonnegative=True)))

    contacts = [_contact(ctx, spec, f"contacts[{i}]", blocks) for i, spec in enumerate(_items(ctx, data, "contacts"))]

    sensors = []
    for i, spec in enumerate(_items(ctx, data, "sensors")):
        key = f"sensors[{i}]"
        node, m = _point_ref(ctx, blocks, spec, key, _SENSOR_KEYS)
        d = m["direction"]
        if isinstance(d, str):
            sign = -1.0 if d.startswith("-") else 1.0
            comp = _COMPONENTS[_choice(ctx, d.lstrip("+-"), f"{key}.direction", tuple(_COMPONENTS))]
            direction = np.zeros(2)
            direction[comp] = sign
        else:
            direction = np.array([_quantity(ctx, v, f"{key}.direction[{j}]", "dimensionless")
                                  for j, v in enumerate(_list(ctx, d, f"{key}.direction", 2))])
            norm = float(np.hypot(*direction))
            if norm == 0.0:
                raise ctx.error(f"{key}.direction", "the direction is the zero vector")
            direction = direction / norm
        quantity = _choice(ctx, m.get("quantity", "acceleration"), f"{key}.quantity", ("acceleration",))
        sensors.append(fm.Sensor(_name(ctx, m["name"], f"{key}.name"), node, direction, quantity))

    reactions = []
    for i, spec in enumerate(_items(ctx, data, "reactions")):
        key = f"reactions[{i}]"
        block, nodes, m = _edge_ref(ctx, blocks, spec, key, _REACTION_KEYS)
        t = _COMPONENTS[_choice(ctx, m["tangential"], f"{key}.tangential", tuple(_COMPONENTS))]
        n = _COMPONENTS[_choice(ctx, m["normal"], f"{key}.normal", tuple(_COMPONENTS))]
        if t == n:
            raise ctx.error(f"{key}.normal", "tangential and normal must be different components")
        free = np.setdiff1d(np.concatenate([2 * nodes + t, 2 * nodes + n]), fixed_dofs)
        if free.size:
            raise ctx.error(key, f"a reaction needs constrained nodes (a clamp or a motion), but "
                                 f"{free.size} of its dofs are free; clamp edge {m['edge']!r} of {block.name!r}")
        reactions.append(fm.Reaction(_name(ctx, m["name"], f"{key}.name"), nodes, t, n))

    loads = []
    for i, spec in enumerate(_items(ctx, data, "loads")):
        key = f"loads[{i}]"
        block, nodes, m = _edge_ref(ctx, blocks, spec, key, _LOAD_KEYS)
        if nodes.size < 2:
            raise ctx.error(key, "a pressure load needs at least 2 nodes of the edge (one segment)")
        loads.append(fm.PressureLoad(_name(ctx, m["name"], f"{key}.name"), block.name,
                                     block.edge_segments(m["edge"], nodes),
                                     _quantity(ctx, m["pressure"], f"{key}.pressure", "Pa"),
                                     _quantity(ctx, m.get("ramp_time", 0.0), f"{key}.ramp_time", "s",
                                               nonnegative=True),
                                     _quantity(ctx, m.get("start", 0.0), f"{key}.start", "s", nonnegative=True)))

    alpha, beta, cutoff = _damping(ctx, top.damping)
    for section, items in (("motions", motions), ("point_masses", point_masses), ("springs", springs),
                           ("contacts", contacts), ("sensors", sensors), ("reactions", reactions),
                           ("loads", loads)):
        names = [x.name for x in items]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ctx.error(section, f"duplicate name(s) {sorted(dup)}; names must be unique within '{section}'")
    return fm.Model(plane=plane, blocks=blocks, n_nodes=n_nodes, coords=coords, fixed_dofs=fixed_dofs,
                 motions=tuple(motions), point_masses=tuple(point_masses), springs=tuple(springs),
                 contacts=tuple(contacts), sensors=tuple(sensors), reactions=tuple(reactions), loads=tuple(loads),
                 rayleigh_alpha=alpha, rayleigh_beta=beta, damping_cutoff=cutoff, source=origin, config=data)


def _damping(ctx, spec: _Damping | None) -> tuple[float, float, float]:
    """``(alpha [s-1], beta [s], cutoff [Hz])`` of the ``damping`` section (cutoff inf: classic Rayleigh)."""
    from fivid.fe.damping import fit_rayleigh

    if spec is None:
        return 0.0, 0.0, math.inf
    if spec.ratios is None:
        return spec.alpha, spec.beta, spec.cutoff
    (f1, z1), (f2, z2) = ((r.frequency, r.ratio) for r in spec.ratios)
    alpha, beta = fit_rayleigh(f1, z1, f2, z2, cutoff=spec.cutoff)
    if alpha < 0 or beta < 0:
        raise ctx.error("damping.ratios", f"these ratios need a negative Rayleigh coefficient (alpha {alpha:.4g} "
                                          f"s-1, beta {beta:.4g} s): no Rayleigh curve passes through both points")
    return alpha, beta, spec.cutoff
