"""A lock on an output folder: one pipeline run at a time.

The lock is the OS file lock of ``<output>/.fivid-run.flock``, taken through the ``filelock``
package (``flock`` on POSIX, ``msvcrt.locking`` on Windows), held for the life of the run. The
holder's pid, host name, start time and command are recorded beside it in ``<output>/.fivid-run.lock``
(JSON, written atomically after the lock is taken, removed when it is released). A second run on the
same folder is refused with a message naming the holder. The OS drops the lock when its holder dies
(even by SIGKILL), so a record left by a dead run on this host is taken over, and the takeover is
logged with the dead run's pid and start time. A record written by another host cannot be checked
from here (file locks are not reliable across NFS): it is refused with a message saying how to
remove it if that run is gone. The empty ``.fivid-run.flock`` stays in the folder: removing a lock
file others may be opening would let two runs lock two different files.
"""

from __future__ import annotations

import datetime as _dt
import json
import logging
import os
import socket
import sys
from pathlib import Path

from fivid.errors import FividError

__all__ = ["OutputLock", "LockedError", "pid_alive"]

log = logging.getLogger("fivid")

LOCK_NAME = ".fivid-run.lock"  # the holder's record (JSON)
FLOCK_NAME = ".fivid-run.flock"  # the file the OS lock is taken on


class LockedError(FividError):
    """Another run holds the output folder."""


def pid_alive(pid: int) -> bool:
    """Whether a process with this pid exists on this host."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _describe(holder: dict) -> str:
    return (f"pid {holder.get('pid')} on host {holder.get('hostname')!r}, started {holder.get('started')}"
            f" ({holder.get('command', '?')})")


class OutputLock:
    """Context manager holding the lock of ``folder`` (created if needed).

    Attributes
    ----------
    took_over : dict or None
        The record of a dead run whose lock was taken over, else None.
    """

    def __init__(self, folder: str | os.PathLike):
        self.folder = Path(folder)
        self.path = self.folder / LOCK_NAME
        self._lock = None  # a filelock.FileLock while held
        self.took_over: dict | None = None

    def _read(self) -> dict:
        try:
            data = self.path.read_bytes()
        except FileNotFoundError:
            return {}
        try:
            obj = json.loads(data.decode("utf-8")) if data.strip() else {}
        except (ValueError, UnicodeDecodeError):
            obj = {"pid": None, "hostname": None, "started": "?", "command": "unreadable lock file"}
        return obj if isinstance(obj, dict) else {}

    def acquire(self) -> "OutputLock":
        """Take the folder's lock (taking over a dead run's stale record); raise LockedError if another run holds it."""
        from filelock import FileLock, Timeout

        self.folder.mkdir(parents=True, exist_ok=True)
        host = socket.gethostname()
        lock = FileLock(self.folder / FLOCK_NAME, timeout=0)
        try:
            lock.acquire()
        except Timeout:
            holder = self._read()  # may be {} for a moment: the holder writes it just after locking
            who = _describe(holder) if holder else "its record is being written"
            raise LockedError(
                f"output folder {str(self.folder)!r} is in use by another fivid run: {who}; "
                "wait for it to finish or use another output folder", file=self.path) from None
        previous = self._read()
        if previous.get("pid") is not None:
            if previous.get("hostname") not in (None, host):
                lock.release()
                raise LockedError(
                    f"output folder {str(self.folder)!r} is locked by a run on another host: {_describe(previous)}; "
                    f"if that run is no longer active, delete {str(self.path)!r}", file=self.path)
            # Same host and we hold the OS lock: the recorded holder is dead (or its pid was reused).
            self.took_over = previous
            log.warning("took over a stale lock of a run that is no longer active: %s", _describe(previous))
        record = {
            "pid": os.getpid(),
            "hostname": host,
            "started": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "command": " ".join(sys.argv),
            "alive_at_takeover": None if previous.get("pid") is None else pid_alive(int(previous["pid"])),
        }
        tmp = self.path.with_name(f"{LOCK_NAME}.{os.getpid()}.tmp")
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(json.dumps(record))
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, self.path)  # a reader sees the old record or the new one, never half of one
        self._lock = lock
        return self

    def release(self) -> None:
        """Remove the lock record and release the OS lock (no-op when not held)."""
        if self._lock is None:
            return
        try:
            self.path.unlink()
        except FileNotFoundError:
            pass
        self._lock.release()
        self._lock = None

    def __enter__(self) -> "OutputLock":
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()
