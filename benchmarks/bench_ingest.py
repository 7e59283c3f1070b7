#!/usr/bin/env python
"""Benchmark: full ingest of a large rig CSV against ``pandas.read_csv(engine="pyarrow")`` alone.

    python benchmarks/bench_ingest.py [--quick] [--rows N] [--repeat R]

Writes a SYNTHETIC fivid-rig-csv file (time [s], acceleration [g], friction_force [N],
normal_force [N], position [mm]; 3,000,000 rows, 300,000 with --quick) in a temporary folder, then
times, interleaved, R times each (the minimum is kept, the least disturbed by other load):

* baseline: ``pandas.read_csv(path, engine="pyarrow", skiprows=<metadata lines>)``, parsing only;
* fivid: ``read_rig_csv`` + ``write_run`` (unit conversion, every check, sha256, netCDF4 write).

Prints one JSON line: ``rows``, ``rows_per_s``, ``time_ratio_vs_pandas_pyarrow`` (target <= 1.3) and
the times, the best fivid run split into ``fivid_read_s`` (parse, checks, sha256 digest) and
``fivid_write_s`` (validation and netCDF write). Memory: ``fivid_peak_rss_mb`` and
``pandas_peak_rss_mb`` are the peak resident memory of a fresh process doing only that read (the
mapped file's pages included), minus the process's memory after its imports, next to ``data_mb``,
the size of the five float64 columns, and ``file_mb``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _load_guard import parse_guarded  # noqa: E402  (benchmarks/, this script's folder)

HEADER = [
    "# fivid-rig-csv: 1",
    "# SYNTHETIC benchmark file written by benchmarks/bench_ingest.py",
    "# run_id: BENCH",
    "# rig: triboair",
    "# sliding_velocity: 10 mm/s",
    "# normal_load: 5 N",
    "# roughness_ra: 0.8 um",
    "time [s],acceleration [g],friction_force [N],normal_force [N],position [mm]",
]


def write_file(path: Path, rows: int, sample_rate: float = 51200.0) -> None:
    """A synthetic rig CSV with ``rows`` data rows, written in blocks (DAQ-like fixed decimals)."""
    import pandas as pd

    rng = np.random.default_rng(0)
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join(HEADER) + "\n")
        block = 500_000
        for start in range(0, rows, block):
            i = np.arange(start, min(rows, start + block))
            frame = pd.DataFrame({
                "t": np.char.mod("%.7f", i / sample_rate),
                "a": np.round(rng.normal(0.0, 0.05, i.size), 5),
                "ft": np.round(1.5 + 0.05 * rng.normal(size=i.size), 4),
                "fn": np.round(5.0 + 0.01 * rng.normal(size=i.size), 4),
                "x": np.round(i * (10.0 / sample_rate), 5),
            })
            frame.to_csv(f, header=False, index=False)


_PEAK = """
import sys
sys.path.insert(0, {root!r})
def rss():
    # peak resident memory since the last reset [MiB] (Linux); the reset is right after the imports
    for line in open("/proc/self/status"):
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
def reset():
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    for line in open("/proc/self/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
if sys.argv[1] == "fivid":
    from fivid.io import read_rig_csv, write_run
    import xarray, pyarrow.csv, netCDF4
    base = reset()
    write_run(read_rig_csv(sys.argv[2]), sys.argv[3], overwrite=True)
else:
    import pandas, pyarrow.csv
    base = reset()
    pandas.read_csv(sys.argv[2], engine="pyarrow", skiprows={skip})
print(rss() - base)
"""


def peak_rss_mb(which: str, path: Path, out: Path) -> float:
    """Peak resident memory [MiB] of a fresh process reading ``path`` with ``which``, above its imports.

    Linux only (``/proc/self/clear_refs``); None elsewhere.
    """
    if not Path("/proc/self/clear_refs").exists():
        return None
    code = _PEAK.format(root=str(Path(__file__).resolve().parents[1]), skip=len(HEADER) - 1)
    proc = subprocess.run([sys.executable, "-c", code, which, str(path), str(out)], capture_output=True,
                          text=True, check=True)
    return round(float(proc.stdout.strip()), 1)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="300,000 rows instead of 3,000,000")
    parser.add_argument("--rows", type=int, default=None, help="number of data rows")
    parser.add_argument("--repeat", type=int, default=3, help="timings of each (the minimum is kept)")
    args, load = parse_guarded(parser, argv)
    rows = args.rows or (300_000 if args.quick else 3_000_000)

    import pandas as pd

    from fivid.io import read_rig_csv, write_run

    with tempfile.TemporaryDirectory(prefix="fivid-bench-ingest-") as tmp:
        path = Path(tmp) / "BENCH.csv"
        write_file(path, rows)
        out = Path(tmp) / "BENCH.nc"
        t_pandas, t_fivid, t_read = [], [], []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            frame = pd.read_csv(path, engine="pyarrow", skiprows=len(HEADER) - 1)
            t_pandas.append(time.perf_counter() - t0)
            assert frame.shape == (rows, 5)
            del frame
            out.unlink(missing_ok=True)  # time a new output, as a first ingest writes
            t0 = time.perf_counter()
            ds = read_rig_csv(path)
            t_read.append(time.perf_counter() - t0)
            write_run(ds, out, overwrite=True)
            t_fivid.append(time.perf_counter() - t0)
            assert ds.sizes["time"] == rows
            del ds
        file_mb = path.stat().st_size / 2**20
        fivid_rss = peak_rss_mb("fivid", path, out)
        pandas_rss = peak_rss_mb("pandas", path, out)
    best_pandas, best_fivid = min(t_pandas), min(t_fivid)
    best = t_fivid.index(best_fivid)  # the parts of the best fivid run
    print(json.dumps({
        "benchmark": "ingest",
        "rows": rows,
        "columns": 5,
        "file_mb": round(file_mb, 1),
        "data_mb": round(rows * 5 * 8 / 2**20, 1),
        "rows_per_s": round(rows / best_fivid),
        "fivid_ingest_s": round(best_fivid, 4),
        "pandas_pyarrow_s": round(best_pandas, 4),
        "fivid_read_s": round(t_read[best], 4),
        "fivid_write_s": round(best_fivid - t_read[best], 4),
        "time_ratio_vs_pandas_pyarrow": round(best_fivid / best_pandas, 3),
        "target_ratio": 1.3,
        "repeat": args.repeat,
        "fivid_peak_rss_mb": fivid_rss,
        "pandas_peak_rss_mb": pandas_rss,
        "cpu_count": os.cpu_count(),
        "load_average_1min": load,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
