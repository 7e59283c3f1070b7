"""The README's main job on the fine and on the coarse model, in one run (issue 30).

    python benchmarks/bench_pipeline.py [--repeats N] [--quick] [--force]

Runs ``fivid run pipelines/calibration.yaml --config configs/runs/sample.yaml`` (the README's main job: the
synthetic twin, simulated on the default 0.5 mm rig with the automatic solver path) and the same run
configuration with ``model`` set to the coarse 2 mm rig (``configs/models/triboair_coarse.yaml``), each in a
fresh process and a fresh output folder. First, per model, an untimed short ``fivid simulate`` of each solver path
(numba's compilation cache filled, as in bench_solver); then one cold job per model (empty cache: it builds the
reduced basis and the static preload, the README's first run), fine then coarse; then ``N`` warm jobs per model
(the same cache again: every later run, e.g. a new data set on the same rig), interleaved fine, coarse, fine,
coarse ... so that a drift of the machine's load hits both alike. A warm job scatters (the fine one 55-68 s run
to run at 1-minute load 0.3-1), hence the medians. Prints one JSON line:

- ``fine_wall_s``, ``coarse_wall_s``: the **median** wall clock of the warm jobs (the fine model on the warm
  reduced path); ``fine_vs_coarse_wall_ratio`` the ratio of these medians (acceptance <= 1.2);
  ``fine_wall_min_s`` / ``fine_wall_max_s`` (and coarse), every warm job's wall ``fine_walls_s`` /
  ``coarse_walls_s`` in run order, and ``wall_ratios`` the per-repeat ratios (fine over the coarse job run right
  after it); ``repeats`` N;
- ``fine_cold_wall_s``, ``coarse_cold_wall_s`` and ``fine_vs_coarse_cold_wall_ratio`` the same for the cold jobs
  (one each);
- ``fine_cpu_s``, ``fine_cold_cpu_s``, ... : user + system time of the job and every process it waited for
  (the dask workers; warm: the median over the repeats);
- ``discretisation_error_db``: the report's estimated model error of the fine (warm) run (``discretisation.json``
  key ``estimate_db``; acceptance <= 1), ``coarse_discretisation_error_db``; the verdicts, the solver paths and
  ``fine_simulate_stage_s`` / ``coarse_simulate_stage_s`` (the simulate stage's own wall time) and their ratio
  ``fine_vs_coarse_simulate_stage_ratio``;
- where the difference lives: ``fine_stages_s`` / ``coarse_stages_s`` (every stage's wall time [s]),
  ``fine_sim_task_mean_s`` / ``coarse_sim_task_mean_s`` (a simulate task's mean wall time on its worker: set-up,
  time loop, records) and their ratio ``fine_vs_coarse_sim_task_ratio``, and per simulation the solver steps
  (``fine_sim_steps``, ``coarse_sim_steps``: the fine rig's reduced step is 1.44 x the coarse one's, band-limited
  damping against classic Rayleigh), the reduced system's size and boundary nodes (``fine_reduced_size``,
  ``fine_reduced_boundary_nodes``, ``coarse_...``; means over the tasks, the boundary growing with the velocity's
  sliding range); ``fine_sim_tasks_s`` / ``coarse_sim_tasks_s`` every task's wall time by name, and
  ``fine_simulate_worker_busy`` / ``coarse_...`` the tasks' summed time over 2 workers x the simulate stage's wall
  (1: no worker idle; below it, the idle tail of an uneven split of the 12 tasks on the 2 workers); these per-job
  figures are the median-wall warm job's (for an even N the lower median's);
- ``load_average_1min`` at the start (the benchmark refuses to run above the core count unless ``--force``) and
  ``load_average_1min_end`` after the last job.

The README's figures (wall and CPU time of the main job) are ``fine_cold_wall_s`` and ``fine_cold_cpu_s``.
``--repeats`` defaults to 5 (about 12 min on an idle 2-core machine: ~1 min of warm-up, the two cold jobs ~2 min,
each warm pair ~1 min 45 s). ``--quick``: 0.15 s of simulated sliding, one seed and 2 repeats unless given (a smoke
run of the same code; its times are not the main job's).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _load_guard import parse_guarded  # noqa: E402  (benchmarks/, this script's folder)

#: dask workers of the jobs (``fivid run``'s default ``--workers``)
WORKERS = 2


def _config(tmp: Path, model: str, quick: bool) -> Path:
    """configs/runs/sample.yaml with absolute paths, ``model`` swapped in (and shortened with ``quick``)."""
    import yaml

    raw = yaml.safe_load((ROOT / "configs/runs/sample.yaml").read_text(encoding="utf-8"))
    runs = ROOT / "configs/runs"
    raw["inputs"]["folder"] = str((runs / raw["inputs"]["folder"]).resolve())
    raw["model"] = str((ROOT / "configs/models" / model).resolve())
    disc = raw.setdefault("discretisation", {})
    for key in ("convergence", "data_model"):
        if disc.get(key):
            disc[key] = str((runs / disc[key]).resolve())
    if quick:
        raw["simulate"]["duration"] = "0.15 s"
        raw["simulate"]["seeds"] = 1
    path = tmp / f"run-{Path(model).stem}.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False), encoding="utf-8")
    return path


def _simulate_tasks(out: Path) -> dict:
    """The simulate stage's tasks of the run in ``out``: their mean wall time on the worker [s] (the pipeline's cache
    records) and the mean solver steps and reduced-system sizes of the simulations they wrote (the files' attrs)."""
    import xarray as xr

    records = [json.loads(p.read_text(encoding="utf-8")) for p in sorted((out / ".fivid-cache" / "simulate").glob("*.json"))]
    attrs = []
    for rec in records:
        for item in rec.get("outputs", {}).values():
            with xr.open_dataset(item["path"]) as ds:
                attrs.append(dict(ds.attrs))
    mean = lambda key: (sum(float(a.get(key, 0)) for a in attrs) / len(attrs)) if attrs else None  # noqa: E731
    seconds = {r["task"]: float(r["seconds"]) for r in records}
    return {"task_mean_s": (sum(seconds.values()) / len(seconds)) if seconds else None,
            "task_sum_s": sum(seconds.values()), "tasks_s": seconds,
            "steps": mean("steps"), "reduced_size": mean("reduced_size"),
            "boundary_nodes": mean("reduced_boundary_nodes")}


def _job(config: Path, out: Path, cache: Path) -> dict:
    """Wall and CPU time of one pipeline run in a fresh process, and what its report says."""
    env = {**os.environ, "FIVID_CACHE_DIR": str(cache)}
    cmd = [sys.executable, "-m", "fivid", "run", str(ROOT / "pipelines/calibration.yaml"), "--config", str(config),
           "-o", str(out), "--no-progress", "--workers", str(WORKERS)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode not in (0, 3):  # 3: scores below thresholds, still a finished run
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr[-2000:]}")
    disc = json.loads((out / "discretisation.json").read_text(encoding="utf-8"))
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    return {"wall_s": wall, "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime),
            "estimate_db": disc.get("estimate_db"), "verdict": summary.get("verdict"),
            "solver_paths": disc.get("reduction", {}).get("paths"), "exit": proc.returncode,
            "simulate_stage_s": next((s["seconds"] for s in summary.get("stages", []) if s["name"] == "simulate"),
                                     None),
            "stages_s": {s["name"]: s["seconds"] for s in summary.get("stages", [])}, **_simulate_tasks(out)}


def _warm_kernels(model: str, tmp: Path) -> None:
    """Untimed: 1 ms of ``fivid simulate`` on each solver path of ``model`` (numba loads or compiles its kernels;
    the basis goes to a cache folder of its own)."""
    env = {**os.environ, "FIVID_CACHE_DIR": str(tmp / "cache-warmup")}
    for path in ([], ["--full"]):
        subprocess.run([sys.executable, "-m", "fivid", "simulate", str(ROOT / "configs/models" / model), "--duration",
                        "1 ms", "-o", str(tmp / "warmup.nc"), "--overwrite", *path], env=env, check=True,
                       stdout=subprocess.DEVNULL)


def _median_job(jobs: list[dict]) -> dict:
    """The job of median wall time (for an even count the lower median's)."""
    return sorted(jobs, key=lambda j: j["wall_s"])[(len(jobs) - 1) // 2]


def _ratio(a, b):
    """``a / b``, None when either is missing or zero."""
    return a / b if a and b else None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="0.15 s of sliding, one seed, 2 repeats (smoke run)")
    ap.add_argument("--repeats", type=int, default=None,
                    help="warm jobs per model, interleaved fine/coarse (default 5; 2 with --quick)")
    args, load = parse_guarded(ap, argv)
    repeats = args.repeats if args.repeats is not None else (2 if args.quick else 5)
    if repeats < 1:
        ap.error(f"--repeats must be >= 1, got {repeats}")
    models = {"fine": "triboair.yaml", "coarse": "triboair_coarse.yaml"}
    cold, warm = {}, {name: [] for name in models}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        configs = {}
        for name, model in models.items():
            _warm_kernels(model, tmp)
            configs[name] = _config(tmp, model, args.quick)
        for name in models:  # builds the basis and the preload
            cold[name] = _job(configs[name], tmp / f"{name}-cold", tmp / f"cache-{name}")
        for r in range(repeats):  # interleaved: a drift of the load hits both models alike
            for name in models:
                warm[name].append(_job(configs[name], tmp / f"{name}-warm{r}", tmp / f"cache-{name}"))
    load_end = round(os.getloadavg()[0], 2)
    walls = {name: [j["wall_s"] for j in jobs] for name, jobs in warm.items()}
    med = {name: statistics.median(w) for name, w in walls.items()}
    fine, coarse = _median_job(warm["fine"]), _median_job(warm["coarse"])
    cpu = {name: statistics.median(j["cpu_s"] for j in jobs) for name, jobs in warm.items()}
    out = {
        "benchmark": "pipeline",
        "quick": bool(args.quick),
        "repeats": repeats,
        "command": "fivid run pipelines/calibration.yaml --config configs/runs/sample.yaml",
        "fine_wall_s": med["fine"],
        "coarse_wall_s": med["coarse"],
        "fine_vs_coarse_wall_ratio": med["fine"] / med["coarse"],
        "fine_wall_min_s": min(walls["fine"]),
        "fine_wall_max_s": max(walls["fine"]),
        "coarse_wall_min_s": min(walls["coarse"]),
        "coarse_wall_max_s": max(walls["coarse"]),
        "fine_walls_s": walls["fine"],
        "coarse_walls_s": walls["coarse"],
        "wall_ratios": [f / c for f, c in zip(walls["fine"], walls["coarse"])],
        "fine_cold_wall_s": cold["fine"]["wall_s"],
        "coarse_cold_wall_s": cold["coarse"]["wall_s"],
        "fine_vs_coarse_cold_wall_ratio": cold["fine"]["wall_s"] / cold["coarse"]["wall_s"],
        "fine_cpu_s": cpu["fine"],
        "coarse_cpu_s": cpu["coarse"],
        "fine_cold_cpu_s": cold["fine"]["cpu_s"],
        "coarse_cold_cpu_s": cold["coarse"]["cpu_s"],
        "fine_simulate_stage_s": fine["simulate_stage_s"],
        "coarse_simulate_stage_s": coarse["simulate_stage_s"],
        "fine_vs_coarse_simulate_stage_ratio": _ratio(fine["simulate_stage_s"], coarse["simulate_stage_s"]),
        "fine_cold_simulate_stage_s": cold["fine"]["simulate_stage_s"],
        "fine_stages_s": fine["stages_s"],
        "coarse_stages_s": coarse["stages_s"],
        "fine_sim_task_mean_s": fine["task_mean_s"],
        "coarse_sim_task_mean_s": coarse["task_mean_s"],
        "fine_vs_coarse_sim_task_ratio": _ratio(fine["task_mean_s"], coarse["task_mean_s"]),
        "fine_sim_tasks_s": fine["tasks_s"],
        "coarse_sim_tasks_s": coarse["tasks_s"],
        "fine_simulate_worker_busy": _ratio(fine["task_sum_s"], WORKERS * (fine["simulate_stage_s"] or 0.0)),
        "coarse_simulate_worker_busy": _ratio(coarse["task_sum_s"], WORKERS * (coarse["simulate_stage_s"] or 0.0)),
        "fine_sim_steps": fine["steps"],
        "coarse_sim_steps": coarse["steps"],
        "fine_reduced_boundary_nodes": fine["boundary_nodes"],
        "coarse_reduced_boundary_nodes": coarse["boundary_nodes"],
        "fine_reduced_size": fine["reduced_size"],
        "coarse_reduced_size": coarse["reduced_size"],
        "discretisation_error_db": fine["estimate_db"],
        "coarse_discretisation_error_db": coarse["estimate_db"],
        "fine_verdict": fine["verdict"],
        "coarse_verdict": coarse["verdict"],
        "fine_solver_paths": fine["solver_paths"],
        "coarse_solver_paths": coarse["solver_paths"],
        "load_average_1min": load,
        "load_average_1min_end": load_end,
    }
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
