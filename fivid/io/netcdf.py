"""RunDataset netCDF4 files: read (validated) and write (atomic, CF attrs rewritten)."""

from __future__ import annotations

import os
from pathlib import Path

from fivid.errors import FividError, SchemaError
from fivid.schema import apply_cf_attrs, validate_run
from fivid.storage import write_netcdf

__all__ = ["read_run", "write_run"]


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

    The dataset is validated first; nothing is written when it is invalid.
    """
    ds = apply_cf_attrs(ds)
    validate_run(ds, name=str(path))
    encoding = {name: {"zlib": False} for name in ds.data_vars}
    return write_netcdf(ds, path, overwrite=overwrite, encoding=encoding)
