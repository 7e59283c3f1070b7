"""SYNTHETIC vibration runs: white noise through a resonant IIR filter (scipy.signal.iirpeak) plus a white floor
26 dB down, from numpy Generators with the seeds given. For the scoring tests."""

import numpy as np
import scipy.signal
import xarray as xr

__all__ = ["resonance_run", "FS"]

FS = 10000.0


def resonance_run(seed, *, n=2**16, fs=FS, peak=1200.0, q=10.0, scale=1.0, run_id="M", units="m s-2"):
    """White noise through a resonator at ``peak`` Hz (quality ``q``) plus a white floor 26 dB down."""
    rng = np.random.default_rng(seed)
    b, a = scipy.signal.iirpeak(peak, q, fs)
    x = scipy.signal.lfilter(b, a, rng.standard_normal(n)) + 0.05 * rng.standard_normal(n)
    t = np.arange(n) / fs
    return xr.Dataset({"acceleration": ("time", scale * x, {"units": units}),
                       "friction_force": ("time", np.ones(n), {"units": "N"})},
                      coords={"time": ("time", t, {"units": "s"})},
                      attrs={"run_id": run_id, "sample_rate": fs})
