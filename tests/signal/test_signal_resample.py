"""Polyphase resampling: rational ratios, passband tone kept, out-of-band tone not aliased, metadata."""

import numpy as np
import pytest
import xarray as xr

from fivid.errors import ConfigError
from fivid.signal.resample import rational_ratio, resample_to

# scipy.signal.resample_poly designs a Kaiser-window FIR with beta = 5: A = beta / 0.1102 + 8.7 = 54.1 dB
# (Kaiser's formula), i.e. passband ripple and stopband gain delta = 10**(-54.1/20) = 2.0e-3.
DELTA = 10 ** (-(5 / 0.1102 + 8.7) / 20)


def run(fs, tones, n_seconds=0.5):
    t = np.arange(int(fs * n_seconds)) / fs
    x = sum(a * np.sin(2 * np.pi * f * t) for f, a in tones)
    return xr.Dataset({"acceleration": ("time", x, {"units": "m s-2"}),
                       "normal_force": ("time", 5.0 + 0 * t, {"units": "N"})},
                      coords={"time": ("time", t, {"units": "s"})},
                      attrs={"run_id": "R1", "sample_rate": fs, "history": "created"})


def amplitude(ds, f, trim):
    t = ds["time"].values[trim:-trim]
    y = ds["acceleration"].values[trim:-trim]
    basis = np.stack([np.sin(2 * np.pi * f * t), np.cos(2 * np.pi * f * t)], axis=1)
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    return float(np.hypot(*coef))


def test_rational_ratio():
    assert rational_ratio(51200.0, 48000.0) == (15, 16)
    assert rational_ratio(20000.0, 51200.0) == (64, 25)
    with pytest.raises(ConfigError, match="ratio"):
        rational_ratio(51200.0, 48000.0 * np.sqrt(2) / 1.4142, max_denominator=100)


def test_tone_kept_and_alias_rejected():
    out = resample_to(run(51200.0, [(1000.0, 1.0), (30000.0, 1.0)]), 48000.0)
    trim = 2000  # well beyond the filter's half length (10 * 16 = 160 input samples)
    assert abs(amplitude(out, 1000.0, trim) - 1.0) <= DELTA
    # 30 kHz is above the new Nyquist (24 kHz) and past the transition band: it would alias to 18 kHz
    assert amplitude(out, 48000.0 - 30000.0, trim) <= DELTA
    assert out.sizes["time"] == 24000
    np.testing.assert_allclose(np.diff(out["time"].values), 1 / 48000.0, rtol=1e-9)
    # padtype "line": no dip at the ends; the FIR gain at 0 Hz is 1 within the passband ripple
    np.testing.assert_allclose(out["normal_force"].values, 5.0, rtol=DELTA)
    assert out.attrs["sample_rate"] == 48000.0
    assert "up=15, down=16" in out.attrs["history"]


def test_same_rate_is_a_copy():
    ds = run(1000.0, [(10.0, 1.0)])
    out = resample_to(ds, 1000.0)
    np.testing.assert_array_equal(out["acceleration"].values, ds["acceleration"].values)


def test_time_dependent_coordinate_is_refused_by_name():
    from fivid.errors import DataQualityError

    ds = run(48000.0, [(1000.0, 1.0)])
    ds = ds.assign_coords(phase=("time", np.zeros(ds.sizes["time"])))
    with pytest.raises(DataQualityError, match="time-dependent coordinate 'phase'"):
        resample_to(ds, 24000.0)
