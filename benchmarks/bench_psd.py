"""Benchmark: fivid Welch PSD against scipy.signal.welch, same signal, same settings, same run.

    python benchmarks/bench_psd.py [--quick]

Prints one JSON line: ``samples``, ``nperseg``, times [s] (best of ``repeats``) and the ratios
``speedup_vs_scipy_welch`` (scipy time / fivid pyfftw time; target >= 1.5 at 2**24 samples, nperseg
8192) and ``speedup_numpy_backend`` (scipy time / fivid numpy-backend time), plus the largest
relative difference between the two results. The signal is synthetic white noise (seed 0).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _load_guard import parse_guarded  # noqa: E402  (benchmarks/, this script's folder)


def best_time(fn, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="2**22 samples, one repeat")
    args, load = parse_guarded(parser, argv)
    import scipy.signal

    from fivid.signal.spectral import SpectralSettings, averaged_spectra

    n = 2**22 if args.quick else 2**24
    repeats = 1 if args.quick else 3
    nperseg, fs = 8192, 51200.0
    x = np.random.default_rng(0).standard_normal(n)
    fast = SpectralSettings(fs=fs, nperseg=nperseg, noverlap=nperseg // 2, window="hann", detrend="constant",
                            backend="pyfftw")
    plain = SpectralSettings(fs=fs, nperseg=nperseg, noverlap=nperseg // 2, window="hann", detrend="constant",
                             backend="numpy")
    t0 = time.perf_counter()
    p_fast = averaged_spectra(x, fast)[1]  # first call: imports pyfftw (which imports dask.array) and plans
    t_first = time.perf_counter() - t0
    t_fivid = best_time(lambda: averaged_spectra(x, fast), repeats)
    t_numpy = best_time(lambda: averaged_spectra(x, plain), repeats)
    two = SpectralSettings(fs=fs, nperseg=nperseg, noverlap=nperseg // 2, window="hann", detrend="constant",
                           backend="pyfftw", threads=2)
    t_two = best_time(lambda: averaged_spectra(x, two), repeats)
    t_scipy = best_time(lambda: scipy.signal.welch(x, fs=fs, window="hann", nperseg=nperseg, noverlap=nperseg // 2,
                                                   detrend="constant", scaling="density"), repeats)
    p_ref = scipy.signal.welch(x, fs=fs, window="hann", nperseg=nperseg, noverlap=nperseg // 2,
                               detrend="constant", scaling="density")[1]
    print(json.dumps({
        "benchmark": "bench_psd",
        "samples": n,
        "nperseg": nperseg,
        "repeats": repeats,
        "time_scipy_welch_s": round(t_scipy, 4),
        "time_fivid_pyfftw_s": round(t_fivid, 4),
        "time_fivid_first_call_incl_pyfftw_import_s": round(t_first, 4),
        "time_fivid_numpy_s": round(t_numpy, 4),
        "time_fivid_pyfftw_2_threads_s": round(t_two, 4),
        "load_average_1min": load,
        "speedup_vs_scipy_welch": round(t_scipy / t_fivid, 3),
        "speedup_numpy_backend": round(t_scipy / t_numpy, 3),
        "max_relative_difference": float(np.max(np.abs(p_fast - p_ref) / p_ref)),
    }))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
