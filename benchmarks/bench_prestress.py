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

``*_cpu`` variants use the process's CPU time, which a shared machine's load does not inflate.
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


def _timed(prep, rounds):
    """Best wall and CPU time [s] of ``rounds`` runs of a prepared run (after one warm-up)."""
    prep.run(progress=False)
    wall = cpu = float("inf")
    for _ in range(rounds):
        t0, c0 = time.perf_counter(), time.process_time()
        prep.run(progress=False)
        wall = min(wall, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    return wall, cpu


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="a coarser ring and shorter runs (noisier)")
    args, load = parse_guarded(ap, argv)

    from fivid.fe import load_model
    from fivid.solver import FrictionInput, IntegrationOptions, OperatingCondition, RunSchedule
    from fivid.solver.driver import prepare_run

    cfg = yaml.safe_load((ROOT / "configs/models/ring.yaml").read_text(encoding="utf-8"))
    if args.quick:
        cfg["bodies"]["ring"]["divisions"] = [120, 8]
    ring = load_model(cfg)
    rig = load_model(ROOT / "configs/models/triboair_coarse.yaml")
    rounds = 2 if args.quick else 4
    out = {"benchmark": "prestress", "quick": bool(args.quick), "ring_dofs": int(ring.n_dofs),
           "rig_dofs": int(rig.n_dofs)}
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
        (w0, c0), (w1, c1) = _timed(plain, rounds), _timed(stressed, rounds)
        steps = plain.settings.n_intervals * plain.settings.steps_per_interval
        assert steps == stressed.settings.n_intervals * stressed.settings.steps_per_interval
        out[f"steps{suffix}"] = int(steps)
        out[f"step_s{suffix}"] = w0 / steps
        out[f"prestress_step_s{suffix}"] = w1 / steps
        out[f"prestress_step_overhead{suffix}"] = w1 / w0 - 1.0
        out[f"prestress_step_overhead{suffix}_cpu"] = c1 / c0 - 1.0
    out["load_average_1min"] = load
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
