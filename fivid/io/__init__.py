"""Reading and writing rig data: rig CSVs → RunDatasets (xarray) → netCDF4 files."""

from fivid.io.netcdf import read_run, write_run

__all__ = ["read_run", "write_run"]
