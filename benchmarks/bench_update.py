"""Benchmark: model updating of the default rig and EMA of a measured-size FRF set. Prints one JSON line.

* update: 3 parameters of configs/models/triboair.yaml (the default rig, 0.5 mm: steel modulus, the upper
  beam's length, the contact's normal stiffness), coupled at the contact under 5 N, against its own 6 lowest modes
  computed with the parameters perturbed by +4 %, -3 %, +20 % (synthetic targets, 0.1 % tolerance): iterations,
  model evaluations, wall time, largest parameter error (target: < 60 s on 2 cores);
* ema: 8 FRFs x 4096 lines of a synthetic 8-DOF system (6 modes in the band, 1 % noise), LSCF up to order 80 +
  stabilisation + LSFD: wall time (target: < 10 s).

    python benchmarks/bench_update.py [--quick]

``--quick`` (the smoke test): 2 parameters against 3 modes, EMA of 2 FRFs x 1024 lines.
"""

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from fivid.ema import identify_modes  # noqa: E402
from fivid.fe.modal import modal_analysis  # noqa: E402
from fivid.fe.build import load_model  # noqa: E402
from fivid.updating import load_targets, update_model  # noqa: E402
from fivid.updating.paths import replace_values  # noqa: E402
from _load_guard import parse_guarded  # noqa: E402  (benchmarks/, this script's folder)

MODEL = ROOT / "configs" / "models" / "triboair.yaml"
PARAMS = [("materials.steel.E", "210 GPa", "218.4 GPa", "150 GPa", "300 GPa"),
          ("bodies.upper.corners[1][0]", "150 mm", "148.2 mm", "140 mm", "160 mm"),
          ("contacts[0].normal_stiffness", "2.1e14 N/m^3", "2.52e14 N/m^3", "1e13 N/m^3", "1e16 N/m^3")]


def bench_update(n_params: int, n_modes: int, tmp: Path) -> dict:
    params = PARAMS[:n_params]
    truth = tmp / "truth.yaml"
    truth.write_text(replace_values(MODEL.read_text(), {p: t for p, _, t, _, _ in params}))
    f = modal_analysis(load_model(str(truth)), n_modes, include_contact=True, normal_load=5.0)["frequency"].values
    lines = ["load: 5 N", "parameters:"]
    lines += [f"  - {{path: '{p}', bounds: [{lo}, {hi}]}}" for p, _, _, lo, hi in params]
    lines += ["modes:"] + [f"  - {{frequency: {float(x)!r} Hz, tolerance: 0.1 %}}" for x in f]
    targets = tmp / "targets.yaml"
    targets.write_text("\n".join(lines) + "\n")
    t0 = time.perf_counter()
    result, _ = update_model(MODEL, load_targets(targets))
    wall = time.perf_counter() - t0
    truth_values = [float(t.split()[0]) for _, _, t, _, _ in params]
    err = max(abs(v / t - 1) for v, t in zip(result.values, truth_values))
    return {"update_params": n_params, "update_modes": n_modes, "update_iterations": result.iterations,
            "update_evaluations": result.evaluations, "update_s": round(wall, 3),
            "update_max_param_error": float(err), "update_converged": result.converged}


def bench_ema(n_frf: int, n_lines: int) -> dict:
    rng = np.random.default_rng(0)
    n = 8
    phi, _ = np.linalg.qr(rng.standard_normal((n, n)))
    fn = np.array([30.0, 55.0, 90.0, 120.0, 160.0, 168.0, 400.0, 500.0])  # 6 in the 20..200 Hz band
    zeta = np.full(n, 0.015)
    f = np.linspace(0, 256, n_lines)
    om, wn = 2 * np.pi * f, 2 * np.pi * fn
    h = sum(np.outer(phi[:n_frf, r] * phi[0, r], 1 / (wn[r] ** 2 - om**2 + 2j * zeta[r] * wn[r] * om))
            for r in range(n))
    h = h + 0.01 * np.abs(h).mean(axis=1, keepdims=True) * (rng.standard_normal(h.shape)
                                                           + 1j * rng.standard_normal(h.shape))
    import sdypy.EMA  # noqa: F401  (its import, with matplotlib, outside the timing)
    t0 = time.perf_counter()
    res = identify_modes(f, h, band=(20, 200), n_modes=6, max_order=40, driving_point=0)
    wall = time.perf_counter() - t0
    err = float(np.max(np.abs(np.sort(res.frequency) / fn[:6] - 1)))
    return {"ema_frfs": n_frf, "ema_lines": n_lines, "ema_s": round(wall, 3), "ema_max_frequency_error": err}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smoke run: smaller update and EMA")
    args, load = parse_guarded(ap)
    with tempfile.TemporaryDirectory() as tmp:
        out = {"benchmark": "update", "quick": args.quick, "load_average_1min": load}
        out.update(bench_update(2, 3, Path(tmp)) if args.quick else bench_update(3, 6, Path(tmp)))
        out.update(bench_ema(2, 1024) if args.quick else bench_ema(8, 4096))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
