"""Content-hash cache of stage outputs.

Every task of a stage (one CSV to ingest, one simulation, ...) has a *key*: the sha256 of its kind,
fivid's version, its parameters and the sha256 of every input file. After a task has written its
outputs (each atomically), a manifest ``<output>/.fivid-cache/<stage>/<task>.json`` is written
(atomically, last) recording the key, the sha256 of each output and when it finished (the outputs
themselves hold no wall-clock time where that would change their bytes: ingested runs). A task is a *hit* when its
manifest has the same key and every output still exists with the recorded sha256; otherwise it
runs again. A run killed at any point therefore leaves either a complete, recorded task or one that
is re-run; and because downstream keys hash the *content* of upstream outputs, a new CSV re-runs
only the tasks whose inputs changed.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path

from fivid import __version__
from fivid.storage import dumps_json, write_json

__all__ = ["file_sha256", "digest", "TaskCache", "Task"]

_CHUNK = 1 << 20


def file_sha256(path: str | os.PathLike) -> str:
    """sha256 (hex) of a file's bytes, read in 1 MiB chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(_CHUNK), b""):
            h.update(chunk)
    return h.hexdigest()


def digest(obj) -> str:
    """sha256 of the canonical JSON of ``obj`` (sorted keys; numpy scalars allowed)."""
    text = json.dumps(json.loads(dumps_json(obj)), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


@dataclass
class Task:
    """One unit of cached work.

    Parameters
    ----------
    stage : str
        Stage name (``ingest``, ``simulate``, ...).
    name : str
        Task name, unique in its stage (file-name safe).
    params : dict
        Everything besides input files that determines the outputs.
    inputs : dict
        ``label -> sha256`` of each input (files or upstream outputs).
    outputs : dict
        ``label -> path`` of each output the task writes.
    """

    stage: str
    name: str
    params: dict
    inputs: dict
    outputs: dict

    @property
    def key(self) -> str:
        """The task's cache key: sha256 over stage, fivid version, parameters and input digests."""
        return digest({"stage": self.stage, "fivid": __version__, "params": self.params, "inputs": self.inputs})


class TaskCache:
    """Manifests of completed tasks under ``<root>/.fivid-cache``."""

    def __init__(self, root: str | os.PathLike):
        self.root = Path(root) / ".fivid-cache"

    def _manifest(self, task: Task) -> Path:
        return self.root / task.stage / f"{task.name}.json"

    def lookup(self, task: Task) -> dict | None:
        """The output digests ``label -> sha256`` if ``task`` is complete and unchanged, else None."""
        path = self._manifest(task)
        try:
            manifest = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        if manifest.get("key") != task.key:
            return None
        recorded = manifest.get("outputs", {})
        if set(recorded) != set(task.outputs):
            return None
        for label, out in task.outputs.items():
            entry = recorded[label]
            p = Path(out)
            if not p.is_file() or p.stat().st_size != entry.get("size") or file_sha256(p) != entry.get("sha256"):
                return None
        return {label: entry["sha256"] for label, entry in recorded.items()}

    def record(self, task: Task, *, seconds: float) -> dict:
        """Write the manifest of a finished task (atomically); returns ``label -> sha256`` of its outputs."""
        outputs = {}
        for label, out in task.outputs.items():
            p = Path(out)
            outputs[label] = {"path": str(p), "sha256": file_sha256(p), "size": p.stat().st_size}
        path = self._manifest(task)
        path.parent.mkdir(parents=True, exist_ok=True)
        write_json(path, {"key": task.key, "stage": task.stage, "task": task.name, "params": task.params,
                          "inputs": task.inputs, "outputs": outputs, "seconds": seconds, "fivid_version": __version__,
                          "finished": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")})
        return {label: e["sha256"] for label, e in outputs.items()}

    def forget(self, task: Task) -> None:
        """Remove a task's manifest (used by ``--force``)."""
        try:
            self._manifest(task).unlink()
        except FileNotFoundError:
            pass
