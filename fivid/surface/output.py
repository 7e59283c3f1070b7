"""A profile and its evaluation as a CF netCDF Dataset, written atomically (:mod:`fivid.storage`)."""

from __future__ import annotations

import numpy as np

from fivid.schema import append_history
from fivid.storage import write_netcdf
from fivid.surface.metrology import PARAMETER_NAMES, PARAMETER_UNITS

__all__ = ["evaluation_dataset", "write_evaluation"]


def _netcdf_attrs(attrs: dict) -> dict:
    """Attrs netCDF can store: numbers and strings; None left out, booleans as 0/1."""
    out = {}
    for k, v in attrs.items():
        if v is None:
            continue
        if isinstance(v, (bool, np.bool_)):
            v = int(v)
        out[k] = v if isinstance(v, (str, int, float, np.integer, np.floating)) else str(v)
    return out


def evaluation_dataset(profile, evaluation):
    """Dataset with the profile, the evaluated roughness (and waviness) and one scalar per parameter.

    Variables: ``height(x)`` [m] as read; ``roughness(x_evaluation)`` [m] and, with a cut-off,
    ``waviness(x_evaluation)`` [m]; scalars ``Ra``, ``Rq``, ... with ``units`` and ``long_name``
    (NaN when undefined). Global attrs: the profile's provenance and the evaluation settings
    (``evaluation_*``), ``Conventions`` and ``history``.
    """
    import xarray as xr

    ev = evaluation
    height = profile.copy()
    height.attrs = {"units": "m", "long_name": "surface height as read (no form removed)"}
    data = {"height": height,
            "roughness": xr.DataArray(ev.roughness, dims="x_evaluation",
                                      attrs={"units": "m", "long_name": "roughness profile over the evaluation length"})}
    if ev.waviness is not None:
        data["waviness"] = xr.DataArray(ev.waviness, dims="x_evaluation",
                                        attrs={"units": "m", "long_name": "waviness profile (Gaussian mean line)"})
    for symbol, value in ev.parameters.items():
        data[symbol] = xr.DataArray(float(value), attrs={"units": PARAMETER_UNITS[symbol],
                                                         "long_name": PARAMETER_NAMES[symbol]})
    ds = xr.Dataset(data, coords={"x_evaluation": ("x_evaluation", ev.x, {
        "units": "m", "long_name": "lateral position of the evaluated samples"})})
    ds["x"].attrs = {"units": "m", "long_name": "lateral position along the trace"}
    attrs = {k: v for k, v in profile.attrs.items() if k not in ("units", "long_name")}
    attrs.update({f"evaluation_{k}": v for k, v in ev.settings.items()})
    ds.attrs = _netcdf_attrs(attrs)
    ds.attrs["Conventions"] = "CF-1.8"
    ds.attrs["title"] = "surface profile and its roughness parameters (fivid.surface)"
    return append_history(ds, f"evaluate_profile {ev.settings['form']} form, cut-off {ev.settings['cutoff']} m, "
                              f"window [{ev.settings['window_start']}, {ev.settings['window_end']}] m")


def write_evaluation(profile, evaluation, path, *, overwrite: bool = False):
    """Write :func:`evaluation_dataset` to netCDF atomically; returns the path."""
    return write_netcdf(evaluation_dataset(profile, evaluation), path, overwrite=overwrite)
