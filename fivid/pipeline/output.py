"""Safety of a pipeline's output folder: whose it is, what may be written in it, what a killed run left.

fivid marks each output folder with a small manifest ``<output>/.fivid-output.json`` (format version,
fivid version, the command that wrote it, when). A run may write into a folder that does not exist,
is empty, or carries the manifest (a re-run); an existing folder holding other files is refused
(:func:`check_output_folder`) unless the caller forces it, so ``-o ~/thesis`` cannot mix pipeline
outputs into unrelated files. Every path a task will write must lie inside the folder
(:func:`check_inside`): a name with ``..`` or a symbolic link pointing elsewhere is refused before
any work. Under the lock, :func:`remove_stale_temporaries` deletes the ``.<name>.<random>.tmp``
files (see :func:`fivid.storage.atomic_path`) that a killed run left behind.
"""

from __future__ import annotations

import datetime as _dt
import json
import logging
import os
from pathlib import Path

from fivid import __version__
from fivid.errors import FividError
from fivid.execution.lock import LOCK_NAME
from fivid.storage import write_json

__all__ = ["MANIFEST_NAME", "check_output_folder", "check_inside", "write_output_manifest",
           "remove_stale_temporaries"]

log = logging.getLogger("fivid")

MANIFEST_NAME = ".fivid-output.json"
MANIFEST_VERSION = 1
# a run's lock (a run starting now), or written by fivid before the manifest existed: a fivid output too
_LEGACY_MARKERS = (LOCK_NAME, ".fivid-run.flock", ".fivid-cache", "summary.json")


def _is_fivid_output(folder: Path) -> bool:
    return any((folder / name).exists() for name in (MANIFEST_NAME, *_LEGACY_MARKERS))


def check_output_folder(folder: str | os.PathLike, *, force: bool = False) -> None:
    """Refuse an existing, non-empty folder that is not a fivid output, unless ``force``.

    Raises :class:`~fivid.errors.FividError` naming the folder, a few of its files and ``--force``.
    """
    folder = Path(folder)
    if not folder.is_dir() or force or _is_fivid_output(folder):
        return
    entries = sorted(p.name for p in folder.iterdir())
    if not entries:
        return
    shown = ", ".join(entries[:3]) + (f" and {len(entries) - 3} more" if len(entries) > 3 else "")
    raise FividError(f"output folder {str(folder)!r} exists and holds files fivid did not write ({shown}; no "
                     f"{MANIFEST_NAME}); give a new or empty folder, or pass --force to write into it anyway")


def check_inside(folder: str | os.PathLike, path: str | os.PathLike, *, what: str = "output") -> None:
    """Refuse ``path`` unless it resolves (symbolic links followed) inside ``folder``."""
    root = Path(folder).resolve()
    target = Path(path).resolve()
    if target != root and root not in target.parents:
        raise FividError(f"{what} {str(path)!r} resolves to {str(target)!r}, outside the output folder "
                         f"{str(root)!r}; fivid writes only inside its output folder (check '..' in names and "
                         "symbolic links)")


def write_output_manifest(folder: str | os.PathLike, command: str) -> Path:
    """Write ``<folder>/.fivid-output.json`` (format and fivid version, ``command``) unless it is current.

    A re-run by the same fivid version leaves the file untouched: a run with nothing to do writes
    only ``summary.json`` and the log.
    """
    path = Path(folder) / MANIFEST_NAME
    try:
        old = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        old = None
    if isinstance(old, dict) and old.get("fivid-output") == MANIFEST_VERSION and old.get("fivid_version") == __version__:
        return path
    now = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    return write_json(path, {"fivid-output": MANIFEST_VERSION, "fivid_version": __version__,
                             "command": command, "written": now})


def remove_stale_temporaries(folder: str | os.PathLike) -> list[Path]:
    """Delete the ``.<name>.<random>.tmp`` files under ``folder`` (call it holding the folder's lock)."""
    removed = []
    for p in Path(folder).rglob(".*.tmp"):
        if p.is_file() and not p.is_symlink():
            p.unlink()
            removed.append(p)
    if removed:
        log.warning("removed %d temporary file(s) left by an interrupted run: %s", len(removed),
                    ", ".join(str(p.relative_to(folder)) for p in removed[:5]))
    return removed
