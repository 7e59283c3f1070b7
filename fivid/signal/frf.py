"""Frequency-response function estimators H1 and H2, and the ordinary coherence.

From Welch auto- and cross-spectra of an input ``x`` (e.g. a force [N]) and an output ``y`` (e.g. an
acceleration [m s-2]) on the same time grid (Bendat & Piersol, *Random Data*, 4th ed., §9.2):

* ``H1 = Pxy / Pxx`` — unbiased by noise on the output;
* ``H2 = Pyy / Pyx = Pyy / conj(Pxy)`` — unbiased by noise on the input;
* ``γ² = |Pxy|² / (Pxx Pyy) = H1 / H2`` — 1 for a noise-free linear system.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import ConfigError
from fivid.units import ratio_units
from fivid.signal.welch import csd

__all__ = ["frf", "coherence", "FRF_ESTIMATORS"]

FRF_ESTIMATORS = ("H1", "H2")


def frf(x, y, *, nperseg=None, estimator="H1", noverlap=None, window="hann", detrend="constant", fs=None, backend=None):
    """Frequency-response function from input ``x`` to output ``y`` by the H1 or H2 estimator.

    Parameters
    ----------
    x, y : xarray.DataArray
        Input [u] and output [v] signals on the same uniform ``time`` [s].
    nperseg, noverlap, window, detrend, fs, backend
        Welch settings, as in :func:`fivid.signal.welch_psd` (default ``nperseg``:
        :func:`fivid.signal.welch.default_nperseg`).
    estimator : {"H1", "H2"}, default "H1"
        H1 when the noise is on the output, H2 when it is on the input.

    Returns
    -------
    xarray.DataArray
        Complex FRF [v u-1] on ``frequency`` [Hz], with coordinate ``coherence`` [1] and the Welch
        settings in attrs.
    """
    import xarray as xr

    if estimator not in FRF_ESTIMATORS:
        raise ConfigError(f"unknown FRF estimator {estimator!r}; choose one of {', '.join(FRF_ESTIMATORS)}",
                          key="estimator")
    spectra = csd(x, y, nperseg=nperseg, noverlap=noverlap, window=window, detrend=detrend, fs=fs, backend=backend)
    pxx, pyy, pxy = (spectra[k].values for k in ("pxx", "pyy", "pxy"))
    with np.errstate(divide="ignore", invalid="ignore"):
        h = pxy / pxx if estimator == "H1" else pyy / np.conj(pxy)
        gamma2 = np.abs(pxy) ** 2 / (pxx * pyy)
    units = ratio_units(y.attrs["units"], x.attrs["units"])
    attrs = dict(spectra.attrs)
    attrs.update({"units": units, "estimator": estimator,
                  "long_name": f"frequency response function {y.name}/{x.name} ({estimator})"})
    return xr.DataArray(
        h, dims="frequency", name=f"frf_{estimator}",
        coords={"frequency": spectra["frequency"],
                "coherence": ("frequency", gamma2, {"units": "1", "long_name": f"coherence of {x.name} and {y.name}"})},
        attrs=attrs,
    )


def coherence(x, y, *, nperseg=None, noverlap=None, window="hann", detrend="constant", fs=None, backend=None):
    """Magnitude-squared coherence ``|Pxy|² / (Pxx Pyy)`` [1] of two signals on the same time grid.

    Equals :func:`scipy.signal.coherence` for identical settings; 1 for a noise-free linear system.
    """
    import xarray as xr

    spectra = csd(x, y, nperseg=nperseg, noverlap=noverlap, window=window, detrend=detrend, fs=fs, backend=backend)
    with np.errstate(divide="ignore", invalid="ignore"):
        gamma2 = np.abs(spectra["pxy"].values) ** 2 / (spectra["pxx"].values * spectra["pyy"].values)
    attrs = dict(spectra.attrs)
    attrs.update({"units": "1", "long_name": f"magnitude-squared coherence of {x.name} and {y.name}"})
    return xr.DataArray(gamma2, dims="frequency", coords={"frequency": spectra["frequency"]}, name="coherence",
                        attrs=attrs)
