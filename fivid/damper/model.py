"""Friction-damper model from a YAML config: a cantilever beam with a Jenkins contact at a node.

Config layout (quantities with units, parsed by pint)::

    name: seed004-model1
    beam: {length: 0.5 m, width: 0.04 m, thickness: 0.008 m, youngs_modulus: 210 GPa,
           density: 7850 kg/m^3, tip_mass: 0.07 kg, n_elements: 20, modal_damping_ratio: 0.005}
    contact: {position: 0.5 m, friction_coefficient: 0.45, stiffness: 3.9e5 N/m}
    excitation: {position: 0.25 m, amplitude: 2 N}
    measurement: {position: 0.35 m}
    frequency_range: [15 Hz, 130 Hz]
    harmonic_balance: {harmonics: [1, 3, 5, 7], samples_per_period: 128}
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from fivid.damper.modal import ModalModel, modal_model_from_matrices
from fivid.errors import ConfigError, FividError
from fivid.fe.beam import cantilever_beam
from fivid.units import parse_quantity

__all__ = ["DamperModel", "load_damper_model", "damper_model_from_dict"]


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
        Tangential contact stiffness ``k_d`` [N/m].
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

    def slip_force(self, normal_force: float) -> float:
        """``mu F_n`` [N] for a normal force [N]."""
        return self.friction_coefficient * float(normal_force)

    def with_parameters(self, friction_coefficient: float | None = None, contact_stiffness: float | None = None):
        """A copy with other contact parameters (for model updating)."""
        kw = {}
        if friction_coefficient is not None:
            kw["friction_coefficient"] = float(friction_coefficient)
        if contact_stiffness is not None:
            kw["contact_stiffness"] = float(contact_stiffness)
        return replace(self, **kw)


# Keys a damper model config may have (a typo of an optional key would otherwise fall back to its default).
_ALLOWED_KEYS = {
    "": {"name", "description", "beam", "contact", "excitation", "measurement", "frequency_range",
         "harmonic_balance"},
    "beam": {"length", "width", "thickness", "youngs_modulus", "density", "tip_mass", "n_elements",
             "modal_damping_ratio", "clamp_rotational_stiffness"},
    "contact": {"position", "friction_coefficient", "stiffness"},
    "excitation": {"position", "amplitude"},
    "measurement": {"position"},
    "harmonic_balance": {"harmonics", "samples_per_period"},
}


def _check_keys(node: dict, name: str) -> None:
    unknown = sorted(str(k) for k in node if k not in _ALLOWED_KEYS[name])
    if unknown:
        key = f"{name}.{unknown[0]}" if name else unknown[0]
        raise ConfigError(f"unknown key; allowed: {', '.join(sorted(_ALLOWED_KEYS[name]))}", key=key)


def _section(cfg: dict, name: str) -> dict:
    sec = cfg.get(name)
    if not isinstance(sec, dict):
        raise ConfigError(f"missing or invalid section {name!r} (a mapping of quantities with units)", key=name)
    _check_keys(sec, name)
    return sec


def _q(sec: dict, path: str, key: str, units: str, default=None) -> float:
    if key not in sec:
        if default is not None:
            return float(default)
        raise ConfigError(f"missing {key!r} (a quantity in units compatible with {units!r})", key=f"{path}.{key}")
    try:
        return parse_quantity(sec[key], units)
    except FividError as exc:
        raise ConfigError(exc.message, key=f"{path}.{key}") from None


def damper_model_from_dict(cfg: dict, *, source: str = "dict") -> DamperModel:
    """Build a :class:`DamperModel` from a parsed config (see the module docstring for the layout)."""
    if not isinstance(cfg, dict):
        raise ConfigError("a damper model config must be a mapping", file=source if source != "dict" else None)
    _check_keys(cfg, "")
    beam = _section(cfg, "beam")
    contact = _section(cfg, "contact")
    excitation = _section(cfg, "excitation")
    measurement = _section(cfg, "measurement")
    length = _q(beam, "beam", "length", "m")
    xc = _q(contact, "contact", "position", "m")
    xe = _q(excitation, "excitation", "position", "m")
    xm = _q(measurement, "measurement", "position", "m")
    for key, x in (("contact.position", xc), ("excitation.position", xe), ("measurement.position", xm)):
        if not (0.0 < x <= length):
            raise ConfigError(f"position {x} m is not on the beam (0, {length}] m", key=key)
    clamp = beam.get("clamp_rotational_stiffness", "inf")
    k_rot = np.inf if str(clamp).strip().lower() == "inf" else _q(beam, "beam", "clamp_rotational_stiffness", "N m")
    n_el = beam.get("n_elements", 20)
    if not isinstance(n_el, int) or n_el < 2:
        raise ConfigError(f"n_elements must be an integer >= 2, got {n_el!r}", key="beam.n_elements")
    props = dict(
        length=length,
        width=_q(beam, "beam", "width", "m"),
        thickness=_q(beam, "beam", "thickness", "m"),
        youngs_modulus=_q(beam, "beam", "youngs_modulus", "Pa"),
        density=_q(beam, "beam", "density", "kg m-3"),
    )
    tip_mass = _q(beam, "beam", "tip_mass", "kg", default=0.0)
    fe = cantilever_beam(**props, n_elements=n_el, points=(xc, xe, xm), tip_mass=tip_mass,
                         clamp_rotational_stiffness=k_rot)
    zeta = _q(beam, "beam", "modal_damping_ratio", "1", default=0.005)
    modal = modal_model_from_matrices(fe.mass, fe.stiffness, fe.transverse_dof(xc), fe.transverse_dof(xe),
                                      fe.transverse_dof(xm), zeta)
    mu = _q(contact, "contact", "friction_coefficient", "1")
    kd = _q(contact, "contact", "stiffness", "N m-1")
    if not mu > 0:
        raise ConfigError(f"friction coefficient must be > 0, got {mu}", key="contact.friction_coefficient")
    if not kd > 0:
        raise ConfigError(f"contact stiffness must be > 0 N/m, got {kd}", key="contact.stiffness")
    fr = cfg.get("frequency_range", ["15 Hz", "130 Hz"])
    if not (isinstance(fr, list) and len(fr) == 2):
        raise ConfigError(f"frequency_range must be [low, high] with units, got {fr!r}", key="frequency_range")
    f_lo, f_hi = (_q({"f": v}, "frequency_range", "f", "Hz") for v in fr)
    if not 0 < f_lo < f_hi:
        raise ConfigError(f"frequency_range must have 0 < low < high, got {fr!r}", key="frequency_range")
    hb = cfg.get("harmonic_balance", {}) or {}
    if not isinstance(hb, dict):
        raise ConfigError(f"harmonic_balance must be a mapping, got {hb!r}", key="harmonic_balance")
    _check_keys(hb, "harmonic_balance")
    harmonics = tuple(hb.get("harmonics", (1, 3, 5, 7)))
    if not harmonics or any((not isinstance(h, int)) or h < 1 or h % 2 == 0 for h in harmonics):
        raise ConfigError(f"harmonics must be odd integers >= 1, got {list(harmonics)!r}", key="harmonic_balance.harmonics")
    nt = hb.get("samples_per_period", 128)
    if not isinstance(nt, int) or nt < 4 * max(harmonics):
        raise ConfigError(f"samples_per_period must be an integer >= 4 x the highest harmonic ({4 * max(harmonics)}), "
                          f"got {nt!r}", key="harmonic_balance.samples_per_period")
    return DamperModel(
        name=str(cfg.get("name", "damper")),
        modal=modal,
        friction_coefficient=mu,
        contact_stiffness=kd,
        excitation_amplitude=_q(excitation, "excitation", "amplitude", "N"),
        frequency_range=(f_lo, f_hi),
        harmonics=harmonics,
        samples_per_period=nt,
        source=source,
        beam=dict(props, tip_mass=tip_mass, n_elements=n_el),
    )


def load_damper_model(path) -> DamperModel:
    """Read a damper model YAML file (see the module docstring)."""
    import yaml

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"cannot read the model file: {exc.strerror}", file=path) from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"not UTF-8 text (byte 0x{exc.object[exc.start]:02x} at offset {exc.start})",
                          file=path) from None
    try:
        cfg = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise ConfigError(f"not valid YAML: {getattr(exc, 'problem', exc)}", file=path,
                          line=None if mark is None else mark.line + 1) from None
    try:
        return damper_model_from_dict(cfg, source=str(path))
    except FividError as exc:
        raise exc.located(file=str(path)) from None
