"""The installation a verification ran on: versions, git revision, CPU, date (the manual's record)."""

from __future__ import annotations

import datetime as _dt
import os
import platform
import subprocess
from importlib import metadata
from pathlib import Path

from fivid import __version__

__all__ = ["environment", "git_revision", "cpu_model"]

_PACKAGES = ("numpy", "scipy", "numba", "xarray", "pandas", "netCDF4", "statsmodels", "pyfftw", "dask",
             "distributed", "matplotlib")


def git_revision(folder: str | os.PathLike | None = None) -> str:
    """The git commit of a development checkout holding fivid (``<hash>`` plus ``-dirty`` when files differ from
    it), or ``"not a git checkout"`` for an installed wheel."""
    folder = Path(folder) if folder is not None else Path(__file__).resolve().parents[2]
    if not (folder / ".git").exists():
        return "not a git checkout"
    try:
        head = subprocess.run(["git", "-C", str(folder), "rev-parse", "HEAD"], capture_output=True, text=True,
                              timeout=10, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(folder), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10, check=True).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return "git unavailable"
    return head + ("-dirty" if dirty else "")


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo`` on Linux, else :func:`platform.processor`)."""
    try:
        for line in Path("/proc/cpuinfo").read_text(encoding="utf-8", errors="replace").splitlines():
            if line.lower().startswith(("model name", "hardware", "cpu model")):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def environment() -> dict:
    """fivid's version and git revision, Python and the numerical packages' versions, the CPU and the date (UTC)."""
    versions = {}
    for pkg in _PACKAGES:
        try:
            versions[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            versions[pkg] = "not installed"
    return {
        "fivid_version": __version__,
        "git_revision": git_revision(),
        "python": platform.python_version(),
        "packages": versions,
        "platform": platform.platform(),
        "cpu": cpu_model(),
        "cpu_count": os.cpu_count(),
        "date": _dt.datetime.now(_dt.timezone.utc).replace(microsecond=0).isoformat(),
    }
