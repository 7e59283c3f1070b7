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
import os
from dataclasses import dataclass, field
from pathlib import Path

from typing import Annotated, Literal

from pydantic import AfterValidator, BeforeValidator, Field, WithJsonSchema, model_validator

from fivid import config_layer
from fivid.config_layer import ConfigModel, Name, Number, Problems, Quantity, fail, validate
from fivid.errors import ConfigError, FividError
from fivid.execution.resources import check_simulation_memory, simulation_memory
from fivid.fe import load_model
from fivid.friction.amplitude import AMPLITUDE_FORMS
from fivid.io import load_rig_profile, read_rig_head
from fivid.io.rig_csv import as_rig_profile
from fivid.signal.welch import default_nperseg
from fivid.solver.options import DEFAULT_REDUCED_TOLERANCE, ReducedToleranceField, SolverPathField

__all__ = [
    "STAGE_REQUIRES",
    "Plan",
    "RunConfig",
    "RunConfigModel",
    "RecipeConfig",
    "Threshold",
    "load_plan",
    "load_recipe",
    "load_run_config",
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
    solver: str = "auto"
    reduced_tolerance: float = DEFAULT_REDUCED_TOLERANCE
    data_model: Path | None = None


@dataclass(frozen=True)
class Plan:
    """A validated recipe plus its run configuration."""

    path: Path | None
    name: str
    stages: tuple[str, ...]
    recipe_sha256: str
    config: RunConfig
    extra: dict = field(default_factory=dict)


def line_of_key(path, key: str) -> int | None:
    """The 1-based line of config ``key`` (``simulate.duration``) in the YAML file ``path``.

    A key that is not in the file (a required one left out) gives the line of its closest parent;
    None when there is none or the file cannot be read. Called only when reporting an error.
    """
    try:
        return config_layer.read_yaml(path, "config", mapping=False).line(key)
    except ConfigError:
        return None


# ---------------------------------------------------------------------------------------------- the recipe


def _stage(value):
    if value not in STAGE_REQUIRES:
        raise fail(f"unknown stage {value!r}; expected one of {', '.join(STAGE_REQUIRES)}")
    return value


Stage = Annotated[str, AfterValidator(_stage), WithJsonSchema({"enum": list(STAGE_REQUIRES)})]


class RecipeConfig(ConfigModel):
    """A pipeline recipe (``pipelines/*.yaml``): which stages run, in which order."""

    fivid_pipeline: Literal[1] = Field(alias="fivid-pipeline", description="recipe format version")
    name: Name | None = None
    description: str = ""
    stages: Annotated[list[Stage], Field(min_length=1)]

    @model_validator(mode="after")
    def _order(self):
        seen: list[str] = []
        for i, stage in enumerate(self.stages):
            if stage in seen:
                raise fail(f"stage {stage!r} is listed twice; expected each stage once", at=("stages", i))
            missing = [r for r in STAGE_REQUIRES[stage] if r not in seen]
            if missing:
                raise fail(f"stage {stage!r} needs {', '.join(missing)} listed before it", at=("stages", i))
            seen.append(stage)
        return self


def load_recipe(path: str | os.PathLike) -> tuple[str, tuple[str, ...], str, dict]:
    """Read and check a recipe; returns ``(name, stages, sha256, raw)``."""
    source = config_layer.read_yaml(path, "pipeline recipe")
    recipe = validate(RecipeConfig, source)
    return str(recipe.name or Path(path).stem), tuple(recipe.stages), source.sha256, source.data


# ---------------------------------------------------------------------------------------------- the run config


def _resolve(base: Path, value) -> Path:
    p = Path(os.path.expanduser(str(value)))
    return Path(os.path.normpath(p if p.is_absolute() else (base / p)))


def _pair(units: str, example: str, *, positive: bool):
    """A ``[low, high]`` pair of quantities, increasing."""

    def check(pair):
        if not pair[0] < pair[1]:
            raise fail(f"expected an increasing pair [low, high] such as {example}, found {pair!r} ({units})")
        return list(pair)  # the type is a list: a tuple here makes every model_dump warn (issue 32 item 6)

    item = Quantity(units, positive=positive, nonnegative=not positive)
    return Annotated[list[item], Field(min_length=2, max_length=2), AfterValidator(check)]


def _int_range(lo: int, hi: int):
    return Annotated[int, Field(ge=lo, le=hi)]


def _open_range(lo: float, hi: float):
    return Annotated[Number, Field(gt=lo, lt=hi)]


class _Inputs(ConfigModel):
    folder: str
    pattern: str = "*.csv"
    rig_profile: str | None = Field(None, description="a rig profile name (configs/rigs/) or the path of one")


class _Analysis(ConfigModel):
    band: _pair("Hz", "[500 Hz, 20 kHz]", positive=True) = [100.0, 20000.0]
    nperseg: _int_range(64, 2**22) | None = Field(
        None, description="Welch segment length [samples]; default: the one rule (fivid.signal.welch.default_nperseg) "
                          "on the simulated steady part")
    settle: Quantity("s", nonnegative=True) = 0.0


def _amplitude_form(value):
    if value not in AMPLITUDE_FORMS:
        raise fail(f"unknown amplitude form {value!r}; expected one of {', '.join(AMPLITUDE_FORMS)}")
    return value


class _Identify(ConfigModel):
    """Keyword arguments of :func:`fivid.identify.identify_friction_law` (only the keys given are passed)."""

    band: _pair("Hz", "[100 Hz, 5 kHz]", positive=False) = None
    tare: _pair("s", "[0 s, 15 ms]", positive=False) = None
    nperseg: _int_range(64, 2**22) = 4096
    tolerance: _open_range(0.0, 1.0) = None
    min_normal_force: Quantity("N", positive=True) | None = None
    mains_frequency: Quantity("Hz", positive=True) | None = None
    shape_method: Literal["smoothed", "rolloff"] = "smoothed"
    smoothing_octaves: _open_range(0.0, 4.0) = None
    forms: Annotated[list[Annotated[str, AfterValidator(_amplitude_form)]], Field(min_length=1)] = None
    weighting: Literal["none", "estimator"] = "none"
    injection: Literal["uniform", "per_node", "convected"] = "uniform"
    confidence: _open_range(0.5, 0.9999) = None


def _seeds(value):
    if isinstance(value, int) and not isinstance(value, bool):
        if 1 <= value <= 1000:
            return tuple(range(value))
    elif isinstance(value, list) and value and all(isinstance(s, int) and not isinstance(s, bool) and s >= 0
                                                   for s in value) and len(set(value)) == len(value):
        return tuple(value)
    raise fail(f"expected a count in [1, 1000] or a list of distinct non-negative integers, found {value!r}")


def _samples(value):
    if value == 0 or 2 <= value <= 10000:
        return value
    raise fail(f"expected 0 (off) or an integer in [2, 10000], found {value!r}")


class _Simulate(ConfigModel):
    duration: Quantity("s", positive=True) = 0.5
    sample_rate: Quantity("Hz", positive=True) = 51200.0
    seeds: Annotated[tuple, BeforeValidator(_seeds), WithJsonSchema({"anyOf": [
        {"type": "integer", "minimum": 1, "maximum": 1000},
        {"type": "array", "items": {"type": "integer", "minimum": 0}, "minItems": 1, "uniqueItems": True}]})] = (0,)
    samples: Annotated[int, AfterValidator(_samples), WithJsonSchema({"anyOf": [
        {"const": 0}, {"type": "integer", "minimum": 2, "maximum": 10000}]})] = Field(
        0, description="Monte-Carlo samples of the law's uncertainty per condition (0: off; docs/uncertainty.md)")
    solver: SolverPathField = "auto"
    reduced_tolerance: ReducedToleranceField = DEFAULT_REDUCED_TOLERANCE


class _Discretisation(ConfigModel):
    convergence: str | None = Field("convergence.json", description="convergence table, relative to this file "
                                                                     "(null: none; docs/pipeline.md)")
    data_model: str | None = Field(None, description="the model config that generated the input data (synthetic twin "
                                                     "data), relative to this file: the discretisation error is then "
                                                     "estimated against it (docs/pipeline.md)")


class _Modal(ConfigModel):
    n_modes: _int_range(1, 200) = 8


def _bound(kind: str):
    """A threshold ``{max: 4}`` (``max_abs``, ``min``) -> its number."""

    def parse(value):
        if not isinstance(value, dict) or set(value) != {kind} or isinstance(value[kind], bool) \
                or not isinstance(value[kind], (int, float)):
            raise fail(f"expected {{{kind}: <number>}}, found {value!r}")
        return float(value[kind])

    schema = {"type": "object", "properties": {kind: {"type": "number"}}, "required": [kind],
              "additionalProperties": False}
    return Annotated[float, BeforeValidator(parse), WithJsonSchema(schema)]


class _Thresholds(ConfigModel):
    """Pass/fail bounds on the scores (DESIGN §6)."""

    lsd_db: _bound("max") | None = None
    level_diff_db: _bound("max_abs") | None = None
    band_level_rms_error_db: _bound("max") | None = None
    shape_correlation: _bound("min") | None = None


class RunConfigModel(ConfigModel):
    """A run configuration (``configs/runs/*.yaml``): the numbers of a pipeline run."""

    fivid_run: Literal[1] = Field(1, alias="fivid-run", description="run-config format version")
    description: str = ""
    inputs: _Inputs
    model: str = Field(description="the FE model config, relative to this file")
    output: str | None = Field(None, description="output folder, relative to this file (created if missing)")
    analysis: _Analysis = _Analysis()
    identify: _Identify = _Identify()
    modal: _Modal = _Modal()
    simulate: _Simulate = _Simulate()
    thresholds: _Thresholds = _Thresholds()
    discretisation: _Discretisation = _Discretisation()

    @model_validator(mode="after")
    def _consistent(self):
        sim, analysis = self.simulate, self.analysis
        if analysis.band[1] > sim.sample_rate / 2:
            raise fail(f"upper edge {analysis.band[1]:g} Hz is above {sim.sample_rate / 2:g} Hz, the Nyquist frequency "
                       f"of simulate.sample_rate: the simulated PSD stops there; expected the band's upper edge lowered "
                       "or simulate.sample_rate raised", at=("analysis", "band"))
        if (sim.duration - analysis.settle) * sim.sample_rate < _nperseg(self):
            raise fail(f"{sim.duration:g} s less analysis.settle at {sim.sample_rate:g} Hz gives fewer samples than "
                       f"analysis.nperseg = {_nperseg(self)}; expected a longer duration or a lower nperseg",
                       at=("simulate", "duration"))
        return self


def _nperseg(cfg: RunConfigModel) -> int:
    """analysis.nperseg, or the one default rule on the simulated steady part (duration less settle)."""
    a, sim = cfg.analysis, cfg.simulate
    if a.nperseg is not None:
        return a.nperseg
    return default_nperseg(sim.sample_rate, max(0, int((sim.duration - a.settle) * sim.sample_rate)))


def load_run_config(path: str | os.PathLike | None, *, output: str | os.PathLike | None = None) -> RunConfig:
    """Read and check a run configuration (every problem at once, with key paths).

    Parameters
    ----------
    path : path-like
        The YAML file.
    output : path-like, optional
        Override of the ``output`` key (e.g. from the command line).
    """
    source = config_layer.read_yaml(path, "run configuration")
    raw = source.data
    base = Path(path).resolve().parent
    problems = Problems(source)
    cfg = validate(RunConfigModel, source, problems)
    if cfg is None:
        problems.raise_if_any()
    if output is None and cfg.output is None:
        problems.add("output", "is required (missing): the output folder (or give one on the command line)")

    folder = _resolve(base, cfg.inputs.folder)
    pattern = cfg.inputs.pattern
    files: tuple[Path, ...] = ()
    if not folder.is_dir():
        problems.add("inputs.folder", f"expected an existing folder, found none at {str(folder)!r}")
    else:
        files = tuple(sorted(p for p in folder.iterdir() if p.is_file() and fnmatch.fnmatch(p.name, pattern)))
        if not files:
            problems.add("inputs.pattern", f"no file in {str(folder)!r} matches {pattern!r}")
    profile = cfg.inputs.rig_profile
    if profile is not None and ("/" in profile or profile.endswith((".yaml", ".yml"))):
        resolved = _resolve(base, profile)
        if not resolved.is_file():
            problems.add("inputs.rig_profile", f"rig profile file {str(resolved)!r} does not exist")
        profile = str(resolved)

    model = _resolve(base, cfg.model)
    if not model.is_file():
        problems.add("model", f"model file {str(model)!r} does not exist")
    data_model = _resolve(base, cfg.discretisation.data_model) if cfg.discretisation.data_model else None
    if data_model is not None and not data_model.is_file():
        problems.add("discretisation.data_model", f"model file {str(data_model)!r} does not exist")

    out = Path(output) if output is not None else _resolve(base, cfg.output or "out")
    if out.exists() and not out.is_dir():
        problems.add("output", f"output {str(out)!r} exists and is not a folder; name a folder (it is created if "
                               "missing)")
    problems.raise_if_any()

    identify = cfg.identify.model_dump(exclude_unset=True)
    for name in ("band", "tare", "forms"):
        if identify.get(name) is not None:
            identify[name] = tuple(identify[name])
    thresholds = []
    for name in (raw.get("thresholds") or {}):  # in the order of the file
        thresholds.append(Threshold(name, _SCORE_KINDS[name], getattr(cfg.thresholds, name)))
    a, sim = cfg.analysis, cfg.simulate
    return RunConfig(
        path=Path(path), sha256=source.sha256, raw=raw, input_folder=folder, input_pattern=pattern, input_files=files,
        rig_profile=profile, model=model, output=out, band=tuple(a.band), nperseg=_nperseg(cfg), settle=a.settle,
        identify=identify, n_modes=cfg.modal.n_modes, duration=sim.duration, sample_rate=sim.sample_rate,
        seeds=tuple(sim.seeds), thresholds=tuple(thresholds), solver=sim.solver,
        reduced_tolerance=float(sim.reduced_tolerance), data_model=data_model,
    )


def _check_simulation_size(cfg: RunConfig, model) -> None:
    """Refuse, at plan time, a simulate stage whose runs cannot fit in memory or time (fivid.execution.resources)."""
    try:
        size = simulation_memory(model, duration=cfg.duration, sample_rate=cfg.sample_rate)
        runs = len(cfg.seeds) * max(1, len(cfg.input_files))  # every test condition with every seed
        check_simulation_memory(size, key="simulate.duration", n_dofs=2 * model.n_nodes, runs=runs)
    except ConfigError as exc:
        raise ConfigError(exc.message, file=cfg.path, line=line_of_key(cfg.path, "simulate.duration"),
                          key="simulate.duration") from None


def _check_bands_against_inputs(cfg: RunConfig, stages) -> None:
    """Refuse an identify or analysis band above the Nyquist frequency of an input file's stated sample rate.

    Only the files' heads are read (:func:`fivid.io.read_rig_head`); a file whose head is bad, or that
    states no sample rate, is left to the ingest stage to report.
    """
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
            load_rig_profile(cfg.rig_profile)
        except FividError as exc:
            raise ConfigError(f"rig profile {cfg.rig_profile!r}: {exc}", file=config, key="inputs.rig_profile") from None
    if any(s in stages for s in ("modal", "simulate")):
        try:
            model = load_model(cfg.model)
        except FividError as exc:
            raise ConfigError(f"model {str(cfg.model)!r}: {exc}", file=config, key="model") from None
        if "simulate" in stages:
            _check_simulation_size(cfg, model)
    return Plan(path=Path(recipe), name=name, stages=stages, recipe_sha256=recipe_sha, config=cfg)
