"""The contact sections of a model file, typed, and the laws built from them.

A ``contacts`` item of a model config (``docs/model-config.md``) names its normal law (``normal:``), its
friction curve (``mu``, ``mu_static``, ``stribeck_velocity``, ``viscous``: :class:`fivid.friction.FrictionCurve`)
and, instead of a master edge, a rigid master surface (``rigid:``). The models here are the schema of those keys
(part of the model file's one pydantic schema, :class:`fivid.fe.config.ModelConfig`); :func:`normal_law`,
:func:`rigid_surface` and :meth:`FrictionKeys.friction_curve` turn a validated section into the law objects.

Units: SI after validation (quantities may carry units, a bare number is SI).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import model_validator
from pydantic_core import PydanticCustomError

from fivid.config_layer import ConfigModel, Quantity, QuantityText, Vector, either, fail, quantity_parser
from fivid.contact.laws import GreenwoodWilliamson, NormalLaw, RigidSurface, composite_modulus
from fivid.friction.curve import FrictionCurve

__all__ = ["NormalLawConfig", "RigidLineConfig", "RigidCircleConfig", "RigidExpansionConfig", "RigidSurfaceConfig", "FrictionKeys",
           "NormalLawField", "NORMAL_LAWS", "normal_law", "rigid_surface"]

#: normal law name -> the keys it needs
NORMAL_LAWS = {"rigid": (), "linear": ("stiffness",), "power": ("coefficient", "exponent"),
               "greenwood-williamson": ("sigma", "asperity_radius", "asperity_density")}
_GW_OPTIONAL = ("e_star", "pressure_range", "max_pressure", "fit")
_DEFAULT_PRESSURE_RANGE = (1e3, 1e6)  # [Pa] of 'fit: power'
_DEFAULT_MAX_PRESSURE = 1e8  # [Pa] of the tabulated law


class NormalLawConfig(ConfigModel):
    """``normal: {law, ...}``: rigid, linear ``p = k d``, power ``p = c d**n`` or Greenwood-Williamson."""

    law: Literal["rigid", "linear", "power", "greenwood-williamson"]
    stiffness: Quantity("N m-3", positive=True, bare_is_si=True) | None = None
    coefficient: QuantityText | None = None
    exponent: Quantity("dimensionless", positive=True, bare_is_si=True) | None = None
    sigma: Quantity("m", positive=True, bare_is_si=True) | None = None
    asperity_radius: Quantity("m", positive=True, bare_is_si=True) | None = None
    asperity_density: Quantity("m-2", positive=True, bare_is_si=True) | None = None
    e_star: Quantity("Pa", positive=True, bare_is_si=True) | None = None
    pressure_range: Vector("Pa", positive=True) | None = None
    max_pressure: Quantity("Pa", positive=True, bare_is_si=True) | None = None
    fit: Literal["none", "power"] = "none"

    @model_validator(mode="after")
    def _parameters_of_the_law(self):
        need = NORMAL_LAWS[self.law]
        for k in need:
            if k not in self.model_fields_set:
                raise fail(f"the {self.law} law needs '{k}' (see docs/model-config.md, contacts)", at=(k,))
        optional = _GW_OPTIONAL if self.law == "greenwood-williamson" else ()
        extra = sorted(set(self.model_fields_set) - {"law", *need, *optional})
        if extra:
            raise fail(f"not a parameter of the {self.law} law; it takes {', '.join(need) or 'no parameters'}",
                       at=(extra[0],))
        if self.law == "power":  # c [Pa m-n]: its units follow the exponent
            try:
                self.power_coefficient
            except PydanticCustomError as exc:
                raise fail(exc.context["message"], at=("coefficient",)) from None
        if self.fit == "none" and "pressure_range" in self.model_fields_set:
            raise fail("pressure_range is the range of 'fit: power'; the exact (tabulated) law takes max_pressure",
                       at=("pressure_range",))
        if self.fit == "power" and "max_pressure" in self.model_fields_set:
            raise fail("max_pressure bounds the exact (tabulated) law; 'fit: power' takes pressure_range",
                       at=("max_pressure",))
        return self

    @property
    def power_coefficient(self) -> float:
        """The power law's ``c`` [Pa m-n] in SI (its units follow ``exponent``)."""
        units = f"Pa / m**{self.exponent!r}"
        return quantity_parser(units, positive=True, bare=units)(self.coefficient)


class RigidLineConfig(ConfigModel):
    """``line: {point, normal}``: a rigid line through ``point`` [m], ``normal`` pointing to the slave side."""

    point: Vector("m")
    normal: Vector("dimensionless")

    @model_validator(mode="after")
    def _nonzero(self):
        if float(np.hypot(*self.normal)) == 0.0:
            raise fail("the normal is the zero vector", at=("normal",))
        return self

    @property
    def unit_normal(self) -> np.ndarray:
        """The normal scaled to length 1 [-]."""
        n = np.array(self.normal, dtype=float)
        return n / float(np.hypot(*n))


class RigidCircleConfig(ConfigModel):
    """``circle: {center, radius, side}``: a rigid circle; the slave body lies ``outside`` or ``inside`` it."""

    center: Vector("m")
    radius: Quantity("m", positive=True, bare_is_si=True)
    side: Literal["outside", "inside"] = "outside"


class RigidExpansionConfig(ConfigModel):
    """``expansion: {mean_pressure | displacement, start, ramp_time}``: a rigid circle's radius grows by a radial
    ``displacement`` [m], or by the one that gives the contact the ``mean_pressure`` [Pa] (solved by the static
    preload, :func:`fivid.fe.static.resolve_expansions`), over a smooth ramp."""

    mean_pressure: Quantity("Pa", positive=True, bare_is_si=True) | None = None
    displacement: Quantity("m", bare_is_si=True) | None = None
    start: Quantity("s", nonnegative=True, bare_is_si=True) = 0.0
    ramp_time: Quantity("s", nonnegative=True, bare_is_si=True) = 0.0

    @model_validator(mode="after")
    def _one_target(self):
        if (self.mean_pressure is None) == (self.displacement is None):
            raise fail("give either 'mean_pressure' (fivid solves the radial displacement that gives it, e.g. "
                       "40 MPa) or 'displacement' (the radial displacement itself, e.g. 20 um)")
        return self


class RigidSurfaceConfig(ConfigModel):
    """``rigid: {line | circle, velocity | speed, start, ramp_time, expansion}``: a rigid master surface."""

    line: RigidLineConfig | None = None
    circle: RigidCircleConfig | None = None
    expansion: RigidExpansionConfig | None = None
    velocity: Vector("m s-1") | None = None
    speed: Quantity("rad s-1", bare_is_si=True) | None = None
    start: Quantity("s", nonnegative=True, bare_is_si=True) = 0.0
    ramp_time: Quantity("s", nonnegative=True, bare_is_si=True) = 0.0

    @model_validator(mode="after")
    def _one_surface(self):
        if (self.line is None) == (self.circle is None):
            raise fail("give either 'line: {point, normal}' or 'circle: {center, radius, side}'")
        if self.line is not None:
            if self.expansion is not None:
                raise fail("only a rigid circle expands (its radius grows); a rigid line cannot move along its "
                           "normal", at=("expansion",))
            if self.speed is not None:
                raise fail("a rigid line moves with 'velocity: [vx, vy]' (along itself); 'speed' is a circle's "
                           "rotation (e.g. 10 rpm)", at=("speed",))
            vel = np.array(self.velocity or (0.0, 0.0))
            normal = self.line.unit_normal
            if abs(vel @ normal) > 1e-9 * max(float(np.hypot(*vel)), 1e-300):
                raise fail(f"a rigid line can only slide along itself: velocity {vel.tolist()} m/s has a component "
                           f"along its normal {normal.tolist()}", at=("velocity",))
        elif self.velocity is not None:
            raise fail("a rigid circle turns with 'speed' (e.g. 10 rpm or 1.05 rad/s, counter-clockwise positive)",
                       at=("velocity",))
        return self


class FrictionKeys(ConfigModel):
    """The friction keys of a contact: kinetic ``mu``, static ``mu_static`` (default ``mu``), the Stribeck
    velocity [m s-1] of the decay from ``mu_static`` to ``mu`` and the viscous coefficient [s m-1]."""

    mu: Quantity("dimensionless", nonnegative=True, bare_is_si=True)
    mu_static: Quantity("dimensionless", nonnegative=True, bare_is_si=True) | None = None
    stribeck_velocity: Quantity("m s-1", nonnegative=True, bare_is_si=True) = 0.0
    viscous: Quantity("s m-1", nonnegative=True, bare_is_si=True) = 0.0

    @model_validator(mode="after")
    def _curve(self):
        mu_s = self.mu if self.mu_static is None else self.mu_static
        if mu_s < self.mu:
            raise fail(f"the static coefficient ({mu_s:g}) must be >= the kinetic mu ({self.mu:g})", at=("mu_static",))
        if self.stribeck_velocity > 0 and mu_s == self.mu:
            raise fail("a Stribeck curve needs mu_static > mu (it decays from mu_static to mu)",
                       at=("stribeck_velocity",))
        return self

    def friction_curve(self) -> FrictionCurve:
        """The curve over the kinetic ``mu``: static excess, Stribeck velocity and viscous term."""
        mu_s = self.mu if self.mu_static is None else self.mu_static
        return FrictionCurve(mu_static_excess=mu_s - self.mu, stribeck_velocity=self.stribeck_velocity,
                             viscous=self.viscous)


#: ``normal:`` as a law name (``normal: rigid``) or a mapping ``{law, ...}``
NormalLawField = either(Literal["rigid", "linear", "power", "greenwood-williamson"], NormalLawConfig)


def normal_law(spec: NormalLawConfig | str | None, materials=()) -> NormalLaw:
    """The :class:`~fivid.contact.laws.NormalLaw` of a validated ``normal:`` section.

    Parameters
    ----------
    spec : NormalLawConfig, str or None
        The section (None: rigid; a law name: that law without parameters, i.e. ``"rigid"``).
    materials : sequence of fivid.fe.Material
        The two bodies' materials (one against a rigid surface): Greenwood-Williamson's composite modulus
        ``E*`` when ``e_star`` is not given.

    Raises
    ------
    fivid.errors.ConfigError
        The Greenwood-Williamson law cannot be tabulated or fitted over the range given (no key: the caller
        names it).
    """
    if spec is None or spec == "rigid":
        return NormalLaw()
    if spec.law == "rigid":
        return NormalLaw()
    if spec.law == "linear":
        return NormalLaw("linear", spec.stiffness)
    if spec.law == "power":
        return NormalLaw("power", spec.power_coefficient, spec.exponent, "given")
    gw = GreenwoodWilliamson(sigma=spec.sigma, radius=spec.asperity_radius, density=spec.asperity_density,
                             e_star=spec.e_star if spec.e_star is not None else composite_modulus(*materials))
    if spec.fit == "none":
        return gw.table_law(spec.max_pressure if spec.max_pressure is not None else _DEFAULT_MAX_PRESSURE)
    return gw.power_fit(tuple(spec.pressure_range) if spec.pressure_range is not None else _DEFAULT_PRESSURE_RANGE)


def rigid_surface(spec: RigidSurfaceConfig) -> RigidSurface:
    """The :class:`~fivid.contact.laws.RigidSurface` of a validated ``rigid:`` section."""
    if spec.line is not None:
        return RigidSurface("line", np.array(spec.line.point), normal=spec.line.unit_normal,
                            velocity=np.array(spec.velocity or (0.0, 0.0)), start=spec.start,
                            ramp_time=spec.ramp_time)
    grow = {}
    if spec.expansion is not None:
        e = spec.expansion
        grow = dict(expansion=math.nan if e.displacement is None else e.displacement, expansion_start=e.start,
                    expansion_ramp_time=e.ramp_time,
                    target_mean_pressure=math.nan if e.mean_pressure is None else e.mean_pressure)
    return RigidSurface("circle", np.array(spec.circle.center), radius=spec.circle.radius, side=spec.circle.side,
                        angular_velocity=spec.speed or 0.0, start=spec.start, ramp_time=spec.ramp_time, **grow)
