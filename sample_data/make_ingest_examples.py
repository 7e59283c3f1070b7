#!/usr/bin/env python
"""Generate the SYNTHETIC ingest examples of sample_data/ (see sample_data/README.md).

    python sample_data/make_ingest_examples.py          # rewrites the two files below, deterministic

* ``R001_v10_ra08.csv``: the fivid-rig-csv format, acceleration in g, velocity in mm/s, position in mm,
  metadata with units (``10 mm/s``, ``0.8 µm``);
* ``R002_v20_ra16.csv``: the same kind of run as a semicolon / decimal-comma DAQ export with a
  ``key;value`` preamble and the accelerometer in mV (100 mV/g), read with ``--rig labdaq``;
  sliding velocity and roughness are only in the file name.

The signals are SYNTHETIC, not measurements: white noise through two lightly damped resonators
(2278 Hz and 12 791 Hz, the upper beam's first bending modes of DESIGN §8) for the acceleration, a
friction coefficient 0.3 with a small low-pass perturbation times a constant normal load, and a
constant sliding velocity. They exist to show the file formats and to exercise ``fivid ingest``;
nothing should be identified from them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy import signal

HERE = Path(__file__).resolve().parent
SAMPLE_RATE = 51200.0  # [Hz]
N_SAMPLES = 6400  # 0.125 s, keeps both files under 0.5 MB each
SYNTHETIC = "SYNTHETIC example written by sample_data/make_ingest_examples.py (not a measurement)"


def synthetic_run(seed: int, velocity_mm_s: float, normal_load: float):
    """Synthetic rig signals in the units a DAQ records: (t [s], a [g], Ft [N], Fn [N], x [mm], v [mm/s])."""
    rng = np.random.default_rng(seed)
    t = np.arange(N_SAMPLES) / SAMPLE_RATE
    a = np.zeros(N_SAMPLES)
    for f0, zeta, gain in ((2278.0, 0.005, 1.0), (12791.0, 0.01, 0.4)):
        # resonator by the bilinear transform of w0^2 / (s^2 + 2 zeta w0 s + w0^2), unit static gain
        w0 = 2 * np.pi * f0
        b, den = signal.bilinear([w0**2], [1.0, 2 * zeta * w0, w0**2], fs=SAMPLE_RATE)
        a += gain * signal.lfilter(b, den, rng.normal(0.0, 0.02, N_SAMPLES))
    b, den = signal.butter(2, 500.0, fs=SAMPLE_RATE)  # friction perturbation below 500 Hz
    mu = 0.3 + signal.lfilter(b, den, rng.normal(0.0, 0.02, N_SAMPLES))
    fn = normal_load * (1.0 + signal.lfilter(b, den, rng.normal(0.0, 0.005, N_SAMPLES)))
    ft = mu * fn
    v = velocity_mm_s * (1.0 + 0.01 * signal.lfilter(b, den, rng.normal(0.0, 1.0, N_SAMPLES)))
    x = np.cumsum(v) / SAMPLE_RATE
    return t, a, ft, fn, x, v


def write_rig_csv(path: Path) -> None:
    """R001: fivid-rig-csv, 10 mm/s, 5 N, Ra 0.8 µm."""
    t, a, ft, fn, x, v = synthetic_run(1, 10.0, 5.0)
    metadata = {
        "run_id": "R001", "rig": "triboair", "sliding_velocity": "10 mm/s", "normal_load": "5 N",
        "roughness_ra": "0.8 µm", "sample_rate": "51.2 kHz",
    }
    lines = ["# fivid-rig-csv: 1", f"# {SYNTHETIC}"] + [f"# {k}: {v}" for k, v in metadata.items()]
    lines.append("time [s],acceleration [g],friction_force [N],normal_force [N],position [mm],velocity [mm/s]")
    lines += [f"{r[0]:.7f},{r[1]:.5f},{r[2]:.4f},{r[3]:.4f},{r[4]:.5f},{r[5]:.4f}" for r in zip(t, a, ft, fn, x, v)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def write_daq_csv(path: Path) -> None:
    """R002: semicolon/decimal-comma export, CRLF line ends, accelerometer in mV at 100 mV/g."""
    t, a, ft, fn, x, _ = synthetic_run(2, 20.0, 5.0)
    preamble = {
        "LabDAQ Export": "v3.2", "Comment": SYNTHETIC, "Run": "R002", "Date": "2026-11-20 14:03:11",
        "Normal load": "5,0 N", "Sample rate": "51200 Hz",
    }
    lines = [f"{k};{v}" for k, v in preamble.items()]
    lines.append('"Time (s)";"Accel Z (mV)";"Fx (N)";"Fz (N)";"Pos (mm)"')
    mv = a * 100.0  # 100 mV/g
    rows = (f"{r[0]:.7f};{r[1]:.3f};{r[2]:.4f};{r[3]:.4f};{r[4]:.5f}" for r in zip(t, mv, ft, fn, x))
    lines += [row.replace(".", ",") for row in rows]
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode("utf-8"))


def main() -> None:
    write_rig_csv(HERE / "R001_v10_ra08.csv")
    write_daq_csv(HERE / "R002_v20_ra16.csv")


if __name__ == "__main__":
    main()
