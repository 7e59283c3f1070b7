"""Cost of one roughness-noise study point (issue 15), next to the default rig, measured in one run.

    python benchmarks/bench_rough.py [--quick]

Prints one JSON line. The rough model is the study's (``configs/studies/roughness_noise.yaml``): the pair of
``configs/models/rough_pair_graded.yaml`` built by :func:`fivid.study.roughness.build_point_model` for one point
(Ra 4.5 um, Rsm level 200 um, 1 N dead load, 10 cm/s), or ``rough_pair_graded_quick.yaml`` with ``--quick``
(the study's ``--quick`` model). Both it and the default rig (``configs/models/triboair.yaml``, the run of
``benchmarks/bench_solver.py``: 5 N, 1 cm/s) run a short preload-and-slide record, interleaved, best of the
rounds (the machine is shared): ``rough_dof_updates_per_s`` and ``default_dof_updates_per_s`` (dofs x steps / wall
time of the whole run), their ratio ``rough_over_default``, the rough model's ``rough_dofs``,
``rough_time_step_s`` (the stable step of its smallest element), ``rough_steps_per_point`` (the study's 4.2 ms
record, or the quick study's 1.2 ms, over that step) and ``rough_point_projected_s`` (those steps at the measured
rate: the simulation time of one study point; ``rough_point_projected_cpu_s`` the same from the process's CPU
time, which a shared machine's load does not inflate, as are the ``*_cpu_dof_updates_per_s`` and
``rough_over_default_cpu``), with the contact's mean Gauss-Seidel sweeps per step.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from _load_guard import parse_guarded  # benchmarks/, this script's folder

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="the quick study's model and shorter runs (noisier)")
    args, load = parse_guarded(ap, argv)

    from fivid.fe import load_model
    from fivid.solver import FrictionInput, IntegrationOptions, OperatingCondition, RunSchedule
    from fivid.solver.driver import prepare_run
    from fivid.study.config import load_study
    from fivid.study.roughness import ROUGHNESS_TASK, build_point_model

    study = load_study(ROOT / "configs/studies/roughness_noise.yaml", quick=args.quick)
    spec = {**ROUGHNESS_TASK, **study.points["roughness"]}
    conditions = {"roughness_ra": 4.5e-6, "sliding_velocity": 0.1, "normal_load": 1.0, "seed": 0}
    rough, _, _, _ = build_point_model(study.model_path, spec, conditions)
    default = load_model(ROOT / "configs/models/triboair.yaml")

    duration = 0.3e-3 if args.quick else 1e-3  # the rough record; the start-up ramps are 0.2 ms
    rough_prep = prepare_run(rough, OperatingCondition(sliding_velocity=conditions["sliding_velocity"],
                                                       roughness_ra=conditions["roughness_ra"]),
                             schedule=RunSchedule(duration=duration,
                                                  sample_rate=study.points["transient"]["sample_rate"],
                                                  settle_time=spec["settle_time"]),
                             integration=IntegrationOptions(gs_tolerance=spec["gs_tolerance"],
                                                            gs_max_iterations=spec["gs_max_iterations"]))
    default_prep = prepare_run(default, OperatingCondition(sliding_velocity=0.01, normal_load=5.0),
                               FrictionInput(mu=0.3),
                               schedule=RunSchedule(duration=1e-4 if args.quick else 5e-4, sample_rate=51200.0,
                                                    preload_time=2e-4, settle_time=0.0, base_ramp_time=1e-4))
    rough_prep.run(progress=False)  # warm-up: load the cached kernels
    t_rough = t_default = c_rough = c_default = float("inf")
    for _ in range(2 if args.quick else 3):
        t0, c0 = time.perf_counter(), time.process_time()
        ds = rough_prep.run(progress=False)
        t_rough = min(t_rough, time.perf_counter() - t0)
        c_rough = min(c_rough, time.process_time() - c0)
        t0, c0 = time.perf_counter(), time.process_time()
        default_prep.run(progress=False)
        t_default = min(t_default, time.perf_counter() - t0)
        c_default = min(c_default, time.process_time() - c0)
    rs, ds_ = rough_prep.settings, default_prep.settings
    rough_steps = rs.n_intervals * rs.steps_per_interval
    default_steps = ds_.n_intervals * ds_.steps_per_interval
    rough_rate = rough.n_dofs * rough_steps / t_rough
    default_rate = default.n_dofs * default_steps / t_default
    point_steps = int(round(study.points["transient"]["duration"] / rs.time_step))
    out = {
        "benchmark": "rough",
        "quick": bool(args.quick),
        "rough_model": str(Path(study.model_path).relative_to(ROOT)),
        "rough_conditions": conditions,
        "rough_dofs": int(rough.n_dofs),
        "rough_slave_nodes": int(sum(c.slave_nodes.size for c in rough.contacts)),
        "rough_time_step_s": rs.time_step,
        "rough_steps_measured": rough_steps,
        "rough_contact_gs_mean_sweeps": ds.attrs.get("contact_gs_mean_sweeps"),
        "rough_dof_updates_per_s": rough_rate,
        "rough_steps_per_point": point_steps,
        "rough_point_record_s": study.points["transient"]["duration"],
        "rough_point_projected_s": point_steps * t_rough / rough_steps,
        "rough_point_projected_cpu_s": point_steps * c_rough / rough_steps,
        "default_model": "configs/models/triboair.yaml",
        "default_dofs": int(default.n_dofs),
        "default_dof_updates_per_s": default_rate,
        "rough_over_default": rough_rate / default_rate,
        "rough_cpu_dof_updates_per_s": rough.n_dofs * rough_steps / c_rough,
        "default_cpu_dof_updates_per_s": default.n_dofs * default_steps / c_default,
        "rough_over_default_cpu": (rough.n_dofs * rough_steps / c_rough) / (default.n_dofs * default_steps / c_default),
        "load_average_1min": load,
    }
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
