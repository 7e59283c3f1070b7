"""Study configs (``configs/studies/*.yaml``) -> a validated :class:`Study`.

A study is a sweep over conditions whose points are each a small analysis (DESIGN §11)::

    fivid-study: 1
    name: hoffmann_mu_sweep
    description: the 2-DOF mode-coupling model across its flutter threshold
    system:                       # an FE model config, relative to this file ...
      model: ../models/triboair_coarse.yaml
    # ... or a lumped model: {lumped: hoffmann, parameters: {mass: 1 kg, k1: 1e6 N/m, ...}}
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
import hashlib
import json
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from fivid.errors import ConfigError
from fivid.fe.config import _quantity  # one quantity check (file, line, key) for every model-side config

__all__ = ["Study", "AXES", "load_study", "STUDY_VERSION"]

STUDY_VERSION = 1
#: sweepable condition -> (SI units, long name); `seed` is an integer
AXES = {
    "normal_load": ("N", "normal load"),
    "sliding_velocity": ("m s-1", "sliding velocity"),
    "roughness_ra": ("m", "roughness Ra"),
    "mu": ("1", "kinetic friction coefficient"),
    "mu_static": ("1", "static friction coefficient"),
    "seed": ("1", "random seed"),
    "mesh": ("1", "mesh refinement factor (divisions x factor)"),
    "time_step": ("1", "time step as a fraction of the critical step"),
}
_TOP = {"fivid-study", "name", "description", "system", "sweep", "cea", "points", "quick"}
_POINT_TASKS = {"modes", "transient", "psd", "roughness"}
_LUMPED = {"hoffmann": {"mass": "kg", "k1": "N m-1", "k2": "N m-1", "k3": "N m-1", "damping": "N s m-1",
                        "preload": "N", "belt_velocity": "m s-1"}}


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
        """sha256 of what every point depends on (system, task settings), not of the sweep itself."""
        model = ""
        if self.model_path is not None:
            model = hashlib.sha256(self.model_path.read_bytes()).hexdigest()
        text = json.dumps({"model": model, "lumped": self.lumped, "points": self.points}, sort_keys=True,
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


def load_study(source: str | PathLike | Mapping[str, Any], *, quick: bool = False) -> Study:
    """Read and validate a study config (a file or a mapping; relative model paths from the file's folder)."""
    from fivid.fe.config import read_config

    data, ctx, origin = read_config(source)
    base = Path(source).resolve().parent if not isinstance(source, Mapping) else Path.cwd()
    if not isinstance(data, dict):
        raise ctx.error("", "a study config is a mapping of keys (see docs/studies.md)")
    unknown = sorted(set(data) - _TOP)
    if unknown:
        raise ctx.error(unknown[0], f"unknown key {unknown[0]!r}; allowed: {', '.join(sorted(_TOP))}")
    version = data.get("fivid-study")
    if version != STUDY_VERSION:
        raise ctx.error("fivid-study", f"expected 'fivid-study: {STUDY_VERSION}' as the format marker, got {version!r}")
    if quick and isinstance(data.get("quick"), Mapping):
        data = _merge({k: v for k, v in data.items() if k != "quick"}, data["quick"])
    model_path, lumped = _system(ctx, data.get("system"), base)
    axes, combine = _sweep(ctx, data.get("sweep") or {})
    cea = None
    if data.get("cea") is not None:
        spec = _mapping(ctx, data["cea"], "cea", {"mu", "normal_load"})
        if "mu" not in spec:
            raise ctx.error("cea", "the study-level CEA needs 'mu' (values, or start/stop/num)")
        cea = {"mu": _values(ctx, spec["mu"], "cea.mu", "1")}
        if "normal_load" in spec:
            cea["normal_load"] = _quantity(ctx, spec["normal_load"], "cea.normal_load", "N")
        if np.any(np.diff(cea["mu"]) <= 0) or np.any(cea["mu"] < 0):
            raise ctx.error("cea.mu", "the CEA's mu must be >= 0 and increasing")
    points = _points(ctx, data.get("points") or {}, lumped is not None, base)
    if cea is not None and model_path is not None and "normal_load" not in cea and not _pressed_by_loads(model_path):
        raise ctx.error("cea", "an FE model's CEA linearises about the preload: give cea.normal_load (e.g. 5 N), "
                               "unless the model's pressure loads press the contact")
    if lumped is not None and ({"mesh", "time_step"} & set(axes)):
        raise ctx.error("sweep", "mesh and time_step axes refine an FE model, not a lumped one")
    if lumped is not None and "transient" in points and "mu" not in axes:
        raise ctx.error("sweep", "a lumped model's transient takes its friction coefficient from a 'mu' axis")
    return Study(name=str(data.get("name", "study")), description=str(data.get("description", "")),
                 model_path=model_path, lumped=lumped, axes=axes, combine=combine, cea=cea, points=points,
                 source=origin, config=data, quick=quick)


def _pressed_by_loads(model_path) -> bool:
    """True when the model config has pressure loads (its contact state under them needs no clamp load)."""
    import yaml

    with open(model_path, encoding="utf-8") as fh:
        return bool((yaml.safe_load(fh) or {}).get("loads"))


def _mapping(ctx, value, key, allowed) -> dict:
    if not isinstance(value, Mapping):
        raise ctx.error(key, f"expected a mapping, got {value!r}")
    bad = sorted(set(value) - set(allowed))
    if bad:
        raise ctx.error(f"{key}.{bad[0]}", f"unknown key {bad[0]!r}; allowed: {', '.join(sorted(allowed))}")
    return dict(value)


def _values(ctx, spec, key, units) -> np.ndarray:
    """``{values: [...]}`` or ``{start, stop, num, spacing: linear|log}`` (or a bare list) -> SI array."""
    if isinstance(spec, (list, tuple)):
        spec = {"values": list(spec)}
    spec = _mapping(ctx, spec, key, {"values", "start", "stop", "num", "spacing"})
    if "values" in spec:
        if len(spec) > 1:
            raise ctx.error(key, "give either values or start/stop/num, not both")
        vals = spec["values"]
        if not isinstance(vals, (list, tuple)) or not vals:
            raise ctx.error(f"{key}.values", f"expected a non-empty list, got {vals!r}")
        return np.array([_quantity(ctx, v, f"{key}.values[{i}]", units) for i, v in enumerate(vals)])
    missing = sorted({"start", "stop", "num"} - set(spec))
    if missing:
        raise ctx.error(key, f"missing {missing[0]!r}: give values, or start, stop and num")
    lo = _quantity(ctx, spec["start"], f"{key}.start", units)
    hi = _quantity(ctx, spec["stop"], f"{key}.stop", units)
    num = spec["num"]
    if isinstance(num, bool) or not isinstance(num, int) or num < 1:
        raise ctx.error(f"{key}.num", f"expected a whole number >= 1, got {num!r}")
    spacing = spec.get("spacing", "linear")
    if spacing == "log":
        if not (lo > 0 and hi > 0):
            raise ctx.error(key, f"log spacing needs start and stop > 0, got {lo:g} and {hi:g}")
        return np.geomspace(lo, hi, num)
    if spacing != "linear":
        raise ctx.error(f"{key}.spacing", f"expected 'linear' or 'log', got {spacing!r}")
    return np.linspace(lo, hi, num)


def _system(ctx, spec, base: Path):
    if spec is None:
        raise ctx.error("system", "missing: give {model: PATH} (an FE model config) or {lumped: hoffmann, ...}")
    spec = _mapping(ctx, spec, "system", {"model", "lumped", "parameters"})
    if ("model" in spec) == ("lumped" in spec):
        raise ctx.error("system", "give exactly one of 'model' (an FE model config) and 'lumped'")
    if "model" in spec:
        path = (base / str(spec["model"])).resolve()
        if not path.is_file():
            raise ctx.error("system.model", f"no such model config: {str(path)!r}")
        return path, None
    kind = spec["lumped"]
    if kind not in _LUMPED:
        raise ctx.error("system.lumped", f"unknown lumped model {kind!r}; allowed: {', '.join(_LUMPED)}")
    units = _LUMPED[kind]
    params = _mapping(ctx, spec.get("parameters") or {}, "system.parameters", set(units))
    si = {k: _quantity(ctx, v, f"system.parameters.{k}", units[k]) for k, v in params.items()}
    from fivid.study.lumped import HoffmannSystem

    try:
        HoffmannSystem(**si)
    except ConfigError as exc:
        raise ctx.error(exc.key or "system.parameters", exc.message) from None
    return None, {"kind": kind, "parameters": si}


def _sweep(ctx, spec):
    spec = dict(_mapping(ctx, spec, "sweep", set(AXES) | {"combine"}))
    combine = spec.pop("combine", "grid")
    if combine not in ("grid", "zip"):
        raise ctx.error("sweep.combine", f"expected 'grid' or 'zip', got {combine!r}")
    axes = {}
    for name, s in spec.items():
        vals = _values(ctx, s, f"sweep.{name}", AXES[name][0])
        if name == "seed":
            if np.any(vals != np.round(vals)) or np.any(vals < 0):
                raise ctx.error("sweep.seed", "seeds are whole numbers >= 0")
            vals = vals.astype(np.int64)
        elif name in ("normal_load", "sliding_velocity", "mesh") and np.any(vals <= 0):
            raise ctx.error(f"sweep.{name}", f"{name} must be > 0, got {vals.min():g}")
        elif np.any(vals < 0):
            raise ctx.error(f"sweep.{name}", f"{name} must be >= 0, got {vals.min():g}")
        if name == "time_step" and np.any((vals <= 0) | (vals > 1)):
            raise ctx.error("sweep.time_step", "a fraction of the critical step: 0 < value <= 1")
        axes[name] = vals
    if combine == "zip" and len({v.size for v in axes.values()}) > 1:
        raise ctx.error("sweep.combine", "zip needs axes of one length: " +
                        ", ".join(f"{k} {v.size}" for k, v in axes.items()))
    return axes, combine


def _points(ctx, spec, lumped: bool, base: Path) -> dict:
    spec = _mapping(ctx, spec, "points", _POINT_TASKS)
    out = {}
    if "modes" in spec:
        if lumped:
            raise ctx.error("points.modes", "modes are computed for FE models (a lumped model has its closed form)")
        m = _mapping(ctx, spec["modes"] or {}, "points.modes", {"n_modes"})
        n = m.get("n_modes", 10)
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise ctx.error("points.modes.n_modes", f"expected a whole number >= 1, got {n!r}")
        out["modes"] = {"n_modes": n}
    if "transient" in spec:
        t = _mapping(ctx, spec["transient"] or {}, "points.transient",
                     {"duration", "sample_rate", "perturbation", "law", "coulomb_reference"})
        tr = {"duration": _quantity(ctx, t.get("duration", "0.1 s"), "points.transient.duration", "s"),
              "sample_rate": _quantity(ctx, t.get("sample_rate", "51.2 kHz"), "points.transient.sample_rate", "Hz")}
        if not (tr["duration"] > 0 and tr["sample_rate"] > 0):
            raise ctx.error("points.transient", "duration and sample_rate must be > 0")
        if "perturbation" in t:
            tr["perturbation"] = _quantity(ctx, t["perturbation"], "points.transient.perturbation", "m")
        if "law" in t:
            if lumped:
                raise ctx.error("points.transient.law", "a lumped model takes mu from the sweep, not a law file")
            law = (base / str(t["law"])).resolve()
            if not law.is_file():
                raise ctx.error("points.transient.law", f"no such law file: {str(law)!r}")
            tr["law"] = str(law)
        if t.get("coulomb_reference"):
            if "law" not in tr:
                raise ctx.error("points.transient.coulomb_reference", "compares a law with its mu0: give 'law' too")
            tr["coulomb_reference"] = True
        out["transient"] = tr
    if "psd" in spec:
        if "transient" not in out:
            raise ctx.error("points.psd", "a PSD needs a transient at each point")
        p = _mapping(ctx, spec["psd"] or {}, "points.psd", {"nperseg", "band"})
        nps = p.get("nperseg", 1024)
        if isinstance(nps, bool) or not isinstance(nps, int) or nps < 16:
            raise ctx.error("points.psd.nperseg", f"expected a whole number >= 16, got {nps!r}")
        psd = {"nperseg": nps}
        if "band" in p:
            b = p["band"]
            if not isinstance(b, (list, tuple)) or len(b) != 2:
                raise ctx.error("points.psd.band", f"expected [low, high], got {b!r}")
            lo, hi = (_quantity(ctx, v, f"points.psd.band[{i}]", "Hz") for i, v in enumerate(b))
            if not 0 <= lo < hi <= out["transient"]["sample_rate"] / 2:
                raise ctx.error("points.psd.band", f"need 0 <= low < high <= Nyquist "
                                                   f"({out['transient']['sample_rate'] / 2:g} Hz), got {lo:g}, {hi:g}")
            psd["band"] = (lo, hi)
        out["psd"] = psd
    if "roughness" in spec:
        out["roughness"] = _roughness_task(ctx, spec["roughness"] or {}, lumped, out)
    return out


def _roughness_task(ctx, spec, lumped: bool, points: dict) -> dict:
    """``points.roughness`` (seed 003's rough pair, :mod:`fivid.study.roughness`) in SI."""
    key = "points.roughness"
    if lumped:
        raise ctx.error(key, "the rough pair is an FE model: give system.model (e.g. ../models/rough_pair_short.yaml)")
    if "transient" not in points:
        raise ctx.error(key, "a rough-pair point is a transient: give points.transient (duration, sample_rate)")
    r = _mapping(ctx, spec, key, {"correlation_length", "profile_step", "seeds", "sensor_every", "gs_tolerance",
                                  "gs_max_iterations", "settle_time"})
    out = {}
    for name, units in (("correlation_length", "m"), ("profile_step", "m"), ("settle_time", "s")):
        if name in r:
            out[name] = _quantity(ctx, r[name], f"{key}.{name}", units)
            if not out[name] > 0:
                raise ctx.error(f"{key}.{name}", f"expected a positive quantity, got {r[name]!r}")
    for name in ("sensor_every", "gs_max_iterations"):
        if name in r:
            v = r[name]
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ctx.error(f"{key}.{name}", f"expected a whole number >= 1, got {v!r}")
            out[name] = v
    if "gs_tolerance" in r:
        v = r["gs_tolerance"]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v < 1:
            raise ctx.error(f"{key}.gs_tolerance", f"expected a number in (0, 1), got {v!r}")
        out["gs_tolerance"] = float(v)
    if "seeds" in r:
        v = r["seeds"]
        if (not isinstance(v, (list, tuple)) or len(v) != 2
                or any(isinstance(s, bool) or not isinstance(s, int) or s < 0 for s in v)):
            raise ctx.error(f"{key}.seeds", f"expected two whole numbers >= 0 (lower, upper profile), got {v!r}")
        out["seeds"] = list(v)
    return out
