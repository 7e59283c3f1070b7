"""SYNTHETIC encoder records with a closed-form velocity profile (trapezoid), for the steady-part tests."""

import numpy as np
import xarray as xr

__all__ = ["steady_sliding_run"]


def steady_sliding_run(*, fs=5000.0, duration=2.0, ramp=0.2, v=0.01, noise=0.0, encoder=None, seed=0, kind="velocity",
                  run_id="SYN1"):
    """Synthetic encoder record: linear ramp 0 -> v over ``ramp`` s, plateau, ramp down over the last ``ramp`` s.

    ``kind="position"`` integrates the profile in closed form and quantises it to ``encoder`` [m].
    """
    t = np.arange(int(duration * fs)) / fs
    up = np.clip(t / ramp, 0, 1)
    down = np.clip((duration - t) / ramp, 0, 1)
    vel = v * np.minimum(up, down)
    rng = np.random.default_rng(seed)
    data = {}
    if kind == "velocity":
        data["velocity"] = ("time", vel + noise * rng.standard_normal(t.size), {"units": "m s-1"})
    else:
        # closed-form integral of the trapezoid profile
        x_up = v * np.minimum(t, ramp) ** 2 / (2 * ramp)
        x_flat = v * np.clip(t - ramp, 0, duration - 2 * ramp)
        td = np.clip(t - (duration - ramp), 0, ramp)
        x_down = v * (td - td**2 / (2 * ramp))
        pos = x_up + x_flat + x_down
        if encoder:
            pos = np.round(pos / encoder) * encoder
        data["position"] = ("time", pos, {"units": "m"})
    return xr.Dataset(data, coords={"time": ("time", t, {"units": "s"})}, attrs={"run_id": run_id})
