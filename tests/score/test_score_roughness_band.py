"""The band-limited vibration level (fivid.score.roughness.band_vibration_level) against closed forms.

Synthetic records (labelled synthetic; generator: ``_record`` below): sums of sinusoids whose frequencies are
whole multiples of 1/T over a record of length T, so that the periodic Hann taper puts each one's power into three
bins (k - 1, k, k + 1): the band's share of the periodogram is that of the sinusoids inside it, exactly, and the
record's mean square is the sum of A**2 / 2, so the band's mean square is the sum of A**2 / 2 over the sinusoids
inside the band, to round-off."""

import numpy as np
import pytest
import xarray as xr

from fivid.errors import ConfigError
from fivid.score.roughness import LV_BAND, band_vibration_level, vibration_level

FS = 2.0e6
T = 1.0e-3


def _record(components, n_sensors=3, fs=FS, duration=T, offset=0.0):
    """Synthetic back-face velocity: ``sum A_s,i sin(2 pi k_i t / T + phase)`` per sensor ``s`` (amplitude
    ``A * (1 + s / 2)``), a constant offset per sensor, sampled at ``fs`` over ``duration``; returns (Dataset,
    the per-sensor amplitude factors)."""
    n = int(round(duration * fs))
    t = 0.25e-3 + np.arange(n) / fs
    scale = 1.0 + np.arange(n_sensors) / 2.0
    rng = np.random.default_rng(7)
    v = np.zeros((n, n_sensors))
    for k, amp in components:
        phase = rng.uniform(0, 2 * np.pi)
        v += np.outer(amp * np.sin(2 * np.pi * k / duration * (t - t[0]) + phase), scale)
    v += offset * np.arange(1, n_sensors + 1)
    ds = xr.Dataset({"sensor_velocity": (("time", "sensor"), v)}, coords={"time": t})
    return ds, scale


def test_band_level_is_the_in_band_sinusoids_power():
    # 1 mm/s at 3 and 12 kHz in the band; 2 mm/s at 250 kHz and 0.1 m/s at 800 kHz (mesh-scale content) outside
    comps = [(3, 1e-3), (12, 1e-3), (250, 2e-3), (800, 0.1)]
    ds, scale = _record(comps, offset=5e-3)
    lv, vband = band_vibration_level(ds, start=float(ds.time[0]))
    expected = np.sqrt(np.mean(scale ** 2) * (1e-3 ** 2 / 2 + 1e-3 ** 2 / 2))
    assert vband == pytest.approx(expected, rel=1e-10)
    assert lv == pytest.approx(20 * np.log10(expected / 1e-9), abs=1e-9)
    # the full-band level of the same record (seed 003's) is the 800 kHz line's
    lv_full, vfull = vibration_level(ds, start=float(ds.time[0]))
    full = np.sqrt(np.mean(scale ** 2) * sum(a * a / 2 for _, a in comps))
    assert vfull == pytest.approx(full, rel=1e-10)
    assert lv_full - lv > 35.0


def test_band_edges_take_whole_bins_and_a_wider_band_adds_the_next_line():
    ds, scale = _record([(5, 1e-3), (40, 3e-3)])
    start = float(ds.time[0])
    _, v1 = band_vibration_level(ds, (1e3, 20e3), start=start)
    _, v2 = band_vibration_level(ds, (1e3, 50e3), start=start)
    assert v1 == pytest.approx(np.sqrt(np.mean(scale ** 2) * 1e-6 / 2), rel=1e-10)
    assert v2 == pytest.approx(np.sqrt(np.mean(scale ** 2) * (1e-6 + 9e-6) / 2), rel=1e-10)


def test_a_record_too_short_for_the_band_or_a_band_past_nyquist_is_refused():
    ds, _ = _record([(3, 1e-3)], duration=0.4e-3)  # 1/(2T) = 1.25 kHz > 1 kHz
    with pytest.raises(ConfigError, match="1/\\(2T\\)"):
        band_vibration_level(ds, LV_BAND, start=float(ds.time[0]))
    ds, _ = _record([(3, 1e-3)])
    with pytest.raises(ConfigError, match="fs/2"):
        band_vibration_level(ds, (1e3, 1.5e6), start=float(ds.time[0]))


def test_a_record_quiet_at_one_end_is_not_louder_in_the_band_than_over_all_frequencies():
    """A slider landing mid-window (synthetic: silence, then a 5 kHz line and a 300 kHz line): the band level is
    the whole record's mean square times the band's share, below the full-band level by the 300 kHz line's share."""
    ds, _ = _record([(5, 1e-3), (300, 1e-3)], n_sensors=1)
    v = ds["sensor_velocity"].values
    v[: v.shape[0] // 2] = 0.0
    ds["sensor_velocity"].values = v
    start = float(ds.time[0])
    lv_full, vfull = vibration_level(ds, start=start)
    lv_band, vband = band_vibration_level(ds, start=start)
    assert vband < vfull
    assert 2.0 < lv_full - lv_band < 4.0  # about half the power is the 300 kHz line's: ~3 dB
