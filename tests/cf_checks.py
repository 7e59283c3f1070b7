"""Run the CF checker (cfchecker's ``cfchecks``) on a file offline, as ../shared/cf/README.md describes.

The standard-name table comes from the compliance-checker wheel (fetched once with ``pip download`` into the
pytest cache folder); the area-type and region tables are the minimal stand-ins in ../shared/cf. Tests that use
it skip when cfchecks, the UDUNITS-2 library or the tables are missing.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
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


def available() -> bool:
    """cfchecks importable (it needs the UDUNITS-2 C library) and the shared stand-in tables present."""
    if not (SHARED_CF / "area-type-table.xml").exists():
        return False
    try:
        import cfchecker.cfchecks  # noqa: F401
    except Exception:  # noqa: BLE001 - missing package or missing libudunits2
        return False
    return True
