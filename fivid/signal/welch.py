"""Welch PSD and cross-spectral density of DataArrays, with units and every setting in attrs.

The CF layer over :mod:`fivid.signal.spectral`: reads the sampling rate from the ``time``
coordinate, checks the data (uniform time, finite, long enough), and returns DataArrays on a
``frequency`` [Hz] dimension with units built from the input's (``m s-2`` → ``m2 s-4 Hz-1``),
χ² confidence bounds and the equivalent number of averages.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import ConfigError, DataQualityError, UnitError
from fivid.signal.fft import FFTW_THREADS, check_backend
from fivid.signal.sampling import check_finite, run_label, sample_rate_of
from fivid.signal.spectral import (
    SpectralSettings,
    averaged_spectra,
    bin_degrees_of_freedom,
    chi2_interval,
    equivalent_degrees_of_freedom,
    segment_window,
)
from fivid.units import power_units, product_units

__all__ = ["welch_psd", "csd", "spectral_settings", "default_nperseg", "NPERSEG_RULE"]

#: The default segment length rule of :func:`default_nperseg`, as recorded in outputs (``nperseg_rule``).
NPERSEG_RULE = ("largest power of two <= n/16 with fs/nperseg >= 2 Hz (>= 256); raised to fs/nperseg <= mains/4 "
                "while nperseg <= n/4 (n: samples analysed)")


def default_nperseg(sample_rate: float, n_samples: int, mains_frequency: float | None = None) -> int:
    """Default Welch segment length [samples] for ``n_samples`` at ``sample_rate`` [Hz]: the one rule
    every fivid spectrum uses when no ``nperseg`` is given (:data:`NPERSEG_RULE`).

    Two needs set it:

    - **averages**: the largest power of two ``m`` with ``m <= n / 16`` (at least ~31
      half-overlapped segments, so the χ² bounds of a bin are about ±1.5 dB at 95 %) and
      ``fs / m >= 2 Hz`` (finer bins than that resolve nothing a rig run holds), and at least 256;
    - **mains lines** (``mains_frequency`` given, the friction identification): the line test of
      :func:`fivid.identify.runs.mains_line_bins` and the interpolation over a line's ±2-bin main
      lobe touch only the line when the bins are narrow compared with the line spacing. With
      ``Δf <= f_m / 4`` a harmonic's lobe spans ±f_m/2 and its floor (5–15 bins away) lies
      1.25–3.75 f_m away, so a line removes 5 bins of width f_m/4 (1.25 f_m of spectrum per
      harmonic, replaced by interpolation, not zeroed). At ``Δf = f_m`` (e.g. 1024 samples at
      51.2 kHz and 50 Hz mains) the lobe is as wide as the line spacing: every bin is "near a
      harmonic", broadband structure is taken for lines and interpolated away — on the synthetic
      twin data this underestimated A by 10–17 %. So ``m`` is raised to the smallest power of two
      with ``fs / m <= f_m / 4``, but not beyond ``n / 4`` (≥ 7 half-overlapped segments, ν ≈ 13 χ²
      degrees of freedom per bin, which the line test's quantile accounts for). A record too short for
      that resolution keeps the averages rule (:func:`fivid.identify.runs.mains_lines_resolved`).

    A band power and its variance do not depend on ``m`` (a sum over the band of a Welch PSD
    estimates ``(1/T) ∫ S² df`` for any resolution), so finer segments cost no precision of a band level.
    A record shorter than 256 samples gets 256 and fails as "shorter than one segment".

    Examples
    --------
    >>> default_nperseg(51200.0, 20000), default_nperseg(51200.0, 20000, mains_frequency=50.0)
    (1024, 4096)
    """
    m = 256
    while 2 * m <= n_samples / 16 and sample_rate / (2 * m) >= 2.0:
        m *= 2
    if mains_frequency:
        while sample_rate / m > mains_frequency / 4 and 2 * m <= n_samples / 4:
            m *= 2
    return m


def _units_of(da, label: str) -> str:
    units = da.attrs.get("units")
    if not isinstance(units, str):
        raise UnitError(
            f"{label}: variable {da.name!r} has no 'units' attribute; set it (UDUNITS, e.g. 'm s-2', '1' "
            "for dimensionless) before spectral analysis"
        )
    return units


def _detrend_name(detrend) -> str:
    if detrend is None or detrend is False:
        return "none"
    if detrend in ("constant", "linear", "none"):
        return detrend
    raise ConfigError(f"unknown detrend {detrend!r}; choose 'constant', 'linear' or 'none' (or False)", key="detrend")


def spectral_settings(da, *, nperseg=None, noverlap=None, window="hann", detrend="constant", fs=None,
                      backend=None, threads=None, label=None) -> tuple[SpectralSettings, np.ndarray]:
    """Validate ``da`` (dim ``time``) and the Welch settings; return them and the time-last values.

    ``nperseg`` None: :func:`default_nperseg` of the record's length and sampling rate.

    Raises DataQualityError (non-uniform time, NaN, fewer samples than one segment) naming the run.
    """
    label = label or run_label(da, default=f"variable {da.name!r}")
    if "time" not in da.dims:
        raise DataQualityError(f"{label}: variable {da.name!r} has dims {da.dims}; expected a 'time' dimension")
    if "time" in da.coords:
        rate = sample_rate_of(da["time"].values, label=label, declared=fs)
    elif fs is None:
        raise ConfigError(f"{label}: no 'time' coordinate; give fs= (the sampling rate [Hz])", key="fs")
    else:
        rate = float(fs)
    nperseg = default_nperseg(rate, da.sizes["time"]) if nperseg is None else int(nperseg)
    noverlap = nperseg // 2 if noverlap is None else int(noverlap)
    settings = SpectralSettings(fs=rate, nperseg=nperseg, noverlap=noverlap, window=window,
                                detrend=_detrend_name(detrend), backend=check_backend(backend), threads=threads)
    values = np.moveaxis(np.asarray(da.values, dtype=np.float64), da.dims.index("time"), -1)
    n = values.shape[-1]
    if n < nperseg:
        raise DataQualityError(
            f"{label}: variable {da.name!r} has {n} samples ({n / rate:.6g} s), shorter than one segment of "
            f"nperseg = {nperseg} samples ({nperseg / rate:.6g} s); use a smaller --nperseg or a longer record"
        )
    check_finite(values.reshape(-1, n).T if values.ndim > 1 else values, label=label, variable=str(da.name),
                 time=da["time"].values if "time" in da.coords else None)
    return settings, values


def _settings_attrs(settings: SpectralSettings, w: np.ndarray, k: int, nu: float, confidence: float,
                    nperseg_given: bool = True) -> dict:
    window = settings.window if isinstance(settings.window, str) else repr(settings.window)
    if isinstance(settings.window, np.ndarray):
        window = "custom array"
    return {
        "estimator": "Welch (WOSA), average='mean'",
        "scaling": "density",
        "onesided": 1,
        "window": window,
        "nperseg": settings.nperseg,
        "nperseg_rule": "given" if nperseg_given else NPERSEG_RULE,
        "noverlap": settings.noverlap,
        "nfft": settings.nperseg,
        "detrend": settings.detrend,
        "sample_rate": settings.fs,
        "sample_rate_units": "Hz",
        "frequency_resolution": settings.fs / settings.nperseg,
        "frequency_resolution_units": "Hz",
        "equivalent_noise_bandwidth": settings.fs * np.dot(w, w) / np.sum(w) ** 2,
        "equivalent_noise_bandwidth_units": "Hz",
        "n_segments": k,
        "equivalent_degrees_of_freedom": nu,
        "equivalent_averages": nu / 2.0,
        "confidence": confidence,
        "fft_backend": settings.backend,
        "fft_threads": settings.threads or FFTW_THREADS,
    }


def welch_psd(da, *, nperseg=None, noverlap=None, window="hann", detrend="constant", fs=None, confidence=0.95,
              backend=None, threads=None, label=None):
    """One-sided power spectral density by Welch's method, with χ² confidence bounds.

    Parameters
    ----------
    da : xarray.DataArray
        Signal with a uniformly sampled ``time`` [s] dimension (other dims, such as ``sensor``, are
        kept) and a ``units`` attribute [u].
    nperseg : int, optional
        Segment length [samples]; the frequency resolution is ``fs / nperseg`` [Hz]. Default
        :func:`default_nperseg` of the record (attr ``nperseg_rule`` says which was used).
    noverlap : int, optional
        Overlap of segments [samples]; default ``nperseg // 2``.
    window : str or tuple, default "hann"
        Taper (:func:`scipy.signal.get_window`, periodic).
    detrend : {"constant", "linear", "none"} or False, default "constant"
        Per-segment detrending.
    fs : float, optional
        Sampling rate [Hz]; default from the ``time`` coordinate (checked against it when both).
    confidence : float, default 0.95
        Level of the two-sided χ² interval ``psd_lower``/``psd_upper``.
    backend : {"pyfftw", "numpy"}, optional
        FFT implementation; both give the same numbers to round-off.
    threads : int, optional
        FFTW threads; default 1 (measured fastest on a shared 2-core machine, see :mod:`fivid.signal.fft`).
    label : str, optional
        How to name the signal in error messages (default: its ``run_id`` attr or name).

    Returns
    -------
    xarray.DataArray
        Density [u2 Hz-1] on dim ``frequency`` [Hz] (0 … fs/2), with coords ``psd_lower`` and
        ``psd_upper`` [u2 Hz-1], the scalar coordinates of ``da`` (a run's test conditions) and attrs recording every setting, ``n_segments``,
        ``equivalent_degrees_of_freedom`` ν (Percival & Walden eq. 292b) and
        ``equivalent_averages`` = ν/2. Scaling equals :func:`scipy.signal.welch` with
        ``scaling="density"``, so ``sum(psd) * df`` is the variance of the detrended signal.

    Raises
    ------
    DataQualityError
        Non-uniform time, NaN, or fewer samples than one segment (the message names the run).

    Examples
    --------
    A sine of amplitude 2 m s-2 has variance 2 (m s-2)²:

    >>> import numpy as np, xarray as xr
    >>> t = np.arange(2**14) / 1024.0
    >>> a = xr.DataArray(2 * np.sin(2 * np.pi * 64.0 * t), dims="time", coords={"time": t},
    ...                  name="acceleration", attrs={"units": "m s-2"})
    >>> p = welch_psd(a, nperseg=1024)
    >>> round(float(p.sum()) * p.attrs["frequency_resolution"], 6), p.attrs["units"]
    (2.0, 'm2 s-4 Hz-1')
    """
    import xarray as xr

    label = label or run_label(da, default=f"variable {da.name!r}")
    settings, values = spectral_settings(da, nperseg=nperseg, noverlap=noverlap, window=window, detrend=detrend,
                                         fs=fs, backend=backend, threads=threads, label=label)
    units = _units_of(da, label)
    lead = values.shape[:-1]
    rows = values.reshape(-1, values.shape[-1])
    psd = np.empty((rows.shape[0], settings.nperseg // 2 + 1))
    for i, row in enumerate(rows):
        f, psd[i], _, _, k = averaged_spectra(row, settings)
    psd = psd.reshape(*lead, -1)
    w = segment_window(settings.window, settings.nperseg)
    nu = equivalent_degrees_of_freedom(w, k, settings.step)
    lower, upper = chi2_interval(psd, bin_degrees_of_freedom(nu, settings.nperseg), confidence)
    dims = tuple(d for d in da.dims if d != "time") + ("frequency",)
    coords = {d: da.coords[d] for d in dims[:-1] if d in da.coords}
    # scalar coordinates (a run's test conditions, a selected sensor) describe the spectrum too
    coords.update({n: c for n, c in da.coords.items() if c.ndim == 0})
    coords["frequency"] = ("frequency", f, {"units": "Hz", "long_name": "frequency"})
    punits = power_units(units)
    long = f"power spectral density of {da.attrs.get('long_name', da.name)}"
    for name, values in (("lower", lower), ("upper", upper)):
        coords[f"psd_{name}"] = (dims, values, {"units": punits,
                                                "long_name": f"{name} {confidence:.0%} χ² bound of the {long}"})
    attrs = {"units": punits, "long_name": long, "variable": str(da.name), "variable_units": units}
    attrs.update(_settings_attrs(settings, w, k, nu, confidence, nperseg_given=nperseg is not None))
    return xr.DataArray(psd, dims=dims, coords=coords, name=f"psd_{da.name}" if da.name else "psd", attrs=attrs)


def csd(x, y, *, nperseg=None, noverlap=None, window="hann", detrend="constant", fs=None, backend=None):
    """Welch cross-spectral density ``E[conj(X) Y]`` of two signals on the same time grid.

    Parameters
    ----------
    x, y : xarray.DataArray
        1-D signals on the same uniformly sampled ``time`` [s], units [u] and [v].
    nperseg, noverlap, window, detrend, fs, backend
        As in :func:`welch_psd` (default ``nperseg``: :func:`default_nperseg`).

    Returns
    -------
    xarray.Dataset
        ``pxx`` [u2 Hz-1], ``pyy`` [v2 Hz-1] and complex ``pxy`` [u v Hz-1] on ``frequency`` [Hz];
        ``pxy`` equals :func:`scipy.signal.csd` (x, y) for identical settings. Attrs as in
        :func:`welch_psd`.
    """
    import xarray as xr

    sx, vx = spectral_settings(x, nperseg=nperseg, noverlap=noverlap, window=window, detrend=detrend, fs=fs,
                               backend=backend)
    sy, vy = spectral_settings(y, nperseg=sx.nperseg, noverlap=noverlap, window=window, detrend=detrend,
                               fs=sx.fs, backend=backend, label=run_label(y, default=f"variable {y.name!r}"))
    if vx.ndim != 1 or vy.ndim != 1:
        raise DataQualityError(f"csd needs 1-D signals; got dims {x.dims} and {y.dims} (select one sensor)")
    if vx.shape != vy.shape or ("time" in x.coords and "time" in y.coords
                                and not np.array_equal(x["time"].values, y["time"].values)):
        raise DataQualityError(
            f"{x.name!r} ({vx.size} samples) and {y.name!r} ({vy.size} samples) are not on the same time grid"
        )
    ux = _units_of(x, f"variable {x.name!r}")
    uy = _units_of(y, f"variable {y.name!r}")
    f, pxx, pyy, pxy, k = averaged_spectra(vx, sx, vy)
    w = segment_window(sx.window, sx.nperseg)
    nu = equivalent_degrees_of_freedom(w, k, sx.step)
    attrs = _settings_attrs(sx, w, k, nu, float("nan"), nperseg_given=nperseg is not None)
    del attrs["confidence"]
    attrs.update({"input": str(x.name), "output": str(y.name)})
    freq = ("frequency", f, {"units": "Hz", "long_name": "frequency"})
    return xr.Dataset(
        {
            "pxx": ("frequency", pxx, {"units": power_units(ux), "long_name": f"power spectral density of {x.name}"}),
            "pyy": ("frequency", pyy, {"units": power_units(uy), "long_name": f"power spectral density of {y.name}"}),
            "pxy": ("frequency", pxy, {"units": product_units(ux, uy),
                                       "long_name": f"cross-spectral density conj({x.name}) {y.name}"}),
        },
        coords={"frequency": freq},
        attrs=attrs,
    )
