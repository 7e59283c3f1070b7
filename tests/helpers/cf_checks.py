"""Run the CF checker (cfchecker's ``cfchecks``) on a file offline, as ../shared/cf/README.md describes.

The standard-name table comes from the compliance-checker wheel (fetched once with ``pip download`` into the
pytest cache folder); the area-type and region tables are the minimal stand-ins in ../shared/cf. Tests that use
it (through :func:`table_or_skip`) skip when cfchecks, the UDUNITS-2 library or the tables are missing, except in
CI (environment variable ``CI`` set, as CI services do), where a missing checker is a failure naming what is
missing: the CF checks must not silently stop running.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SHARED_CF = ROOT.parent / "shared" / "cf"


def standard_name_table(cache: Path) -> Path | None:
    """The CF standard-name table XML, extracted from the compliance-checker wheel (downloaded once)."""
    target = cache / "cf-standard-name-table.xml"
    if target.exists():
        return target
    cache.mkdir(parents=True, exist_ok=True)
    proc = subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps", "-q", "-d", str(cache),
                           "compliance-checker"], capture_output=True, text=True, timeout=300)
    wheels = sorted(cache.glob("compliance_checker-*.whl"))
    if proc.returncode != 0 or not wheels:
        return None
    with zipfile.ZipFile(wheels[-1]) as z:
        target.write_bytes(z.read("compliance_checker/data/cf-standard-name-table.xml"))
    return target


def cf_check(path: Path, table: Path) -> tuple[int, int, str]:
    """``(errors, warnings, output)`` of cfchecks on ``path``."""
    exe = shutil.which("cfchecks") or str(Path(sys.executable).parent / "cfchecks")
    proc = subprocess.run([exe, "-s", str(table), "-a", str(SHARED_CF / "area-type-table.xml"),
                           "-r", str(SHARED_CF / "region-names.xml"), str(path)],
                          capture_output=True, text=True, timeout=300)
    out = proc.stdout + proc.stderr
    err = re.search(r"ERRORS detected:\s*(\d+)", out)
    warn = re.search(r"WARNINGS given:\s*(\d+)", out)
    if err is None:
        raise AssertionError(f"cfchecks did not finish on {path}:\n{out[-3000:]}")
    return int(err.group(1)), int(warn.group(1)) if warn else 0, out


def missing() -> str | None:
    """Why the checker cannot run here (None when it can): cfchecks needs the UDUNITS-2 C library and the
    shared stand-in tables."""
    if not (SHARED_CF / "area-type-table.xml").exists():
        return f"{SHARED_CF / 'area-type-table.xml'} is missing (../shared/cf beside the repository)"
    try:
        import cfchecker.cfchecks  # noqa: F401
    except Exception as exc:  # noqa: BLE001 - missing package or missing libudunits2
        return (f"cfchecks cannot be imported ({type(exc).__name__}: {exc}); install the 'test' extra (cfchecker) "
                "and the UDUNITS-2 library (Debian: apt-get install -y libudunits2-0)")
    return None


def available() -> bool:
    """cfchecks importable (it needs the UDUNITS-2 C library) and the shared stand-in tables present."""
    return missing() is None


def table_or_skip(config) -> Path:
    """The standard-name table for :func:`cf_check`; skips the test when the checker cannot run, fails in CI.

    ``config`` is pytest's ``request.config`` (its cache folder keeps the table between runs).
    """
    import pytest

    act = pytest.fail if os.environ.get("CI") else pytest.skip
    reason = missing()
    if reason is not None:
        act(f"CF checker unavailable: {reason}")
    cache = getattr(config, "cache", None)
    folder = Path(cache.mkdir("cf")) if cache is not None else Path(tempfile.gettempdir()) / "fivid-cf"
    table = standard_name_table(folder)
    if table is None:
        act("CF checker unavailable: the CF standard-name table could not be fetched (pip download "
            "compliance-checker)")
    return table
