"""The pipeline plan (recipe) and the run configuration (numbers), validated whole before any work.

A *recipe* (``pipelines/*.yaml``) says which stages run and in which order::

    fivid-pipeline: 1
    name: calibration
    stages: [ingest, identify, modal, simulate, score, report]

A *run configuration* (``configs/runs/*.yaml``) gives the numbers: input folder, rig profile, model,
analysis band, simulation settings, Monte-Carlo seeds, thresholds and the output folder. Relative
paths in a run configuration are relative to the file that contains them. Quantities carry units
(``band: [500 Hz, 20 kHz]``, ``duration: 0.4 s``).

:func:`load_plan` reads both and checks everything it can without computing: keys (unknown keys
are errors, so a typo is not silently ignored), types, units and ranges, that the input folder
holds matching files, that the model and the rig profile exist. Every problem is reported with
the file and the key path (``simulate.duration``).
"""

from __future__ import annotations

import fnmatch
import hashlib
import os
from dataclasses import dataclass, field
from pathlib import Path

from fivid.errors import ConfigError, FividError, UnitError
from fivid.units import parse_quantity

__all__ = [
    "STAGE_REQUIRES",
    "Plan",
    "RunConfig",
    "Threshold",
    "load_plan",
    "load_recipe",
    "load_run_config",
    "read_yaml",
    "line_of_key",
]

# Each stage kind and the stage kinds that must run before it (their outputs are its inputs).
STAGE_REQUIRES: dict[str, tuple[str, ...]] = {
    "ingest": (),
    "identify": ("ingest",),
    "modal": ("ingest",),  # linearised about the preload: needs the test conditions' normal loads
    "simulate": ("ingest", "identify"),
    "score": ("ingest", "simulate"),
    "report": ("ingest", "identify", "simulate", "score"),
}

# Scores that may carry a threshold, and the direction that passes.
_SCORE_KINDS = {
    "lsd_db": "max",
    "level_diff_db": "max_abs",
    "band_level_rms_error_db": "max",
    "shape_correlation": "min",
}


@dataclass(frozen=True)
class Threshold:
    """A pass/fail bound on one score: ``max``, ``max_abs`` (|score| ≤ value) or ``min``."""

    score: str
    kind: str
    value: float

    def passes(self, x: float | None) -> bool:
        """Whether score value ``x`` meets the bound (a missing/NaN score fails)."""
        if x is None or x != x:
            return False
        if self.kind == "max":
            return x <= self.value
        if self.kind == "max_abs":
            return abs(x) <= self.value
        return x >= self.value

    def describe(self) -> str:
        """The threshold as an inequality for reports, e.g. ``lsd_db <= 6``."""
        return {"max": f"{self.score} <= {self.value:g}", "max_abs": f"|{self.score}| <= {self.value:g}",
                "min": f"{self.score} >= {self.value:g}"}[self.kind]


@dataclass(frozen=True)
class RunConfig:
    """The numbers of a pipeline run, in SI units; paths resolved against the config file."""

    path: Path | None
    sha256: str
    raw: dict
    input_folder: Path
    input_pattern: str
    input_files: tuple[Path, ...]
    rig_profile: str | None
    model: Path
    output: Path
    band: tuple[float, float]
    nperseg: int
    settle: float
    identify: dict
    n_modes: int
    duration: float
    sample_rate: float
    seeds: tuple[int, ...]
    thresholds: tuple[Threshold, ...]


@dataclass(frozen=True)
class Plan:
    """A validated recipe plus its run configuration."""

    path: Path | None
    name: str
    stages: tuple[str, ...]
    recipe_sha256: str
    config: RunConfig
    extra: dict = field(default_factory=dict)


def read_yaml(path: str | os.PathLike, what: str) -> tuple[dict, str]:
    """Load a YAML mapping; returns ``(mapping, sha256 of the file bytes)``."""
    import yaml

    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{what} {str(path)!r} does not exist", file=path)
    data = path.read_bytes()
    try:
        obj = yaml.safe_load(data.decode("utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError) as exc:
        mark = getattr(exc, "problem_mark", None)
        # one line: the parser's problem and its line/column, not its multi-line excerpt of the file
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        where = "" if mark is None else f" at column {mark.column + 1}"
        raise ConfigError(f"not valid YAML: {problem}{where}", file=path,
                          line=None if mark is None else mark.line + 1) from None
    if not isinstance(obj, dict):
        raise ConfigError(f"{what} must be a YAML mapping, got {type(obj).__name__}", file=path)
    return obj, hashlib.sha256(data).hexdigest()


def line_of_key(path, key: str) -> int | None:
    """The 1-based line of config ``key`` (``simulate.duration``) in the YAML file ``path``.

    A key that is not in the file (a required one left out) gives the line of its closest parent;
    None when there is none or the file cannot be read. Called only when reporting an error.
    """
    import re

    import yaml

    from fivid.fe.config import _compose_lines  # the model config's key -> line map, reused

    lines: dict = {}
    try:
        _compose_lines(yaml.compose(Path(path).read_text(encoding="utf-8")), "", lines)
    except (OSError, yaml.YAMLError, UnicodeDecodeError, AttributeError):  # AttributeError: an empty file
        return None
    while key:
        if key in lines:
            return lines[key]
        key = re.sub(r"(\[\d+\]|\.?[^.\[]*)$", "", key, count=1)
    return None


class _Checker:
    """Collects every problem of one file, each with its key path, and raises them together.

    The error carries the line of the (first) offending key, looked up in the YAML file's nodes.
    """

    def __init__(self, file):
        self.file = file
        self.problems: list[tuple[str, str]] = []

    def add(self, key: str, msg: str) -> None:
        self.problems.append((key, msg))

    def section(self, raw: dict, key: str, allowed: set[str], required: set[str] = frozenset()) -> dict:
        node = raw.get(key, {}) if key else raw
        if node is None:
            node = {}
        if not isinstance(node, dict):
            self.add(key, f"must be a mapping, got {node!r}")
            return {}
        prefix = f"{key}." if key else ""
        for k in node:
            if k not in allowed:
                self.add(f"{prefix}{k}", f"unknown key; allowed: {', '.join(sorted(allowed))}")
        for k in sorted(required - set(node)):
            self.add(f"{prefix}{k}", "is required")
        return node

    def quantity(self, node: dict, key: str, name: str, units: str, default=None, positive=True):
        value = node.get(name, default)
        if value is None:
            return None
        try:
            q = parse_quantity(value, units)
        except UnitError as exc:
            self.add(key, exc.message)
            return None
        if positive and not q > 0:
            self.add(key, f"must be positive, got {value!r}")
            return None
        return q

    def integer(self, node: dict, key: str, name: str, default: int, lo: int, hi: int) -> int:
        value = node.get(name, default)
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            self.add(key, f"must be an integer in [{lo}, {hi}], got {value!r}")
            return default
        return value

    def raise_if_any(self) -> None:
        if not self.problems:
            return
        key, msg = self.problems[0]
        more = ""
        if len(self.problems) > 1:
            def at(k):
                line = line_of_key(self.file, k)
                return k if line is None else f"{k} (line {line})"

            more = f" (and {len(self.problems) - 1} more: " + "; ".join(f"{at(k)}: {m}" for k, m in self.problems[1:]) + ")"
        raise ConfigError(msg + more, file=self.file, key=key, line=line_of_key(self.file, key))


def load_recipe(path: str | os.PathLike) -> tuple[str, tuple[str, ...], str, dict]:
    """Read and check a recipe; returns ``(name, stages, sha256, raw)``."""
    raw, sha = read_yaml(path, "pipeline recipe")
    chk = _Checker(path)
    chk.section(raw, "", {"fivid-pipeline", "name", "description", "stages"}, {"fivid-pipeline", "stages"})
    if raw.get("fivid-pipeline") not in (1, None):
        chk.add("fivid-pipeline", f"unsupported recipe version {raw.get('fivid-pipeline')!r}; this fivid reads 1")
    stages = raw.get("stages") or []
    if not isinstance(stages, list) or not stages:
        chk.add("stages", f"must be a non-empty list of stage names from {', '.join(STAGE_REQUIRES)}")
        stages = []
    seen: list[str] = []
    for i, stage in enumerate(stages):
        if stage not in STAGE_REQUIRES:
            chk.add(f"stages[{i}]", f"unknown stage {stage!r}; known stages: {', '.join(STAGE_REQUIRES)}")
            continue
        if stage in seen:
            chk.add(f"stages[{i}]", f"stage {stage!r} is listed twice")
            continue
        missing = [r for r in STAGE_REQUIRES[stage] if r not in seen]
        if missing:
            chk.add(f"stages[{i}]", f"stage {stage!r} needs {', '.join(missing)} listed before it")
        seen.append(stage)
    chk.raise_if_any()
    return str(raw.get("name") or Path(path).stem), tuple(seen), sha, raw


def _resolve(base: Path, value) -> Path:
    p = Path(os.path.expanduser(str(value)))
    return Path(os.path.normpath(p if p.is_absolute() else (base / p)))


_IDENTIFY_CHOICES = {"shape_method": ("smoothed", "rolloff"), "weighting": ("none", "estimator"),
                     "injection": ("uniform", "per_node", "convected")}


def _identify_options(chk: _Checker, raw: dict) -> dict:
    """The ``identify`` section as keyword arguments of :func:`fivid.identify.identify_friction_law` (SI)."""
    node = chk.section(raw, "identify", {"band", "tare", "nperseg", "tolerance", "min_normal_force", "mains_frequency",
                                         "shape_method", "smoothing_octaves", "forms", "weighting", "injection",
                                         "confidence"})
    out: dict = {}
    for name, units, example in (("band", "Hz", "[100 Hz, 5 kHz]"), ("tare", "s", "[0 s, 15 ms]")):
        if name in node:
            b = node[name]
            if not isinstance(b, (list, tuple)) or len(b) != 2:
                chk.add(f"identify.{name}", f"must be a pair with units, e.g. {example}, got {b!r}")
                continue
            q = [chk.quantity({"v": v}, f"identify.{name}[{i}]", "v", units, positive=False) for i, v in enumerate(b)]
            if None not in q:
                if not 0 <= q[0] < q[1]:
                    chk.add(f"identify.{name}", f"must be increasing and non-negative, got {b!r}")
                else:
                    out[name] = (q[0], q[1])
    if "nperseg" in node:
        out["nperseg"] = chk.integer(node, "identify.nperseg", "nperseg", 4096, 64, 2**22)
    for name, units in (("min_normal_force", "N"), ("mains_frequency", "Hz")):
        if name in node:
            out[name] = chk.quantity(node, f"identify.{name}", name, units) if node[name] is not None else None
    for name, lo, hi in (("tolerance", 0.0, 1.0), ("smoothing_octaves", 0.0, 4.0), ("confidence", 0.5, 0.9999)):
        if name in node:
            v = node[name]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not lo < v < hi:
                chk.add(f"identify.{name}", f"must be a number in ({lo:g}, {hi:g}), got {v!r}")
            else:
                out[name] = float(v)
    for name, choices in _IDENTIFY_CHOICES.items():
        if name in node:
            if node[name] not in choices:
                chk.add(f"identify.{name}", f"must be one of {', '.join(choices)}, got {node[name]!r}")
            else:
                out[name] = node[name]
    if "forms" in node:
        from fivid.friction.amplitude import AMPLITUDE_FORMS

        forms = node["forms"]
        if not isinstance(forms, list) or not forms or any(f not in AMPLITUDE_FORMS for f in forms):
            chk.add("identify.forms", f"must be a list of amplitude forms from {', '.join(AMPLITUDE_FORMS)}, "
                    f"got {forms!r}")
        else:
            out["forms"] = tuple(forms)
    return out


def load_run_config(path: str | os.PathLike | None, *, output: str | os.PathLike | None = None) -> RunConfig:
    """Read and check a run configuration (every problem at once, with key paths).

    Parameters
    ----------
    path : path-like
        The YAML file.
    output : path-like, optional
        Override of the ``output`` key (e.g. from the command line).
    """
    raw, sha = read_yaml(path, "run configuration")
    base = Path(path).resolve().parent
    chk = _Checker(path)
    top = {"fivid-run", "description", "inputs", "model", "output", "analysis", "identify", "modal",
           "simulate", "thresholds"}
    chk.section(raw, "", top, {"inputs", "model"} | (set() if output else {"output"}))
    if raw.get("fivid-run") not in (1, None):
        chk.add("fivid-run", f"unsupported run-config version {raw.get('fivid-run')!r}; this fivid reads 1")

    inputs = chk.section(raw, "inputs", {"folder", "pattern", "rig_profile"}, {"folder"})
    folder = _resolve(base, inputs.get("folder", "."))
    pattern = str(inputs.get("pattern", "*.csv"))
    files: tuple[Path, ...] = ()
    if "folder" in inputs:
        if not folder.is_dir():
            chk.add("inputs.folder", f"input folder {str(folder)!r} does not exist")
        else:
            files = tuple(sorted(p for p in folder.iterdir() if p.is_file() and fnmatch.fnmatch(p.name, pattern)))
            if not files:
                chk.add("inputs.pattern", f"no file in {str(folder)!r} matches {pattern!r}")
    profile = inputs.get("rig_profile")
    if profile is not None and not isinstance(profile, str):
        chk.add("inputs.rig_profile", f"must be a rig profile name or path, got {profile!r}")
        profile = None
    if isinstance(profile, str) and ("/" in profile or profile.endswith((".yaml", ".yml"))):
        resolved = _resolve(base, profile)
        if not resolved.is_file():
            chk.add("inputs.rig_profile", f"rig profile file {str(resolved)!r} does not exist")
        profile = str(resolved)

    model = _resolve(base, raw.get("model", ""))
    if "model" in raw and not model.is_file():
        chk.add("model", f"model file {str(model)!r} does not exist")

    out = Path(output) if output is not None else _resolve(base, raw.get("output", "out"))
    if out.exists() and not out.is_dir():
        chk.add("output", f"output {str(out)!r} exists and is not a folder; name a folder (it is created if missing)")

    analysis = chk.section(raw, "analysis", {"band", "nperseg", "settle"})
    band_raw = analysis.get("band", ["100 Hz", "20 kHz"])
    band = (0.0, 0.0)
    if not isinstance(band_raw, (list, tuple)) or len(band_raw) != 2:
        chk.add("analysis.band", f"must be [f_lo, f_hi] with units, e.g. [500 Hz, 20 kHz], got {band_raw!r}")
    else:
        lo = chk.quantity({"v": band_raw[0]}, "analysis.band[0]", "v", "Hz")
        hi = chk.quantity({"v": band_raw[1]}, "analysis.band[1]", "v", "Hz")
        if lo is not None and hi is not None:
            if not lo < hi:
                chk.add("analysis.band", f"f_lo must be below f_hi, got {band_raw!r}")
            band = (lo, hi)
    nperseg = chk.integer(analysis, "analysis.nperseg", "nperseg", 4096, 64, 2**22)
    settle = chk.quantity(analysis, "analysis.settle", "settle", "s", default="0 s", positive=False)
    if settle is not None and settle < 0:
        chk.add("analysis.settle", f"must be >= 0 s, got {analysis.get('settle')!r}")

    identify = _identify_options(chk, raw)

    modal = chk.section(raw, "modal", {"n_modes"})
    n_modes = chk.integer(modal, "modal.n_modes", "n_modes", 8, 1, 200)

    sim = chk.section(raw, "simulate", {"duration", "sample_rate", "seeds"})
    duration = chk.quantity(sim, "simulate.duration", "duration", "s", default="0.5 s")
    sample_rate = chk.quantity(sim, "simulate.sample_rate", "sample_rate", "Hz", default="51.2 kHz")
    seeds_raw = sim.get("seeds", 1)
    if isinstance(seeds_raw, int) and not isinstance(seeds_raw, bool) and 1 <= seeds_raw <= 1000:
        seeds = tuple(range(seeds_raw))
    elif isinstance(seeds_raw, list) and seeds_raw and all(isinstance(s, int) and s >= 0 for s in seeds_raw) \
            and len(set(seeds_raw)) == len(seeds_raw):
        seeds = tuple(seeds_raw)
    else:
        chk.add("simulate.seeds", f"must be a count in [1, 1000] or a list of distinct non-negative integers, got {seeds_raw!r}")
        seeds = (0,)
    if sample_rate and band[1] > sample_rate / 2:
        chk.add("analysis.band", f"upper edge {band[1]:g} Hz is above {sample_rate / 2:g} Hz, the Nyquist frequency of "
                f"simulate.sample_rate = {sim.get('sample_rate', '51.2 kHz')!r}: the simulated PSD stops there; lower "
                "the band's upper edge or raise simulate.sample_rate")
    if duration is not None and nperseg and sample_rate and (duration - (settle or 0.0)) * sample_rate < nperseg:
        chk.add("simulate.duration", f"{sim.get('duration')!r} less analysis.settle at {sample_rate:g} Hz gives "
                f"fewer samples than analysis.nperseg = {nperseg}; lengthen it or lower nperseg")

    thr_node = chk.section(raw, "thresholds", set(_SCORE_KINDS))
    thresholds = []
    for name, spec in thr_node.items():
        if name not in _SCORE_KINDS:
            continue
        kind = _SCORE_KINDS[name]
        if not isinstance(spec, dict) or set(spec) != {kind} or isinstance(spec[kind], bool) \
                or not isinstance(spec[kind], (int, float)):
            chk.add(f"thresholds.{name}", f"must be {{{kind}: <number>}}, got {spec!r}")
            continue
        thresholds.append(Threshold(name, kind, float(spec[kind])))
    chk.raise_if_any()
    return RunConfig(
        path=Path(path), sha256=sha, raw=raw, input_folder=folder, input_pattern=pattern, input_files=files,
        rig_profile=profile, model=model, output=out, band=band, nperseg=nperseg, settle=settle or 0.0,
        identify=identify,
        n_modes=n_modes, duration=duration, sample_rate=sample_rate, seeds=seeds, thresholds=tuple(thresholds),
    )


def _check_bands_against_inputs(cfg: RunConfig, stages) -> None:
    """Refuse an identify or analysis band above the Nyquist frequency of an input file's stated sample rate.

    Only the files' heads are read (:func:`fivid.io.read_rig_head`); a file whose head is bad, or that
    states no sample rate, is left to the ingest stage to report.
    """
    from fivid.io import read_rig_head
    from fivid.io.rig_csv import as_rig_profile

    profile = as_rig_profile(cfg.rig_profile)
    rates = {}
    for path in cfg.input_files:
        try:
            rate = read_rig_head(path, profile).attrs.get("sample_rate")
        except FividError:
            continue
        if rate:
            rates[path] = float(rate)
    if not rates:
        return
    slowest = min(rates, key=rates.get)
    nyquist = rates[slowest] / 2
    bands = [("analysis.band", cfg.band)] if "score" in stages else []
    if "identify" in stages and "band" in cfg.identify:
        bands.append(("identify.band", cfg.identify["band"]))
    for key, (_, hi) in bands:
        if hi > nyquist:
            n = sum(r / 2 < hi for r in rates.values())
            raise ConfigError(
                f"upper edge {hi:g} Hz is above {nyquist:g} Hz, the Nyquist frequency of input file {slowest.name} "
                f"(sample_rate {rates[slowest]:g} Hz; {n} of {len(rates)} input file(s) are too slow); lower the "
                "band's upper edge", file=cfg.path, key=key, line=line_of_key(cfg.path, key))


def load_plan(recipe: str | os.PathLike, config: str | os.PathLike | None = None, *,
              output: str | os.PathLike | None = None) -> Plan:
    """Read and validate a recipe and its run configuration; nothing is computed.

    Parameters
    ----------
    recipe : path-like
        ``pipelines/<name>.yaml``.
    config : path-like, optional
        ``configs/runs/<name>.yaml``; default: the recipe's ``default_config`` neighbour
        ``configs/runs/<recipe name>.yaml`` two folders up is *not* guessed — a config is required.
    output : path-like, optional
        Output folder overriding the config's ``output``.

    Raises
    ------
    ConfigError
        With the file and key path of the (first) problem and a count of the others.
    """
    name, stages, recipe_sha, raw = load_recipe(recipe)
    if config is None:
        raise ConfigError("no run configuration given; pass --config configs/runs/<name>.yaml", file=recipe)
    cfg = load_run_config(config, output=output)
    if "ingest" in stages and not cfg.input_files:
        raise ConfigError("no input files", file=config, key="inputs.folder")
    if "ingest" in stages:
        _check_bands_against_inputs(cfg, stages)
    if cfg.rig_profile is not None and "ingest" in stages:
        try:
            from fivid.io import load_rig_profile
        except ImportError:  # pragma: no cover - ingest not installed
            raise ConfigError("this fivid has no rig profiles (fivid.io.load_rig_profile)", file=config,
                              key="inputs.rig_profile") from None
        try:
            load_rig_profile(cfg.rig_profile)
        except FividError as exc:
            raise ConfigError(f"rig profile {cfg.rig_profile!r}: {exc}", file=config, key="inputs.rig_profile") from None
    if any(s in stages for s in ("modal", "simulate")):
        from fivid.fe import load_model

        try:
            load_model(cfg.model)
        except FividError as exc:
            raise ConfigError(f"model {str(cfg.model)!r}: {exc}", file=config, key="model") from None
    return Plan(path=Path(recipe), name=name, stages=stages, recipe_sha256=recipe_sha, config=cfg)
