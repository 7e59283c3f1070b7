"""The pipeline's stages: each expands into cached tasks and runs the ones not in the cache.

A stage has ``plan(ctx) -> list[Task]`` (names, parameters, input digests and output paths, without
computing anything), ``execute(ctx, tasks)`` (run the given tasks, each ending with
``ctx.finish(task, seconds)``) and ``collect(ctx, tasks)`` (read what later stages need).

=========  ======================================  ==========================================
stage      one task per                             inputs hashed into its key
=========  ======================================  ==========================================
ingest     input CSV                                CSV sha256, rig profile
identify   pipeline run                             every ingested run, identify options
modal      distinct normal load of the conditions   model file, n_modes, normal load
simulate   test condition × Monte-Carlo seed        model file, law file, condition, seed, settings
score      test condition                           its measured runs and simulations, band
report     pipeline run                             everything above, thresholds
=========  ======================================  ==========================================

A test condition is a distinct (sliding velocity, normal load, roughness Ra) among the ingested runs.
"""

from __future__ import annotations

import json
import logging
import time
from pathlib import Path

from fivid.errors import ConfigError, FividError
from fivid.fe import load_model
from fivid.fe.modal import modal_analysis
from fivid.friction import load_law
from fivid.identify import identification_arguments, identify_friction_law
from fivid.identify.montecarlo import EnvelopeSpectrum
from fivid.io import load_rig_profile, read_rig_csv, read_run, write_run
from fivid.pipeline.cache import Task, file_sha256
from fivid.pipeline.discretisation import DEFAULT_TABLE, discretisation_estimate
from fivid.pipeline.montecarlo import SampleExecution, run_monte_carlo
from fivid.pipeline.scoring import score_condition
from fivid.pipeline.sweep import run_simulations, simulation_inputs
from fivid.report import render_report
from fivid.schema import new_history
from fivid.solver.preload_cache import cached_preload
from fivid.storage import write_json, write_netcdf

__all__ = ["STAGES", "condition_name", "evaluate_thresholds", "solver_path"]

log = logging.getLogger("fivid")


def condition_name(velocity: float, load: float, roughness: float) -> str:
    """File-safe name of a test condition, e.g. ``v10mm_s-fn5N-ra0.8um`` (SI inputs)."""
    return f"v{velocity * 1e3:.4g}mm_s-fn{load:.4g}N-ra{roughness * 1e6:.4g}um"


def evaluate_thresholds(scores: dict, thresholds) -> list[dict]:
    """Each condition's headline scores against each threshold, as check records."""
    return [
        {"condition": cond, "score": thr.score, "value": s.get(thr.score), "threshold": thr.describe(),
         "pass": thr.passes(s.get(thr.score))}
        for cond, s in sorted(scores.items()) for thr in thresholds
    ]


def _timed(ctx, task, fn) -> None:
    t0 = time.perf_counter()
    fn()
    ctx.finish(task, time.perf_counter() - t0)


def _progress(ctx, iterable, desc: str, total: int):
    from tqdm.auto import tqdm

    return tqdm(iterable, desc=desc, total=total, disable=None if ctx.progress is None else not ctx.progress,
                leave=False, unit="task")


class Ingest:
    """One task per input CSV: read it (rig profile applied), validate, write ``runs/<stem>.nc``."""

    name = "ingest"

    def plan(self, ctx) -> list[Task]:
        cfg = ctx.config
        profile = None
        if cfg.rig_profile is not None:  # keyed by the profile file's content, found by name or path
            found = load_rig_profile(cfg.rig_profile).path
            profile = {"profile": cfg.rig_profile, "sha256": file_sha256(found) if found else None}
        tasks, shas = [], {}
        for path in cfg.input_files:
            sha = file_sha256(path)
            shas[path.name] = sha
            tasks.append(Task("ingest", path.stem, {"profile": profile, "file": path.name}, {"csv": sha},
                              {"run": str(ctx.out / "runs" / f"{path.stem}.nc")}))
        ctx.data["input_sha256"] = shas
        ctx.data["input_paths"] = {t.name: p for t, p in zip(tasks, cfg.input_files)}
        return tasks

    def execute(self, ctx, tasks) -> None:
        (ctx.out / "runs").mkdir(parents=True, exist_ok=True)
        rejected = []
        for task in _progress(ctx, tasks, "ingest", len(tasks)):
            src = ctx.data["input_paths"][task.name]

            def work(src=src, task=task):
                ds = read_rig_csv(src, profile=ctx.config.rig_profile)
                write_run(ds, task.outputs["run"], overwrite=True)
            try:
                _timed(ctx, task, work)
            except FividError as exc:
                log.info("rejected %s: %s", src, exc)
                rejected.append(str(exc))
        if rejected:
            raise FividError(f"{len(rejected)} input file(s) rejected, nothing computed after ingest: "
                             + " | ".join(rejected))

    def collect(self, ctx, tasks) -> None:
        import xarray as xr

        runs = {}
        for task in tasks:
            with xr.open_dataset(task.outputs["run"], engine="netcdf4") as ds:
                a = ds.attrs
                runs[task.name] = {"path": task.outputs["run"], "run_id": a["run_id"],
                                   "sliding_velocity": float(a["sliding_velocity"]),
                                   "normal_load": float(a["normal_load"]), "roughness_ra": float(a["roughness_ra"]),
                                   "sample_rate": float(a["sample_rate"]), "sha256": ctx.digests["ingest"][task.name]["run"]}
        conditions: dict[str, dict] = {}
        for name, r in sorted(runs.items()):
            cond = condition_name(r["sliding_velocity"], r["normal_load"], r["roughness_ra"])
            c = conditions.setdefault(cond, {"sliding_velocity": r["sliding_velocity"], "normal_load": r["normal_load"],
                                             "roughness_ra": r["roughness_ra"], "runs": []})
            c["runs"].append(name)
        ctx.data["runs"], ctx.data["conditions"] = runs, conditions


class Identify:
    """Identify the friction law from every ingested run; writes ``law.nc`` and ``law.json``."""

    name = "identify"

    def plan(self, ctx) -> list[Task]:
        inputs = {f"run:{k}": v["run"] for k, v in sorted(ctx.digests["ingest"].items())}
        params = {k: (list(v) if isinstance(v, tuple) else v) for k, v in sorted(ctx.config.identify.items())}
        return [Task("identify", "law", params, inputs,
                     {"law": str(ctx.out / "law.nc"), "json": str(ctx.out / "law.json")})]

    def execute(self, ctx, tasks) -> None:
        task = tasks[0]

        def work():
            runs = [read_run(r["path"]) for _, r in sorted(ctx.data["runs"].items())]
            result = identify_friction_law(runs, **identification_arguments(ctx.config.identify))
            result.write(task.outputs["law"], overwrite=True)
            write_json(task.outputs["json"], result.to_json())
        _timed(ctx, task, work)

    def collect(self, ctx, tasks) -> None:
        text = Path(tasks[0].outputs["json"]).read_text(encoding="utf-8")
        ctx.data["law_summary"] = json.loads(text)
        ctx.data["law_path"] = tasks[0].outputs["law"]
        for message in ctx.data["law_summary"].get("warnings", []):  # also in summary.json's law.warnings
            log.warning("identify: %s", message)


class Modal:
    """Modal analysis of the model linearised about its preloaded contact state, one per distinct normal load of
    the test conditions (frequencies [Hz] to compare with measured peaks); writes ``modal.nc`` (one load) or
    ``modal-fn<load>N.nc`` (several)."""

    name = "modal"

    def plan(self, ctx) -> list[Task]:
        cfg = ctx.config
        loads = sorted({float(c["normal_load"]) for c in ctx.data["conditions"].values()})
        model_sha = file_sha256(cfg.model)
        tasks = []
        for load in loads:
            name = "modal" if len(loads) == 1 else f"modal-fn{load:.4g}N"
            tasks.append(Task("modal", name, {"n_modes": cfg.n_modes, "normal_load": load}, {"model": model_sha},
                              {"modes": str(ctx.out / f"{name}.nc")}))
        return tasks

    def execute(self, ctx, tasks) -> None:
        model = load_model(ctx.config.model)
        for task in tasks:
            _timed(ctx, task, lambda t=task: write_netcdf(_modes(model, ctx.config.n_modes, t.params["normal_load"]),
                                                          t.outputs["modes"]))

    def collect(self, ctx, tasks) -> None:
        # the report shows one modal analysis: that of the lowest load (all of them when the loads agree)
        ctx.data["modal_path"] = tasks[0].outputs["modes"] if tasks else None
        ctx.data["modal_paths"] = {t.params["normal_load"]: t.outputs["modes"] for t in tasks}


def _modes(model, n_modes: int, normal_load: float):
    """The modal analysis about the contact state under ``normal_load`` [N], that state read from the preload cache
    when an earlier run solved it (:func:`fivid.solver.preload_cache.cached_preload`, each pair's ``mu``)."""
    preload = cached_preload(model, normal_load)[0] if model.contacts else None
    return modal_analysis(model, n_modes=n_modes, include_contact=True, normal_load=normal_load, preload=preload)


def envelope_samples(config) -> int:
    """``simulate.samples`` of the run configuration: Monte-Carlo samples of the law's uncertainty per test
    condition (0, the default: no envelope)."""
    node = config.raw.get("simulate") or {}
    value = node.get("samples", 0) if isinstance(node, dict) else 0
    if isinstance(value, bool) or not isinstance(value, int) or not (value == 0 or 2 <= value <= 10000):
        raise ConfigError(f"simulate.samples must be 0 (off) or an integer in [2, 10000], got {value!r}",
                          file=getattr(config, "path", None), key="simulate.samples")
    return value


def solver_path(config) -> dict:
    """The solver-path arguments of :func:`fivid.solver.simulate` from ``simulate.solver`` (auto, full, reduced) and
    ``simulate.reduced_tolerance`` [dB] of the run configuration, the estimate's band being the scoring band (part
    of the simulate tasks' parameters, hence of their cache keys)."""
    solver = getattr(config, "solver", "auto")  # a hand-built config (tests) may lack them: the defaults
    return {"reduced": {"full": None}.get(solver, solver),
            "reduced_tolerance": float(getattr(config, "reduced_tolerance", 0.5)),
            "error_band": [float(b) for b in config.band] if hasattr(config, "band") else None}


class Simulate:
    """One simulation per test condition and Monte-Carlo seed, spread over dask workers; with
    ``simulate.samples`` N > 0 also one Monte-Carlo envelope per condition (N draws of the law's uncertainty,
    :func:`fivid.pipeline.montecarlo.run_monte_carlo`)."""

    name = "simulate"

    def plan(self, ctx) -> list[Task]:
        cfg = ctx.config
        model_sha = file_sha256(cfg.model)
        law_sha = ctx.digests["identify"]["law"]["law"]
        tasks = []
        for cond, c in sorted(ctx.data["conditions"].items()):
            for seed in cfg.seeds:
                params = {"sliding_velocity": c["sliding_velocity"], "normal_load": c["normal_load"],
                          "roughness_ra": c["roughness_ra"], "seed": seed, "duration": cfg.duration,
                          "sample_rate": cfg.sample_rate, "run_id": f"{cond}-seed{seed}", **solver_path(cfg)}
                tasks.append(Task("simulate", f"{cond}-seed{seed}", params, {"model": model_sha, "law": law_sha},
                                  {"sim": str(ctx.out / "sims" / f"{cond}-seed{seed}.nc")}))
            samples = envelope_samples(cfg)
            if samples:
                params = {"sliding_velocity": c["sliding_velocity"], "normal_load": c["normal_load"],
                          "roughness_ra": c["roughness_ra"], "samples": samples, "seed": cfg.seeds[0],
                          "duration": cfg.duration, "sample_rate": cfg.sample_rate, "nperseg": cfg.nperseg,
                          "settle": cfg.settle, **solver_path(cfg)}
                tasks.append(Task("simulate", f"{cond}-envelope", params, {"model": model_sha, "law": law_sha},
                                  {"envelope": str(ctx.out / "sims" / f"{cond}-envelope.nc")}))
        return tasks

    def execute(self, ctx, tasks) -> None:
        (ctx.out / "sims").mkdir(parents=True, exist_ok=True)
        sims = [t for t in tasks if "sim" in t.outputs]
        if sims:
            run_simulations(ctx, sims)
        for task in [t for t in tasks if "envelope" in t.outputs]:
            _timed(ctx, task, lambda task=task: _envelope(ctx, task))

    def collect(self, ctx, tasks) -> None:
        sims: dict[str, list[str]] = {}
        envelopes: dict[str, str] = {}
        for task in tasks:
            if "envelope" in task.outputs:
                envelopes[task.name.rsplit("-envelope", 1)[0]] = task.outputs["envelope"]
                continue
            cond = task.name.rsplit("-seed", 1)[0]
            sims.setdefault(cond, []).append(task.outputs["sim"])
        ctx.data["sims"] = sims
        ctx.data["envelopes"] = envelopes


def _envelope(ctx, task) -> None:
    """One condition's Monte-Carlo envelope, written to the task's output."""
    p = dict(task.params)
    law_path = ctx.data["law_path"]
    condition, schedule, integration = simulation_inputs(p)
    env = run_monte_carlo(load_model(ctx.config.model), load_law(law_path), condition, schedule, samples=p["samples"],
                          seed=p["seed"], integration=integration,
                          spectrum=EnvelopeSpectrum(nperseg=p["nperseg"], settle=p["settle"]),
                          execution=SampleExecution(ctx.workers, ctx.scheduler, ctx.progress),
                          attrs={"law_file": str(law_path), "law_file_sha256": file_sha256(law_path),
                                 "model": str(ctx.config.model), "history": new_history(
                                     f"fivid pipeline: Monte-Carlo envelope {task.name}, {p['samples']} samples")})
    write_netcdf(env, task.outputs["envelope"], overwrite=True)


class Score:
    """Per test condition: PSD scores of every simulation seed against every measured run."""

    name = "score"

    def plan(self, ctx) -> list[Task]:
        cfg = ctx.config
        tasks = []
        for cond, c in sorted(ctx.data["conditions"].items()):
            inputs = {f"run:{r}": ctx.digests["ingest"][r]["run"] for r in c["runs"]}
            for t in ctx.tasks["simulate"].values():
                if t.name.rsplit("-seed", 1)[0] == cond:
                    inputs[f"sim:{t.name}"] = ctx.digests["simulate"][t.name]["sim"]
            tasks.append(Task("score", cond, {"band": list(cfg.band), "nperseg": cfg.nperseg, "settle": cfg.settle},
                              inputs,
                              {"scores": str(ctx.out / "scores" / f"{cond}.json"),
                               "psd": str(ctx.out / "scores" / f"{cond}-psd.nc")}))
        return tasks

    def execute(self, ctx, tasks) -> None:
        (ctx.out / "scores").mkdir(parents=True, exist_ok=True)
        for task in _progress(ctx, tasks, "score", len(tasks)):
            c = ctx.data["conditions"][task.name]
            measured = [ctx.data["runs"][r]["path"] for r in c["runs"]]
            simulated = ctx.data["sims"][task.name]

            def work(task=task, measured=measured, simulated=simulated):
                scores, psd = score_condition(measured, simulated, band=ctx.config.band, nperseg=ctx.config.nperseg,
                                               settle=ctx.config.settle)
                write_netcdf(psd, task.outputs["psd"])
                write_json(task.outputs["scores"], scores)
            _timed(ctx, task, work)

    def collect(self, ctx, tasks) -> None:
        scores = {}
        for task in tasks:
            scores[task.name] = json.loads(Path(task.outputs["scores"]).read_text(encoding="utf-8"))["summary"]
        ctx.data["scores"] = scores


class Report:
    """The validation report ``report.html`` (self-contained)."""

    name = "report"

    def plan(self, ctx) -> list[Task]:
        inputs = {f"{stage}:{task}:{label}": sha for stage, d in sorted(ctx.digests.items())
                  for task, outs in sorted(d.items()) for label, sha in sorted(outs.items())}
        table = convergence_table(ctx.config)
        inputs["model"] = file_sha256(ctx.config.model)
        inputs["convergence_table"] = file_sha256(table) if table is not None and table.is_file() else None
        params = {"thresholds": [t.describe() for t in ctx.config.thresholds], "band": list(ctx.config.band),
                  "nperseg": ctx.config.nperseg, "config_sha256": ctx.config.sha256,
                  "convergence_table": str(table) if table is not None else None,
                  "data_model": None if ctx.config.data_model is None else file_sha256(ctx.config.data_model)}
        return [Task("report", "report", params, inputs,
                     {"html": str(ctx.out / "report.html"), "discretisation": str(ctx.out / "discretisation.json")})]

    def execute(self, ctx, tasks) -> None:
        task = tasks[0]
        checks = evaluate_thresholds(ctx.data.get("scores", {}), ctx.config.thresholds)

        def work():
            cfg = ctx.config
            est = discretisation_estimate(cfg.model, cfg.band, convergence_table(cfg),
                                          bin_width=cfg.sample_rate / cfg.nperseg)
            est.update(model_error_estimate(est, cfg, ctx.data.get("sims", {}), checks))
            write_json(task.outputs["discretisation"], est)
            ctx.data["discretisation"] = est
            render_report(task.outputs["html"], ctx_to_report_inputs(ctx, checks))
        _timed(ctx, task, work)

    def collect(self, ctx, tasks) -> None:
        ctx.data["report_path"] = tasks[0].outputs["html"]
        ctx.data["discretisation"] = json.loads(Path(tasks[0].outputs["discretisation"]).read_text(encoding="utf-8"))


def _reduction_record(sim_paths) -> dict:
    """The solver paths of the simulations and the largest estimated in-band error of the reduced ones [dB]."""
    import math

    import xarray as xr

    paths, estimates, tol = {}, [], None
    for path in sim_paths:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            a = ds.attrs
            paths[a.get("solver_path", "full")] = paths.get(a.get("solver_path", "full"), 0) + 1
            if a.get("solver_path") == "reduced" and math.isfinite(float(a.get("reduced_error_estimate_db", math.nan))):
                estimates.append(float(a["reduced_error_estimate_db"]))
            tol = a.get("reduced_error_tolerance_db", tol)
    return {"paths": paths, "estimate_db": max(estimates) if estimates else 0.0,
            "tolerance_db": None if tol is None else float(tol)}


def model_error_estimate(est: dict, cfg, sims: dict, checks: list) -> dict:
    """What the report states about the simulated model's own error in the scoring band (issue 30 item 3):

    - ``reduction``: the simulations' solver paths and the largest estimated error of the reduced ones
      (:mod:`fivid.solver.reduced_error`);
    - ``estimate_db``, ``estimate_reference``: the total estimate against the reference that matters for these
      data -- with ``discretisation.data_model`` the same model file as the simulated one (synthetic twin data),
      the mesh adds nothing against the data and only the reduction remains; otherwise the convergence table's
      band-level error (against the extrapolated continuum) plus the reduction's;
    - ``direct_check``: the largest ``|level_diff_db|`` of the scores (simulated against measured, the direct
      comparison) and the level threshold, and ``consistent``: whether the estimate is below that threshold (a
      model error the size of the threshold would decide the verdict, not the model's physics).
    """
    red = _reduction_record([p for paths in sims.values() for p in paths])
    mesh = est.get("band_level_error_db") if est.get("covered") else None
    same = cfg.data_model is not None and file_sha256(cfg.data_model) == file_sha256(cfg.model)
    if same:
        total, reference = red["estimate_db"], (f"the model that generated the data ({cfg.data_model.name}, the same "
                                                "file as the simulated one): mesh error nil, the reduction's remains")
    elif mesh is not None:
        total, reference = float(mesh) + red["estimate_db"], ("the convergence table's band level against the "
                                                              "extrapolated continuum, plus the reduction's")
    else:
        total, reference = None, "not estimated (no convergence table covers the model)"
    levels = [c for c in checks if c["score"] == "level_diff_db" and c["value"] is not None]
    direct = {"largest_abs_level_diff_db": max((abs(float(c["value"])) for c in levels), default=None),
              "level_threshold": levels[0]["threshold"] if levels else None}
    limit = next((float(t.value) for t in cfg.thresholds if t.score == "level_diff_db"), None)
    return {"reduction": red, "estimate_db": total, "estimate_reference": reference,
            "mesh_against_continuum_db": None if mesh is None else float(mesh), "direct_check": direct,
            "level_threshold_db": limit,
            "consistent": None if total is None or limit is None else bool(total < limit)}


def convergence_table(cfg) -> Path | None:
    """The convergence table of the run: ``discretisation.convergence`` of the run configuration (relative to it;
    null: none), by default ``convergence.json`` next to it (:mod:`fivid.pipeline.discretisation`)."""
    node = cfg.raw.get("discretisation") or {}
    name = node.get("convergence", DEFAULT_TABLE) if isinstance(node, dict) else DEFAULT_TABLE
    if name is None:
        return None
    path = Path(name)
    base = Path(cfg.path).resolve().parent if cfg.path is not None else Path.cwd()
    return path if path.is_absolute() else base / path


def ctx_to_report_inputs(ctx, checks) -> dict:
    """Everything the report shows, as plain data and file paths (the report layer knows no pipeline)."""
    cfg = ctx.config
    return {
        "title": f"fivid validation report — {ctx.plan.name}",
        "synthetic_note": cfg.raw.get("description"),
        "provenance": {
            "pipeline": {"path": str(ctx.plan.path), "sha256": ctx.plan.recipe_sha256, "stages": list(ctx.plan.stages)},
            "config": {"path": str(cfg.path), "sha256": cfg.sha256, "content": cfg.raw},
            "model": {"path": str(cfg.model), "sha256": file_sha256(cfg.model)},
            "discretisation": ctx.data.get("discretisation"),
            "inputs": ctx.data.get("input_sha256", {}),
            "settings": effective_settings(ctx),
        },
        "runs": ctx.data.get("runs", {}),
        "conditions": ctx.data.get("conditions", {}),
        "law_path": ctx.data.get("law_path"),
        "law_summary": ctx.data.get("law_summary"),
        "modal_path": ctx.data.get("modal_path"),
        "sims": ctx.data.get("sims", {}),
        "scores": ctx.data.get("scores", {}),
        "score_files": {t.name: t.outputs["scores"] for t in ctx.tasks.get("score", {}).values()},
        "psd_files": {t.name: t.outputs["psd"] for t in ctx.tasks.get("score", {}).values()},
        "envelope_files": ctx.data.get("envelopes", {}),
        "band": cfg.band,
        "nperseg": cfg.nperseg,
        "checks": checks,
    }


def effective_settings(ctx) -> dict:
    """The settings the run used (config values after defaults and command-line overrides), SI units."""
    cfg = ctx.config
    return {
        "output folder": str(ctx.out),
        "inputs": f"{cfg.input_folder / cfg.input_pattern} ({len(cfg.input_files)} files)",
        "rig profile": cfg.rig_profile or "fivid-rig-csv (none)",
        "model": str(cfg.model),
        "scoring band [Hz]": list(cfg.band),
        "Welch nperseg [samples]": cfg.nperseg,
        "settle [s]": cfg.settle,
        "identify": dict(cfg.identify),
        "modes": cfg.n_modes,
        "simulated duration [s]": cfg.duration,
        "simulated sample rate [Hz]": cfg.sample_rate,
        "seeds": list(cfg.seeds),
        "thresholds": [t.describe() for t in cfg.thresholds],
        "workers": ctx.workers if ctx.scheduler is None else f"scheduler {ctx.scheduler}",
    }


STAGES = {s.name: s for s in (Ingest(), Identify(), Modal(), Simulate(), Score(), Report())}
