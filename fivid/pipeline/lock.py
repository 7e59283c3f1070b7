"""A lock on an output folder: one pipeline run at a time.

The lock file ``<output>/.fivid-run.lock`` holds an exclusive ``flock`` for the life of the run and
records the holder's pid, host name, start time and command. A second run on the same folder is
refused with a message naming the holder. The kernel drops the ``flock`` when its holder dies (even
by SIGKILL), so a lock file left by a dead run on this host is taken over, and the takeover is
logged with the dead run's pid and start time. A lock file written by another host cannot be
checked from here (``flock`` is not reliable across NFS): it is refused with a message saying how
to remove it if that run is gone.
"""

from __future__ import annotations

import datetime as _dt
import errno
import fcntl
import json
import logging
import os
import socket
import sys
from pathlib import Path

from fivid.errors import FividError

__all__ = ["OutputLock", "LockedError", "pid_alive"]

log = logging.getLogger("fivid")

LOCK_NAME = ".fivid-run.lock"


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
        self.fd: int | None = None
        self.took_over: dict | None = None

    def _read(self, fd: int) -> dict:
        os.lseek(fd, 0, os.SEEK_SET)
        data = b""
        while chunk := os.read(fd, 65536):
            data += chunk
        try:
            obj = json.loads(data.decode("utf-8")) if data.strip() else {}
        except (ValueError, UnicodeDecodeError):
            obj = {"pid": None, "hostname": None, "started": "?", "command": "unreadable lock file"}
        return obj if isinstance(obj, dict) else {}

    def acquire(self) -> "OutputLock":
        self.folder.mkdir(parents=True, exist_ok=True)
        host = socket.gethostname()
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                if exc.errno not in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                    os.close(fd)
                    raise
                holder = self._read(fd)
                os.close(fd)
                raise LockedError(
                    f"output folder {str(self.folder)!r} is in use by another fivid run: {_describe(holder)}; "
                    "wait for it to finish or use another output folder", file=self.path) from None
            # The file may have been unlinked by a finishing holder between our open and flock.
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(self.path))
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        previous = self._read(fd)
        if previous.get("pid") is not None:
            if previous.get("hostname") not in (None, host):
                os.close(fd)
                raise LockedError(
                    f"output folder {str(self.folder)!r} is locked by a run on another host: {_describe(previous)}; "
                    f"if that run is no longer active, delete {str(self.path)!r}", file=self.path)
            # Same host and we hold the flock: the recorded holder is dead (or its pid was reused).
            self.took_over = previous
            log.warning("took over a stale lock of a run that is no longer active: %s", _describe(previous))
        record = {
            "pid": os.getpid(),
            "hostname": host,
            "started": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "command": " ".join(sys.argv),
            "alive_at_takeover": None if previous.get("pid") is None else pid_alive(int(previous["pid"])),
        }
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, json.dumps(record).encode("utf-8"))
        os.fsync(fd)
        self.fd = fd
        return self

    def release(self) -> None:
        if self.fd is None:
            return
        try:
            self.path.unlink()
        except FileNotFoundError:
            pass
        os.close(self.fd)  # closing drops the flock
        self.fd = None

    def __enter__(self) -> "OutputLock":
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()
