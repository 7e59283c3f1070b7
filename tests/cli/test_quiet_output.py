"""Quiet, informative output (issue 32 item 6): no library warnings on a run, a line per finished task without a
terminal ending with the report's path, the stop message once and no leaked-semaphore warning, JSON where --json
is given, ``ingest -q`` quiet. Inputs: the SYNTHETIC ingest examples (sample_data/R001*) via make_pipeline."""

import json
import os
import signal
import socket
import subprocess
import sys
import time
import warnings

import pytest
from tests.pipeline.test_pipeline_runner import make_pipeline
from tests.pipeline.test_pipeline_safety import _wait_for_stage

from fivid.cli import main
from tests.helpers.cli import fivid_process

ROOT_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_run_config_dump_has_no_serializer_warning(tmp_path, root, capsys):
    """The identify band and tare were stored as tuples in list-typed fields: every dump warned."""
    s = make_pipeline(tmp_path, root, "ingest, identify", "identify: {band: [100 Hz, 5 kHz], tare: [0 s, 15 ms]}")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert main(["run", str(s["recipe"]), "--config", str(s["config"]), "--dry-run", "--json"]) == 0
    plan = json.loads(capsys.readouterr().out)
    assert plan["dry_run"] is True and plan["plan"]


def test_local_cluster_with_port_8787_taken_does_not_warn():
    from fivid.execution.cluster import dask_client

    sock = socket.socket()
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind(("", 8787))
            sock.listen()
        except OSError:
            pass  # taken already: the case in question
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            with dask_client(workers=1) as client:
                assert client.submit(sum, [1, 2]).result() == 3
        assert not [w for w in caught if "8787" in str(w.message)], [str(w.message) for w in caught]
    finally:
        sock.close()


def test_run_without_terminal_logs_each_task(tmp_path, root):
    """The report's path as the last line is checked on the full pipeline (test_pipeline_sample.py, slow)."""
    s = make_pipeline(tmp_path, root, "ingest, modal", "modal: {n_modes: 4}")
    proc = fivid_process("run", str(s["recipe"]), "--config", str(s["config"]))
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    lines = err.strip().splitlines()
    assert "ingest: 2 task(s), 0 cached, running 2" in lines
    assert any(ln.strip().startswith("ingest/A done in") and ln.endswith("of 2)") for ln in lines), lines
    assert any(ln.strip().startswith("modal/modal done in") for ln in lines), lines
    assert lines[-1].startswith("fivid run: pass (exit 0)") and "open the report" not in err  # no report stage
    assert "warn" not in err.lower(), err
    proc = fivid_process("run", str(s["recipe"]), "--config", str(s["config"]))  # all cached: a line per stage
    _, err = proc.communicate(timeout=300)
    assert "ingest: 2 task(s), all cached" in err and " done in " not in err


def test_sigint_message_once(tmp_path, root):
    s = make_pipeline(tmp_path, root, "ingest, identify", "identify: {band: [100 Hz, 5 kHz]}")
    proc = fivid_process("run", str(s["recipe"]), "--config", str(s["config"]))
    _wait_for_stage(proc, s["out"], "identify")
    assert proc.poll() is None, "the run ended before it could be interrupted"
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.count("interrupted by SIGINT") == 1, err


@pytest.mark.slow
def test_ctrl_c_during_the_dask_sweep_prints_one_message_and_no_leak_warning(tmp_path, root):
    """Ctrl-C reaches the whole process group (the workers too); the workers were killed by it mid-task and
    multiprocessing's resource tracker warned about their leaked semaphores."""
    s = make_pipeline(tmp_path, root, "ingest, identify, simulate",
                      "simulate: {duration: 0.3 s, sample_rate: 51.2 kHz, seeds: 2}\n"
                      "analysis: {band: [500 Hz, 5 kHz], nperseg: 512}")
    proc = fivid_process("run", str(s["recipe"]), "--config", str(s["config"]), "--workers", "2", start_new_session=True)
    _wait_for_stage(proc, s["out"], "simulate")
    time.sleep(8.0)  # the workers are simulating
    assert proc.poll() is None, "the run ended before it could be interrupted"
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert err.count("interrupted by SIGINT") == 1, err
    assert "leaked semaphore" not in err and "Traceback" not in err, err


def test_simulate_dry_run_json(root, capsys):
    model = str(root / "configs/models/triboair_coarse.yaml")
    assert main(["simulate", model, "--dry-run", "--json", "--duration", "20 ms", "-o", "unused.nc"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert record["dry_run"] is True and "984 dofs" in record["model"]
    assert record["memory_bytes"] == sum(record["memory_parts_bytes"].values())
    assert main(["simulate", model, "--dry-run", "--duration", "20 ms", "-o", "unused.nc"]) == 0
    text = capsys.readouterr().out
    assert f"{record['output_samples']:,} output samples" in text and f"{record['solver_steps']:,} solver steps" in text


def test_ingest_quiet(root, tmp_path, capsys):
    src = str(root / "sample_data" / "R001_v10_ra08.csv")
    assert main(["ingest", src, "-o", str(tmp_path / "a"), "-q"]) == 0
    assert capsys.readouterr().out == ""
    assert main(["ingest", src, "-o", str(tmp_path / "b")]) == 0
    assert "R001.nc" in capsys.readouterr().out
