"""Band RMS, 1/3-octave band levels (IEC 61260-1 base-10) and the vibration level Lv(dB).

All work on a one-sided PSD DataArray from :func:`fivid.signal.welch_psd`. A PSD bin ``k`` stands for
the rectangle ``[f_k - df/2, f_k + df/2]``; a band takes each bin with the fraction of that rectangle
inside the band, so adjacent bands add up to the total (no bin counted twice or lost at an edge).
"""

from __future__ import annotations

import numpy as np

from fivid.errors import ConfigError, UnitError

__all__ = [
    "bin_weights",
    "band_power",
    "band_rms",
    "third_octave_bands",
    "third_octave_weights",
    "third_octave_levels",
    "vibration_level_db",
    "VELOCITY_REFERENCE",
]

VELOCITY_REFERENCE = 1e-9  # [m s-1], reference of Lv(dB) (seed 003, ISO 1683)
_OCTAVE_RATIO = 10 ** 0.3  # IEC 61260-1:2014 base-ten octave frequency ratio G


def bin_weights(frequency: np.ndarray, lower: float, upper: float) -> np.ndarray:
    """Fraction of each bin's rectangle ``[f - df/2, f + df/2]`` inside ``[lower, upper]``, times df [Hz].

    ``sum(P * bin_weights(f, lo, hi))`` is the power of a PSD ``P`` in the band; the first bin's
    rectangle is clipped at 0 Hz and the last at the Nyquist frequency.
    """
    f = np.asarray(frequency, dtype=np.float64)
    df = f[1] - f[0]
    left = np.maximum(f - df / 2, f[0])
    right = np.minimum(f + df / 2, f[-1])
    return np.clip(np.minimum(right, upper) - np.maximum(left, lower), 0.0, None)


def _check_band(psd, band) -> tuple[float, float]:
    f = psd["frequency"].values
    f_lo, f_hi = (float(b) for b in band)
    if not (0 <= f_lo < f_hi <= f[-1] * (1 + 1e-12)):
        raise ConfigError(
            f"band [{f_lo!r}, {f_hi!r}] Hz must satisfy 0 <= f_lo < f_hi <= Nyquist frequency {f[-1]!r} Hz", key="band"
        )
    return f_lo, f_hi


def band_power(psd, band) -> np.ndarray:
    """Power [u2] of a PSD [u2 Hz-1] in ``band = (f_lo, f_hi)`` [Hz] (leading dims kept)."""
    f_lo, f_hi = _check_band(psd, band)
    w = bin_weights(psd["frequency"].values, f_lo, f_hi)
    return np.asarray(psd.values, dtype=np.float64) @ w


def _signal_units(psd) -> str:
    units = psd.attrs.get("variable_units")
    if not isinstance(units, str):
        raise UnitError("PSD has no 'variable_units' attribute (the units of the analysed signal); "
                        "compute it with fivid.signal.welch_psd")
    return units


def band_rms(psd, band):
    """RMS [u] of the signal in ``band = (f_lo, f_hi)`` [Hz]: ``sqrt(∫ P df)`` over the band.

    Returns an xarray.DataArray (0-d, or with the PSD's leading dims such as ``sensor``).
    """
    import xarray as xr

    f_lo, f_hi = _check_band(psd, band)
    power = band_power(psd, band)
    dims = psd.dims[:-1]
    return xr.DataArray(np.sqrt(power), dims=dims, coords={d: psd.coords[d] for d in dims if d in psd.coords},
                        name="band_rms",
                        attrs={"units": _signal_units(psd), "long_name": f"RMS of {psd.attrs.get('variable')} "
                               f"in [{f_lo:g}, {f_hi:g}] Hz", "band_lower": f_lo, "band_upper": f_hi,
                               "band_units": "Hz"})


def third_octave_bands(f_lo: float, f_hi: float) -> dict[str, np.ndarray]:
    """IEC 61260-1:2014 base-10 one-third-octave bands lying entirely within ``[f_lo, f_hi]`` [Hz].

    Exact mid-band frequencies ``f_m = 1000 · G^(x/3)`` Hz with ``G = 10^(3/10)`` (i.e. 1000·10^(x/10))
    and band edges ``f_m · G^(∓1/6)``.

    Returns
    -------
    dict with ``index`` (x), ``centre``, ``lower``, ``upper`` [Hz] arrays.
    """
    if not (0 < f_lo < f_hi):
        raise ConfigError(f"1/3-octave bands need 0 < f_lo < f_hi, got [{f_lo!r}, {f_hi!r}] Hz", key="band")
    edge = _OCTAVE_RATIO ** (1 / 6)
    x_min = int(np.ceil(10 * np.log10(f_lo * edge / 1000.0) - 1e-9))
    x_max = int(np.floor(10 * np.log10(f_hi / edge / 1000.0) + 1e-9))
    x = np.arange(x_min, x_max + 1)
    centre = 1000.0 * _OCTAVE_RATIO ** (x / 3)
    return {"index": x, "centre": centre, "lower": centre / edge, "upper": centre * edge}


def third_octave_weights(frequency: np.ndarray, f_lo: float, f_hi: float, *, min_bins: float = 1.0):
    """The 1/3-octave bands inside ``[f_lo, f_hi]`` at least ``min_bins`` PSD bins wide, and their bin weights.

    Returns
    -------
    bands : dict
        As :func:`third_octave_bands`, plus ``n_bins`` (band width in bins).
    weights : ndarray, shape (n_frequencies, n_bands)
        :func:`bin_weights` [Hz] of each band; ``psd @ weights`` are the band powers.
    """
    f = np.asarray(frequency, dtype=np.float64)
    df = f[1] - f[0]
    bands = third_octave_bands(max(f_lo, df / 2), f_hi)
    width = bands["upper"] - bands["lower"]
    keep = width >= min_bins * df
    bands = {k: v[keep] for k, v in bands.items()}
    bands["n_bins"] = width[keep] / df
    if not bands["centre"].size:
        return bands, np.zeros((f.size, 0))
    weights = np.stack([bin_weights(f, lo, hi) for lo, hi in zip(bands["lower"], bands["upper"])], axis=-1)
    return bands, weights


def third_octave_levels(psd, *, band=None, reference=1.0, min_bins=1.0):
    """Band RMS and level of a PSD in the 1/3-octave bands within ``band``.

    Parameters
    ----------
    psd : xarray.DataArray
        One-sided PSD [u2 Hz-1] (last dim ``frequency``).
    band : (float, float), optional
        ``(f_lo, f_hi)`` [Hz]; default from the second bin to the Nyquist frequency.
    reference : float, default 1.0
        Reference RMS [u] of the level: ``L = 20 log10(rms / reference)`` dB.
    min_bins : float, default 1.0
        Drop bands narrower than this many PSD bins (their level rests on too few estimates).

    Returns
    -------
    xarray.Dataset
        ``band_rms`` [u] and ``level`` [dB re reference] on dim ``band_centre`` [Hz] (exact IEC
        mid-band frequencies), with coords ``band_lower``/``band_upper`` [Hz] and ``n_bins``.
    """
    import xarray as xr

    f = psd["frequency"].values
    f_lo, f_hi = _check_band(psd, band if band is not None else (f[1], f[-1]))
    bands, weights = third_octave_weights(f, f_lo, f_hi, min_bins=min_bins)
    power = np.asarray(psd.values, dtype=np.float64) @ weights
    rms = np.sqrt(power)
    with np.errstate(divide="ignore"):
        level = 20 * np.log10(rms / reference)
    units = _signal_units(psd)
    dims = psd.dims[:-1] + ("band_centre",)
    coords = {d: psd.coords[d] for d in dims[:-1] if d in psd.coords}
    coords.update({
        "band_centre": ("band_centre", bands["centre"], {"units": "Hz", "long_name": "IEC 61260-1 base-10 exact "
                                                         "mid-band frequency of the 1/3-octave band"}),
        "band_lower": ("band_centre", bands["lower"], {"units": "Hz", "long_name": "lower band-edge frequency"}),
        "band_upper": ("band_centre", bands["upper"], {"units": "Hz", "long_name": "upper band-edge frequency"}),
        "band_index": ("band_centre", bands["index"], {"long_name": "IEC 61260-1 band number x (1000 Hz is 0)"}),
        "n_bins": ("band_centre", bands["n_bins"], {"units": "1", "long_name": "band width in PSD bins"}),
    })
    return xr.Dataset(
        {"band_rms": (dims, rms, {"units": units, "long_name": "1/3-octave band RMS"}),
         "level": (dims, level, {"units": "dB", "long_name": f"1/3-octave band level re {reference:g} {units}",
                                 "reference": reference, "reference_units": units})},
        coords=coords,
        attrs={"variable": psd.attrs.get("variable", ""), "standard": "IEC 61260-1:2014, base-ten bands"},
    )


def vibration_level_db(psd, band, *, reference=VELOCITY_REFERENCE) -> float:
    """Vibration velocity level ``Lv = 20 log10(v_rms / 1e-9 m s-1)`` [dB] in ``band`` [Hz].

    ``psd`` is a PSD of acceleration [m2 s-4 Hz-1] — integrated to velocity in the frequency domain,
    ``P_v(f) = P_a(f) / (2π f)²`` — or of velocity [m2 s-2 Hz-1]. The band must exclude 0 Hz.
    """
    units = _signal_units(psd)
    f_lo, f_hi = _check_band(psd, band)
    if f_lo <= 0:
        raise ConfigError(f"Lv band must start above 0 Hz (velocity from acceleration diverges), got {f_lo!r}",
                          key="band")
    f = psd["frequency"].values
    p = np.asarray(psd.values, dtype=np.float64)
    if units == "m s-2":
        with np.errstate(divide="ignore"):
            p = np.where(f > 0, p / (2 * np.pi * np.where(f > 0, f, 1.0)) ** 2, 0.0)
    elif units != "m s-1":
        raise UnitError(f"Lv needs a PSD of acceleration (m s-2) or velocity (m s-1), got one of {units!r}")
    v_rms = np.sqrt(p @ bin_weights(f, f_lo, f_hi))
    return 20 * np.log10(v_rms / reference)
