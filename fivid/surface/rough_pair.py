"""Two rough profiles for a sliding pair (seed 003): Gaussian synthetic profiles of a given Ra, and how a Gaussian
profile's Rq, Ra, Rsm and correlation length relate."""

from __future__ import annotations

import numpy as np

from fivid.surface.profile import make_profile
from fivid.surface.synthesis import gaussian_random_profile

__all__ = ["RQ_PER_RA", "RSM_PER_CORRELATION_LENGTH", "synthetic_rough_profiles"]

#: Rq / Ra of a Gaussian height distribution, sqrt(pi / 2)
RQ_PER_RA = float(np.sqrt(np.pi / 2.0))
#: Rsm / correlation length of a Gaussian-ACF profile (ACF exp(-x^2/xi^2)): an element is a peak and a valley,
#: twice the mean zero-crossing spacing pi sqrt(-R(0)/R''(0)) = pi xi / sqrt(2) (Rice 1944)
RSM_PER_CORRELATION_LENGTH = float(np.sqrt(2.0) * np.pi)


def synthetic_rough_profiles(ra: float, length: float, *, correlation_length: float = 1e-3, step: float = 50e-6,
                             seeds=(3, 4), acf: str = "gaussian"):
    """Two Gaussian random profiles (lower, upper) of expected ``Rq = sqrt(pi/2) ra`` over ``[0, length]`` [m].

    The profiles are periodic (spectral synthesis); the first sample is repeated at ``x = length`` so that they
    cover the body. ``ra = 0`` gives flat (zero) profiles.
    """
    out = []
    for seed in seeds:
        p = gaussian_random_profile(RQ_PER_RA * float(ra), correlation_length, length, step, acf=acf, seed=int(seed))
        x = np.append(p["x"].values, length)
        z = np.append(p.values, p.values[0])
        out.append(make_profile(x, z, attrs=dict(p.attrs), label="synthetic profile"))
    return tuple(out)
