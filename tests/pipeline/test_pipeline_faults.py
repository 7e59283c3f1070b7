"""Issue 18: fault injection and load on ``fivid run``.

* SIGKILL at 20 seeded random points spread over a run's wall time, each followed by a re-run: every output
  opens and equals an uninterrupted run's (tiny recipe ingest -> identify -> modal on three SYNTHETIC runs,
  the sample_data/R001 example under other run ids; the simulate stage is exercised by the kill in
  test_pipeline_sample.py).
* 200 SYNTHETIC runs through ingest -> identify in one call: peak memory stays below twice that of 20 runs.
"""

import json
import os
import random
import resource
import signal
import subprocess
import sys
import time

import pytest
from tests.pipeline.test_pipeline_runner import _assert_same_content, _content, _variant

from fivid.cli import main
from tests.helpers.cli import pipeline_process

ROOT_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _make(base, root, n_runs, stages):
    data = base / "data"
    data.mkdir(parents=True)
    src = root / "sample_data" / "R001_v10_ra08.csv"
    for i in range(n_runs):  # two velocities: the amplitude law needs more than one
        _variant(src, data / f"S{i:03d}.csv", f"S{i:03d}", 10 if i % 2 else 12)
    (base / "recipe.yaml").write_text(f"fivid-pipeline: 1\nstages: [{', '.join(stages)}]\n")
    (base / "run.yaml").write_text(f"inputs: {{folder: data}}\nmodel: {root / 'configs/models/triboair_coarse.yaml'}\n"
                                   "output: out\nidentify: {band: [100 Hz, 5 kHz]}\nmodal: {n_modes: 4}\n")
    return base


def _check_outputs_open(out):
    import xarray as xr

    for p in out.rglob("*"):
        if p.is_file() and p.suffix == ".nc":
            with xr.open_dataset(p) as ds:
                ds.load()
        elif p.is_file() and p.suffix == ".json":
            json.loads(p.read_text(encoding="utf-8"))
    assert not [p for p in out.rglob("*.tmp")], "a stale temporary survived the re-run"


@pytest.mark.slow
def test_sigkill_at_20_random_points_then_rerun_equals_an_uninterrupted_run(tmp_path, root):
    stages = ["ingest", "identify", "modal"]
    ref = _make(tmp_path / "ref", root, 3, stages)
    t0 = time.monotonic()
    proc = pipeline_process(ref / "recipe.yaml", ref / "run.yaml", stdout=subprocess.DEVNULL)
    assert proc.wait(timeout=300) == 0, proc.stderr.read()
    t_full = time.monotonic() - t0
    reference = _content(ref / "out")
    base = _make(tmp_path / "k", root, 3, stages)
    rng = random.Random(18)
    # 0.9 t_full: a forced re-run may be quicker than the reference (warm page cache, less load)
    points = sorted(rng.uniform(0.0, 0.9 * t_full) for _ in range(20))
    killed = 0
    for i, t_kill in enumerate(points):
        proc = pipeline_process(base / "recipe.yaml", base / "run.yaml", stdout=subprocess.DEVNULL, *(["--force"] if i else []))  # --force: every task is redone, so there is work to kill
        time.sleep(t_kill)
        if proc.poll() is None:
            killed += 1
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        # the re-run in this process: numba compiles once, so the 20 re-runs take seconds
        assert main(["run", str(base / "recipe.yaml"), "--config", str(base / "run.yaml"), "--no-progress"]) == 0, \
            (i, t_kill)
        _check_outputs_open(base / "out")
        _assert_same_content(_content(base / "out"), reference)
        summary = json.loads((base / "out" / "summary.json").read_text())
        assert summary["status"] == "pass" and summary["cache"]["tasks"] == 3 + 1 + 1
    assert killed >= 12, f"only {killed} of 20 kills landed while the run was working"


def _peak_rss_of_run(base) -> int:
    """Peak resident memory [bytes] of one ``fivid run`` child process (ru_maxrss of the waited child)."""
    code = ("import resource, sys\nfrom fivid.cli import main\nstatus = main(sys.argv[1:])\n"
            "print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)\nsys.exit(status)\n")
    proc = subprocess.run([sys.executable, "-c", code, "run", str(base / "recipe.yaml"), "--config",
                           str(base / "run.yaml"), "--no-progress"], cwd=ROOT_DIR, capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": ROOT_DIR}, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return int(proc.stdout.strip().splitlines()[-1]) * 1024  # Linux: kB


@pytest.mark.slow
def test_200_runs_in_one_call_with_bounded_memory(tmp_path, root):
    """Peak RSS of 200 runs < 2 x that of 20 runs.

    Each run is ~6000 samples x 6 variables (0.3 MB as float64); the interpreter with numpy, xarray, numba
    and pyarrow is ~250 MB. Holding every run's dataset and its intermediate arrays (PSD segments, tare,
    friction coefficient, several copies each) would add >10 x 0.3 MB per run, i.e. >0.6 GB for 200, far
    beyond the 20-run peak; a stage that streams stays near it.
    """
    stages = ["ingest", "identify"]
    small = _peak_rss_of_run(_make(tmp_path / "r20", root, 20, stages))
    t0 = time.perf_counter()
    large = _peak_rss_of_run(_make(tmp_path / "r200", root, 200, stages))
    print(f"peak RSS: 20 runs {small / 2**20:.0f} MiB, 200 runs {large / 2**20:.0f} MiB "
          f"({time.perf_counter() - t0:.0f} s)")
    summary = json.loads((tmp_path / "r200" / "out" / "summary.json").read_text())
    assert summary["cache"]["tasks"] == 201 and summary["status"] == "pass"
    assert large < 2 * small, (small, large)
    assert resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024 >= large
