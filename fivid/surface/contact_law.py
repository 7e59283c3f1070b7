"""Greenwood-Williamson parameters of a rough surface from a measured profile (McCool's spectral moments).

The Greenwood-Williamson (GW) contact law (:mod:`fivid.contact.laws`) needs three summit statistics: the
standard deviation of the summit heights ``sigma_s`` [m], the summit radius ``R`` [m] and the summit density
``eta`` [m-2]. A stylus profile does not show summits (2D maxima), only profile peaks, so they are estimated
from the profile's spectral moments under the assumption of an isotropic Gaussian surface (Nayak 1971, Random
process model of rough surfaces, J. Lubr. Technol. 93: 398-407; McCool 1986, Comparison of models for the
contact of rough surfaces, Wear 107: 37-60, eqs. 9-13):

- ``m0 = <z^2>``, ``m2 = <z'^2>``, ``m4 = <z''^2>`` (mean-square height, slope, curvature of the profile;
  slope and curvature by central differences), bandwidth ``alpha = m0 m4 / m2^2`` (>= 1.5 for an isotropic
  surface, 3 for a Gaussian autocorrelation, large for broadband surfaces);
- ``eta = m4 / (6 pi sqrt(3) m2)`` (Nayak's summit density, exact for an isotropic Gaussian surface);
- ``R = 0.375 sqrt(pi / m4)`` (the inverse of the mean summit curvature ``(8/3) sqrt(m4 / pi)``);
- ``sigma_s = sqrt(1 - 0.8968 / alpha) sqrt(m0)``, with the summits' mean height ``4 sqrt(m0 / (pi alpha))``
  above the mean plane.

The curvature moment weighs the shortest wavelengths most: stylus noise and the stylus tip set it as much as the
surface does. Filter the profile's short wavelengths first (``fivid profile --short-cutoff``, ISO 3274's lambda_s)
and report the cut-off with the parameters. Why GW and not a law that fits better: for the normal stiffness at
the preloads of a beam contact (nominal pressures 1 kPa-1 MPa, a few per cent of the summits touching), GW with
these parameters is within the spread of the more elaborate asperity models (McCool's comparison: Bush-Gibson-
Thomas and Nayak's model differ from GW mostly through ``alpha``, little for ``alpha`` >= 3) and it is the law the
solver tabulates exactly; Persson's theory gains over it near full contact, far above these loads.

Checked against direct summit identification (8-neighbour maxima, curvature from the 5-point Laplacian) on
synthetic isotropic Gaussian surfaces (:func:`gaussian_random_surface`, :func:`surface_summits`): tests/surface/test_surface_contact_law.py.
"""

from __future__ import annotations

import math

import numpy as np

from fivid.errors import ConfigError

__all__ = ["spectral_moments", "gw_from_moments", "gw_parameters", "gw_config", "gaussian_random_surface",
           "surface_summits", "SUMMIT_SIGMA_COEFFICIENT"]

#: McCool's coefficient in sigma_s = sqrt(1 - c / alpha) sqrt(m0)
SUMMIT_SIGMA_COEFFICIENT = 0.8968


def spectral_moments(z, step: float) -> tuple[float, float, float]:
    """``(m0 [m2], m2 [1], m4 [m-2])`` of a profile's heights ``z`` [m] sampled every ``step`` [m].

    ``m0`` is the mean square of ``z - mean(z)``, ``m2`` that of the central-difference slope and ``m4`` that of the
    second difference (interior samples only; a form is removed beforehand by the caller). The differences
    under-estimate ``m2`` and ``m4`` by about ``(k h)^2 / 6`` and ``(k h)^2 / 12`` at wavenumber ``k``: sample at
    least ten points per shortest wavelength kept.
    """
    z = np.asarray(z, dtype=np.float64)
    if z.ndim != 1 or z.size < 5:
        raise ConfigError(f"a profile needs at least 5 heights to estimate spectral moments, got {z.size}", key="z")
    if not step > 0:
        raise ConfigError(f"the sampling step must be > 0 m, got {step!r}", key="step")
    z = z - z.mean()
    slope = (z[2:] - z[:-2]) / (2.0 * step)
    curv = (z[2:] - 2.0 * z[1:-1] + z[:-2]) / step**2
    return float(np.mean(z**2)), float(np.mean(slope**2)), float(np.mean(curv**2))


def gw_from_moments(m0: float, m2: float, m4: float) -> dict:
    """GW summit statistics of an isotropic Gaussian surface from its profile moments (McCool 1986; module doc).

    Returns ``{"sigma": sigma_s [m], "asperity_radius": R [m], "asperity_density": eta [m-2], "alpha",
    "mean_summit_height" [m], "rq" [m]}``. Raises :class:`ConfigError` for moments not positive or a bandwidth
    below the isotropic bound 1.5 (not an isotropic Gaussian surface: a periodic or very narrow-band profile).
    """
    if not (m0 > 0 and m2 > 0 and m4 > 0):
        raise ConfigError(f"spectral moments must be > 0, got m0 {m0!r} m2, m2 {m2!r}, m4 {m4!r} m-2 (a flat profile?)",
                          key="profile")
    alpha = m0 * m4 / m2**2
    if alpha < 1.5:
        raise ConfigError(f"bandwidth parameter alpha = m0 m4 / m2^2 = {alpha:.3g} is below 1.5, the bound of an "
                          "isotropic Gaussian surface: the profile is not one (periodic or narrow-band)", key="profile")
    return {"sigma": math.sqrt(1.0 - SUMMIT_SIGMA_COEFFICIENT / alpha) * math.sqrt(m0),
            "asperity_radius": 0.375 * math.sqrt(math.pi / m4),
            "asperity_density": m4 / (6.0 * math.pi * math.sqrt(3.0) * m2),
            "alpha": alpha, "mean_summit_height": 4.0 * math.sqrt(m0 / (math.pi * alpha)), "rq": math.sqrt(m0)}


def gw_parameters(z, step: float) -> dict:
    """:func:`gw_from_moments` of :func:`spectral_moments` of a profile (heights ``z`` [m] every ``step`` [m]), with
    the moments ``m0``, ``m2``, ``m4`` added."""
    m0, m2, m4 = spectral_moments(z, step)
    return {**gw_from_moments(m0, m2, m4), "m0": m0, "m2": m2, "m4": m4}


def gw_config(params: dict) -> dict:
    """The ``normal:`` block of a model config's contact (docs/model-config.md) from :func:`gw_parameters`."""
    return {"law": "greenwood-williamson", "sigma": f"{params['sigma']:.4g} m",
            "asperity_radius": f"{params['asperity_radius']:.4g} m",
            "asperity_density": f"{params['asperity_density']:.4g} m^-2"}


def gaussian_random_surface(n: int, step: float, psd, rq: float, *, seed: int | None = None) -> np.ndarray:
    """A periodic isotropic Gaussian random surface (``n x n`` heights [m], SYNTHETIC) by spectral synthesis.

    ``psd(q)``: the radial spectral shape at wavenumbers ``q`` [cycles m-1] (any scale: the heights are scaled to
    the sample rms ``rq`` [m]); complex Gaussian Fourier coefficients of variance ``psd(|q|)``, inverse FFT (numpy),
    real part. ``seed``: :func:`numpy.random.default_rng`.
    """
    rng = np.random.default_rng(seed)
    k = np.fft.fftfreq(int(n), step)
    q = np.hypot(*np.meshgrid(k, k, indexing="ij"))
    amp = np.sqrt(np.asarray(psd(q), dtype=np.float64))
    amp[0, 0] = 0.0
    z = np.fft.ifft2((rng.standard_normal(q.shape) + 1j * rng.standard_normal(q.shape)) * amp).real
    return z * (rq / z.std())


def surface_summits(z, step: float) -> dict:
    """Summits of a periodic surface ``z`` [m] on a square grid of ``step`` [m], identified directly.

    A summit is a sample higher than its 8 neighbours; its curvature is the mean of the two principal curvatures,
    ``-(z_xx + z_yy) / 2`` by the 5-point Laplacian. Returns ``{"density" [m-2], "heights" [m] (above the mean
    plane), "curvatures" [m-1], "radius": 1 / mean curvature [m], "sigma": std of the summit heights [m]}`` -- the
    reference of the spectral-moment estimator (resolve the shortest wavelength by >= 10 samples).
    """
    z = np.asarray(z, dtype=np.float64) - np.mean(z)
    top = np.ones(z.shape, dtype=bool)
    for i in (-1, 0, 1):
        for j in (-1, 0, 1):
            if i or j:
                top &= z > np.roll(np.roll(z, i, 0), j, 1)
    lap = (np.roll(z, 1, 0) + np.roll(z, -1, 0) + np.roll(z, 1, 1) + np.roll(z, -1, 1) - 4.0 * z) / step**2
    curv = -0.5 * lap[top]
    return {"density": float(top.sum() / (z.size * step**2)), "heights": z[top], "curvatures": curv,
            "radius": float(1.0 / np.mean(curv)), "sigma": float(np.std(z[top]))}
