"""Band-limited vs classic Rayleigh damping on the default rig (issue 17, item 1), as ratios in one run.

    python benchmarks/bench_damping.py [--quick] [--cutoff "60 kHz"]

Simulates the same run twice — the default rig (``configs/models/triboair.yaml``; ``--quick``: the coarse rig)
with the sample data's ground-truth friction law (``sample_data/ground_truth.yaml``, V 10 mm/s, Ra 1.6 um,
5 N, one seed) — once with classic Rayleigh damping (today's scheme: ``beta K v``, the step cut by
``sqrt(1+xi^2) - xi``) and once with band-limited damping (``beta K v_f``, ``v_f`` low-passed at the cut-off,
Rayleigh refitted so that the configured ratios hold at the configured frequencies; :mod:`fivid.fe.damping`).

Prints one JSON line: per scheme the time step, steps/s and wall time of the run (after a compile warm-up);
``fast_speedup`` (classic wall / band-limited wall), ``fast_band_lsd_db`` (log-spectral distance between the two
sensor PSDs, steady part, 200 Hz - 10 kHz) and the same over the scored band 800 Hz - 5 kHz
(``fast_scored_band_lsd_db``), the sensor RMS ratio, the step ratio against the undamped Courant step, and
``damping_ratio_1khz`` / ``damping_ratio_10khz``: the effective modal damping ratios of the band-limited scheme
there (its curve, which tests/solver/test_solver_damping.py checks against measured free decays).
"""

from __future__ import annotations

import argparse
import copy
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "sample_data"))

from _load_guard import parse_guarded  # noqa: E402  (benchmarks/, the script's own folder)


def _psd(ds):
    from scipy.signal import welch

    a = ds["acceleration"]
    a = a.isel(sensor=0) if "sensor" in a.dims else a
    steady = a.where(a["time"] >= ds.attrs["transient_end"], drop=True).values
    fs = float(ds.attrs["sample_rate"])
    f, p = welch(steady, fs=fs, window="hann", nperseg=1024, noverlap=512, detrend="constant", scaling="density")
    return f, p, float(np.sqrt(np.mean((steady - steady.mean()) ** 2)))


def _lsd(f, p_ref, p, lo, hi):
    sel = (f >= lo) & (f <= hi)
    d = 10.0 * np.log10(p[sel] / p_ref[sel])
    return float(np.sqrt(np.mean(d * d)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="the coarse rig (2 mm mesh) instead of the default rig")
    ap.add_argument("--cutoff", default="60 kHz", help="cut-off of the band-limited scheme (default 60 kHz)")
    ap.add_argument("--duration", default=None, help="steady duration [s] (default 0.1 s)")
    args, load = parse_guarded(ap, argv)

    import yaml

    from generate import load_truth, truth_law

    from fivid.fe import load_model
    from fivid.fe.damping import damping_ratio
    from fivid.solver import FrictionInput, OperatingCondition, OutputOptions, RunSchedule, simulate
    from fivid.units import parse_quantity

    cfg_path = ROOT / "configs" / "models" / ("triboair_coarse.yaml" if args.quick else "triboair.yaml")
    cfg = yaml.safe_load(cfg_path.read_text(encoding="utf-8"))
    cutoff = parse_quantity(args.cutoff, "Hz")
    duration = float(args.duration) if args.duration else 0.1
    law = truth_law(load_truth())
    kw = dict(condition=OperatingCondition(sliding_velocity=0.01, normal_load=5.0, roughness_ra=1.6e-6),
              friction=FrictionInput(law=law, seed=7), output=OutputOptions(progress=False))
    out = {"model": cfg_path.stem, "cutoff_hz": cutoff, "duration_s": duration, "quick": bool(args.quick)}
    runs = {}
    for name, cut in (("rayleigh", None), ("band_limited", cutoff)):
        c = copy.deepcopy(cfg)
        c["damping"] = dict(c["damping"])
        c["damping"].pop("cutoff", None)
        if cut is not None:
            c["damping"]["cutoff"] = f"{cut} Hz"
        model = load_model(c)
        simulate(model, schedule=RunSchedule(duration=2e-4, sample_rate=51200.0), **kw)  # compile / warm caches
        t0 = time.perf_counter()
        ds = simulate(model, schedule=RunSchedule(duration=duration, sample_rate=51200.0), **kw)
        wall = time.perf_counter() - t0
        runs[name] = ds
        out[f"{name}_time_step_s"] = float(ds.attrs["time_step"])
        out[f"{name}_steps_per_s"] = round(ds.attrs["steps"] / wall, 1)
        out[f"{name}_wall_s"] = round(wall, 3)
        if name == "band_limited":
            out["damping_ratio_1khz"] = round(float(damping_ratio(1e3, model.rayleigh_alpha, model.rayleigh_beta,
                                                                  model.damping_cutoff)), 6)
            out["damping_ratio_10khz"] = round(float(damping_ratio(1e4, model.rayleigh_alpha, model.rayleigh_beta,
                                                                   model.damping_cutoff)), 6)
            out["step_over_undamped_courant"] = round(ds.attrs["critical_time_step"] * ds.attrs["omega_max"] / 2, 4)
    f, p_ref, rms_ref = _psd(runs["rayleigh"])
    _, p_fast, rms_fast = _psd(runs["band_limited"])
    out["fast_speedup"] = round(out["rayleigh_wall_s"] / out["band_limited_wall_s"], 3)
    out["fast_band_lsd_db"] = round(_lsd(f, p_ref, p_fast, 200.0, 1e4), 4)
    out["fast_scored_band_lsd_db"] = round(_lsd(f, p_ref, p_fast, 800.0, 5e3), 4)
    out["fast_rms_ratio"] = round(rms_fast / rms_ref, 4)
    out["load_average_1min"] = load
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
