"""What the prestress stiffness adds to an explicit step (issue 31 item 2: at most 20 %), measured in one run.

    python benchmarks/bench_prestress.py [--quick]

Prints one JSON line. The explicit solver carries ``K_sigma`` folded into the stencil coefficients
(:func:`fivid.solver.stencil.block_stencils` with ``prestress``) plus one load group, the reference force
``K_sigma u0`` (:func:`fivid.solver.setup.kernel_arrays`). Two models run each with and without it (the same model,
``prestress`` switched), interleaved, best of the rounds (the machine is shared):

* the ring of seed 002 (``configs/models/ring.yaml``, expanded to 40 MPa; ``--quick``: 120 x 8 elements instead of
  360 x 20): a periodic annulus, already on the mapped stencil path, so the fold costs nothing and the load group
  one pass over the dofs: ``prestress_step_overhead`` = time per step with / without - 1;
* the two-beam rig (``configs/models/triboair_coarse.yaml``, 5 N): rectangular uniform blocks whose preload stress
  varies, so with the prestress they leave the uniform stencil for the mapped one -- the worst case:
  ``prestress_step_overhead_rig``.

Timing (robust on a shared machine): the ring's overhead taken as the best of four single short runs moved from
0.08 to 0.41 with a busy neighbour. Now each *sample* repeats the run until it has used ``--sample-seconds`` of process CPU time
(default 2 s, ``--quick`` 0.05 s) and reports the time per run; the two variants alternate within each of
``--rounds`` rounds (default 7; ABBA order, so a drift of the load hits both alike), and a figure is the
minimum over the rounds (the run's time plus the other jobs' interference, which only adds). ``*_cpu`` variants use
the process's CPU time, which waiting for a core does not inflate (contention for caches and memory bandwidth
still does, hence the minimum); the wall-time keys are kept beside them. ``*_cpu_spread`` is the range of the
per-round paired CPU overheads: the figure is trustworthy when it is small against the 0.20 target.

Idle figures: ``python benchmarks/bench_prestress.py`` (about 5 minutes on an idle 2-core machine, estimated
from the ``--quick`` step times: a run of the full ring takes longer than a sample, so its samples are single
runs of ~10 s; the rig's repeat ~15 runs each).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import yaml
from _load_guard import parse_guarded  # benchmarks/, this script's folder

ROOT = Path(__file__).resolve().parents[1]


def _sample(prep, min_seconds):
    """Wall and CPU time [s] per run of a prepared run, over as many runs as use ``min_seconds`` of process CPU
    time (at least one)."""
    runs = 0
    t0, c0 = time.perf_counter(), time.process_time()
    while True:
        prep.run(progress=False)
        runs += 1
        cpu = time.process_time() - c0
        if cpu >= min_seconds:
            return (time.perf_counter() - t0) / runs, cpu / runs


def _timed_pair(plain, stressed, rounds, min_seconds):
    """Per-run wall and CPU times [s] of the two prepared runs over ``rounds`` rounds, alternating their order
    (ABBA...) after one warm-up run each: ``{"plain": [(wall, cpu), ...], "stressed": [...]}``."""
    plain.run(progress=False)
    stressed.run(progress=False)
    times = {"plain": [], "stressed": []}
    for r in range(rounds):
        order = (("plain", plain), ("stressed", stressed))
        for name, prep in order if r % 2 == 0 else order[::-1]:
            times[name].append(_sample(prep, min_seconds))
    return times


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="a coarser ring, shorter runs and samples (a smoke run)")
    ap.add_argument("--rounds", type=int, default=None, help="rounds of the two variants (default 7, --quick 2)")
    ap.add_argument("--sample-seconds", type=float, default=None,
                    help="process CPU time each sample repeats its run for [s] (default 2, --quick 0.05)")
    args, load = parse_guarded(ap, argv)

    from fivid.fe import load_model
    from fivid.solver import FrictionInput, IntegrationOptions, OperatingCondition, RunSchedule
    from fivid.solver.driver import prepare_run

    cfg = yaml.safe_load((ROOT / "configs/models/ring.yaml").read_text(encoding="utf-8"))
    if args.quick:
        cfg["bodies"]["ring"]["divisions"] = [120, 8]
    ring = load_model(cfg)
    rig = load_model(ROOT / "configs/models/triboair_coarse.yaml")
    rounds = args.rounds if args.rounds is not None else 2 if args.quick else 7
    min_seconds = args.sample_seconds if args.sample_seconds is not None else 0.05 if args.quick else 2.0
    out = {"benchmark": "prestress", "quick": bool(args.quick), "ring_dofs": int(ring.n_dofs),
           "rig_dofs": int(rig.n_dofs), "rounds": int(rounds), "sample_seconds": float(min_seconds),
           "target_max_overhead": 0.20}
    full = IntegrationOptions(reduced=None)
    cases = {
        "": lambda m: prepare_run(m, schedule=RunSchedule(duration=2e-4 if args.quick else 1e-3, sample_rate=100e3),
                                  integration=full),
        "_rig": lambda m: prepare_run(m, OperatingCondition(sliding_velocity=0.01, normal_load=5.0),
                                      FrictionInput(mu=0.3),
                                      schedule=RunSchedule(duration=1e-4 if args.quick else 5e-4, sample_rate=51200.0,
                                                           preload_time=2e-4, settle_time=0.0, base_ramp_time=1e-4),
                                      integration=full),
    }
    for suffix, model in (("", ring), ("_rig", rig)):
        plain = cases[suffix](dataclasses.replace(model, prestress=False))
        stressed = cases[suffix](dataclasses.replace(model, prestress=True))
        times = _timed_pair(plain, stressed, rounds, min_seconds)
        (w0, c0), (w1, c1) = (tuple(min(col) for col in zip(*times[k])) for k in ("plain", "stressed"))
        paired = [b[1] / a[1] - 1.0 for a, b in zip(times["plain"], times["stressed"])]
        steps = plain.settings.n_intervals * plain.settings.steps_per_interval
        assert steps == stressed.settings.n_intervals * stressed.settings.steps_per_interval
        out[f"steps{suffix}"] = int(steps)
        out[f"step_s{suffix}"] = w0 / steps
        out[f"prestress_step_s{suffix}"] = w1 / steps
        out[f"cpu_step_s{suffix}"] = c0 / steps
        out[f"prestress_cpu_step_s{suffix}"] = c1 / steps
        out[f"prestress_step_overhead{suffix}"] = w1 / w0 - 1.0
        out[f"prestress_step_overhead{suffix}_cpu"] = c1 / c0 - 1.0
        out[f"prestress_step_overhead{suffix}_cpu_spread"] = max(paired) - min(paired)
    out["load_average_1min"] = load
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
