"""Running the CLI: in-process (the bad-input tests) or as a ``python -m fivid`` process (the pipeline's
interruption, resumption and console tests)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from fivid.cli import main


def fails(capsys, argv) -> str:
    """Run the CLI, check exit 2 without a traceback, return stderr."""
    status = main(argv)
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    assert status == 2, err
    return err


ROOT = Path(__file__).resolve().parents[2]


def fivid_process(*args, stdout=subprocess.PIPE, **popen) -> subprocess.Popen:
    """``python -m fivid *args`` started from the repository root with this checkout first on ``PYTHONPATH`` (text
    pipes; stderr captured; ``popen`` passed on, e.g. ``start_new_session``)."""
    return subprocess.Popen([sys.executable, "-m", "fivid", *map(str, args)], cwd=ROOT, stdout=stdout,
                            stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(ROOT)}, **popen)


def pipeline_process(recipe, config, *extra, **popen) -> subprocess.Popen:
    """``fivid run RECIPE --config CONFIG --no-progress *extra`` as a process (:func:`fivid_process`)."""
    return fivid_process("run", recipe, "--config", config, "--no-progress", *extra, **popen)
