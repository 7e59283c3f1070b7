"""Band RMS, IEC 61260-1 1/3-octave bands and levels, Lv(dB): closed forms on analytic and synthetic PSDs."""

import numpy as np
import pytest
import xarray as xr

from fivid.errors import ConfigError, UnitError
from fivid.signal import welch_psd
from fivid.signal.levels import band_rms, bin_weights, third_octave_bands, third_octave_levels, vibration_level_db

# IEC 61260-1:2014 Annex E nominal mid-band frequencies, 20 Hz ... 20 kHz
NOMINAL = [20, 25, 31.5, 40, 50, 63, 80, 100, 125, 160, 200, 250, 315, 400, 500, 630, 800, 1000, 1250, 1600, 2000,
           2500, 3150, 4000, 5000, 6300, 8000, 10000, 12500, 16000, 20000]


def flat_psd(level, fs=1024.0, nperseg=1024, units="m s-2"):
    f = np.arange(nperseg // 2 + 1) * fs / nperseg
    return xr.DataArray(np.full(f.size, level), dims="frequency", coords={"frequency": f}, name="psd",
                        attrs={"units": f"({units})2 Hz-1", "variable_units": units, "variable": "acceleration"})


def test_iec_centres_round_to_the_nominal_values():
    b = third_octave_bands(17.0, 23000.0)
    assert b["index"][0] == -17 and b["index"][-1] == 13
    # nominal values are the exact ones rounded to 2-3 significant figures (at most 1.6 % off: 31.5 vs 31.62)
    np.testing.assert_allclose(b["centre"], NOMINAL, rtol=0.016)
    np.testing.assert_allclose(b["upper"] / b["lower"], 10 ** 0.1, rtol=1e-14)  # one third of a base-10 octave
    np.testing.assert_allclose(b["upper"][:-1], b["lower"][1:], rtol=1e-14)  # contiguous


def test_bin_weights_integrate_a_flat_psd_exactly():
    p = flat_psd(2.0)
    for lo, hi in [(10.3, 17.9), (0.0, 512.0), (100.0, 101.0), (511.7, 512.0)]:
        power = np.sum(p.values * bin_weights(p["frequency"].values, lo, hi))
        assert power == pytest.approx(2.0 * (hi - lo), rel=1e-13)


def test_third_octave_levels_of_a_flat_psd():
    s = 1e-4
    lv = third_octave_levels(flat_psd(s), band=(20, 500), reference=1e-6)
    width = lv["band_upper"].values - lv["band_lower"].values
    expected = 10 * np.log10(s * width / 1e-12)  # band power S * width, level re (1e-6 m s-2)^2
    np.testing.assert_allclose(lv["level"].values, expected, atol=1e-12)
    np.testing.assert_allclose(lv["band_rms"].values ** 2, s * width, rtol=1e-13)
    assert lv["level"].attrs["reference"] == 1e-6 and lv["band_rms"].attrs["units"] == "m s-2"
    # adjacent bands add up to the power between the first lower and the last upper edge
    total = np.sum(flat_psd(s).values * bin_weights(flat_psd(s)["frequency"].values, lv["band_lower"].values[0],
                                                    lv["band_upper"].values[-1]))
    assert np.sum(lv["band_rms"].values ** 2) == pytest.approx(total, rel=1e-13)


def sine_psd(amp, f0, fs=8192.0, nperseg=8192):
    t = np.arange(nperseg * 8) / fs
    a = xr.DataArray(amp * np.sin(2 * np.pi * f0 * t), dims="time", coords={"time": t}, name="acceleration",
                     attrs={"units": "m s-2"})
    return welch_psd(a, nperseg=nperseg)


def test_band_rms_of_a_sine():
    p = sine_psd(0.3, 1000.0)
    assert float(band_rms(p, (900, 1100))) == pytest.approx(0.3 / np.sqrt(2), rel=1e-10)
    assert float(band_rms(p, (1100, 2000))) < 1e-10


def test_vibration_level_of_a_sine():
    amp, f0 = 0.5, 100.0
    lv = vibration_level_db(sine_psd(amp, f0), (50, 200))
    v_rms = amp / (2 * np.pi * f0) / np.sqrt(2)
    # Hann spreads the tone over f0 and f0 +- df with weights 2/3, 1/6, 1/6; integrating with 1/f^2 per bin gives
    # power (1 + (df/f0)^2) times the exact one: 10 log10(1 + 1e-4) = 4.3e-4 dB at df = 1 Hz, f0 = 100 Hz.
    assert lv == pytest.approx(20 * np.log10(v_rms / 1e-9), abs=10 * np.log10(1 + 1e-4) * 1.01)


def test_level_errors():
    with pytest.raises(ConfigError, match="Nyquist"):
        band_rms(flat_psd(1.0), (10, 600))
    with pytest.raises(ConfigError, match="above 0 Hz"):
        vibration_level_db(flat_psd(1.0), (0, 100))
    with pytest.raises(UnitError, match="'N'"):
        vibration_level_db(flat_psd(1.0, units="N"), (10, 100))


def test_vibration_level_matches_full_record_integration():
    # Independent path: velocity of the whole record by division by 2 pi i f in one FFT, band-limited to
    # [50, 500] Hz, v_rms by Parseval. The Welch band power differs from it by its estimation error: relative std
    # sqrt(2/nu (1 + 2(4/9 + 1/36)) / n_bins) ~ 0.3 % for nu ~ 965, 450 bins, i.e. 0.013 dB; 5 sigma allowed.
    rng = np.random.default_rng(11)
    fs, n, nperseg = 4096.0, 2**20, 4096
    acc = rng.standard_normal(n)
    spec = np.fft.rfft(acc)
    f = np.fft.rfftfreq(n, 1 / fs)
    keep = (f >= 50) & (f <= 500)
    vel = np.zeros_like(spec)
    vel[keep] = spec[keep] / (2j * np.pi * f[keep])
    v_rms = np.sqrt(2 * np.sum(np.abs(vel) ** 2)) / n  # one-sided Parseval (no DC/Nyquist bins in the band)
    t = np.arange(n) / fs
    p = welch_psd(xr.DataArray(acc, dims="time", coords={"time": t}, name="acceleration", attrs={"units": "m s-2"}),
                  nperseg=nperseg)
    nu = p.attrs["equivalent_degrees_of_freedom"]
    rel_sd = np.sqrt(2 / nu * (1 + 2 * (4 / 9 + 1 / 36)) / 450)
    lv = vibration_level_db(p, (50, 500))
    assert lv == pytest.approx(20 * np.log10(v_rms / 1e-9), abs=5 * 10 * np.log10(1 + rel_sd))
