"""Benchmark: a 200-point FRF of the seed 004 beam by harmonic balance against the time-domain reference.

Prints one JSON line: seconds for the 200-point HBM FRF (fixed frequencies, each started from the
previous solution), for the arclength-continued branch (with and without Floquet stability), and for
the Newmark time-domain reference run to steady state at the same frequencies (``--quick``: every
10th frequency, scaled to 200), their ratio, and the largest HBM/time-domain amplitude difference at
the timed points. Model 1 at Fn = 2 N (stick-slip: the nonlinear regime).

    python benchmarks/bench_frf.py [--quick]
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path

# The matrices here are tiny (8 unknowns, 17x17 Floquet propagators): BLAS threads only add
# synchronisation, which on a shared 2-core machine costs ~9 ms per expm instead of 0.03 ms.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fivid.damper.continuation import continue_frequency_response  # noqa: E402
from fivid.damper.hbm import HarmonicBalance  # noqa: E402
from fivid.damper.model import load_damper_model  # noqa: E402
from fivid.damper.timedomain import steady_state_response  # noqa: E402
from _load_guard import parse_guarded  # noqa: E402  (benchmarks/, this script's folder)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="time the time-domain reference on every 10th point")
    args, load = parse_guarded(ap)
    model = load_damper_model(ROOT / "configs" / "dampers" / "seed004_model1.yaml")
    fn = 2.0
    freqs = np.linspace(*model.frequency_range, 200)
    hb = HarmonicBalance.from_model(model, fn)
    hb.sweep(freqs[:3])  # compile / load the numba kernels outside the timing
    steady_state_response(model.modal, model.series_stiffness, model.slip_force(fn), model.excitation_amplitude, 50.0,
                          max_periods=2)
    best = np.inf
    for _ in range(3):
        t0 = time.perf_counter()
        sols = hb.sweep(freqs)
        best = min(best, time.perf_counter() - t0)
    t0 = time.perf_counter()
    curve = continue_frequency_response(hb, *model.frequency_range, stability=False)
    t_arc = time.perf_counter() - t0
    t0 = time.perf_counter()
    continue_frequency_response(hb, *model.frequency_range, stability=True)
    t_arc_stab = time.perf_counter() - t0
    idx = np.arange(0, 200, 10) if args.quick else np.arange(200)
    t0 = time.perf_counter()
    diffs = []
    for i in idx:
        td = steady_state_response(model.modal, model.series_stiffness, model.slip_force(fn),
                                   model.excitation_amplitude, freqs[i])
        diffs.append(abs(abs(sols[i].measurement[0]) / abs(td.harmonic("measurement")) - 1))
    t_td = (time.perf_counter() - t0) * 200 / idx.size
    print(json.dumps({
        "benchmark": "frf", "model": model.name, "normal_load_N": fn, "points": 200,
        "harmonics": list(map(int, hb.harmonics)), "samples_per_period": hb.n_samples,
        "hbm_frf_s": round(best, 4),
        "arclength_points": int(curve.frequency.size), "arclength_s": round(t_arc, 4),
        "arclength_with_floquet_s": round(t_arc_stab, 4),
        "time_domain_s": round(t_td, 3), "time_domain_points_timed": int(idx.size),
        "ratio_time_domain_over_hbm": round(t_td / best, 1),
        "max_rel_amplitude_difference": float(f"{max(diffs):.3g}"),
        "load_average_1min": load,
    }))


if __name__ == "__main__":
    main()
