"""Two rough profiles for a sliding pair (seed 003): Gaussian synthetic profiles of a given Ra, seed 003's Table 1
surfaces (Gaussian profiles matched to the table's Ra and Rsm, :func:`table1_profiles`), and how a Gaussian
profile's Rq, Ra, Rsm and correlation length relate."""

from __future__ import annotations

import numpy as np

from fivid.errors import ConfigError
from fivid.surface.metrology import evaluate_profile
from fivid.surface.profile import make_profile, sampling_step
from fivid.surface.readers import read_profile
from fivid.surface.synthesis import gaussian_random_profile

__all__ = ["RQ_PER_RA", "RSM_PER_CORRELATION_LENGTH", "TABLE1", "iso_cutoff", "synthetic_rough_profiles",
           "table1_profile", "table1_profiles", "table1_row", "profile_over_length", "measured_rough_profiles"]

#: Rq / Ra of a Gaussian height distribution, sqrt(pi / 2)
RQ_PER_RA = float(np.sqrt(np.pi / 2.0))
#: Rsm / correlation length of a Gaussian-ACF profile (ACF exp(-x^2/xi^2)): an element is a peak and a valley,
#: twice the mean zero-crossing spacing pi sqrt(-R(0)/R''(0)) = pi xi / sqrt(2) (Rice 1944)
RSM_PER_CORRELATION_LENGTH = float(np.sqrt(2.0) * np.pi)

#: seed 003's Table 1 (EDM surfaces measured by profilometer): Ra [m], skewness Sk, kurtosis Ek, Rsm [m], sigma [m]
#: (std of the asperity heights), attack angle alpha [deg] and apex angle theta [deg], one row per surface
TABLE1 = (
    {"Ra": 1e-6, "Sk": -0.07, "Ek": 3.1, "Rsm": 92e-6, "sigma": 1.1e-6, "alpha": 6.3, "theta": 167.4},
    {"Ra": 4.5e-6, "Sk": -0.03, "Ek": 3.15, "Rsm": 150e-6, "sigma": 4.1e-6, "alpha": 7.3, "theta": 165.4},
    {"Ra": 10e-6, "Sk": 0.17, "Ek": 2.96, "Rsm": 276e-6, "sigma": 10e-6, "alpha": 12.2, "theta": 155.6},
    {"Ra": 20e-6, "Sk": 0.25, "Ek": 2.9, "Rsm": 410e-6, "sigma": 13e-6, "alpha": 13.0, "theta": 154.0},
    {"Ra": 26e-6, "Sk": 0.0, "Ek": 2.83, "Rsm": 516e-6, "sigma": 8.62e-6, "alpha": 13.5, "theta": 153.0},
)


def table1_row(ra: float) -> dict:
    """The :data:`TABLE1` row of roughness ``ra`` [m] (within 1 %); ConfigError naming the table's Ra otherwise."""
    for row in TABLE1:
        if abs(float(ra) - row["Ra"]) <= 0.01 * row["Ra"]:
            return dict(row)
    raise ConfigError(f"Ra {float(ra) * 1e6:g} um is not a row of seed 003's Table 1; allowed: "
                      f"{', '.join(format(r['Ra'] * 1e6, 'g') for r in TABLE1)} um", key="roughness_ra")


def iso_cutoff(rsm: float) -> float:
    """ISO 4288's (Table 3) roughness cut-off lambda_c [m] for measuring RSm: by the profile's ``rsm`` [m]
    (<= 40 um: 0.08 mm, <= 130 um: 0.25 mm, <= 400 um: 0.8 mm, <= 1.3 mm: 2.5 mm, above: 8 mm). Rsm's width
    discrimination (1 % of the sampling length lambda_c) and height discrimination (10 % of Rz) depend on it."""
    for bound, lc in ((40e-6, 0.08e-3), (130e-6, 0.25e-3), (400e-6, 0.8e-3), (1.3e-3, 2.5e-3)):
        if rsm <= bound * (1 + 1e-9):
            return lc
    return 8e-3


def _iso(profile, cutoff: float) -> dict:
    return evaluate_profile(profile, form="line", cutoff=cutoff).parameters


def table1_profile(ra: float, rsm: float, length: float, *, seed: int, step: float | None = None,
                   tolerance: float = 0.05, max_iterations: int = 15):
    """A Gaussian random profile over ``[0, length]`` [m] whose ISO 4287 Ra and Rsm match ``ra`` and ``rsm`` [m].

    Spectral synthesis (:func:`fivid.surface.gaussian_random_profile`, Gaussian ACF, seed ``seed``); its
    correlation length starts at Rice's ``rsm /`` :data:`RSM_PER_CORRELATION_LENGTH` and is corrected by the ratio
    target / realised Rsm (fixed point, damped after two steps; the same random phases every iteration) until the
    realised Rsm is within ``tolerance / 5``, else scanned over +-15 % about the closest (a short profile's Rsm moves
    by whole elements), keeping the closest, which must be within ``tolerance``; the heights are then scaled so the
    realised Ra equals ``ra``. Ra and Rsm are measured as a
    profilometer does (:func:`fivid.surface.evaluate_profile`: line removed, Gaussian filter at ISO 4288's
    cut-off :func:`iso_cutoff` for ``rsm``, the cut-off's half trimmed at each end, Rsm with ISO's 10 %-of-Rz
    height discrimination). ``step`` [m]: synthesis step, default a sixth of the starting correlation length
    (rounded so that ``length`` is a whole number of steps).

    Returns
    -------
    xarray.DataArray
        The profile (the first sample repeated at ``x = length``, periodic); attrs ``correlation_length``,
        ``iso_Ra``, ``iso_Rsm``, ``iso_Rz`` [m], ``iso_cutoff`` [m], ``target_Ra``, ``target_Rsm`` [m],
        ``iterations``.

    Raises
    ------
    ConfigError
        Rsm not within ``tolerance`` after ``max_iterations`` (the closest value reached named).
    """
    ra, rsm = float(ra), float(rsm)
    lc = iso_cutoff(rsm)
    xi = rsm / RSM_PER_CORRELATION_LENGTH
    step = float(step) if step else xi / 6.0
    step = length / max(1, round(length / step))  # a whole number of steps: the periodic copy lands on x = length
    best = None
    for it in range(1, int(max_iterations) + 1):
        p = gaussian_random_profile(RQ_PER_RA * ra, xi, length, step, seed=int(seed))
        got = _iso(p, lc)
        err = abs(got["Rsm"] / rsm - 1.0)
        if best is None or err < best[0]:
            best = (err, p, got, xi, it)
        if err <= tolerance / 5:
            break
        # a short profile's Rsm moves in steps of whole elements: damp the correction after the first two
        xi *= (rsm / got["Rsm"]) ** (1.0 if it <= 2 else 0.5)
    if best[0] > tolerance / 5:  # a step function of xi near the target: scan +-15 % about the closest
        for f in np.linspace(0.85, 1.15, 31):
            p = gaussian_random_profile(RQ_PER_RA * ra, best[3] * f, length, step, seed=int(seed))
            got = _iso(p, lc)
            err = abs(got["Rsm"] / rsm - 1.0)
            it += 1
            if err < best[0]:
                best = (err, p, got, best[3] * f, it)
    err, p, got, xi, it = best
    if err > tolerance:
        raise ConfigError(f"Rsm {rsm * 1e6:g} um not reached within {tolerance:.0%} after {max_iterations} "
                          f"iterations (closest {got['Rsm'] * 1e6:.4g} um at correlation length {xi * 1e6:.4g} um, "
                          f"seed {seed})", key="rsm")
    z = p.values * (ra / got["Ra"])
    x = np.append(p["x"].values, length)
    out = make_profile(x, np.append(z, z[0]), attrs=dict(p.attrs), label="synthetic profile (seed 003 Table 1)")
    final = _iso(out, lc)
    out.attrs.update({"correlation_length": float(xi), "iso_Ra": float(final["Ra"]), "iso_Rsm": float(final["Rsm"]),
                      "iso_Rz": float(final["Rz"]), "iso_cutoff": lc, "target_Ra": ra, "target_Rsm": rsm,
                      "iterations": it})
    return out


def table1_profiles(ra: float, length: float, *, seeds=(3, 4), rsm: float | None = None, step: float | None = None):
    """Two :func:`table1_profile` s (lower, upper) of seed 003's Table 1 surface of roughness ``ra`` [m] (its Rsm
    from :data:`TABLE1` unless ``rsm`` [m] is given), one seed each."""
    rsm = table1_row(ra)["Rsm"] if rsm is None else float(rsm)
    return tuple(table1_profile(ra, rsm, length, seed=int(s), step=step) for s in seeds)


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


def profile_over_length(profile, length: float):
    """A measured profile (heights [m] over ``x`` [m], uniformly sampled) laid over ``[0, length]`` [m]: its
    least-squares line removed, ``x`` from 0, and, when shorter than ``length``, continued by mirror images
    (trace, reversed trace, trace ...: continuous heights, no step at the joins; the continuation repeats the
    trace's asperities, so Rsm and the height distribution are kept, not its longest wavelengths). attrs
    ``mirrored_copies`` (how many traces cover the length) and ``trace_length`` [m]."""
    x = np.asarray(profile["x"].values, float)
    z = np.asarray(profile.values, float)
    z = z - np.polyval(np.polyfit(x, z, 1), x)
    step = sampling_step(profile)
    span = x[-1] - x[0]
    copies = int(np.ceil(length / span - 1e-9)) if span > 0 else 1
    parts = [z if k % 2 == 0 else z[::-1] for k in range(copies)]
    joined = np.concatenate([parts[0]] + [p[1:] for p in parts[1:]])  # the mirror shares the end sample
    xs = np.arange(joined.size) * step
    keep = xs <= length + 0.5 * step
    if xs[keep][-1] < length:  # cover the body to its end
        keep[np.argmax(~keep)] = True
    out = make_profile(xs[keep], joined[keep], attrs=dict(profile.attrs), label=str(profile.attrs.get("source",
                                                                                                      "profile")))
    out.attrs.update({"mirrored_copies": copies, "trace_length": float(span)})
    return out


def measured_rough_profiles(lower, upper, length: float):
    """Two measured profiles (lower, upper) for a rough pair of length ``length`` [m]: each a path
    (:func:`fivid.surface.read_profile`: Dektak CSV, X3P, x/z columns) or a DataArray, laid over the length by
    :func:`profile_over_length`."""
    return tuple(profile_over_length(read_profile(p) if not hasattr(p, "values") else p, length)
                 for p in (lower, upper))
