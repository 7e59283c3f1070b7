"""The run's ``sensor_velocity``: its time integral is the sensor displacement (tests/helpers/solver_models.py block)."""

import numpy as np

from fivid.fe import load_model
from fivid.solver import OutputOptions, RunSchedule, simulate
from tests.helpers.solver_models import block_on_base


def test_sensor_velocity_integrates_to_the_displacement():
    """oversample 1: sample i is (v(iT) + v((i+1)T))/2 and sensor_displacement[i] is u((i+1)T), so
    T sum_{a..b-1} vel = u[b-1] - u[a-1] up to the trapezoid's error (T^2/12 max|a| per interval) and the
    half-step lag of the central-difference velocity (dt/2 |v(t_b) - v(t_a)|)."""
    model = load_model(block_on_base(mu=0.3, spring=1.24e4, v0=3.0, load=-2e-9))
    ds = simulate(model, schedule=RunSchedule(duration=0.004, sample_rate=100e3, settle_time=0.0),
                  output=OutputOptions(oversample=1, progress=False))
    assert ds["sensor_velocity"].attrs["units"] == "m s-1"
    T = 1.0 / 100e3
    v, u = ds.sensor_velocity.values, ds.sensor_displacement.values
    a, b = 10, v.size - 1
    moved = u[b - 1] - u[a - 1]
    assert abs(moved) > 1e-5  # the block moves: the check can fail
    acc = np.abs(ds.acceleration.values).max()
    lag = ds.attrs["time_step"] / 2 * abs(v[b] - v[a]) * 1.5
    bound = (b - a) * T**3 / 12 * acc + lag
    assert abs(T * v[a:b].sum() - moved) <= bound
