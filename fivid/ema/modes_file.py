"""MODES.nc, the file ``fivid ema`` writes (and ``fivid update`` reads for MAC pairing), and its JSON summary.

Layout (CF attributes; netCDF4 has no complex type, so shapes are two real variables)::

    frequency(mode) [Hz], damping_ratio(mode) [1], n_orders(mode) [1]
    shape_real(mode, dof), shape_imag(mode, dof)      [kg-1/2 when mass_normalised, else 1]
    node(dof), direction(dof), channel(dof)           the measured DOFs
    stab_order(pole), stab_frequency(pole) [Hz], stab_damping_ratio(pole), stab_stable(pole)
    attrs: settings (JSON), sources, frf_form, mass_normalised, reconstruction_error,
           rayleigh_alpha [s-1], rayleigh_beta [s] (with two modes or more)
"""

from __future__ import annotations

import json

import numpy as np

from fivid.errors import FividError, SchemaError
from fivid.schema import new_history
from fivid.storage import atomic_path, write_netcdf

__all__ = ["modes_dataset", "write_modes_file", "read_modes", "modes_json", "stabilisation_figure"]


def modes_dataset(result, frfs, rayleigh=None):
    """The MODES.nc Dataset of an :class:`~fivid.ema.lscf.EMAResult` identified from an :class:`FRFSet`."""
    import xarray as xr

    d = result.diagram
    shape_units = "kg-1/2" if result.mass_normalised else "1"
    attrs = {
        "title": "fivid experimental modal analysis",
        "settings": json.dumps(result.settings),
        "sources": json.dumps(frfs.sources),
        "frf_form": frfs.form,
        "frf_units": frfs.units,
        "mass_normalised": int(result.mass_normalised),
        "reconstruction_error": float(result.reconstruction_error),
        "history": new_history("fivid ema"),
    }
    if rayleigh is not None:
        attrs.update(rayleigh_alpha=rayleigh.alpha, rayleigh_beta=rayleigh.beta,
                     rayleigh_alpha_stderr=rayleigh.alpha_stderr, rayleigh_beta_stderr=rayleigh.beta_stderr)
    return xr.Dataset(
        {
            "frequency": ("mode", result.frequency, {"units": "Hz", "long_name": "natural frequency |lambda|/2pi"}),
            "damping_ratio": ("mode", result.damping_ratio, {"units": "1", "long_name": "modal damping ratio"}),
            "n_orders": ("mode", result.n_orders, {"units": "1", "long_name": "model orders the mode is stable at"}),
            "shape_real": (("mode", "dof"), result.shape.real, {"units": shape_units,
                                                                "long_name": "mode shape, real part"}),
            "shape_imag": (("mode", "dof"), result.shape.imag, {"units": shape_units,
                                                                "long_name": "mode shape, imaginary part"}),
            "stab_order": ("pole", d.order, {"units": "1", "long_name": "model order of the pole"}),
            "stab_frequency": ("pole", d.frequency, {"units": "Hz", "long_name": "pole natural frequency"}),
            "stab_damping_ratio": ("pole", d.damping_ratio, {"units": "1", "long_name": "pole damping ratio"}),
            "stab_stable": ("pole", d.stable.astype(np.int8), {"units": "1",
                                                              "long_name": "pole stable against the previous order"}),
        },
        coords={
            "mode": ("mode", np.arange(1, result.frequency.size + 1), {"units": "1", "long_name": "mode number"}),
            "node": ("dof", np.asarray(frfs.node, dtype=np.int64), {"units": "1", "long_name": "response node"}),
            "direction": ("dof", np.asarray(frfs.direction, dtype=str), {"long_name": "response direction"}),
            "channel": ("dof", np.asarray(frfs.name, dtype=str), {"long_name": "FRF channel"}),
        },
        attrs=attrs,
    )


def write_modes_file(ds, path, *, overwrite: bool = False):
    """Write a MODES.nc Dataset atomically."""
    return write_netcdf(ds, path, overwrite=overwrite)


def read_modes(path):
    """Read a MODES.nc written by ``fivid ema``; a SchemaError naming the file when it is not one."""
    import xarray as xr

    try:
        with xr.open_dataset(path) as ds:
            ds.load()
    except FileNotFoundError:
        raise FividError(f"cannot read {str(path)!r}: it does not exist", file=path) from None
    except Exception as exc:
        raise FividError(f"cannot open as netCDF: {type(exc).__name__}: {exc}", file=path) from None
    for var in ("frequency", "shape_real", "shape_imag"):
        if var not in ds:
            raise SchemaError(f"not a MODES.nc of 'fivid ema': no variable {var!r}", file=path)
    return ds


def modes_json(ds) -> dict:
    """``{"modes": [{frequency_hz, damping_ratio, shape: [{node, direction, re, im}]}], "settings": ...}``."""
    modes = []
    for k in range(ds.sizes["mode"]):
        shape = [{"node": int(n), "direction": str(d), "channel": str(c), "re": float(re), "im": float(im)}
                 for n, d, c, re, im in zip(ds["node"].values, ds["direction"].values, ds["channel"].values,
                                            ds["shape_real"].values[k], ds["shape_imag"].values[k])]
        modes.append({"frequency_hz": float(ds["frequency"][k]), "damping_ratio": float(ds["damping_ratio"][k]),
                      "stable_orders": int(ds["n_orders"][k]), "shape": shape})
    out = {"modes": modes, "settings": json.loads(ds.attrs["settings"]), "sources": json.loads(ds.attrs["sources"]),
           "frf_form": ds.attrs["frf_form"], "mass_normalised": bool(ds.attrs["mass_normalised"]),
           "shape_units": str(ds["shape_real"].attrs.get("units", "1")),
           "reconstruction_error": float(ds.attrs["reconstruction_error"])}
    if "rayleigh_alpha" in ds.attrs:
        out["rayleigh"] = {"alpha": float(ds.attrs["rayleigh_alpha"]), "alpha_units": "s-1",
                           "beta": float(ds.attrs["rayleigh_beta"]), "beta_units": "s",
                           "alpha_stderr": float(ds.attrs["rayleigh_alpha_stderr"]),
                           "beta_stderr": float(ds.attrs["rayleigh_beta_stderr"])}
    return out


def stabilisation_figure(ds, path, frfs=None) -> None:
    """PNG of the stabilisation diagram (poles per order; stable ones filled; selected modes as lines) over
    the FRF magnitudes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5))
    st = ds["stab_stable"].values.astype(bool)
    f, o = ds["stab_frequency"].values, ds["stab_order"].values
    ax.plot(f[~st], o[~st], "o", mfc="none", mec="0.6", ms=3, label="pole")
    ax.plot(f[st], o[st], "o", color="C0", ms=3, label="stable in f and zeta")
    for fk in ds["frequency"].values:
        ax.axvline(fk, color="C3", lw=0.8)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    lo, hi = json.loads(ds.attrs["settings"])["band_hz"]
    ax.set_xlim(lo, hi)
    if frfs is not None:
        twin = ax.twinx()
        band = (frfs.frequency >= lo) & (frfs.frequency <= hi)
        for row in frfs.frf:
            twin.semilogy(frfs.frequency[band], np.abs(row[band]), color="0.3", lw=0.6, alpha=0.6)
        twin.set_ylabel(f"|FRF| [{frfs.units}]")
    ax.set_title(f"stabilisation diagram: {ds.sizes['mode']} modes (red)")
    ax.legend(loc="upper left", fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
