"""The schema of a model file (``configs/models/*.yaml``, ``docs/model-config.md``): one pydantic model.

Every section is typed here, the inner ones too (bodies, contacts, motions, springs, sensors, reactions,
loads): unknown keys, missing keys, wrong types, units and ranges are checked by the config layer
(:mod:`fivid.config_layer`) with its one error format (file, line, key path, value, what is allowed), and the
published JSON Schema (``docs/schema/model.schema.json``, ``fivid schema model``) is generated from these
models. What needs the mesh (a body or edge that must exist, a point that must lie on a body, a reaction's
constrained nodes) is checked by :func:`fivid.fe.build.build_model`, in the same format.

Quantities may carry units (``210 GPa``, ``10 mm``); a bare number is SI. The contact sections (normal law,
rigid surface, friction curve) are :mod:`fivid.contact.config`'s.
"""

from __future__ import annotations

import math
from os import PathLike
from typing import Annotated, Any, Literal, Mapping

import numpy as np
from pydantic import BeforeValidator, Field, WithJsonSchema, model_validator
from pydantic_core import PydanticCustomError

from fivid.config_layer import (ConfigModel, ConfigSource, Name, Number, Quantity, QuantityText, Vector, either, fail,
                                from_mapping, none_as, quantity_parser, quantity_schema, read_yaml)
from fivid.contact.config import FrictionKeys, NormalLawField, RigidSurfaceConfig
from fivid.fe.model import ANNULUS_EDGES, EDGES

__all__ = ["read_config", "ModelConfig", "MaterialConfig", "DampingConfig", "BodyConfig", "AnnulusConfig",
           "ProfileConfig", "GradingConfig", "EdgeRefConfig", "PointRefConfig", "MotionConfig", "PointMassConfig",
           "SpringConfig", "SensorConfig", "ReactionConfig", "LoadConfig", "ContactConfig", "COMPONENTS"]

#: a component name -> its dof offset (x: 0, y: 1)
COMPONENTS = {"x": 0, "y": 1}
_Component = Literal["x", "y"]


def read_config(source: str | PathLike | Mapping[str, Any]) -> tuple[dict, ConfigSource, str]:
    """Parse a config file (:func:`fivid.config_layer.read_yaml`) or take a mapping:
    ``(mapping, source with the key lines, provenance string with sha256)``."""
    src = from_mapping(source) if isinstance(source, Mapping) else read_yaml(source, "model config")
    return src.data, src, src.origin


def _item_name(value):
    if not isinstance(value, str) or not value.strip():
        raise fail(f"expected a non-empty name, found {value!r}")
    return value


#: The name of an item (a motion, a sensor, a contact ...): non-empty text.
ItemName = Annotated[str, BeforeValidator(_item_name), WithJsonSchema({"type": "string", "minLength": 1})]


def _quantity_error(value, units: str, at: tuple, **range_) -> None:
    """Raise a validator error at ``at`` when ``value`` is not a quantity in ``units``."""
    try:
        quantity_parser(units, bare=units, **range_)(value)
    except PydanticCustomError as exc:
        raise fail(exc.context["message"], at=at) from None


# ---------------------------------------------------------------------------------------------- material, damping


class MaterialConfig(ConfigModel):
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


def _inf_or_frequency(value):
    if value in (None, "none", "inf"):
        return math.inf
    return quantity_parser("Hz", positive=True, bare="Hz")(value)


class DampingConfig(ConfigModel):
    """Rayleigh damping: ``alpha`` and ``beta`` given, or solved for through two modal damping ``ratios``."""

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


# ---------------------------------------------------------------------------------------------- bodies


class AnnulusConfig(ConfigModel):
    """``annulus: {center, inner_radius, outer_radius, angles}``: a ring (no angles) or an arc [rad]."""

    center: Vector("m")
    inner_radius: Quantity("m", positive=True, bare_is_si=True)
    outer_radius: Quantity("m", positive=True, bare_is_si=True)
    angles: Vector("rad") | None = None

    @model_validator(mode="after")
    def _radii_and_span(self):
        if not self.outer_radius > self.inner_radius:
            raise fail(f"outer radius {self.outer_radius} m must exceed the inner radius {self.inner_radius} m",
                       at=("outer_radius",))
        a0, a1 = self.angle_range
        if not 0.0 < a1 - a0 <= 2.0 * np.pi * (1.0 + 1e-12):
            raise fail(f"expected start < end <= start + 360 deg (counter-clockwise), found "
                       f"[{np.degrees(a0):.6g} deg, {np.degrees(a1):.6g} deg]", at=("angles",))
        return self

    @property
    def angle_range(self) -> tuple[float, float]:
        """``(start, end)`` [rad]; a ring: ``(0, 2 pi)``."""
        return (float(self.angles[0]), float(self.angles[1])) if self.angles is not None else (0.0, 2.0 * np.pi)

    @property
    def periodic(self) -> bool:
        """A full ring (the span is 360 deg): it has a seam, no start/end edges."""
        a0, a1 = self.angle_range
        return abs((a1 - a0) - 2.0 * np.pi) <= 1e-12 * 2.0 * np.pi


class _ProfileUnits(ConfigModel):
    x: Name | None = None
    z: Name | None = None

    @model_validator(mode="after")
    def _lengths(self):
        for c in ("x", "z"):
            if getattr(self, c) is not None:
                _quantity_error(f"1 {getattr(self, c)}", "m", (c,))
        return self

    def scale(self, axis: str) -> float:
        """Metres per unit of the ``axis`` column (1 when not given)."""
        unit = getattr(self, axis)
        return 1.0 if unit is None else quantity_parser("m", bare="m")(f"1 {unit}")


class _Sine(ConfigModel):
    amplitude: Quantity("m", bare_is_si=True)
    wavelength: Quantity("m", positive=True, bare_is_si=True)
    phase: Quantity("rad", bare_is_si=True) = 0.0


class _Gaussian(ConfigModel):
    amplitude: Quantity("m", bare_is_si=True)
    width: Quantity("m", positive=True, bare_is_si=True)
    center: Quantity("m", bare_is_si=True)


def _numbers(value):
    """A profile's ``x``/``z`` given in code as a 1-D numpy array is read as its list of numbers."""
    return value.tolist() if isinstance(value, np.ndarray) and value.ndim == 1 else value


_Numbers = Annotated[list[Number], BeforeValidator(_numbers)]


class ProfileConfig(ConfigModel):
    """``profile: {edge, sine | gaussian | file | x and z, units}``: the height profile of a body's edge."""

    edge: Literal["bottom", "top"]
    x: _Numbers | None = None
    z: _Numbers | None = None
    file: Name | None = None
    units: _ProfileUnits = _ProfileUnits()
    sine: _Sine | None = None
    gaussian: _Gaussian | None = None

    @model_validator(mode="after")
    def _one_profile(self):
        kinds = [k for k in ("sine", "gaussian", "file", "x") if getattr(self, k) is not None]
        if len(kinds) != 1 and not (kinds == ["file", "x"]):
            raise fail("give exactly one profile: 'sine', 'gaussian', 'file', or 'x' and 'z' arrays")
        if self.file is not None and (self.x is not None or self.z is not None):
            raise fail("give the profile either as 'file' or as 'x' and 'z' arrays, not both", at=("file",))
        if self.file is None and self.sine is None and self.gaussian is None:
            if self.x is None or self.z is None:
                raise fail("a measured profile needs both 'x' and 'z' (or 'file', 'sine' or 'gaussian')")
            for k in ("x", "z"):
                if not np.all(np.isfinite(getattr(self, k))):
                    raise fail("contains values that are not finite", at=(k,))
            if len(self.x) != len(self.z) or len(self.x) < 2:
                raise fail(f"expected x and z of the same length >= 2, found {len(self.x)} and {len(self.z)}",
                           at=("z",))
            if not np.all(np.diff(self.x) > 0):
                raise fail("profile x must increase strictly", at=("x",))
        return self


class GradingConfig(ConfigModel):
    """``grading: {edge, ratio}``: divisions in geometric progression, ``ratio`` > 1 refining toward ``edge``."""

    edge: Name | None = None
    ratio: Quantity("dimensionless", positive=True, bare_is_si=True)


def _as_list(value):
    return [value] if isinstance(value, str) else list(value) if isinstance(value, tuple) else value


_Divisions = Annotated[list[Annotated[int, Field(ge=1)]], BeforeValidator(_as_list), Field(min_length=2, max_length=2)]


class BodyConfig(ConfigModel):
    """One body: a structured block (``corners`` quadrilateral, ``annulus`` or a ``profile``d rectangle)."""

    corners: Annotated[list[Vector("m")], Field(min_length=4, max_length=4)] | None = None
    annulus: AnnulusConfig | None = None
    profile: ProfileConfig | None = None
    grading: GradingConfig | None = None
    divisions: _Divisions
    material: either(Name, MaterialConfig)
    thickness: Quantity("m", positive=True, bare_is_si=True)
    clamp: Annotated[list[Name], BeforeValidator(_as_list), none_as(list),
                     WithJsonSchema({"anyOf": [{"type": "string"}, {"type": "array", "items": {"type": "string"}}]})
                     ] = []
    initial_velocity: Vector("m s-1") = [0.0, 0.0]

    @model_validator(mode="after")
    def _shape(self):
        if (self.annulus is None) == (self.corners is None):
            raise fail("give exactly one of 'corners' (a quadrilateral) or 'annulus' (a ring or arc)")
        if self.annulus is not None:
            if self.profile is not None:
                raise fail("a profile edge is available on 'corners' bodies only", at=("profile",))
            nx = self.divisions[0]
            a0, a1 = self.annulus.angle_range
            if self.annulus.periodic and nx < 3:
                raise fail(f"a full ring needs at least 3 divisions around, found {nx}", at=("annulus",))
            if not self.annulus.periodic and (a1 - a0) / nx > np.pi / 2:
                raise fail(f"{nx} divisions over {np.degrees(a1 - a0):.6g} deg: an element may span at most 90 deg",
                           at=("annulus",))
        else:
            _check_corners(np.array(self.corners, dtype=float))
            c = np.array(self.corners, dtype=float)
            if self.profile is not None and not (c[0, 1] == c[1, 1] and c[2, 1] == c[3, 1] and c[0, 0] == c[3, 0]
                                                 and c[1, 0] == c[2, 0]):
                raise fail(f"a profiled body needs axis-aligned rectangular corners, found {c.tolist()}",
                           at=("profile",))
        if self.grading is not None:
            edges = EDGES + (tuple(ANNULUS_EDGES) if self.annulus is not None else ())
            if self.grading.edge is None and self.profile is None:
                raise fail("missing 'edge': the edge the mesh is refined toward "
                           f"({', '.join(edges)}; a profile block defaults to its profiled edge)", at=("grading",))
            if self.grading.edge is not None and self.grading.edge not in edges:
                raise fail(f"expected one of {', '.join(edges)}, found {self.grading.edge!r}", at=("grading", "edge"))
            if self.annulus is not None and self.graded_edge in ("left", "right"):
                raise fail("an annulus grades radially only: edge inner or outer", at=("grading", "edge"))
        return self

    @property
    def shape(self) -> str:
        """``"annulus"``, ``"profile"`` or ``"quad"`` (:data:`fivid.fe.model.SHAPES`)."""
        return "annulus" if self.annulus is not None else "profile" if self.profile is not None else "quad"

    @property
    def graded_edge(self) -> str | None:
        """The edge the divisions are refined toward (its :data:`~fivid.fe.model.EDGES` name), or None."""
        if self.grading is None:
            return None
        edge = self.grading.edge if self.grading.edge is not None else self.profile.edge
        return ANNULUS_EDGES.get(edge, edge)


def _check_corners(corners: np.ndarray) -> None:
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
            raise fail(f"corners {corners.tolist()} are {why} at corner {k}; give 4 corners of a convex "
                       "quadrilateral counter-clockwise from bottom-left", at=("corners",))


# ---------------------------------------------------------------------------------------------- items


class EdgeRefConfig(ConfigModel):
    """``{body, edge, x: [lo, hi] | y: [lo, hi]}``: (part of) a body's edge; ``x``/``y`` keep the nodes in range [m]."""

    body: Name
    edge: Name
    x: Vector("m") | None = None
    y: Vector("m") | None = None


class PointRefConfig(ConfigModel):
    """``{body, at: [x, y]}``: the node of a body nearest the point [m]."""

    body: Name
    at: Vector("m")


class MotionConfig(EdgeRefConfig):
    """An imposed velocity or displacement of an edge's nodes in one component, ramped smoothly."""

    name: ItemName
    component: _Component
    kind: Literal["velocity", "displacement"]
    amplitude: QuantityText
    ramp_time: Quantity("s", nonnegative=True, bare_is_si=True) = 0.0
    role: Literal["base", "load"] | None = None

    @model_validator(mode="after")
    def _amplitude_units(self):
        _quantity_error(self.amplitude, self.amplitude_units, ("amplitude",))
        return self

    @property
    def amplitude_units(self) -> str:
        """``m s-1`` (velocity) or ``m`` (displacement)."""
        return "m s-1" if self.kind == "velocity" else "m"

    @property
    def amplitude_si(self) -> float:
        """The amplitude in :attr:`amplitude_units`."""
        return quantity_parser(self.amplitude_units, bare=self.amplitude_units)(self.amplitude)


class PointMassConfig(PointRefConfig):
    """A point mass [kg] at a node."""

    name: ItemName
    mass: Quantity("kg", positive=True, bare_is_si=True)


class SpringConfig(ConfigModel):
    """A spring (and dashpot) in one component between two nodes, or a node and the ground."""

    name: ItemName
    a: PointRefConfig
    b: either(Literal["ground"], PointRefConfig)
    component: _Component
    stiffness: Quantity("N m-1", nonnegative=True, bare_is_si=True)
    damping: Quantity("N s m-1", nonnegative=True, bare_is_si=True) = 0.0


_DIRECTIONS = {"x": (1.0, 0.0), "+x": (1.0, 0.0), "-x": (-1.0, 0.0), "y": (0.0, 1.0), "+y": (0.0, 1.0),
               "-y": (0.0, -1.0)}


class SensorConfig(PointRefConfig):
    """An accelerometer at a node, along ``direction`` (``x``, ``-y`` ... or a vector)."""

    name: ItemName
    direction: either(Literal["x", "y", "+x", "+y", "-x", "-y"], Vector("dimensionless"))
    quantity: Literal["acceleration"] = "acceleration"

    @model_validator(mode="after")
    def _nonzero(self):
        if not isinstance(self.direction, str) and float(np.hypot(*self.direction)) == 0.0:
            raise fail("the direction is the zero vector", at=("direction",))
        return self

    @property
    def unit_direction(self) -> np.ndarray:
        """The direction as a unit vector [-]."""
        d = np.array(_DIRECTIONS[self.direction] if isinstance(self.direction, str) else self.direction, dtype=float)
        return d / float(np.hypot(*d))


class ReactionConfig(EdgeRefConfig):
    """The reaction force at a constrained edge, split into its ``tangential`` and ``normal`` components."""

    name: ItemName
    tangential: _Component
    normal: _Component

    @model_validator(mode="after")
    def _different(self):
        if self.tangential == self.normal:
            raise fail("tangential and normal must be different components", at=("normal",))
        return self


class LoadConfig(EdgeRefConfig):
    """A uniform pressure [Pa] on an edge, ramped from ``start`` over ``ramp_time`` [s]."""

    name: ItemName
    pressure: Quantity("Pa", bare_is_si=True)
    ramp_time: Quantity("s", nonnegative=True, bare_is_si=True) = 0.0
    start: Quantity("s", nonnegative=True, bare_is_si=True) = 0.0


class ContactConfig(FrictionKeys):
    """A contact pair: a slave edge against a master edge or a rigid surface, with its normal law and friction."""

    name: ItemName
    slave: EdgeRefConfig
    master: EdgeRefConfig | None = None
    rigid: RigidSurfaceConfig | None = None
    normal: NormalLawField | None = None
    normal_stiffness: Quantity("N m-3", positive=True, bare_is_si=True) | None = None

    @model_validator(mode="before")
    @classmethod
    def _law_name(cls, data):
        if isinstance(data, Mapping) and isinstance(data.get("normal"), str):  # normal: linear -> {law: linear}
            data = {**data, "normal": {"law": data["normal"]}}
        return data

    @model_validator(mode="after")
    def _one_master(self):
        if (self.master is None) == (self.rigid is None):
            raise fail("give either 'master' (an edge of another body) or 'rigid' (a rigid line or circle)")
        return self


def _items(model):
    return Annotated[list[model], none_as(list)]


class ModelConfig(ConfigModel):
    """A finite-element model config (``configs/models/*.yaml``, ``docs/model-config.md``): every section typed."""

    name: Name = ""
    description: str = ""
    plane: Literal["stress", "strain"] = "stress"
    materials: Annotated[dict[str, MaterialConfig], none_as(dict)] = {}
    bodies: Annotated[dict[str, BodyConfig], Field(min_length=1)]
    damping: DampingConfig | None = None
    contacts: _items(ContactConfig) = []
    motions: _items(MotionConfig) = []
    point_masses: _items(PointMassConfig) = []
    springs: _items(SpringConfig) = []
    sensors: _items(SensorConfig) = []
    reactions: _items(ReactionConfig) = []
    loads: _items(LoadConfig) = []
    prestress: bool = False

    @model_validator(mode="after")
    def _references(self):
        for name, body in self.bodies.items():
            if isinstance(body.material, str) and body.material not in self.materials:
                raise fail(f"material {body.material!r} is not defined under 'materials' (defined: "
                           f"{', '.join(self.materials) or 'none'})", at=("bodies", name, "material"))
        for section in ("motions", "point_masses", "springs", "contacts", "sensors", "reactions", "loads"):
            names = [x.name for x in getattr(self, section)]
            dup = {n for n in names if names.count(n) > 1}
            if dup:
                raise fail(f"duplicate name(s) {sorted(dup)}; names must be unique within '{section}'", at=(section,))
        roles = [m.role for m in self.motions if m.role is not None]
        for i, m in enumerate(self.motions):
            if m.role is not None and roles.count(m.role) > 1 and m is not next(x for x in self.motions
                                                                               if x.role == m.role):
                raise fail(f"a second motion with role {m.role!r}; only one is allowed", at=("motions", i, "role"))
        return self
