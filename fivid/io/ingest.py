"""Convert many rig files to RunDataset netCDF files, ``<outdir>/<run_id>.nc``.

Valid files are written even when others are bad; every bad one becomes a :class:`Rejection` whose
message names the file, the line and the column or key. Nothing is left behind for a rejected file,
and every output goes through :func:`fivid.storage.atomic_path` (temporary file + rename), so a
killed ingest never leaves a partial ``.nc``.

The files' heads are read first (cheap), so a ``run_id`` shared by several files in one call, or an
existing output, is found before any data are converted.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

from fivid.errors import FividError, OutputExistsError, SchemaError
from fivid.io.daq import DAQ_SUFFIXES, is_daq_file, read_daq_file, read_daq_head
from fivid.io.netcdf import write_run
from fivid.io.rig_csv import as_rig_profile, read_rig_csv
from fivid.io.rig_header import read_rig_head
from fivid.storage import check_folder_writable

__all__ = ["ingest_files", "IngestResult", "Rejection", "prepare_output_folder", "expand_inputs", "read_recording",
           "INPUT_SUFFIXES"]

#: Suffixes of the files ``ingest`` reads (a folder is expanded to its files of these kinds).
INPUT_SUFFIXES = (".csv", *DAQ_SUFFIXES)

log = logging.getLogger("fivid")


@dataclass(frozen=True)
class Rejection:
    """A file that was not converted, and why."""

    path: Path
    error: FividError

    def __str__(self) -> str:
        return str(self.error)


@dataclass
class IngestResult:
    """What :func:`ingest_files` did.

    Attributes
    ----------
    written : list of Path
        The netCDF files written, in input order.
    rejected : list of Rejection
        The files refused, with their errors.
    """

    written: list = field(default_factory=list)
    rejected: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when no file was rejected."""
        return not self.rejected


def prepare_output_folder(outdir) -> Path:
    """Create ``outdir`` if needed and prove it writable by creating (and removing) a file in it.

    A real write is the only reliable test (``os.access`` says yes to root on a read-only mount).

    Raises
    ------
    FividError
        The folder cannot be created or written, with the reason.
    """
    outdir = Path(outdir)
    try:
        outdir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise FividError(f"cannot create the output folder {str(outdir)!r}: {exc.strerror or exc}") from None
    if not outdir.is_dir():
        raise FividError(f"the output {str(outdir)!r} is not a folder")
    check_folder_writable(outdir)
    return outdir


def _is_input(path: Path) -> bool:
    return path.suffix.lower() in INPUT_SUFFIXES and path.is_file()


def read_recording(path, profile=None, *, allow_implausible: bool = False):
    """Read a rig CSV or a DAQ file (by its suffix: :data:`fivid.io.daq.DAQ_SUFFIXES`) into a RunDataset."""
    read = read_daq_file if is_daq_file(path) else read_rig_csv
    return read(path, profile, allow_implausible=allow_implausible)


def _read_head(path, profile):
    return read_daq_head(path, profile) if is_daq_file(path) else read_rig_head(path, profile)


def expand_inputs(paths) -> list[Path]:
    """Input paths with folders expanded to their rig CSV and DAQ files (sorted); the same file once."""
    out, seen = [], set()
    for p in paths:
        p = Path(p)
        found = sorted(q for q in p.iterdir() if _is_input(q)) if p.is_dir() else [p]
        for q in found:
            key = q.resolve() if q.exists() else q
            if key not in seen:
                seen.add(key)
                out.append(q)
    return out


def _folders_without_csv(paths) -> list[Path]:
    """The folders among ``paths`` that hold no input file (they would silently convert nothing)."""
    return [p for p in map(Path, paths) if p.is_dir() and not any(_is_input(q) for q in p.iterdir())]


def _convert(path: Path, head, target: Path, profile, overwrite: bool, allow_implausible: bool):
    """Read one file and write its RunDataset to ``target``; raises FividError."""
    if target.exists() and not overwrite:
        raise OutputExistsError(f"output {str(target)!r} exists; pass --overwrite to replace it", file=path)
    ds = read_recording(path, profile, allow_implausible=allow_implausible)
    if ds.attrs["run_id"] != head.attrs["run_id"]:
        raise SchemaError(f"the file changed during the ingest (run_id {head.attrs['run_id']!r} became "
                          f"{ds.attrs['run_id']!r}); run the ingest again", file=path, key="run_id")
    try:
        write_run(ds, target, overwrite=overwrite)
    except OSError as exc:
        raise FividError(f"cannot write {str(target)!r}: {exc.strerror or exc}", file=path) from None
    return ds


def ingest_files(paths, outdir, *, profile=None, overwrite: bool = False, on_written=None,
                 on_file_done=None, allow_implausible: bool = False) -> IngestResult:
    """Convert rig files to ``<outdir>/<run_id>.nc``, one RunDataset per file.

    Parameters
    ----------
    paths : iterable of str or path-like
        Rig CSV files or DAQ files (``.tdms``, ``.uff``, ``.mat``, ``.lvm``, ``.mf4``; by suffix);
        folders are expanded to such files.
    outdir : str or path-like
        Output folder, created if missing.
    profile : RigProfile, str or path-like, optional
        Rig profile for every file (see :func:`fivid.io.read_rig_csv`).
    overwrite : bool, default False
        Replace existing outputs; otherwise a file whose output exists is rejected.
    on_written : callable, optional
        Called as ``on_written(input_path, output_path, dataset)`` after each file is written.
    on_file_done : callable, optional
        Called as ``on_file_done(input_path)`` after each file whose data were converted or
        rejected (for a progress bar; files rejected from their head alone are not counted).
    allow_implausible : bool, default False
        Keep runs that fail an overridable plausibility check, recorded in each file (see
        :func:`fivid.io.read_rig_csv`).

    Returns
    -------
    IngestResult
        Written paths and rejections. A file is rejected for any bad input (see
        :func:`~fivid.io.read_rig_csv`), for an output that exists (unless ``overwrite``), and when
        its ``run_id`` is also the ``run_id`` of another file of the call (all of them are rejected:
        which one is right is for a person to decide). A folder holding no ``*.csv`` file is
        rejected too, so that a wrong folder does not pass as a successful ingest of nothing.

    Raises
    ------
    FividError
        The output folder cannot be created or written, or the profile is invalid (nothing is
        converted then).
    """
    profile = as_rig_profile(profile)
    outdir = prepare_output_folder(outdir)
    result = IngestResult()
    inputs = expand_inputs(paths)
    for folder in _folders_without_csv(paths):
        result.rejected.append(Rejection(folder, FividError(
            "the folder holds no *.csv file (nor a DAQ file: " + ", ".join(f"*{x}" for x in DAQ_SUFFIXES)
            + "); give rig CSV or DAQ files or a folder of them", file=folder)))
    heads = {}
    for path in inputs:
        try:
            heads[path] = _read_head(path, profile)
        except FividError as exc:
            result.rejected.append(Rejection(path, exc.located(file=path)))
    by_run: dict[str, list[Path]] = {}
    for path, head in heads.items():
        by_run.setdefault(head.attrs["run_id"], []).append(path)
    for run_id, group in by_run.items():
        if len(group) > 1:
            for path in group:
                others = ", ".join(str(p) for p in group if p != path)
                result.rejected.append(Rejection(path, SchemaError(
                    f"run_id {run_id!r} is also the run_id of {others} in this call; give each run its own run_id",
                    file=path, key="run_id")))
                del heads[path]
    for path, head in heads.items():
        target = outdir / f"{head.attrs['run_id']}.nc"
        try:
            ds = _convert(path, head, target, profile, overwrite, allow_implausible)
        except FividError as exc:
            result.rejected.append(Rejection(path, exc.located(file=path)))
        else:
            log.info("%s -> %s", path, target)
            result.written.append(target)
            if on_written is not None:
                on_written(path, target, ds)
        if on_file_done is not None:
            on_file_done(path)
    order = {p: i for i, p in enumerate(inputs)}
    result.rejected.sort(key=lambda r: order.get(r.path, len(order)))
    return result
