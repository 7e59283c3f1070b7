"""A SIGTERM after ``fivid run`` has written its summary keeps the run's exit status (fivid.cli._SignalPolicy).

Before the fix, such a signal gave 143 ("interrupted") while summary.json said ``pass`` / exit 0 when it came
while the CLI printed its last lines, and -15 (killed) when it came during the interpreter's shutdown after a
dask run (~1.5 s in which the handlers were back at their defaults). The run is a real ``fivid run`` process;
each test waits for a line of its output, never for a fixed time. The two fast cases hold the process in the
window under test with a hook (a pause after the summary is written; a slow atexit clean-up registered during
the command, as dask.distributed registers its own), so the signal lands there on any machine load; the slow
case is a plain ``python -m fivid run`` with a dask simulate stage, signalled as soon as its summary line shows.

Inputs: the SYNTHETIC ingest example sample_data/R001 under two run ids (as in test_pipeline_runner.py).
"""

import json
import os
import signal
import subprocess
import sys
import threading
import time

import pytest

from tests.helpers.cli import ROOT, pipeline_process
from tests.pipeline.test_pipeline_runner import make_pipeline

#: seconds a hooked window lasts; the run must end long before when the signal lands in it
HOLD = 60.0

# the hooks, run as ``python -c HOOK run RECIPE --config CONFIG --no-progress`` (the CLI as a process: argv None)
_PRELUDE = "import atexit, sys, time\nimport fivid.cli.commands.run as command\noriginal = command._run\n"
_HOOKS = {
    # the summary is written and the outcome settled; the CLI has not printed its status line yet
    "while_printing": _PRELUDE + (
        "import fivid.pipeline as pipeline\nrun_pipeline = pipeline.run_pipeline\n"
        "def held(*a, **k):\n"
        "    out = run_pipeline(*a, **k)\n"
        "    print('HOOK summary written', file=sys.stderr, flush=True)\n"
        "    time.sleep(3.0)  # the signal lands here (noted), then the CLI prints and ends\n"
        "    return out\n"
        "pipeline.run_pipeline = held\n"),
    # main has returned: a slow atexit clean-up registered during the command (dask's are)
    "during_exit": _PRELUDE + (
        "def clean_up():\n"
        "    print('HOOK exit clean-up', file=sys.stderr, flush=True)\n"
        f"    time.sleep({HOLD})\n"
        "def hooked(args):\n"
        "    atexit.register(clean_up)\n"
        "    return original(args)\n"
        "command._run = hooked\n"),
}
_MARKS = {"while_printing": "HOOK summary written", "during_exit": "HOOK exit clean-up"}


def _hooked_process(hook, recipe, config) -> subprocess.Popen:
    code = _HOOKS[hook] + "from fivid.cli import main\nsys.exit(main())\n"
    return subprocess.Popen([sys.executable, "-c", code, "run", str(recipe), "--config", str(config), "--no-progress"],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": str(ROOT)})


def _signal_after_line(proc, mark, timeout=600.0):
    """Read stderr until a line starts with ``mark``, then send SIGTERM; returns (stderr, seconds from the signal
    to the process's end). A watchdog kills a process that never prints the line."""
    watchdog = threading.Timer(timeout, proc.kill)
    watchdog.start()
    try:
        lines = []
        for line in proc.stderr:
            lines.append(line)
            if line.startswith(mark):
                break
        else:
            pytest.fail(f"the run ended (status {proc.wait()}) without the line {mark!r}:\n{''.join(lines)}")
        t0 = time.monotonic()
        proc.send_signal(signal.SIGTERM)
        _, rest = proc.communicate(timeout=timeout)
        return "".join(lines) + rest, time.monotonic() - t0
    finally:
        watchdog.cancel()


def _ingest_pipeline(base):
    return make_pipeline(base, ROOT, "ingest", "")


@pytest.mark.parametrize("hook", ["while_printing", "during_exit"])
def test_sigterm_after_the_summary_keeps_the_run_status(tmp_path, hook):
    s = _ingest_pipeline(tmp_path)
    proc = _hooked_process(hook, s["recipe"], s["config"])
    err, seconds = _signal_after_line(proc, _MARKS[hook])
    summary = json.loads((s["out"] / "summary.json").read_text())
    assert summary["status"] == "pass" and summary["interrupted"] is None
    assert proc.returncode == summary["exit_code"] == 0, err  # before: 143 (while printing), -15 (during exit)
    assert "Traceback" not in err and "interrupted" not in err, err
    assert "fivid: SIGTERM after the command had finished (outputs complete); exit status 0" in err, err
    assert "fivid run: pass (exit 0)" in err  # the status line is still printed when the signal came before it
    assert seconds < HOLD / 2, seconds  # ends at once, not after the held clean-up
    assert not (s["out"] / ".fivid-run.lock").exists()


def test_a_finished_run_ends_without_waiting_for_the_interpreter_shutdown(tmp_path):
    """No signal: the process still ends with the run's status, and its stdout (--json) is complete."""
    s = _ingest_pipeline(tmp_path)
    proc = pipeline_process(s["recipe"], s["config"], "--json")
    out, err = proc.communicate(timeout=600)
    assert proc.returncode == 0, err
    assert json.loads(out)["exit_code"] == 0


@pytest.mark.slow
def test_sigterm_after_the_summary_of_a_dask_run_keeps_its_status(tmp_path):
    # a plain `python -m fivid run` whose simulate stage runs on a dask LocalCluster; SIGTERM as soon as the
    # summary line shows (before the fix: -15 from the dask shutdown at exit, or 143 while the CLI printed)
    s = make_pipeline(tmp_path, ROOT, "ingest, identify, simulate", "identify: {band: [100 Hz, 5 kHz]}\n"
                      "simulate: {duration: 0.02 s, sample_rate: 51.2 kHz, seeds: 1}\n"
                      "analysis: {band: [500 Hz, 5 kHz], nperseg: 512}")
    proc = pipeline_process(s["recipe"], s["config"], "--workers", "1")
    err, seconds = _signal_after_line(proc, "fivid run: ")
    summary = json.loads((s["out"] / "summary.json").read_text())
    assert summary["status"] == "pass" and [st["ran"] for st in summary["stages"]] == [2, 1, 2]
    assert proc.returncode == summary["exit_code"] == 0, err
    assert "Traceback" not in err and "interrupted" not in err, err
    assert seconds < 30, seconds
