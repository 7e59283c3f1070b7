"""Issue 18: the output folder is fivid's own (manifest, no foreign folder, nothing written outside it, stale
temporaries cleaned), and SIGINT/SIGTERM stop ``fivid run`` cleanly (exit 130/143, summary ``interrupted``).

Inputs are the SYNTHETIC ingest example sample_data/R001 under two run ids (as in test_pipeline_runner.py).
"""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from fivid.cli import main

ROOT_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


from tests.pipeline.test_pipeline_runner import _assert_same_content, _content, make_pipeline  # noqa: E402
from tests.helpers.cli import pipeline_process


def _make(base, root):
    return make_pipeline(base, root, "ingest, identify", "identify: {band: [100 Hz, 5 kHz]}")


@pytest.fixture
def setup(tmp_path, root):
    return _make(tmp_path, root)


def _run(s, *extra):
    return main(["run", str(s["recipe"]), "--config", str(s["config"]), "--no-progress", *extra])


# --- output safety -------------------------------------------------------------------------------------------

def test_foreign_folder_is_refused_unless_force(setup, capsys):
    foreign = setup["dir"] / "thesis"
    foreign.mkdir()
    (foreign / "chapter1.tex").write_text("precious")
    assert _run(setup, "-o", str(foreign), "--dry-run") == 2  # a doomed run is refused before any work
    assert _run(setup, "-o", str(foreign)) == 2
    err = capsys.readouterr().err
    assert str(foreign) in err and "--force" in err and "chapter1.tex" in err
    assert sorted(p.name for p in foreign.iterdir()) == ["chapter1.tex"]  # nothing written, not even a lock
    assert _run(setup, "-o", str(foreign), "--force") == 0
    assert (foreign / "chapter1.tex").read_text() == "precious"
    manifest = json.loads((foreign / ".fivid-output.json").read_text())
    assert manifest["fivid-output"] == 1 and "run" in manifest["command"]


def test_manifest_marks_the_folder_and_a_rerun_is_accepted(setup):
    assert _run(setup) == 0
    manifest = setup["out"] / ".fivid-output.json"
    first = manifest.read_bytes()
    assert json.loads(first)["fivid_version"]
    assert _run(setup) == 0  # a fivid output: no --force needed; the manifest is not rewritten
    assert manifest.read_bytes() == first


def test_empty_existing_folder_is_accepted(setup):
    setup["out"].mkdir()
    assert _run(setup, "--dry-run") == 0


def test_output_names_leading_outside_the_folder_are_refused(setup, capsys):
    # a symbolic link inside the output folder pointing elsewhere: runs/*.nc would land outside
    elsewhere = setup["dir"] / "elsewhere"
    elsewhere.mkdir()
    setup["out"].mkdir()
    (setup["out"] / ".fivid-output.json").write_text('{"fivid-output": 1}')
    (setup["out"] / "runs").symlink_to(elsewhere, target_is_directory=True)
    assert _run(setup) == 2
    err = capsys.readouterr().err
    assert "outside the output folder" in err and "runs" in err
    assert list(elsewhere.iterdir()) == []


def test_check_inside_refuses_dotdot(tmp_path):
    from fivid.errors import FividError
    from fivid.pipeline.output import check_inside

    check_inside(tmp_path, tmp_path / "runs" / "a.nc")
    with pytest.raises(FividError, match="outside the output folder"):
        check_inside(tmp_path / "out", tmp_path / "out" / ".." / "a.nc")


def test_stale_temporaries_are_removed_on_the_next_run(setup, caplog):
    assert _run(setup) == 0
    stale = [setup["out"] / ".law.nc.abc123.tmp", setup["out"] / "runs" / ".A.nc.x9y8.tmp"]
    for p in stale:
        p.write_bytes(b"partial")
    keep = setup["out"] / "notes.tmp"  # not fivid's temporary-name pattern: left alone
    keep.write_text("mine")
    assert _run(setup) == 0
    assert not any(p.exists() for p in stale) and keep.exists()
    assert "removed 2 temporary file(s)" in (setup["out"] / "fivid-run.log").read_text()


# --- interruption --------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted run's outputs."""
    from tests.conftest import ROOT

    s = _make(tmp_path_factory.mktemp("reference"), ROOT)
    assert _run(s) == 0
    return _content(s["out"])


def _wait_for_log(proc, out, text, timeout=300):
    """Poll the run's log until ``text`` appears in it (or the run ends)."""
    logfile = out / "fivid-run.log"
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        if logfile.is_file() and text in logfile.read_text(encoding="utf-8"):
            return
        time.sleep(0.02)


def _wait_for_stage(proc, out, stage, timeout=300):
    """Poll the run's log until ``stage`` starts (the stages before it have finished)."""
    _wait_for_log(proc, out, f"stage {stage}: ", timeout)


@pytest.mark.parametrize("signum, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_signal_stops_the_run_cleanly_and_a_rerun_completes(setup, reference, signum, status):
    proc = pipeline_process(setup["recipe"], setup["config"])
    _wait_for_stage(proc, setup["out"], "identify")
    assert proc.poll() is None, "the run ended before it could be interrupted"
    t_signal = time.monotonic()
    proc.send_signal(signum)
    out, err = proc.communicate(timeout=60)
    stopped_in = time.monotonic() - t_signal
    assert proc.returncode == status, err
    assert stopped_in < 20, stopped_in  # seconds, not the rest of the run
    assert "Traceback" not in err and f"interrupted by {signal.Signals(signum).name}" in err
    summary = json.loads((setup["out"] / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["exit_code"] == status
    assert summary["interrupted"] == {"signal": signal.Signals(signum).name, "stage": "identify"}
    assert not (setup["out"] / ".fivid-run.lock").exists()
    assert _run(setup) == 0  # resumes: the finished stage is kept
    again = json.loads((setup["out"] / "summary.json").read_text())
    ingest = next(st for st in again["stages"] if st["name"] == "ingest")
    assert ingest["cached"] == 2 and ingest["ran"] == 0
    _assert_same_content(_content(setup["out"]), reference)


@pytest.mark.slow
@pytest.mark.parametrize("moment", ["cluster", "simulating"])  # while the dask cluster starts; while workers simulate
def test_sigterm_during_the_dask_sweep_stops_cleanly(setup, moment):
    # six simulations on one worker: after the first one is done the stage has five left (~5-30 s each, with the
    # machine's load), so the signal lands mid-sweep. A fixed sleep did not: once the reduced path got faster the
    # two-task stage ended inside an 8 s delay, and the signal hit the exiting process (stop 36's CI failure).
    setup["recipe"].write_text("fivid-pipeline: 1\nstages: [ingest, identify, simulate]\n")
    with open(setup["config"], "a") as f:
        f.write("simulate: {duration: 0.1 s, sample_rate: 51.2 kHz, seeds: 3}\n"
                "analysis: {band: [500 Hz, 5 kHz], nperseg: 512}\n")
    proc = pipeline_process(setup["recipe"], setup["config"], "--workers", "1")
    _wait_for_stage(proc, setup["out"], "simulate")
    if moment == "cluster":
        time.sleep(0.5)
    else:
        _wait_for_log(proc, setup["out"], "simulate/")  # the log names a simulate task when it is done
    assert proc.poll() is None, "the run ended before it could be interrupted"
    t_signal = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert "Traceback" not in err, err  # a half-started LocalCluster used to print one at exit
    assert time.monotonic() - t_signal < 30
    summary = json.loads((setup["out"] / "summary.json").read_text())
    assert summary["interrupted"] == {"signal": "SIGTERM", "stage": "simulate"}
