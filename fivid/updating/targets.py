"""The targets file of ``fivid update``: which parameters to update, within which bounds, against which modes.

Layout (quantities with units; relative file names are relative to the targets file)::

    parameters:                         # dotted paths into the model config, bounds with units
      - {path: materials.steel.E, bounds: [150 GPa, 250 GPa]}
      - {path: springs[0].stiffness, bounds: [1e4 N/m, 1e8 N/m]}
    modes:                              # target modes: frequency and its tolerance (absolute or %)
      - {frequency: 1503 Hz, tolerance: 0.5 %}
      - {frequency: 2410 Hz, tolerance: 5 Hz, shape: {file: MODES.nc, mode: 2, sensors: [acc_a, acc_b]}}
      - {frequency: 86 Hz, tolerance: 1 Hz, normal_load: 40 N}     # damper models: FRF peak at that load
      - {frequency: 10.5 kHz, tolerance: 2 %, mode: 6, interface: rigid}   # with the contact's springs rigid
    count_below: [{frequency: 5 kHz, count: 6}]    # optional: how many modes lie below a frequency
    critical_mu:         # optional (FE models with a contact): CEA critical friction coefficient of a mode pair
      - {value: 0.15, tolerance: 0.02, mode: 6, mu: [0, 1, 21]}
    prestress: false     # optional: modes and CEA about the prestressed state (as 'fivid modes --prestress')
    load: 5 N            # optional: preloaded contact, as 'fivid modes --load'
    contact: false       # optional: couple the bodies at the contact (with load, or the model's pressure loads)
    n_modes: 12          # optional: modes computed (default: 2 x the targets, at least 10)
    mass: consistent     # optional: consistent or lumped

``interface: rigid`` (FE models with ``contact``): the target is the mode's frequency with the contact's normal
springs made rigid (:func:`fivid.fe.modal.modal_analysis` with ``interface_scale`` ``RIGID_INTERFACE_SCALE``: the
frequency's deficit from the rigid limit falls as 1 / scale), beside the others' at the model's own interface
stiffness: a frequency measured or computed with a rigid counterpart (seed 002's transient, whose inner disc is
rigid, against its CEA's deformable one) is what identifies the interface stiffness.

Pairing: a mode with ``shape`` is paired with the model mode of highest MAC between its measured shape
(``mode`` of the MODES.nc written by ``fivid ema``, its measured DOFs in file order) and the model's shape at
the model sensors listed (same order); a mode without is paired by order (the k-th such target with the
k-th elastic model mode, or ``mode: N`` to name the model mode).

A ``critical_mu`` target is the friction coefficient at which the pair containing CEA mode ``mode`` (numbered by
frequency at the first ``mu``, as ``fivid cea`` numbers them) turns unstable: the smaller of the two modes'
critical μ (:func:`fivid.fe.cea.complex_eigenvalue_analysis` over ``mu`` = [start, stop, steps], refined by root
finding), with the model's contact preload (``load`` or its pressure loads).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fivid.config_layer import ConfigSource, read_yaml
from fivid.ema.modes_file import read_modes
from fivid.errors import FividError, UnitError
from fivid.units import parse_quantity

__all__ = ["ParameterSpec", "ModeTarget", "CountTarget", "CriticalMuTarget", "Targets", "load_targets"]

_TOP = ("parameters", "modes", "count_below", "critical_mu", "prestress", "load", "contact", "n_modes", "mass")
_CRIT = ("value", "tolerance", "mode", "mu", "name")
_PARAM = ("path", "bounds")
_MODE = ("frequency", "tolerance", "shape", "mode", "normal_load", "name", "interface")
_INTERFACES = ("model", "rigid")
_SHAPE = ("file", "mode", "sensors")
_PERCENT = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*%\s*")
_VALUE = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*")


@dataclass(frozen=True)
class ParameterSpec:
    """One parameter to update, as written in the targets file.

    Attributes
    ----------
    path : str
        Dotted key path in the model config.
    bounds : (str, str)
        The bounds as written (``"150 GPa"``); converted against the model's value by :mod:`fivid.updating.fit`.
    key : str
        Where it is in the targets file (``parameters[0]``).
    """

    path: str
    bounds: tuple
    key: str


@dataclass(frozen=True)
class ModeTarget:
    """A target mode.

    Attributes
    ----------
    frequency : float
        [Hz].
    tolerance : float
        Absolute tolerance [Hz] (a percentage is converted with the frequency): the residual's scale, read as
        one standard deviation of the target.
    key : str
        ``modes[k]`` in the targets file.
    name : str
    model_mode : int or None
        1-based elastic model mode to pair with (order pairing), if given.
    shape : ndarray of complex or None
        Measured shape at the sensors (MODES.nc), for MAC pairing.
    sensors : tuple of str
        Model sensor names matching ``shape``.
    normal_load : float or None
        [N]; damper models: the target is the FRF peak at this normal load.
    interface : {"model", "rigid"}
        The contact's normal springs as modelled, or rigid (module docstring).
    """

    frequency: float
    tolerance: float
    key: str
    name: str
    model_mode: int | None = None
    shape: np.ndarray | None = None
    sensors: tuple = ()
    normal_load: float | None = None
    interface: str = "model"


@dataclass(frozen=True)
class CountTarget:
    """``count`` modes below ``frequency`` [Hz] (checked on the updated model)."""

    frequency: float
    count: int
    key: str


@dataclass(frozen=True)
class CriticalMuTarget:
    """The critical friction coefficient of the CEA mode pair containing ``mode``.

    Attributes
    ----------
    value, tolerance : float
        Target critical μ and its tolerance (one standard deviation) [1].
    mode : int
        1-based CEA mode (by frequency at the first μ of the sweep).
    mu : ndarray
        The CEA's friction coefficients [1].
    key, name : str
    """

    value: float
    tolerance: float
    mode: int
    mu: np.ndarray
    key: str
    name: str


@dataclass(frozen=True)
class Targets:
    """A parsed targets file (see the module docstring)."""

    parameters: tuple
    modes: tuple
    count_below: tuple = ()
    critical_mu: tuple = ()
    prestress: bool = False
    load: float | None = None
    contact: bool = False
    n_modes: int | None = None
    mass: str = "consistent"
    source: ConfigSource = field(default=None, compare=False)


def _mapping(src: ConfigSource, value, key: str, allowed, required=(), why: str = "") -> dict:
    if not isinstance(value, dict):
        raise src.error(key, f"expected a mapping with keys {', '.join(allowed)}, found {type(value).__name__} "
                             f"{value!r}")
    for k in value:
        if k not in allowed:
            raise src.error(f"{key}.{k}" if key else str(k),
                            f"unknown key {k!r}; allowed here: {', '.join(allowed)}")
    for k in required:
        if k not in value:
            raise src.error(key, f"missing key {k!r}: {why}")
    return value


def _quantity(src: ConfigSource, value, key: str, units: str, *, positive: bool = True) -> float:
    try:
        q = parse_quantity(value, units)
    except UnitError as exc:
        raise src.error(key, f"expected a quantity in {units!r} (e.g. '5 {units}'), found {value!r}: "
                             f"{exc.message}") from None
    if positive and not q > 0:
        raise src.error(key, f"expected a positive quantity in {units!r}, found {value!r}")
    return float(q)


def _tolerance(src: ConfigSource, value, key: str, frequency: float) -> float:
    m = _PERCENT.fullmatch(str(value))
    if m is not None:
        tol = float(m.group(1)) / 100 * frequency
    else:
        tol = _quantity(src, value, key, "Hz")
    if not tol > 0:
        raise src.error(key, f"expected a tolerance > 0 (e.g. '1 Hz' or '0.5 %'), found {value!r}")
    return tol


def _list(src: ConfigSource, value, key: str, *, min_length: int = 0) -> list:
    if not isinstance(value, list) or len(value) < min_length:
        raise src.error(key, f"expected a list of at least {min_length} item(s), found {value!r}")
    return value


def _shape(src: ConfigSource, spec, key: str, base: Path):
    s = _mapping(src, spec, key, _SHAPE, _SHAPE, "a shape target needs file, mode and sensors")
    path = Path(str(s["file"]))
    path = path if path.is_absolute() else base / path
    try:
        modes = read_modes(path)
    except FividError as exc:
        raise src.error(f"{key}.file", exc.message) from None
    n = modes.sizes["mode"]
    mode = s["mode"]
    if not isinstance(mode, int) or not 1 <= mode <= n:
        raise src.error(f"{key}.mode", f"expected a mode number 1..{n} of {path}, found {mode!r}")
    sensors = _list(src, s["sensors"], f"{key}.sensors", min_length=2)
    dofs = modes.sizes["dof"]
    if len(sensors) != dofs:
        raise src.error(f"{key}.sensors", f"{path} has {dofs} measured DOFs; list one model sensor per DOF, in "
                                          f"file order; found {len(sensors)}")
    shape = (modes["shape_real"] + 1j * modes["shape_imag"]).isel(mode=mode - 1).values
    return shape, tuple(str(x) for x in sensors)


def load_targets(path) -> Targets:
    """Read and check a targets file; every problem is a ConfigError naming file, line and key."""
    src = read_yaml(path, "targets file")
    data = _mapping(src, src.data, "", _TOP, ("parameters", "modes"),
                    "a targets file lists the parameters to update and the target modes")
    base = Path(src.file).parent
    params = []
    for i, p in enumerate(_list(src, data["parameters"], "parameters", min_length=1)):
        key = f"parameters[{i}]"
        p = _mapping(src, p, key, _PARAM, _PARAM, "a parameter needs 'path' (dotted key in the model config) and "
                                                  "'bounds' [low, high]")
        b = p["bounds"]
        if not isinstance(b, list) or len(b) != 2:
            raise src.error(f"{key}.bounds", f"expected [low, high] with units, e.g. [150 GPa, 250 GPa], found {b!r}")
        params.append(ParameterSpec(str(p["path"]), (b[0], b[1]), key))
    paths = [p.path for p in params]
    for i, p in enumerate(paths):
        if paths.index(p) != i:
            raise src.error(f"parameters[{i}].path", f"{p!r} is listed twice")
    modes = []
    for i, m in enumerate(_list(src, data["modes"], "modes", min_length=1)):
        key = f"modes[{i}]"
        m = _mapping(src, m, key, _MODE, ("frequency", "tolerance"),
                     "a target mode needs 'frequency' and 'tolerance' (e.g. '1 Hz' or '0.5 %')")
        f = _quantity(src, m["frequency"], f"{key}.frequency", "Hz")
        tol = _tolerance(src, m["tolerance"], f"{key}.tolerance", f)
        model_mode = m.get("mode")
        if model_mode is not None and (not isinstance(model_mode, int) or model_mode < 1):
            raise src.error(f"{key}.mode", f"expected a model mode number >= 1, found {model_mode!r}")
        shape, sensors = (None, ()) if "shape" not in m else _shape(src, m["shape"], f"{key}.shape", base)
        load = None if "normal_load" not in m else _quantity(src, m["normal_load"], f"{key}.normal_load", "N")
        interface = m.get("interface", "model")
        if interface not in _INTERFACES:
            raise src.error(f"{key}.interface", f"expected one of {', '.join(_INTERFACES)}, found {interface!r}")
        modes.append(ModeTarget(f, tol, key, str(m.get("name", key)), model_mode, shape, sensors, load, interface))
    counts = []
    cb = data.get("count_below", [])
    for i, c in enumerate(_list(src, cb if isinstance(cb, list) else [cb], "count_below")):
        key = f"count_below[{i}]" if isinstance(cb, list) else "count_below"
        c = _mapping(src, c, key, ("frequency", "count"), ("frequency", "count"),
                     "count_below needs frequency and count")
        if not isinstance(c.get("count"), int) or c["count"] < 0:
            raise src.error(f"{key}.count", f"expected a number of modes >= 0, found {c.get('count')!r}")
        counts.append(CountTarget(_quantity(src, c.get("frequency"), f"{key}.frequency", "Hz"), c["count"], key))
    crits = [_critical_mu(src, c, f"critical_mu[{i}]")
             for i, c in enumerate(_list(src, data.get("critical_mu", []), "critical_mu"))]
    prestress = data.get("prestress", False)
    if not isinstance(prestress, bool):
        raise src.error("prestress", f"expected true or false, found {prestress!r}")
    load = None if data.get("load") is None else _quantity(src, data["load"], "load", "N")
    contact = data.get("contact", False)
    if not isinstance(contact, bool):
        raise src.error("contact", f"expected true or false, found {contact!r}")
    n_modes = data.get("n_modes")
    if n_modes is not None and (not isinstance(n_modes, int) or n_modes < 1):
        raise src.error("n_modes", f"expected a number of modes >= 1, found {n_modes!r}")
    mass = data.get("mass", "consistent")
    if mass not in ("consistent", "lumped"):
        raise src.error("mass", f"expected 'consistent' or 'lumped', found {mass!r}")
    contact = bool(contact or load is not None or crits)
    rigid = [t for t in modes if t.interface == "rigid"]
    if rigid and not contact:
        raise src.error(f"{rigid[0].key}.interface", "an 'interface: rigid' target makes the contact's springs "
                                                     "rigid: it needs 'contact: true' (or a 'load')")
    return Targets(tuple(params), tuple(modes), tuple(counts), tuple(crits), prestress, load, contact, n_modes,
                   mass, src)


def _critical_mu(src: ConfigSource, spec, key: str) -> CriticalMuTarget:
    c = _mapping(src, spec, key, _CRIT, ("value", "tolerance", "mode", "mu"),
                 "a critical_mu target needs value, tolerance, mode (the CEA mode) and mu [start, stop, steps]")
    vals = {}
    for k in ("value", "tolerance"):
        v = c[k]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0:
            raise src.error(f"{key}.{k}", f"expected a friction coefficient > 0 (a bare number), found {v!r}")
        vals[k] = float(v)
    mode = c["mode"]
    if not isinstance(mode, int) or isinstance(mode, bool) or mode < 1:
        raise src.error(f"{key}.mode", f"expected a CEA mode number >= 1, found {mode!r}")
    mu = c["mu"]
    ok = (isinstance(mu, list) and len(mu) == 3 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                        for x in mu))
    if not ok or not (0 <= mu[0] < mu[1] and isinstance(mu[2], int) and mu[2] >= 2):
        raise src.error(f"{key}.mu", f"expected [start, stop, steps] with 0 <= start < stop and steps >= 2 "
                                     f"(e.g. [0, 1, 21]), found {mu!r}")
    if not mu[0] < vals["value"] < mu[1]:
        raise src.error(f"{key}.value", f"the target {vals['value']:g} lies outside the sweep mu {mu!r}")
    return CriticalMuTarget(vals["value"], vals["tolerance"], mode, np.linspace(mu[0], mu[1], mu[2]), key,
                            str(c.get("name", key)))
