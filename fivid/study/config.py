"""Study configs (``configs/studies/*.yaml``) -> a validated :class:`Study`.

A study is a sweep over conditions whose points are each a small analysis (DESIGN §11)::

    fivid-study: 1
    name: hoffmann_mu_sweep
    description: the 2-DOF mode-coupling model across its flutter threshold
    system:                       # an FE model config, relative to this file ...
      model: ../models/triboair_coarse.yaml
    # ... or a lumped kind's model: {lumped: hoffmann, parameters: {mass: 1 kg, k1: 1e6 N/m, ...}}
    kind: weak_strong             # the study kind (fivid.study.kind registry); default: system.lumped, else the
                                  # first kind that claims the config (docs/studies.md)
    sweep:                        # axes with units; the points are their grid (or `combine: zip`)
      mu: {values: [0.9, 1.1]}
      normal_load: {start: 0.2 N, stop: 50 N, num: 9, spacing: log}
    cea: {mu: {start: 0, stop: 2, num: 41}}            # once for the study (critical mu, coalescing pair)
    points:                       # computed at every point
      modes: {n_modes: 10}        # FE: preloaded modes at the point's normal load
      transient: {duration: 0.3 s, sample_rate: 20 kHz}
      psd: {nperseg: 1024, band: [100 Hz, 5 kHz]}
    quick:                        # overrides for --quick (same keys)
      sweep: {normal_load: {start: 0.2 N, stop: 50 N, num: 3, spacing: log}}

Every problem raises :class:`~fivid.errors.ConfigError` with the file, line and key path.
"""

from __future__ import annotations

import copy
import functools
import hashlib
import json
import re
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Annotated, Any, Literal, Mapping

import numpy as np
from pydantic import BeforeValidator, ConfigDict, Field, model_validator

from fivid.config_layer import (
    ConfigModel,
    Name,
    Quantity,
    fail,
    from_mapping,
    read_yaml,
    unknown_key_message,
    validate,
)
from fivid.errors import ConfigError
from fivid.solver.options import DEFAULT_REDUCED_TOLERANCE, ReducedToleranceField, SolverPathField
from fivid.study.axes import AXES
from fivid.study.kind import guess_kind, registered_kinds, study_kind
from fivid.study.kinds import BUILTIN_KINDS  # noqa: F401  (importing it registers the shipped kinds)

__all__ = ["Study", "StudyConfig", "AXES", "load_study", "STUDY_VERSION"]

STUDY_VERSION = 1


@dataclass(frozen=True)
class Study:
    """A validated study.

    Attributes
    ----------
    name, description : str
    model_path : Path or None
        FE model config (absolute), or None for a lumped system.
    lumped : dict or None
        ``{"kind": "hoffmann", "parameters": {...SI...}}``.
    axes : dict
        Axis name -> 1-D array of SI values, in config order.
    combine : {"grid", "zip"}
    cea : dict or None
        ``{"mu": array}`` of the study-level CEA.
    points : dict
        Per-point task settings in SI (``modes``, ``transient``, ``psd``).
    source : str
        ``"<path> sha256:<hex>"`` of the config.
    config : dict
        The mapping read (after the ``--quick`` overrides).
    quick : bool
        The ``--quick`` variant.
    kind : StudyKind
        The study kind (:mod:`fivid.study.kind`): what every point and the whole study compute.
    """

    name: str
    description: str
    model_path: Path | None
    lumped: dict | None
    axes: dict
    combine: str
    cea: dict | None
    points: dict
    source: str
    config: dict = field(default_factory=dict)
    quick: bool = False
    kind: Any = None

    def point_table(self) -> list[dict]:
        """Every point's conditions ``{axis: value}`` in SI (grid: last axis fastest; zip: element-wise)."""
        names = list(self.axes)
        if not names:
            return [{}]
        values = [self.axes[n] for n in names]
        if self.combine == "zip":
            return [dict(zip(names, (v[i] for v in values))) for i in range(len(values[0]))]
        mesh = np.meshgrid(*values, indexing="ij")
        return [dict(zip(names, (m.flat[i] for m in mesh))) for i in range(mesh[0].size)]

    @property
    def digest(self) -> str:
        """sha256 of what every point depends on (kind, system, task settings), not of the sweep itself."""
        model = ""
        if self.model_path is not None:
            model = hashlib.sha256(self.model_path.read_bytes()).hexdigest()
        text = json.dumps({"kind": getattr(self.kind, "name", None), "model": model, "lumped": self.lumped,
                           "points": self.points}, sort_keys=True,
                          default=_jsonable)
        return hashlib.sha256(text.encode()).hexdigest()


def _jsonable(x):
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, Path):
        return str(x)
    raise TypeError(type(x))


def _merge(base: dict, over: Mapping, path: str = "") -> dict:
    """``over`` merged into ``base`` key by key; a sweep axis is replaced whole (values vs start/stop/num)."""
    out = copy.deepcopy(base)
    for k, v in over.items():
        if isinstance(v, Mapping) and isinstance(out.get(k), Mapping) and path != "sweep":
            out[k] = _merge(out[k], v, k if not path else f"{path}.{k}")
        else:
            out[k] = copy.deepcopy(v)
    return out


# ---------------------------------------------------------------------------------------------- typed sections


def _as_values(spec):
    """A bare list is ``{values: [...]}``."""
    return {"values": list(spec)} if isinstance(spec, (list, tuple)) else spec


@functools.lru_cache(maxsize=None)
def _axis(units: str):
    """The model of a sweep axis (or the CEA's mu) in ``units``: ``{values}`` or ``{start, stop, num, spacing}``."""
    q = Quantity(units, bare_is_si=True)

    class Axis(ConfigModel):
        values: Annotated[list[q], Field(min_length=1)] | None = None
        start: q | None = None
        stop: q | None = None
        num: Annotated[int, Field(ge=1)] | None = None
        spacing: Literal["linear", "log"] = "linear"

        @model_validator(mode="after")
        def _one_way(self):
            given = self.model_fields_set
            if self.values is not None:
                if given - {"values"}:
                    raise fail("give either values or start/stop/num, not both")
                return self
            missing = [k for k in ("start", "stop", "num") if getattr(self, k) is None]
            if missing:
                raise fail(f"missing {missing[0]!r}: expected values, or start, stop and num")
            if self.spacing == "log" and not (self.start > 0 and self.stop > 0):
                raise fail(f"log spacing needs start and stop > 0, found {self.start:g} and {self.stop:g}")
            return self

        def array(self) -> np.ndarray:
            if self.values is not None:
                return np.array(self.values)
            make = np.geomspace if self.spacing == "log" else np.linspace
            return make(self.start, self.stop, self.num)

    Axis.__name__ = Axis.__qualname__ = f"Axis_{re.sub(r'[^A-Za-z0-9]', '_', units)}"
    return Annotated[Axis, BeforeValidator(_as_values)]


class _Sweep(ConfigModel):
    """Axes with units; the points are their grid (or, with ``combine: zip``, element-wise)."""

    combine: Literal["grid", "zip"] = "grid"
    normal_load: _axis("N") | None = None
    sliding_velocity: _axis("m s-1") | None = None
    roughness_ra: _axis("m") | None = None
    mu: _axis("1") | None = None
    mu_static: _axis("1") | None = None
    seed: _axis("1") | None = None
    mesh: _axis("1") | None = None
    time_step: _axis("1") | None = None

    @model_validator(mode="after")
    def _ranges(self):
        sizes = {}
        for name in AXES:
            axis = getattr(self, name)
            if axis is None:
                continue
            vals = axis.array()
            sizes[name] = vals.size
            if name == "seed":
                if np.any(vals != np.round(vals)) or np.any(vals < 0):
                    raise fail("expected seeds as whole numbers >= 0", at=("seed",))
            elif name in ("normal_load", "sliding_velocity", "mesh") and np.any(vals <= 0):
                raise fail(f"expected {name} > 0, found {vals.min():g}", at=(name,))
            elif np.any(vals < 0):
                raise fail(f"expected {name} >= 0, found {vals.min():g}", at=(name,))
            if name == "time_step" and np.any((vals <= 0) | (vals > 1)):
                raise fail("expected a fraction of the critical step: 0 < value <= 1", at=("time_step",))
        if self.combine == "zip" and len(set(sizes.values())) > 1:
            raise fail("zip needs axes of one length, found " + ", ".join(f"{k} {v}" for k, v in sizes.items()),
                       at=("combine",))
        return self


class _System(ConfigModel):
    """The system of every point: an FE model config (relative to the study file) or a lumped kind's model (its
    registered name, with ``parameters``: that kind's section, validated by the kind)."""

    model: str | None = None
    lumped: Name | None = Field(None, description="a lumped study kind (fivid.study.kind registry), e.g. hoffmann")
    parameters: dict[str, Any] | None = Field(None, description="the lumped kind's parameters (its config section)")

    @model_validator(mode="after")
    def _exactly_one(self):
        if (self.model is None) == (self.lumped is None):
            raise fail("give exactly one of 'model' (an FE model config) and 'lumped'")
        return self


class _Cea(ConfigModel):
    mu: _axis("1")
    normal_load: Quantity("N", bare_is_si=True) | None = None

    @model_validator(mode="after")
    def _increasing(self):
        mu = self.mu.array()
        if np.any(np.diff(mu) <= 0) or np.any(mu < 0):
            raise fail("expected the CEA's mu >= 0 and increasing", at=("mu",))
        return self


class _Modes(ConfigModel):
    n_modes: Annotated[int, Field(ge=1)] = 10


class _Transient(ConfigModel):
    duration: Quantity("s", positive=True, bare_is_si=True) = 0.1
    sample_rate: Quantity("Hz", positive=True, bare_is_si=True) = 51200.0
    perturbation: Quantity("m", bare_is_si=True) | None = None
    law: str | None = Field(None, description="friction law file (netCDF), relative to the study file")
    coulomb_reference: bool = False
    solver: SolverPathField = "auto"
    reduced_tolerance: ReducedToleranceField = DEFAULT_REDUCED_TOLERANCE


class _Psd(ConfigModel):
    nperseg: Annotated[int, Field(ge=16)] = 1024
    band: Annotated[list[Quantity("Hz", bare_is_si=True)], Field(min_length=2, max_length=2)] | None = None


class _Points(ConfigModel):
    """The analyses computed at every point; a kind's own section may sit here too (``points.roughness``),
    validated by the kind."""

    model_config = ConfigDict(**{**ConfigModel.model_config, "extra": "allow"})

    modes: _Modes | None = None
    transient: _Transient | None = None
    psd: _Psd | None = None

    @model_validator(mode="before")
    @classmethod
    def _asked_with_defaults(cls, data):  # ``modes:`` with nothing under it asks for the task with its defaults
        return {k: ({} if v is None else v) for k, v in data.items()} if isinstance(data, dict) else data


class StudyConfig(ConfigModel):
    """A study config (``configs/studies/*.yaml``, ``docs/studies.md``)."""

    fivid_study: Literal[1] = Field(alias="fivid-study", description="study format version")
    kind: Name | None = Field(None, description="the study kind (fivid.study.kind registry; docs/studies.md); "
                                                "default: system.lumped, else the kind that claims the config")
    name: Name = "study"
    description: str = ""
    system: _System
    sweep: _Sweep = _Sweep()
    cea: _Cea | None = None
    points: _Points = _Points()
    quick: dict[str, Any] | None = Field(None, description="overrides for --quick (same keys)")

    @model_validator(mode="after")
    def _consistent(self):
        pts = self.points
        if pts.transient is not None and pts.transient.coulomb_reference and pts.transient.law is None:
            raise fail("compares a law with its mu0: give 'law' too", at=("points", "transient", "coulomb_reference"))
        if pts.psd is not None:
            if pts.transient is None:
                raise fail("a PSD needs a transient at each point", at=("points", "psd"))
            nyquist = pts.transient.sample_rate / 2
            if pts.psd.band is not None and not 0 <= pts.psd.band[0] < pts.psd.band[1] <= nyquist:
                raise fail(f"expected 0 <= low < high <= Nyquist ({nyquist:g} Hz), found {pts.psd.band[0]:g}, "
                           f"{pts.psd.band[1]:g}", at=("points", "psd", "band"))
        return self


def _kind(src, cfg: StudyConfig, data: Mapping):
    """The study's kind: ``kind:``, else ``system.lumped``, else the first registered kind that claims the config;
    a lumped kind needs ``system.lumped`` and an FE kind ``system.model``."""
    if cfg.kind is not None:
        kind = _registered(src, cfg.kind, "kind")
    elif cfg.system.lumped is not None:
        kind = _registered(src, cfg.system.lumped, "system.lumped")
    else:
        kind = guess_kind(dict(data))
        if kind is None:
            raise src.error("kind", "no registered study kind claims this config; name one: "
                                    + ", ".join(registered_kinds()))
    if kind.lumped and cfg.system.lumped != kind.name:
        raise src.error("system", f"kind {kind.name!r} is a lumped model: give system.lumped: {kind.name} "
                                  "(and its parameters), not an FE model")
    if not kind.lumped and cfg.system.model is None:
        raise src.error("system", f"kind {kind.name!r} runs an FE model: give system.model (a model config)"
                        + (f"; system.lumped {cfg.system.lumped!r} is another kind" if cfg.system.lumped else ""))
    return kind


def _registered(src, name: str, key: str):
    try:
        return study_kind(name, key=key)
    except ConfigError as exc:
        raise src.error(key, exc.message) from None


def _kind_section(src, kind, data: Mapping):
    """The kind's section validated by its model (``kind.config``), and a check that ``points`` holds no other
    unknown key; returns the kind's settings (SI, :meth:`StudyKind.settings`)."""
    own = kind.section
    extra = set(data.get("points") or {}) - set(_Points.model_fields)
    for key in sorted(extra):
        if own != ("points", key):
            owners = [k.name for k in registered_kinds().values() if k.section == ("points", key)]
            hint = f"; it belongs to kind {owners[0]!r} (kind: {owners[0]})" if owners else ""
            raise src.error(f"points.{key}", unknown_key_message(key, list(_Points.model_fields)) + hint)
    if own is None:
        if (data.get("system") or {}).get("parameters") is not None:
            raise src.error("system.parameters", f"kind {kind.name!r} takes no parameters")
        return kind.settings(None)
    raw = (data.get(own[0]) or {}).get(own[1])
    section = validate(kind.config, src, data={} if raw is None else raw, prefix=own)
    try:
        return kind.settings(section)
    except ConfigError as exc:
        key = ".".join(own) + (f".{exc.key}" if exc.key and exc.key not in own else "")
        raise src.error(key, exc.message) from None


def load_study(source: str | PathLike | Mapping[str, Any], *, quick: bool = False) -> Study:
    """Read and validate a study config (a file or a mapping; relative model paths from the file's folder)."""
    if isinstance(source, Mapping):
        src, base = from_mapping(source), Path.cwd()
    else:
        src, base = read_yaml(source, "study config"), Path(source).resolve().parent
    data = src.data
    if quick and isinstance(data.get("quick"), Mapping):
        validate(StudyConfig, src)  # the base too: a wrong type there is an error even where 'quick' overrides it
        data = _merge({k: v for k, v in data.items() if k != "quick"}, data["quick"])
    cfg = validate(StudyConfig, src, data=data)
    kind = _kind(src, cfg, data)
    for key, message in kind.check(cfg):
        raise src.error(key, message)
    settings = _kind_section(src, kind, data)
    model_path, lumped = None, None
    if cfg.system.model is not None:
        model_path = (base / cfg.system.model).resolve()
        if not model_path.is_file():
            raise src.error("system.model", f"no such model config: {str(model_path)!r}")
    if kind.lumped:
        lumped = {"kind": kind.name, "parameters": settings}
    axes = {}
    for name in (data.get("sweep") or {}):  # in the order of the file
        if name != "combine":
            vals = getattr(cfg.sweep, name).array()
            axes[name] = vals.astype(np.int64) if name == "seed" else vals
    cea = None
    if cfg.cea is not None:
        cea = {"mu": cfg.cea.mu.array()}
        if cfg.cea.normal_load is not None:
            cea["normal_load"] = cfg.cea.normal_load
        if model_path is not None and "normal_load" not in cea and not _pressed_by_loads(model_path):
            raise src.error("cea", "an FE model's CEA linearises about the preload: give cea.normal_load (e.g. 5 N), "
                                   "unless the model's pressure loads or an expanding rigid circle press the contact")
    points = _points(src, cfg.points, base)
    if kind.section is not None and kind.section[0] == "points":
        points[kind.section[1]] = settings
    return Study(name=cfg.name, description=cfg.description, model_path=model_path, lumped=lumped, axes=axes,
                 combine=cfg.sweep.combine, cea=cea, points=points, source=src.origin, config=data, quick=quick,
                 kind=kind)


def _pressed_by_loads(model_path) -> bool:
    """True when the model config has pressure loads or an expanding rigid circle (its contact state under them
    needs no clamp load; :func:`fivid.fe.static.pressed_by_itself` of the built model)."""
    data = read_yaml(model_path, "model config").data
    expanding = any(isinstance(c, dict) and isinstance(c.get("rigid"), dict) and c["rigid"].get("expansion")
                    for c in data.get("contacts") or ())
    return bool(data.get("loads")) or expanding


def _points(src, spec: _Points, base: Path) -> dict:
    """The per-point task settings in SI, as the tasks take them (only the keys given, beside the defaults)."""
    out = {}
    if spec.modes is not None:
        out["modes"] = {"n_modes": spec.modes.n_modes}
    if spec.transient is not None:
        t = spec.transient
        tr = {"duration": t.duration, "sample_rate": t.sample_rate}
        if t.perturbation is not None:
            tr["perturbation"] = t.perturbation
        if t.law is not None:
            law = (base / t.law).resolve()
            if not law.is_file():
                raise src.error("points.transient.law", f"no such law file: {str(law)!r}")
            tr["law"] = str(law)
        if t.coulomb_reference:
            tr["coulomb_reference"] = True
        if "solver" in t.model_fields_set:
            tr["solver"] = t.solver
        if "reduced_tolerance" in t.model_fields_set:
            tr["reduced_tolerance"] = float(t.reduced_tolerance)
        out["transient"] = tr
    if spec.psd is not None:
        out["psd"] = {"nperseg": spec.psd.nperseg}
        if spec.psd.band is not None:
            out["psd"]["band"] = tuple(spec.psd.band)
    return out
