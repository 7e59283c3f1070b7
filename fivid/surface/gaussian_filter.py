"""The Gaussian profile filter of ISO 16610-21 (formerly ISO 11562): mean line, roughness, waviness.

Weighting function (ISO 16610-21 eq. 1)::

    s(x) = 1 / (α λc) · exp(-π (x / (α λc))²),   α = sqrt(ln 2 / π) ≈ 0.4697

Its amplitude transmission is ``exp(-π (α λc / λ)²)`` for the mean line: 50 % at λ = λc. The
roughness profile is the profile minus the mean line (transmission 1 - that); the waviness
profile is the mean line itself.

Discretisation: s is sampled at ``k Δx`` for ``|k Δx| <= λc`` (truncation at ±λc, where s has
fallen to 6.5e-7 of its peak) and the weights ``Δx s(k Δx)`` are divided by their sum, so a
constant passes unchanged (ISO 16610-21 §4.2).

Ends: near the ends of the record the truncated weights are divided by the sum of the weights
that fall on the record (the zero-order end-effect correction of ISO/TS 16610-28), so the mean line
is defined everywhere. It is still biased within about λc/2 of each end, where the weights are
one-sided; :func:`fivid.surface.evaluate_profile` therefore drops λc/2 at each end before
computing parameters (``ends="trim"``, the run-in/run-out of ISO 21920-3) unless asked to keep them.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["ALPHA", "gaussian_weights", "gaussian_weighting_function", "gaussian_mean_line",
           "mean_line_transmission", "TRUNCATION"]

ALPHA = math.sqrt(math.log(2.0) / math.pi)
TRUNCATION = 1.0  # the weights cover ±TRUNCATION·λc


def gaussian_weighting_function(x, cutoff: float):
    """s(x) [m-1] of ISO 16610-21 for cut-off ``cutoff`` = λc [m] at offsets ``x`` [m]."""
    a = ALPHA * cutoff
    return np.exp(-np.pi * (np.asarray(x, dtype=np.float64) / a) ** 2) / a


def gaussian_weights(step: float, cutoff: float) -> tuple[np.ndarray, np.ndarray]:
    """Offsets [m] and normalised discrete weights [1] of the Gaussian filter (odd length, symmetric).

    ``weights = Δx s(offsets) / Σ Δx s(offsets)`` with offsets ``k Δx``, ``|k| <= λc / Δx``.
    """
    half = int(math.floor(TRUNCATION * cutoff / step + 1e-9))
    offsets = np.arange(-half, half + 1) * step
    weights = step * gaussian_weighting_function(offsets, cutoff)
    return offsets, weights / weights.sum()


def mean_line_transmission(wavelength, cutoff: float):
    """Amplitude transmission of the mean line for a sine of ``wavelength`` [m]: exp(-π (α λc / λ)²)."""
    return np.exp(-np.pi * (ALPHA * cutoff / np.asarray(wavelength, dtype=np.float64)) ** 2)


def gaussian_mean_line(z, step: float, cutoff: float) -> np.ndarray:
    """The Gaussian mean line [m] of heights ``z`` [m] sampled every ``step`` [m], for cut-off λc [m].

    Same length as ``z``; near the ends the weights on the record are renormalised (module notes).
    """
    from scipy.signal import oaconvolve

    z = np.asarray(z, dtype=np.float64)
    _, w = gaussian_weights(step, cutoff)
    if w.size > 2 * z.size - 1:  # the kernel only needs to reach across the record
        excess = (w.size - (2 * z.size - 1)) // 2
        w = w[excess:w.size - excess]
    smoothed = oaconvolve(z, w, mode="same")
    coverage = oaconvolve(np.ones_like(z), w, mode="same")
    return smoothed / coverage
