"""Synthetic Gaussian random profiles by spectral synthesis (numpy FFT), reproducible from a seed.

A periodic profile of ``n`` samples every ``Δx`` is built from its discrete Fourier coefficients:
at the spatial frequencies ``f_m = m / (n Δx)``, ``m = 1 ... n/2``, each coefficient is a complex
Gaussian whose power is ``G(f_m) Δf`` (one-sided PSD ``G`` [m3], ``Δf = 1 / (n Δx)``), the mean is
zero. The heights are then a stationary Gaussian process with that PSD; the expected mean square
is ``Σ G(f_m) Δf``, and a realisation scatters about it with variance ``Σ (G(f_m) Δf)²``.

Parametric forms (ACF → one-sided PSD, f in cycles per metre, σ = Rq, ξ = correlation length at
which the ACF falls to 1/e):

* Gaussian ACF ``σ² exp(-(τ/ξ)²)`` → ``G(f) = 2 σ² ξ √π exp(-(π f ξ)²)``;
* exponential ACF ``σ² exp(-|τ|/ξ)`` → ``G(f) = 4 σ² ξ / (1 + (2 π f ξ)²)``.

For these the discrete PSD is scaled so that the expected Rq² is exactly σ² on the chosen grid.
Results carry ``synthetic = "yes"``, the generator, its parameters and the seed in attrs.
"""

from __future__ import annotations

import math

import numpy as np

from fivid.errors import ConfigError
from fivid.schema import new_history
from fivid.surface.profile import MIN_POINTS, make_profile

__all__ = ["gaussian_random_profile", "profile_from_psd", "acf_psd", "ACF_SHAPES"]

ACF_SHAPES = ("gaussian", "exponential")


def acf_psd(frequency, rq: float, correlation_length: float, acf: str = "gaussian"):
    """One-sided PSD [m3] at spatial frequencies ``frequency`` [m-1] of a Gaussian or exponential ACF."""
    f = np.asarray(frequency, dtype=np.float64)
    xi = correlation_length
    if acf == "gaussian":
        return 2 * rq**2 * xi * math.sqrt(math.pi) * np.exp(-((math.pi * f * xi) ** 2))
    if acf == "exponential":
        return 4 * rq**2 * xi / (1 + (2 * math.pi * f * xi) ** 2)
    raise ConfigError(f"unknown autocorrelation shape {acf!r}; choose one of {ACF_SHAPES}", key="acf")


def _grid(length: float, step: float) -> int:
    if not (step > 0 and length > 0 and math.isfinite(length) and math.isfinite(step)):
        raise ConfigError(f"length and step must be positive lengths, got {length!r} m and {step!r} m",
                          key="length")
    n = int(round(length / step))
    if n < MIN_POINTS:
        raise ConfigError(f"length {length:g} m / step {step:g} m gives {n} points; need at least {MIN_POINTS}",
                          key="length")
    return n


def _synthesise(bin_power: np.ndarray, n: int, rng) -> np.ndarray:
    """Heights whose DFT bin m (1 ... n//2) carries expected power ``bin_power[m]`` [m2] (bin 0 must be 0)."""
    coeff = rng.standard_normal(n // 2 + 1) + 1j * rng.standard_normal(n // 2 + 1)
    scale = n * np.sqrt(bin_power) / 2
    if n % 2 == 0:  # the Nyquist bin is real and carries its power alone
        coeff[-1] = rng.standard_normal() * math.sqrt(2.0)
        scale[-1] = n * math.sqrt(bin_power[-1]) / math.sqrt(2.0)
    return np.fft.irfft(coeff * scale, n)


def _wrap(z, step, rng_seed, attrs):
    x = np.arange(z.size) * step
    base = {"synthetic": "yes", "instrument": "none (synthetic)", "seed": "none" if rng_seed is None else rng_seed,
            "sample_spacing": step, "sample_spacing_units": "m"}
    base.update(attrs)
    base["source"] = base["generator"]
    base["history"] = new_history(f"{base['generator']} with {attrs.get('parameters', '')}, seed {base['seed']}")
    return make_profile(x, z, attrs=base, label="synthetic profile")


def gaussian_random_profile(rq: float, correlation_length: float, length: float, step: float, *,
                            acf: str = "gaussian", seed: int | None = None):
    """A Gaussian random profile with rms height ``rq`` [m] and 1/e correlation length [m].

    Parameters
    ----------
    rq : float
        Expected Rq [m] (σ of the heights).
    correlation_length : float
        Lag [m] at which the autocorrelation falls to 1/e.
    length : float
        Record length [m]; ``n = round(length / step)`` samples, periodic.
    step : float
        Sampling step [m]; keep it well below the correlation length (≤ ξ/5) to resolve the ACF.
    acf : {"gaussian", "exponential"}, default "gaussian"
        Shape of the autocorrelation.
    seed : int, optional
        Seed of :func:`numpy.random.default_rng`; the same seed gives the same profile.

    Returns
    -------
    xarray.DataArray
        The profile; attrs ``synthetic = "yes"``, ``generator``, ``rq``, ``correlation_length``,
        ``acf``, ``seed``, ``history``. A realisation's Rq scatters about ``rq`` with a relative standard
        deviation of about ``sqrt(ξ √(2π) / L) / 2`` (Gaussian ACF; record length L).
    """
    if not (rq >= 0 and correlation_length > 0):
        raise ConfigError(f"rq must be >= 0 and correlation_length > 0, got {rq!r} m and {correlation_length!r} m",
                          key="rq")
    n = _grid(length, step)
    f = np.arange(n // 2 + 1) / (n * step)
    power = acf_psd(f, 1.0, correlation_length, acf) / (n * step)
    power[0] = 0.0
    power *= rq**2 / power.sum() if power.sum() > 0 else 0.0
    z = _synthesise(power, n, np.random.default_rng(seed))
    params = f"rq={rq!r} m, correlation_length={correlation_length!r} m, acf={acf}, length={n * step!r} m"
    return _wrap(z, step, seed, {"generator": "fivid.surface.gaussian_random_profile (spectral synthesis, numpy FFT)",
                                 "parameters": params, "rq": float(rq), "rq_units": "m",
                                 "correlation_length": float(correlation_length), "correlation_length_units": "m",
                                 "acf": acf})


def profile_from_psd(psd, length: float, step: float, *, seed: int | None = None):
    """A Gaussian random profile with a given one-sided PSD.

    Parameters
    ----------
    psd : callable or (ndarray, ndarray)
        ``G(f)`` [m3] of the spatial frequency f [m-1], or a table ``(f, G)`` interpolated linearly
        (zero outside it).
    length, step : float
        Record length and sampling step [m].
    seed : int, optional
        Seed of :func:`numpy.random.default_rng`.

    Returns
    -------
    xarray.DataArray
        The profile (expected Rq² = Σ G(f_m) Δf over the grid's frequencies), ``synthetic = "yes"``.
    """
    n = _grid(length, step)
    f = np.arange(n // 2 + 1) / (n * step)
    if callable(psd):
        g, how = np.asarray(psd(f), dtype=np.float64), "callable"
    else:
        ft, gt = (np.asarray(a, dtype=np.float64) for a in psd)
        g, how = np.interp(f, ft, gt, left=0.0, right=0.0), f"table of {ft.size} points"
    if g.shape != f.shape or not np.all(np.isfinite(g)) or np.any(g < 0):
        raise ConfigError("the PSD must give finite values >= 0 at every frequency", key="psd")
    power = g / (n * step)
    power[0] = 0.0
    z = _synthesise(power, n, np.random.default_rng(seed))
    return _wrap(z, step, seed, {"generator": "fivid.surface.profile_from_psd (spectral synthesis, numpy FFT)",
                                 "parameters": f"psd={how}, length={n * step!r} m",
                                 "expected_rq": float(math.sqrt(power.sum())), "expected_rq_units": "m"})
