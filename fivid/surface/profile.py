"""The ``Profile``: surface heights z [m] over a lateral coordinate ``x`` [m], as an xarray.DataArray.

Every reader returns one, every metrology and statistics function takes one. A profile is named
``height``, has one dimension ``x`` (strictly increasing), ``units = "m"`` on the values and on ``x``,
and provenance attrs (``source``, ``instrument``, ``history``; ``synthetic = "yes"`` for generated ones).
"""

from __future__ import annotations

import numpy as np

from fivid.errors import DataQualityError

__all__ = ["make_profile", "sampling_step", "MIN_POINTS", "SAMPLING_RTOL"]

# The 7-point slope of ISO 4287 / ISO 21920-2 (RΔq) needs 7 samples; fewer cannot be evaluated.
MIN_POINTS = 7

# A profilometer writes x rounded to a few decimals; a dropped sample changes one step by 100 %.
SAMPLING_RTOL = 0.01


def make_profile(x, z, *, attrs: dict | None = None, label: str = "profile"):
    """Wrap heights ``z`` [m] over ``x`` [m] into a profile DataArray, after checking them.

    Parameters
    ----------
    x : array_like [m]
        Lateral positions, strictly increasing.
    z : array_like [m]
        Heights, finite, same length as ``x``.
    attrs : dict, optional
        Provenance attrs added to the DataArray (``source``, ``instrument``, ...).
    label : str
        How to name the data in error messages (e.g. the file name).

    Raises
    ------
    DataQualityError
        Different lengths, fewer than :data:`MIN_POINTS` points, non-finite values, or ``x`` not
        strictly increasing (the message gives the first offending index and value).
    """
    import xarray as xr

    x = np.asarray(x, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    if x.ndim != 1 or x.shape != z.shape:
        raise DataQualityError(f"{label}: x and z must be 1-D of the same length, got {x.shape} and {z.shape}")
    if x.size < MIN_POINTS:
        raise DataQualityError(f"{label}: {x.size} point(s); a profile needs at least {MIN_POINTS}")
    for name, v in (("x", x), ("z", z)):
        bad = ~np.isfinite(v)
        if bad.any():
            i = int(np.argmax(bad))
            raise DataQualityError(f"{label}: {name}[{i}] = {float(v[i])!r} is not finite")
    steps = np.diff(x)
    if not np.all(steps > 0):
        i = int(np.argmax(~(steps > 0))) + 1
        raise DataQualityError(
            f"{label}: x is not strictly increasing at point {i}: x = {float(x[i])!r} m after {float(x[i - 1])!r} m"
        )
    base = {"units": "m", "long_name": "surface height"}
    base.update(attrs or {})
    return xr.DataArray(
        z, dims="x", name="height", attrs=base,
        coords={"x": ("x", x, {"units": "m", "long_name": "lateral position along the trace"})},
    )


def sampling_step(profile, *, label: str | None = None) -> float:
    """The uniform sampling step Δx [m] of a profile, after checking that it is uniform.

    Filters, slopes and spectra assume equal steps. Steps may differ by :data:`SAMPLING_RTOL` of the
    mean step (rounding of exported positions); more is a :class:`~fivid.errors.DataQualityError`
    naming the first irregular point (resample the profile first).
    """
    x = np.asarray(profile["x"].values, dtype=np.float64)
    label = label or str(profile.attrs.get("source", "profile"))
    if x.size < 2:
        raise DataQualityError(f"{label}: {x.size} point(s); need at least 2 for a sampling step")
    dx = (x[-1] - x[0]) / (x.size - 1)
    dev = np.abs(np.diff(x) - dx)
    if dev.max() > SAMPLING_RTOL * dx:
        i = int(np.argmax(dev > SAMPLING_RTOL * dx))
        raise DataQualityError(
            f"{label}: non-uniform sampling: step {x[i + 1] - x[i]:.6g} m at x = {x[i]:.6g} m against a mean "
            f"step of {dx:.6g} m (tolerance {SAMPLING_RTOL:.0%}); resample the profile to a uniform step"
        )
    return float(dx)
