#!/usr/bin/env python
"""Generate the SYNTHETIC twin data set of sample_data/ from sample_data/ground_truth.yaml.

    python sample_data/generate.py [--jobs 2]        # rewrites twin/, twin_daq/ and twin.sha256

For every (sliding velocity, roughness) of the ground truth:

1. fivid's explicit FE solver simulates the rig (``fivid.solver.simulate``: preload, settle, base
   ramp, steady sliding) with the ground-truth friction law μ = μ0 + μp(t), μp synthesised from the
   law's spectrum and amplitude A(V, Ra) with a per-run seed;
2. a sensor chain turns the simulated physical signals into what a DAQ records: an unloaded
   pre-trigger interval, accelerometer noise floor, force-transducer bandwidth (2nd-order Butterworth),
   force zero offsets, mains hum, ADC quantisation and clipping, and an encoder position quantised to
   its resolution (the base motion is the solver's imposed velocity ramp);
3. the record is written twice: ``twin/T0k_...csv`` in the fivid-rig-csv format (acceleration in g)
   and ``twin_daq/T0k_v<V>_ra<Ra>.csv`` in the LabDAQ export format of ``configs/rigs/labdaq.yaml``
   (semicolons, decimal commas, accelerometer in mV at 100 mV/g, velocity and Ra only in the name).

``twin.sha256`` registers the sha256 of every file; tests/pipeline/test_pipeline_sample.py checks it. The
generation is deterministic (seeded synthesis, serial kernels) for a given version of fivid's solver;
the files were written with the solver of this commit's history (a later solver change that moves
the results by round-off changes the bytes, not the statistics: checked 2 % RMS, 0.002 dB band power).
"""

from __future__ import annotations

import argparse
import hashlib
import math
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
STANDARD_GRAVITY = 9.80665  # [m s-2]


def load_truth(path: Path = HERE / "ground_truth.yaml") -> dict:
    """The ground truth in SI units (quantities parsed with fivid.units)."""
    import yaml

    from fivid.units import parse_quantity as q

    raw = yaml.safe_load(path.read_text(encoding="utf-8"))
    law, cond, rec, chain = raw["law"], raw["conditions"], raw["record"], raw["sensor_chain"]
    amp = law["amplitude"]
    return {
        "raw": raw,
        "seed": int(raw["seed"]),
        "model": (path.parent / raw["model"]).resolve(),
        "mu0": float(law["mu0"]),
        "injection": law["injection"],
        "band": tuple(q(b, "Hz") for b in law["band"]),
        "corner": q(law["shape"]["corner"], "Hz"),
        "roughness_levels": tuple(q(r, "m") for r in amp["roughness_levels"]),
        "intercept": tuple(float(a) for a in amp["intercept"]),
        "velocity_slope": tuple(q(b, "s m-1") for b in amp["velocity_slope"]),
        "velocities": tuple(q(v, "m s-1") for v in cond["sliding_velocity"]),
        "roughnesses": tuple(q(r, "m") for r in cond["roughness_ra"]),
        "normal_load": q(cond["normal_load"], "N"),
        "sample_rate": q(rec["sample_rate"], "Hz"),
        "steady_duration": q(rec["steady_duration"], "s"),
        "pretrigger": q(rec["pretrigger"], "s"),
        "acc_noise": float(chain["accelerometer"]["noise_density"]),  # [m s-2 Hz^-1/2]
        "acc_sensitivity": q(chain["accelerometer"]["sensitivity"], "V") / STANDARD_GRAVITY,  # [V per m s-2]
        "acc_range": q(chain["accelerometer"]["adc_range"], "V"),
        "acc_bits": int(chain["accelerometer"]["adc_bits"]),
        "force_bandwidth": q(chain["force"]["bandwidth"], "Hz"),
        "force_noise": float(chain["force"]["noise_density"]),  # [N Hz^-1/2]
        "friction_offset": q(chain["force"]["friction_offset"], "N"),
        "normal_offset": q(chain["force"]["normal_offset"], "N"),
        "force_range": q(chain["force"]["adc_range"], "N"),
        "force_bits": int(chain["force"]["adc_bits"]),
        "mains": q(chain["mains"]["frequency"], "Hz"),
        "harmonics": tuple(int(h) for h in chain["mains"]["harmonics"]),
        "mains_acc": q(chain["mains"]["acceleration_amplitude"], "m s-2"),
        "mains_force": q(chain["mains"]["force_amplitude"], "N"),
        "encoder_resolution": q(chain["encoder"]["resolution"], "m"),
    }


def truth_law(truth: dict):
    """The ground-truth friction law object (fivid.friction)."""
    from fivid.friction import AmplitudeModel, PerturbedCoulombLaw

    n = len(truth["roughness_levels"])
    names, coef = [], []
    for r in range(n):
        names += [f"intercept[{r}]", f"velocity_slope[{r}]"]
        coef += [truth["intercept"][r], truth["velocity_slope"][r]]
    model = AmplitudeModel(form="linear_velocity", coefficients=np.array(coef), names=tuple(names),
                           stderr=np.zeros(len(coef)), covariance=np.zeros((len(coef), len(coef))),
                           terms=("sliding_velocity", "roughness_ra"), roughness_levels=truth["roughness_levels"])
    lo, hi = truth["band"]
    f = np.geomspace(lo, hi, 400)
    shape = 1.0 / (1.0 + (f / truth["corner"]) ** 2)
    return PerturbedCoulombLaw(truth["mu0"], f, shape, model, (lo, hi), injection=truth["injection"])


def conditions(truth: dict) -> list[dict]:
    """Every run: id, velocity [m s-1], roughness [m], seed."""
    runs = []
    for ra in truth["roughnesses"]:
        for v in truth["velocities"]:
            k = len(runs) + 1
            runs.append({"run_id": f"T{k:02d}", "sliding_velocity": v, "roughness_ra": ra, "seed": truth["seed"] + k})
    return runs


def _quantise(x, full_range, bits):
    """ADC: round to the LSB of a ±full_range converter and clip at its limits."""
    lsb = 2.0 * full_range / 2**bits
    return np.clip(np.round(x / lsb) * lsb, -full_range, full_range - lsb)


def _base_motion(model, ds, velocity, t):
    """Imposed base velocity [m s-1] and position [m] at simulation times ``t`` (the solver's smooth ramp)."""
    base = next(m for m in model.motions if m.role == "base")
    tr = float(base.ramp_time)
    t0 = float(ds.attrs["transient_end"]) - tr
    s = np.clip((t - t0) / tr, 0.0, None)
    r = np.where(s >= 1.0, 1.0, s - np.sin(2 * np.pi * s) / (2 * np.pi))
    # ∫ ramp: s^2/2 + (cos(2πs) - 1)/(4π^2) on [0, 1], then 1/2 + (s - 1)
    sc = np.minimum(s, 1.0)
    integral = sc**2 / 2 + (np.cos(2 * np.pi * sc) - 1) / (4 * np.pi**2) + np.maximum(s - 1.0, 0.0)
    return velocity * r, velocity * tr * integral


def sensor_chain(truth: dict, model, ds, run: dict) -> dict:
    """What the DAQ records, in SI: time, acceleration, friction/normal force, encoder position."""
    from scipy import signal

    fs = truth["sample_rate"]
    rng = np.random.default_rng(run["seed"] + 10_000)
    n_pre = int(round(truth["pretrigger"] * fs))
    t_sim = ds["time"].values
    n = n_pre + t_sim.size
    t = np.arange(n) / fs
    acc = np.concatenate([np.zeros(n_pre), np.asarray(ds["acceleration"].values, float).reshape(t_sim.size, -1)[:, 0]])
    ft = np.concatenate([np.zeros(n_pre), ds["friction_force"].values])
    fn = np.concatenate([np.zeros(n_pre), ds["normal_force"].values])
    _, x = _base_motion(model, ds, run["sliding_velocity"], t_sim)
    x = np.concatenate([np.zeros(n_pre), x])
    # white noise floors: one-sided density d -> standard deviation d * sqrt(fs / 2)
    acc = acc + rng.normal(0.0, truth["acc_noise"] * math.sqrt(fs / 2), n)
    sos = signal.butter(2, truth["force_bandwidth"], fs=fs, output="sos")
    ft = signal.sosfilt(sos, ft) + truth["friction_offset"] + rng.normal(0.0, truth["force_noise"] * math.sqrt(fs / 2), n)
    fn = signal.sosfilt(sos, fn) + truth["normal_offset"] + rng.normal(0.0, truth["force_noise"] * math.sqrt(fs / 2), n)
    phase = rng.uniform(0, 2 * np.pi, len(truth["harmonics"]))
    hum = sum(np.sin(2 * np.pi * h * truth["mains"] * t + p) / h for h, p in zip(truth["harmonics"], phase))
    acc = acc + truth["mains_acc"] * hum
    ft, fn = ft + truth["mains_force"] * hum, fn + truth["mains_force"] * hum
    volts = _quantise(acc * truth["acc_sensitivity"], truth["acc_range"], truth["acc_bits"])
    acc = volts / truth["acc_sensitivity"]
    ft = _quantise(ft, truth["force_range"], truth["force_bits"])
    fn = _quantise(fn, truth["force_range"], truth["force_bits"])
    x = np.round(x / truth["encoder_resolution"]) * truth["encoder_resolution"]
    return {"time": t, "acceleration": acc, "friction_force": ft, "normal_force": fn, "position": x}


def _fmt_um(ra):
    return f"{ra * 1e6:g} µm"


def write_rig_csv(path: Path, run: dict, rec: dict, truth: dict) -> None:
    """fivid-rig-csv format 1, acceleration in g, position in mm."""
    head = [
        "# fivid-rig-csv: 1",
        "# SYNTHETIC twin data: fivid solver + sensor chain, written by sample_data/generate.py "
        "from sample_data/ground_truth.yaml (not a measurement)",
        f"# run_id: {run['run_id']}",
        "# rig: triboair",
        f"# sliding_velocity: {run['sliding_velocity'] * 1e3:g} mm/s",
        f"# normal_load: {truth['normal_load']:g} N",
        f"# roughness_ra: {_fmt_um(run['roughness_ra'])}",
        f"# sample_rate: {truth['sample_rate'] / 1e3:g} kHz",
        "time [s],acceleration [g],friction_force [N],normal_force [N],position [mm]",
    ]
    a_g = rec["acceleration"] / STANDARD_GRAVITY
    rows = (f"{t:.9f},{a:.6f},{f1:.5f},{f2:.5f},{x:.4f}" for t, a, f1, f2, x in
            zip(rec["time"], a_g, rec["friction_force"], rec["normal_force"], rec["position"] * 1e3))
    path.write_text("\n".join(head) + "\n" + "\n".join(rows) + "\n", encoding="utf-8")


def daq_name(run: dict) -> str:
    """LabDAQ file name carrying velocity [mm/s] and Ra [0.1 µm]: ``T01_v5_ra04.csv``."""
    return f"{run['run_id']}_v{run['sliding_velocity'] * 1e3:g}_ra{round(run['roughness_ra'] * 1e7):02d}.csv"


def write_daq_csv(path: Path, run: dict, rec: dict, truth: dict) -> None:
    """The LabDAQ export of configs/rigs/labdaq.yaml: ';' and ',' decimals, CRLF, accelerometer in mV."""
    head = [
        "LabDAQ Export;v3.2",
        "Comment;SYNTHETIC twin data written by sample_data/generate.py (not a measurement)",
        f"Run;{run['run_id']}",
        "Date;2026-11-21 09:00:00",
        f"Normal load;{truth['normal_load']:.1f} N".replace(".", ","),
        f"Sample rate;{truth['sample_rate']:.0f} Hz",
        '"Time (s)";"Accel Z (mV)";"Fx (N)";"Fz (N)";"Pos (mm)"',
    ]
    mv = rec["acceleration"] * truth["acc_sensitivity"] * 1e3
    rows = (f"{t:.9f};{a:.4f};{f1:.5f};{f2:.5f};{x:.4f}".replace(".", ",") for t, a, f1, f2, x in
            zip(rec["time"], mv, rec["friction_force"], rec["normal_force"], rec["position"] * 1e3))
    path.write_bytes(("\r\n".join(head) + "\r\n" + "\r\n".join(rows) + "\r\n").encode("utf-8"))


def rig_csv_name(run: dict) -> str:
    return f"{run['run_id']}_v{run['sliding_velocity'] * 1e3:g}mm_s_ra{run['roughness_ra'] * 1e6:g}um.csv"


def generate_run(run: dict) -> str:
    """Simulate one run and write both files; returns its id."""
    from fivid.fe import load_model
    from fivid.solver import FrictionInput, OperatingCondition, OutputOptions, RunSchedule, simulate

    truth = load_truth()
    model = load_model(truth["model"])
    ds = simulate(model, OperatingCondition(sliding_velocity=run["sliding_velocity"], normal_load=truth["normal_load"],
                                            roughness_ra=run["roughness_ra"]),
                  FrictionInput(law=truth_law(truth), seed=run["seed"]),
                  schedule=RunSchedule(duration=truth["steady_duration"], sample_rate=truth["sample_rate"]),
                  output=OutputOptions(progress=False, run_id=run["run_id"]))
    rec = sensor_chain(truth, model, ds, run)
    write_rig_csv(HERE / "twin" / rig_csv_name(run), run, rec, truth)
    write_daq_csv(HERE / "twin_daq" / daq_name(run), run, rec, truth)
    return run["run_id"]


def write_registry() -> Path:
    """``twin.sha256``: ``<sha256>  <path relative to sample_data>`` for every twin file (sha256sum format)."""
    lines = []
    for folder in ("twin", "twin_daq"):
        for p in sorted((HERE / folder).glob("*.csv")):
            lines.append(f"{hashlib.sha256(p.read_bytes()).hexdigest()}  {folder}/{p.name}")
    out = HERE / "twin.sha256"
    out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return out


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument("--jobs", type=int, default=2, help="parallel simulations (processes)")
    args = parser.parse_args(argv)
    (HERE / "twin").mkdir(exist_ok=True)
    (HERE / "twin_daq").mkdir(exist_ok=True)
    runs = conditions(load_truth())
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        for run_id in pool.map(generate_run, runs):
            print(f"generated {run_id}", flush=True)
    print(f"wrote {write_registry()}")


if __name__ == "__main__":
    main()
