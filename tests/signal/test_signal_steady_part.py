"""steady_part: the one steady part of a run (issue 20 item 1).

A measured run is cropped to its encoder's steady-sliding window, a simulated run from its
``transient_end`` on (its encoder is not consulted), both less an optional settle time. Expected windows
come from the closed-form velocity profile of the synthetic runs (tests/signal/test_signal_steady.py).
"""

import numpy as np
import pytest
import xarray as xr

from fivid.errors import ConfigError, DataQualityError
from fivid.signal import steady_part, steady_sliding_window
from tests.helpers.steady_runs import steady_sliding_run

FS = 5000.0


def _simulated(transient_end=0.3, duration=1.0, v=0.01):
    """A simulated run whose base slides at v from t = 0 (the encoder alone would keep the whole record)."""
    t = np.arange(int(duration * FS)) / FS
    return xr.Dataset({"velocity": ("time", np.full(t.size, v), {"units": "m s-1"})},
                      coords={"time": ("time", t, {"units": "s"})},
                      attrs={"run_id": "SIM", "transient_end": transient_end})


def test_measured_run_is_cut_to_its_encoder_window():
    ds = steady_sliding_run(fs=FS)  # ramps of 0.2 s: within 5 % from 0.19 s to 1.81 s (closed form)
    part = steady_part(ds)
    t0, t1 = steady_sliding_window(ds)
    assert part.time.values[0] == t0 and part.time.values[-1] == t1
    assert abs(t0 - 0.19) <= 0.05 / 2 + 1 / FS and abs(t1 - 1.81) <= 0.05 / 2 + 1 / FS  # half the smoothing


def test_measured_run_with_settle_starts_later_by_settle():
    ds = steady_sliding_run(fs=FS)
    t0, t1 = steady_sliding_window(ds)
    part = steady_part(ds, settle=0.1)
    assert part.time.values[0] == pytest.approx(t0 + 0.1, abs=1 / FS) and part.time.values[-1] == t1


def test_simulated_run_starts_at_transient_end_not_at_its_encoder_window():
    ds = _simulated(transient_end=0.3)
    assert steady_sliding_window(ds) == (0.0, ds.time.values[-1])  # the encoder sees sliding from the start
    part = steady_part(ds)
    assert part.time.values[0] == pytest.approx(0.3, abs=0.5 / FS)
    assert part.time.values[-1] == ds.time.values[-1]
    settled = steady_part(ds, settle=0.2)
    assert settled.time.values[0] == pytest.approx(0.5, abs=0.5 / FS)


def test_settle_longer_than_the_steady_part_is_an_error_naming_the_run():
    with pytest.raises(DataQualityError, match=r"run 'SIM'.*nothing is left.*settle time of 0\.8 s"):
        steady_part(_simulated(transient_end=0.3), settle=0.8)
    with pytest.raises(ConfigError, match="settle must be a duration >= 0"):
        steady_part(_simulated(), settle=-0.1)


def test_run_without_window_raises_or_is_used_whole_on_request():
    ds = steady_sliding_run(fs=FS).drop_vars("velocity")
    ds["acceleration"] = ("time", np.zeros(ds.time.size), {"units": "m s-2"})
    with pytest.raises(DataQualityError, match=r"^rig A: run 'SYN1'.*neither 'velocity' nor 'position'"):
        steady_part(ds, label="rig A")
    whole = steady_part(ds, whole_record_if_none=True, settle=0.5)
    assert whole.time.values[0] == pytest.approx(0.5, abs=0.5 / FS) and whole.time.size == ds.time.size - 2500


def test_score_runs_steady_crops_a_simulation_at_its_transient_end():
    """The test that would have caught score_runs(steady=True) ignoring ``transient_end``: a simulation that
    slides from t = 0 but rings loudly during its preload must be scored without the ringing."""
    from fivid.score import score_runs

    rng = np.random.default_rng(3)
    n = int(2.0 * FS)
    t = np.arange(n) / FS
    meas = xr.Dataset({"acceleration": ("time", rng.standard_normal(n), {"units": "m s-2"}),
                       "velocity": ("time", np.full(n, 0.01), {"units": "m s-1"})},
                      coords={"time": ("time", t, {"units": "s"})}, attrs={"run_id": "M", "sample_rate": FS})
    a = rng.standard_normal(n)
    a[t < 0.5] *= 30.0  # preload transient, 29.5 dB above the steady level
    sim = meas.copy(data={"acceleration": a, "velocity": np.full(n, 0.01)}).assign_attrs(run_id="S",
                                                                                      transient_end=0.5)
    sc = score_runs(meas, sim, nperseg=512, steady=True)
    # same white noise level after transient_end: no significant level difference (keeping the first 0.5 s
    # would add 10 log10((0.25 * 900 + 0.75) / 1) ≈ 23.5 dB)
    assert not bool(sc.level_diff_db_significant), float(sc.level_diff_db)
    assert abs(float(sc.level_diff_db)) < 1.0
