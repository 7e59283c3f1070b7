"""Reading and writing rig data: rig CSVs → RunDatasets (xarray) → netCDF4 files.

* :func:`read_rig_csv` reads a ``fivid-rig-csv: 1`` file or a DAQ export described by a rig profile
  (:func:`load_rig_profile`, ``configs/rigs/*.yaml``) into a validated RunDataset in SI units;
* :func:`read_daq_file` reads a DAQ file (TDMS, UFF58, MATLAB, LVM, MDF4) through the same profile;
* :func:`ingest_files` converts many files to ``<outdir>/<run_id>.nc`` (what ``fivid ingest`` runs);
* :func:`read_run` / :func:`write_run` read and write RunDataset netCDF files; :func:`open_runs` stacks many
  along a ``run`` dimension indexed by their test conditions.
"""

from fivid.io.daq import read_daq_file
from fivid.io.ingest import IngestResult, Rejection, ingest_files
from fivid.io.netcdf import open_runs, read_run, write_run
from fivid.io.rig_csv import read_rig_csv
from fivid.io.rig_header import read_rig_head
from fivid.io.rig_profile import ColumnSpec, RigProfile, load_rig_profile

__all__ = [
    "read_rig_csv",
    "read_daq_file",
    "read_rig_head",
    "load_rig_profile",
    "RigProfile",
    "ColumnSpec",
    "ingest_files",
    "IngestResult",
    "Rejection",
    "read_run",
    "write_run",
    "open_runs",
]
