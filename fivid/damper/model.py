"""Friction-damper model from a YAML config: a cantilever beam with a Jenkins contact at a node.

Config layout (quantities with units, parsed by pint)::

    name: seed004-model1
    beam: {length: 0.5 m, width: 0.04 m, thickness: 0.008 m, youngs_modulus: 210 GPa,
           density: 7850 kg/m^3, tip_mass: 0.07 kg, n_elements: 20, modal_damping_ratio: 0.005}
    contact: {position: 0.5 m, friction_coefficient: 0.45, stiffness: 3.9e5 N/m, device_stiffness: 2.5e5 N/m}
    excitation: {position: 0.25 m, amplitude: 2 N}
    measurement: {position: 0.35 m}
    frequency_range: [15 Hz, 130 Hz]
    harmonic_balance: {harmonics: [1, 3, 5, 7], samples_per_period: 128}
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Annotated

from pydantic import BeforeValidator, Field, WithJsonSchema, model_validator

from fivid.builtin import find_builtin
from fivid.config_layer import (ConfigModel, Name, Quantity, fail, from_mapping, quantity_parser, quantity_schema,
                                read_yaml, validate)
from fivid.damper.modal import ModalModel, modal_model_from_matrices
from fivid.errors import ConfigError
from fivid.fe.beam import cantilever_beam

__all__ = ["DamperModel", "DamperConfig", "load_damper_model", "damper_model_from_dict"]


@dataclass(frozen=True)
class DamperModel:
    """A linear structure (modal) with one Jenkins contact, a harmonic force and a sensor.

    Attributes
    ----------
    name : str
    modal : ModalModel
        Modes at the contact, excitation and measurement dofs.
    friction_coefficient : float
        ``mu`` [1]; slip force ``F_s = mu F_n``.
    contact_stiffness : float
        Tangential contact stiffness ``k_d`` [N/m] (the Jenkins spring of the interface).
    device_stiffness : float
        Tangential stiffness of the rubbing device (its post and force sensor) in series with the contact
        [N/m]; ``inf`` for a rigid device. A massless spring in series with a Jenkins element is a Jenkins
        element of stiffness :attr:`series_stiffness` and the same slip force.
    excitation_amplitude : float
        Amplitude of the harmonic force [N].
    frequency_range : tuple of float
        Sweep range [Hz].
    harmonics : tuple of int
        Harmonics kept in the harmonic balance (odd: the Jenkins loop is half-wave symmetric).
    samples_per_period : int
        Time samples per period in the alternating frequency-time evaluation.
    source : str
        Where the model came from (file path or ``"dict"``).
    """

    name: str
    modal: ModalModel
    friction_coefficient: float
    contact_stiffness: float
    excitation_amplitude: float
    frequency_range: tuple = (15.0, 130.0)
    harmonics: tuple = (1, 3, 5, 7)
    samples_per_period: int = 128
    source: str = "dict"
    beam: dict = field(default_factory=dict, compare=False)
    device_stiffness: float = math.inf

    @property
    def series_stiffness(self) -> float:
        """Stiffness the beam feels while the contact sticks [N/m]: ``k_d k_s / (k_d + k_s)`` (``k_d`` when
        the device is rigid)."""
        if not math.isfinite(self.device_stiffness):
            return self.contact_stiffness
        return self.contact_stiffness * self.device_stiffness / (self.contact_stiffness + self.device_stiffness)

    def slip_force(self, normal_force: float) -> float:
        """``mu F_n`` [N] for a normal force [N]."""
        return self.friction_coefficient * float(normal_force)

    def with_parameters(self, friction_coefficient: float | None = None, contact_stiffness: float | None = None,
                        device_stiffness: float | None = None):
        """A copy with other contact parameters (for model updating)."""
        kw = {}
        if device_stiffness is not None:
            kw["device_stiffness"] = float(device_stiffness)
        if friction_coefficient is not None:
            kw["friction_coefficient"] = float(friction_coefficient)
        if contact_stiffness is not None:
            kw["contact_stiffness"] = float(contact_stiffness)
        return replace(self, **kw)


def _stiffness_or_inf(units: str):
    """A parser of ``inf`` (rigid) or a stiffness quantity in ``units``."""
    parse = quantity_parser(units, positive=True)

    def parser(value):
        if str(value).strip().lower() == "inf":
            return math.inf
        return parse(value)

    return parser


class _Beam(ConfigModel):
    length: Quantity("m", positive=True)
    width: Quantity("m", positive=True)
    thickness: Quantity("m", positive=True)
    youngs_modulus: Quantity("Pa", positive=True)
    density: Quantity("kg m-3", positive=True)
    tip_mass: Quantity("kg", nonnegative=True) = 0.0
    n_elements: Annotated[int, Field(ge=2)] = 20
    modal_damping_ratio: Quantity("1", nonnegative=True) = 0.005
    clamp_rotational_stiffness: Annotated[float, BeforeValidator(_stiffness_or_inf("N m")),
                                          WithJsonSchema(quantity_schema("N m", positive=True, also=("inf",)))
                                          ] = math.inf


class _Contact(ConfigModel):
    position: Quantity("m")
    friction_coefficient: Quantity("1", positive=True)
    stiffness: Quantity("N m-1", positive=True)
    device_stiffness: Annotated[float, BeforeValidator(_stiffness_or_inf("N m-1")),
                                WithJsonSchema(quantity_schema("N m-1", positive=True, also=("inf",)))] = math.inf


class _Excitation(ConfigModel):
    position: Quantity("m")
    amplitude: Quantity("N")


class _Measurement(ConfigModel):
    position: Quantity("m")


class _HarmonicBalance(ConfigModel):
    harmonics: Annotated[list[Annotated[int, Field(ge=1)]], Field(min_length=1)] = [1, 3, 5, 7]
    samples_per_period: int = 128

    @model_validator(mode="after")
    def _odd_and_sampled(self):
        if any(h % 2 == 0 for h in self.harmonics):
            raise fail(f"expected odd harmonics (the Jenkins loop is half-wave symmetric), found {self.harmonics!r}",
                       at=("harmonics",))
        if self.samples_per_period < 4 * max(self.harmonics):
            raise fail(f"expected samples_per_period >= 4 x the highest harmonic ({4 * max(self.harmonics)}), "
                       f"found {self.samples_per_period!r}", at=("samples_per_period",))
        return self


class DamperConfig(ConfigModel):
    """A damper model config (``configs/dampers/*.yaml``); quantities in SI after validation."""

    name: Name = "damper"
    description: str = ""
    beam: _Beam
    contact: _Contact
    excitation: _Excitation
    measurement: _Measurement
    frequency_range: Annotated[list[Quantity("Hz", positive=True)], Field(min_length=2, max_length=2)] = [15.0, 130.0]
    harmonic_balance: _HarmonicBalance = _HarmonicBalance()

    @model_validator(mode="after")
    def _positions_and_range(self):
        for section in ("contact", "excitation", "measurement"):
            x = getattr(self, section).position
            if not 0.0 < x <= self.beam.length:
                raise fail(f"expected a position in (0, {self.beam.length:g}] m, found {x:g} m: not on the beam",
                           at=(section, "position"))
        lo, hi = self.frequency_range
        if not lo < hi:
            raise fail(f"expected [low, high] with low < high, found {[lo, hi]!r} Hz", at=("frequency_range",))
        return self


def damper_model_from_dict(cfg: dict, *, source: str = "dict") -> DamperModel:
    """Build a :class:`DamperModel` from a parsed config (see the module docstring for the layout)."""
    if not isinstance(cfg, dict):
        raise ConfigError("a damper model config must be a mapping", file=source if source != "dict" else None)
    return _build(validate(DamperConfig, from_mapping(cfg)), source)


def _build(c: DamperConfig, source: str) -> DamperModel:
    b = c.beam
    xc, xe, xm = c.contact.position, c.excitation.position, c.measurement.position
    props = dict(length=b.length, width=b.width, thickness=b.thickness, youngs_modulus=b.youngs_modulus,
                 density=b.density)
    fe = cantilever_beam(**props, n_elements=b.n_elements, points=(xc, xe, xm), tip_mass=b.tip_mass,
                         clamp_rotational_stiffness=b.clamp_rotational_stiffness)
    modal = modal_model_from_matrices(fe.mass, fe.stiffness, fe.transverse_dof(xc), fe.transverse_dof(xe),
                                      fe.transverse_dof(xm), b.modal_damping_ratio)
    return DamperModel(
        name=c.name,
        modal=modal,
        friction_coefficient=c.contact.friction_coefficient,
        contact_stiffness=c.contact.stiffness,
        excitation_amplitude=c.excitation.amplitude,
        frequency_range=tuple(c.frequency_range),
        harmonics=tuple(c.harmonic_balance.harmonics),
        samples_per_period=c.harmonic_balance.samples_per_period,
        source=source,
        device_stiffness=c.contact.device_stiffness,
        beam=dict(props, tip_mass=b.tip_mass, n_elements=b.n_elements),
    )


def load_damper_model(path) -> DamperModel:
    """Read a damper model YAML file (see the module docstring), or a built-in one by name (``seed004_model1``)."""
    text = str(path)
    if not Path(path).exists() and not any(c in text for c in "/\\"):
        path = find_builtin("dampers", text) or path
    path = Path(path)
    source = read_yaml(path, "damper model")
    return _build(validate(DamperConfig, source), str(path))
