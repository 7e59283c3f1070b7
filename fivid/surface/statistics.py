"""Statistics of a profile: height distribution, power spectral density, autocorrelation, correlation length.

Each function takes a profile (heights [m] over ``x`` [m], uniformly sampled) and returns a
DataArray with units and the estimator settings in attrs.
"""

from __future__ import annotations

import math

import numpy as np

from fivid.errors import ConfigError
from fivid.signal.spectral import welch_density
from fivid.surface.profile import sampling_step

__all__ = ["height_distribution", "profile_psd", "autocorrelation", "correlation_length"]


def height_distribution(profile, *, bins: int = 50):
    """Histogram estimate of the probability density of the heights [m-1] over bin centres ``height`` [m].

    ``density=True``: the sum of density × bin width is 1.
    """
    import xarray as xr

    if int(bins) < 1:
        raise ConfigError(f"bins must be >= 1, got {bins!r}", key="bins")
    density, edges = np.histogram(np.asarray(profile.values, dtype=np.float64), bins=int(bins), density=True)
    centres = 0.5 * (edges[:-1] + edges[1:])
    return xr.DataArray(
        density, dims="height", name="height_pdf",
        coords={"height": ("height", centres, {"units": "m", "long_name": "height (bin centre)"})},
        attrs={"units": "m-1", "long_name": "probability density of the profile heights", "bins": int(bins),
               "bin_width": float(edges[1] - edges[0]), "bin_width_units": "m", "estimator": "numpy.histogram"},
    )


def _default_nperseg(n: int) -> int:
    """Largest power of two <= n / 4 (about 7 averaged segments at 50 % overlap), at least 8, at most n."""
    return min(n, max(8, 2 ** int(math.floor(math.log2(max(n / 4, 1))))))


def profile_psd(profile, *, nperseg: int | None = None, noverlap: int | None = None, window: str = "hann",
                detrend: str = "linear"):
    """One-sided PSD of the heights [m3 = m2 / m-1] over ``spatial_frequency`` [m-1] (Welch).

    Parameters
    ----------
    profile : xarray.DataArray
        Heights [m] over uniformly sampled ``x`` [m].
    nperseg : int, optional
        Segment length [samples]; default the largest power of two <= n / 4.
    noverlap : int, optional
        Overlap [samples]; default ``nperseg // 2``.
    window : str, default "hann"
        Taper (:func:`scipy.signal.get_window`).
    detrend : {"linear", "constant", False}, default "linear"
        Per-segment detrending.

    Returns
    -------
    xarray.DataArray
        Density such that ``sum(psd) * df`` is the variance of the detrended heights [m2]; all the
        settings, ``sample_spacing`` [m] and ``frequency_resolution`` [m-1] in attrs. Computed by
        fivid's Welch estimator (:func:`fivid.signal.spectral.welch_density`) with ``fs = 1 / Δx``.
    """
    import xarray as xr

    step = sampling_step(profile)
    z = np.asarray(profile.values, dtype=np.float64)
    nperseg = _default_nperseg(z.size) if nperseg is None else int(nperseg)
    if not 2 <= nperseg <= z.size:
        raise ConfigError(f"nperseg must be between 2 and the {z.size} samples of the profile, got {nperseg}",
                          key="nperseg")
    noverlap = nperseg // 2 if noverlap is None else int(noverlap)
    f, psd = welch_density(z, 1.0 / step, nperseg=nperseg, noverlap=noverlap, window=window, detrend=detrend)
    return xr.DataArray(
        psd, dims="spatial_frequency", name="psd_height",
        coords={"spatial_frequency": ("spatial_frequency", f, {"units": "m-1", "long_name": "spatial frequency"})},
        attrs={"units": "m3", "long_name": "power spectral density of the profile heights",
               "estimator": "Welch (fivid.signal.spectral.welch_density), average='mean'", "scaling": "density", "window": window,
               "nperseg": nperseg, "noverlap": noverlap, "detrend": str(detrend), "sample_spacing": step,
               "sample_spacing_units": "m", "frequency_resolution": 1.0 / (nperseg * step),
               "frequency_resolution_units": "m-1"},
    )


def autocorrelation(profile, *, max_lag: float | None = None):
    """Normalised autocorrelation ρ(τ) [1] of the heights (mean removed) over ``lag`` τ [m].

    The biased estimator ``Σ z_i z_(i+k) / Σ z_i²`` (by FFT with zero padding), which is positive
    semi-definite; ``max_lag`` [m] limits the lags returned (default half the record).
    """
    import xarray as xr

    step = sampling_step(profile)
    z = np.asarray(profile.values, dtype=np.float64)
    z = z - z.mean()
    n = z.size
    nfft = 1 << (2 * n - 1).bit_length()
    spec = np.fft.rfft(z, nfft)
    acov = np.fft.irfft(spec * np.conj(spec), nfft)[:n]
    if acov[0] <= 0:
        raise ConfigError("the profile is flat: its autocorrelation is undefined", key="profile")
    kmax = n // 2 if max_lag is None else min(n - 1, int(math.floor(max_lag / step)))
    lag = np.arange(kmax + 1) * step
    return xr.DataArray(
        acov[: kmax + 1] / acov[0], dims="lag", name="autocorrelation",
        coords={"lag": ("lag", lag, {"units": "m", "long_name": "lag"})},
        attrs={"units": "1", "long_name": "normalised autocorrelation of the profile heights",
               "estimator": "biased (divided by the sum of squares), mean removed, FFT"},
    )


def correlation_length(acf, *, level: float = math.exp(-1.0)) -> float:
    """First lag [m] where the autocorrelation falls to ``level`` (1/e by default), interpolated linearly.

    NaN if it never does within the lags given.
    """
    rho = np.asarray(acf.values, dtype=np.float64)
    lag = np.asarray(acf["lag"].values, dtype=np.float64)
    below = np.flatnonzero(rho <= level)
    if below.size == 0 or below[0] == 0:
        return float("nan")
    k = below[0]
    return float(lag[k - 1] + (rho[k - 1] - level) / (rho[k - 1] - rho[k]) * (lag[k] - lag[k - 1]))
