"""RunDataset netCDF4 files: read (validated) and write (atomic, CF attrs rewritten)."""

from __future__ import annotations

import os
from pathlib import Path

from fivid.errors import FividError, SchemaError
from fivid.schema import apply_cf_attrs, registry, validate_run, with_condition_coords
from fivid.storage import write_netcdf

__all__ = ["open_runs", "read_run", "write_run"]


def read_run(path: str | os.PathLike, *, validate: bool = True):
    """Load a RunDataset from a netCDF file into memory.

    Parameters
    ----------
    path : str or path-like
        A file written by ``fivid ingest`` or ``fivid simulate``.
    validate : bool, default True
        Check it against the schema (:func:`fivid.schema.validate_run`), reporting every problem.

    Raises
    ------
    FividError
        The file does not exist or is not netCDF.
    SchemaError
        It is not a valid RunDataset.
    """
    import xarray as xr

    path = Path(path)
    if path.is_dir():
        raise FividError(f"{str(path)!r} is a folder; give a RunDataset netCDF file (e.g. written by fivid ingest)")
    if not path.is_file():
        raise FividError(f"no such file: {str(path)!r}")
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            ds = ds.load()
    except (OSError, ValueError) as exc:
        raise SchemaError(f"cannot read {str(path)!r} as netCDF ({exc})") from None
    if validate:
        validate_run(ds, name=str(path))
    return ds


def write_run(ds, path: str | os.PathLike, *, overwrite: bool = False) -> Path:
    """Write a RunDataset to ``path`` atomically, with CF attrs rewritten from the registry.

    The test conditions (``run_id``, ``sliding_velocity``, ``normal_load``, ``roughness_ra``) are written both as
    global attributes and as scalar coordinates with units (:func:`fivid.schema.with_condition_coords`), so
    :func:`open_runs` stacks runs along ``run`` with them as coordinates. Text is stored as char arrays and
    coordinates have no ``_FillValue`` (:func:`fivid.storage.cf_encoding`). The dataset is validated first;
    nothing is written when it is invalid.
    """
    ds = apply_cf_attrs(with_condition_coords(ds))
    validate_run(ds, name=str(path))
    encoding = {name: {"zlib": False} for name in ds.data_vars}
    return write_netcdf(ds, path, overwrite=overwrite, encoding=encoding)


def open_runs(paths, *, dim: str = "run", **kwargs):
    """Open several RunDataset files stacked along a new dimension ``dim``, indexed by their test conditions.

    ``xr.open_mfdataset(paths, combine="nested", concat_dim=dim, coords="all")`` (lazily, with dask; ``coords="all"``
    puts a condition along ``dim`` even when every run shares it: plain ``open_mfdataset`` keeps those scalar)
    followed by an index on every condition coordinate (``run_id``, ``sliding_velocity``, ``normal_load``, ``roughness_ra``), so that
    ``.sel(sliding_velocity=0.01)`` picks the runs at that velocity; ``.where(ds.roughness_ra > 1e-6, drop=True)``
    works with or without the index.

    Parameters
    ----------
    paths : str, path-like or sequence of them
        A glob string (``"runs/*.nc"``) or the files, written by ``fivid ingest`` or ``fivid simulate``.
    dim : str, default "run"
        Name of the new dimension.
    **kwargs
        Passed on to :func:`xarray.open_mfdataset` (e.g. ``join="override"`` for runs of equal length whose
        time values differ by round-off; runs of different lengths are outer-joined on ``time``, NaN-filled).

    Examples
    --------
    >>> runs = open_runs("runs/*.nc")                              # doctest: +SKIP
    >>> runs.sel(sliding_velocity=0.01)["acceleration"].mean("time")  # doctest: +SKIP
    """
    import xarray as xr

    if isinstance(paths, (str, os.PathLike)):
        paths = str(paths)
    else:
        paths = [str(p) for p in paths]
    kwargs.setdefault("coords", "all")
    ds = xr.open_mfdataset(paths, combine="nested", concat_dim=dim, engine="netcdf4", **kwargs)
    for name in registry().conditions:
        if name in ds.coords and ds[name].dims == (dim,):
            ds = ds.set_xindex(name)
    return ds
