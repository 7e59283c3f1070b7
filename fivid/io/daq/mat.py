"""MATLAB .mat files: v4-v7 through scipy.io.loadmat, v7.3 (HDF5) through h5py."""

from __future__ import annotations

import numpy as np

from fivid.errors import FividError
from fivid.io.daq.channels import ChannelFile, require

__all__ = ["read_mat"]


def _add(data: ChannelFile, name: str, value, where: str) -> None:
    """A numeric vector becomes a channel, a text a metadata value; other things are left out."""
    if isinstance(value, str):
        data.metadata[name] = (value, where)
        return
    array = np.asarray(value)
    if np.issubdtype(array.dtype, np.number) and array.ndim >= 1 and array.size > 1 and \
            sum(d > 1 for d in array.shape) == 1:
        data.channels[name] = np.real(array).ravel()


def _flatten(data: ChannelFile, prefix: str, value) -> None:
    if isinstance(value, dict):
        for key, item in value.items():
            _flatten(data, f"{prefix}.{key}" if prefix else key, item)
    else:
        _add(data, prefix, value, f"variable {prefix!r}")


def _read_hdf5(path, data: ChannelFile) -> None:
    h5py = require("h5py", "h5py", "MATLAB v7.3 files (.mat)")

    def visit(name, obj):
        if not isinstance(obj, h5py.Dataset) or name.startswith("#refs#"):
            return
        key = name.replace("/", ".")
        kind = obj.attrs.get("MATLAB_class", b"")
        kind = kind.decode() if isinstance(kind, bytes) else str(kind)
        if kind == "char":
            _add(data, key, "".join(map(chr, np.asarray(obj).ravel())), f"variable {key!r}")
        else:
            _add(data, key, obj[()], f"variable {key!r}")

    with h5py.File(path, "r") as f:
        f.visititems(visit)


def read_mat(path) -> ChannelFile:
    """The variables of a MATLAB file.

    A channel is a numeric vector, named by its variable name, or ``struct.field`` for a field of a
    struct (any depth; in a v7.3 file a group's dataset likewise). Text variables are the metadata
    (``Run = 'R002'``). MAT files state no units: the profile gives them. v7.3 files (HDF5) are read
    with h5py.
    """
    data = ChannelFile("mat")
    with open(path, "rb") as f:
        head = f.read(128)
    if head[:10] == b"MATLAB 7.3" or head[:8] == b"\x89HDF\r\n\x1a\n":
        data.format = "mat-v7.3"
        _read_hdf5(path, data)
        return data
    import scipy.io

    try:
        variables = scipy.io.loadmat(str(path), simplify_cells=True)
    except (ValueError, TypeError, OSError) as exc:
        raise FividError(f"cannot read the file as a MATLAB .mat file: {exc}", file=path) from None
    _flatten(data, "", {k: v for k, v in variables.items() if not k.startswith("__")})
    return data
