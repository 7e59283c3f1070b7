"""DAQ file formats read through rig profiles: NI TDMS, UFF58, MATLAB .mat, LabVIEW LVM, ASAM MDF4.

Each format's reader returns a :class:`ChannelFile` (named channels, units, metadata, an implicit
time axis); :func:`read_daq_file` applies a rig profile to it exactly as to a rig CSV and runs the
same checks, so a recording ingests to the same RunDataset in any format. The format is chosen by
the file's suffix (:data:`DAQ_SUFFIXES`). The libraries are the optional extra ``fivid[daq]``.
"""

from __future__ import annotations

from pathlib import Path

from fivid.errors import FividError
from fivid.io.daq.channels import ChannelFile, channel_head, run_from_channels
from fivid.io.daq.lvm import read_lvm
from fivid.io.daq.mat import read_mat
from fivid.io.daq.mdf import read_mdf
from fivid.io.daq.tdms import read_tdms
from fivid.io.daq.uff import read_uff58
from fivid.io.rig_csv import as_rig_profile

__all__ = ["DAQ_SUFFIXES", "ChannelFile", "is_daq_file", "read_channels", "read_daq_file", "read_daq_head"]

#: File suffix (lower case) -> reader of the format.
DAQ_SUFFIXES = {
    ".tdms": read_tdms,
    ".uff": read_uff58,
    ".unv": read_uff58,
    ".mat": read_mat,
    ".lvm": read_lvm,
    ".mf4": read_mdf,
    ".mdf": read_mdf,
}


def is_daq_file(path) -> bool:
    """Whether ``path``'s suffix is one of the DAQ formats (not a rig CSV)."""
    return Path(path).suffix.lower() in DAQ_SUFFIXES


def read_channels(path) -> ChannelFile:
    """The channels, units and metadata of a DAQ file, by its suffix; no profile applied."""
    path = Path(path)
    if not path.is_file():
        raise FividError("no such file" if not path.exists() else "not a regular file", file=path)
    reader = DAQ_SUFFIXES.get(path.suffix.lower())
    if reader is None:
        raise FividError(f"unknown DAQ file suffix {path.suffix!r}; known: {', '.join(DAQ_SUFFIXES)}", file=path)
    try:
        return reader(path)
    except FividError:
        raise
    except Exception as exc:  # a library's own error on a damaged or foreign file: say which file and format
        raise FividError(f"cannot read the file as {reader.__name__.removeprefix('read_').upper()}: "
                         f"{type(exc).__name__}: {exc}", file=path) from None


def read_daq_head(path, profile=None):
    """The :class:`~fivid.io.rig_header.RigHead` of a DAQ file (channels mapped, metadata resolved)."""
    return channel_head(path, as_rig_profile(profile), read_channels(path))


def read_daq_file(path, profile=None, *, allow_implausible: bool = False):
    """Read a DAQ file into a RunDataset in SI units, through a rig profile.

    Parameters
    ----------
    path : str or path-like
        A ``.tdms``, ``.uff``/``.unv`` (dataset 58), ``.mat``, ``.lvm`` or ``.mf4``/``.mdf`` file.
    profile : RigProfile, str or path-like, optional
        The rig profile: its ``columns`` name the file's channels (``docs/ingest.md``, "Formats"),
        its ``metadata.in_file.keys`` the file's metadata keys. Default: the ``fivid-rig-csv``
        format, for files whose channels carry canonical names and units.
    allow_implausible : bool, default False
        As for :func:`fivid.io.read_rig_csv`.

    Returns
    -------
    xarray.Dataset
        A valid RunDataset, as :func:`fivid.io.read_rig_csv` returns for the same recording in a
        CSV, plus the attribute ``source_format``.

    Raises
    ------
    FividError
        The file cannot be read, or the format's library is missing (with the install command).
    SchemaError, UnitError, DataQualityError
        As for a rig CSV; messages name the file and the channel or metadata key, and the sample
        (not a line) of a bad value.
    """
    return run_from_channels(path, as_rig_profile(profile), read_channels(path), allow_implausible=allow_implausible)
