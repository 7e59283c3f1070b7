"""Atomic file output: write to a temporary file beside the target, then rename.

A killed process leaves at most a ``.<name>.<random>.tmp`` file, never a partial target; a failed
write removes its temporary file. Layer L1: used by every writer in fivid.
"""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path

from fivid.errors import FividError, OutputExistsError

__all__ = [
    "atomic_path", "cf_encoding", "write_netcdf", "write_text", "write_json", "dumps_json", "check_writable", "check_folder_writable",
]


def check_folder_writable(folder: str | os.PathLike) -> None:
    """Prove ``folder`` writable by creating (and removing) a file in it.

    A real write is the only reliable test: ``os.access`` says yes to root on a read-only mount
    or on ``/proc``. Raises :class:`~fivid.errors.FividError` naming the folder and the reason.
    """
    try:
        fd, probe = tempfile.mkstemp(prefix=".fivid-write-test.", dir=folder)
    except OSError as exc:
        raise FividError(f"output folder {str(folder)!r} is not writable: {exc.strerror or exc}") from None
    os.close(fd)
    os.unlink(probe)


def check_writable(path: str | os.PathLike, *, overwrite: bool = False) -> Path:
    """Check that ``path`` may be written: its folder exists and is writable; it exists only if ``overwrite``.

    Raises :class:`~fivid.errors.OutputExistsError` or :class:`~fivid.errors.FividError` with a
    message naming the path (missing or unwritable folder; ``path`` is itself a folder).
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise FividError(f"output folder {str(folder)!r} does not exist")
    check_folder_writable(folder)
    if path.is_dir():  # checked before "exists": --overwrite cannot replace a folder by a file
        raise FividError(f"output {str(path)!r} is a folder; give the name of a file to write")
    if path.exists() and not overwrite:
        raise OutputExistsError(f"output {str(path)!r} exists; pass --overwrite to replace it")
    return path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, overwrite: bool = True):
    """Yield a temporary path in the target's folder; on success rename it onto ``path``.

    On an exception the temporary file is removed and ``path`` is left as it was. With
    ``overwrite=False`` the rename refuses to replace a file that appeared meanwhile.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    os.close(fd)
    tmp = Path(tmp)
    os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; give the file the mode open() would
    try:
        yield tmp
        if overwrite:
            os.replace(tmp, path)
        else:
            try:
                os.link(tmp, path)  # fails if path exists: no race with a concurrent writer
            except FileExistsError:
                raise OutputExistsError(f"output {str(path)!r} exists; pass --overwrite to replace it") from None
            tmp.unlink()
    finally:
        if tmp.exists():
            tmp.unlink()


def cf_encoding(ds) -> dict:
    """The netCDF encoding that keeps a Dataset CF-compliant, per variable.

    * text (``str``/object) variables are written as char arrays (``dtype S1``, a ``string<N>`` dimension): CF has
      no variable-length strings; xarray decodes them back to ``str``;
    * coordinate variables (dimension and scalar coordinates) get no ``_FillValue``: CF does not allow missing
      values in coordinate variables, and xarray would otherwise add a NaN ``_FillValue`` to every float one.
    """
    encoding: dict = {}
    for name, var in ds.variables.items():
        enc = {}
        if var.dtype == object or var.dtype.kind == "U":
            enc["dtype"] = "S1"
        if name in ds.coords:
            enc["_FillValue"] = None
        if enc:
            encoding[name] = enc
    return encoding


def write_netcdf(ds, path: str | os.PathLike, *, overwrite: bool = True, encoding: dict | None = None) -> Path:
    """Write an xarray Dataset to netCDF4 atomically, with :func:`cf_encoding` under ``encoding``; returns the path."""
    path = Path(path)
    merged = cf_encoding(ds)
    for name, enc in (encoding or {}).items():
        merged[name] = {**merged.get(name, {}), **enc}
    with atomic_path(path, overwrite=overwrite) as tmp:
        ds.to_netcdf(tmp, format="NETCDF4", engine="netcdf4", encoding=merged)
    return path


def write_text(path: str | os.PathLike, text: str, *, overwrite: bool = True) -> Path:
    """Write text (UTF-8) atomically; returns the path."""
    path = Path(path)
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path


def write_json(path: str | os.PathLike, obj, *, overwrite: bool = True) -> Path:
    """Write ``obj`` as indented JSON atomically (NaN written as null)."""
    return write_text(path, dumps_json(obj) + "\n", overwrite=overwrite)


def _clean(obj):
    import math

    import numpy as np

    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def dumps_json(obj) -> str:
    """JSON text of ``obj`` with numpy scalars/arrays converted and non-finite floats as ``null``."""
    return json.dumps(_clean(obj), indent=2, allow_nan=False)
