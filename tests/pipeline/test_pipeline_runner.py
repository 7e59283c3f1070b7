"""The runner: whole-plan validation, cache (no-op re-run, only dependents re-run), lock, kill-and-rerun.

These use the ingest and modal stages on the small ingest examples (SYNTHETIC, sample_data/R001*).
The full pipeline on the twin data is exercised in test_pipeline_sample.py.
"""

import json
import os
import random
import signal
import subprocess
import sys
import time

import pytest

from fivid.cli import main
from tests.helpers.cli import pipeline_process

ROOT_DIR = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _variant(src, dst, run_id, velocity_mm_s):
    """A copy of a fivid-rig-csv file with another run id and nominal velocity (different bytes)."""
    lines = src.read_text(encoding="utf-8").splitlines(keepends=True)
    out = []
    for ln in lines:
        if ln.startswith("# run_id:"):
            ln = f"# run_id: {run_id}\n"
        elif ln.startswith("# sliding_velocity:"):
            ln = f"# sliding_velocity: {velocity_mm_s} mm/s\n"
        out.append(ln)
    dst.write_text("".join(out), encoding="utf-8")
    return dst


def make_pipeline(base, root, stages: str, section: str) -> dict:
    """A two-run pipeline in ``base``: runs A (10 mm/s) and B (12 mm/s) made from the sample CSV, a recipe with
    ``stages`` (e.g. "ingest, modal") and a run config on the coarse rig with the extra ``section`` line."""
    data = base / "data"
    data.mkdir()
    src = root / "sample_data" / "R001_v10_ra08.csv"
    _variant(src, data / "A.csv", "A", 10)
    _variant(src, data / "B.csv", "B", 12)
    recipe = base / "recipe.yaml"
    recipe.write_text(f"fivid-pipeline: 1\nstages: [{stages}]\n")
    config = base / "run.yaml"
    config.write_text(f"inputs: {{folder: data}}\nmodel: {root / 'configs/models/triboair_coarse.yaml'}\n"
                      f"output: out\n{section}\n")
    return {"dir": base, "data": data, "src": src, "recipe": recipe, "config": config, "out": base / "out"}


@pytest.fixture
def setup(tmp_path, root):
    return make_pipeline(tmp_path, root, "ingest, modal", "modal: {n_modes: 4}")


def _run(s, *extra):
    return main(["run", str(s["recipe"]), "--config", str(s["config"]), "--no-progress", *extra])


def _summary(s):
    return json.loads((s["out"] / "summary.json").read_text())


def _stage(summary, name):
    return next(st for st in summary["stages"] if st["name"] == name)


def _mtimes(folder):
    return {p: p.stat().st_mtime_ns for p in folder.rglob("*") if p.is_file() and p.name not in
            ("summary.json", "fivid-run.log")}


def test_second_run_does_no_work_and_writes_nothing(setup):
    assert _run(setup) == 0
    first = _summary(setup)
    assert _stage(first, "ingest")["ran"] == 2 and _stage(first, "modal")["ran"] == 1
    before = _mtimes(setup["out"])
    assert _run(setup) == 0
    second = _summary(setup)
    assert second["cache"] == {"tasks": 3, "cached": 3, "ran": 0}
    assert _mtimes(setup["out"]) == before
    log = (setup["out"] / "fivid-run.log").read_text()
    assert "all cached" in log and "summary: pass" in log


def test_new_csv_reruns_only_what_depends_on_it(setup):
    assert _run(setup) == 0
    before = _mtimes(setup["out"])
    _variant(setup["src"], setup["data"] / "C.csv", "C", 14)
    assert _run(setup) == 0
    s = _summary(setup)
    assert (_stage(s, "ingest")["ran"], _stage(s, "ingest")["cached"]) == (1, 2)
    assert _stage(s, "modal")["ran"] == 0  # the model does not depend on the CSVs
    after = _mtimes(setup["out"])
    assert all(after[p] == t for p, t in before.items())  # nothing written before was rewritten
    assert (setup["out"] / "runs" / "C.nc").exists()


def test_changed_csv_or_damaged_output_is_redone_and_force_redoes_all(setup):
    assert _run(setup) == 0
    _variant(setup["src"], setup["data"] / "B.csv", "B", 13)   # same name, new content
    (setup["out"] / "modal.nc").write_bytes(b"garbage")         # a damaged output
    assert _run(setup) == 0
    s = _summary(setup)
    assert _stage(s, "ingest")["ran"] == 1 and _stage(s, "modal")["ran"] == 1
    assert _run(setup, "--force") == 0
    assert _summary(setup)["cache"]["ran"] == 3


def test_dry_run_prints_the_plan_and_writes_nothing(setup, capsys):
    assert _run(setup, "--dry-run") == 0
    out = capsys.readouterr().out
    assert "ingest    2 task(s): 0 cached, 2 to run" in out and "would run A" in out
    assert "modal     runs after ingest" in out  # linearised about the conditions' normal load: needs the CSVs
    assert not setup["out"].exists()
    assert _run(setup) == 0
    capsys.readouterr()
    assert _run(setup, "--dry-run") == 0
    assert "modal     1 task(s): 1 cached, 0 to run" in capsys.readouterr().out


def test_bad_config_is_refused_before_any_work(setup, capsys):
    setup["config"].write_text(setup["config"].read_text() + "simulate: {duration: 3 kg}\n")
    assert _run(setup) == 2
    err = capsys.readouterr().err
    assert "key 'simulate.duration'" in err and str(setup["config"]) in err
    assert not setup["out"].exists()


def test_bad_csv_gives_exit_2_naming_the_file_and_line(setup, capsys):
    (setup["data"] / "Z.csv").write_text("# fivid-rig-csv: 1\n# run_id: Z\nnot,a,run\n")
    assert _run(setup) == 2
    err = capsys.readouterr().err
    assert "Z.csv" in err and "rejected" in err
    s = _summary(setup)
    assert s["status"] == "bad_input" and s["exit_code"] == 2
    assert _stage(s, "ingest")["ran"] == 3 and _stage(s, "modal")["tasks"] == 0  # stopped after ingest


_HOLDER = """
import sys, time
from fivid.execution.lock import OutputLock
lock = OutputLock(sys.argv[1]).acquire()
print("locked", flush=True)
time.sleep(60)
"""


def test_concurrent_run_on_the_same_output_is_refused(setup, capsys):
    proc = subprocess.Popen([sys.executable, "-c", _HOLDER, str(setup["out"])], stdout=subprocess.PIPE, text=True,
                            cwd=ROOT_DIR)
    try:
        assert proc.stdout.readline().strip() == "locked"
        assert _run(setup) == 2
        err = capsys.readouterr().err
        assert "in use by another fivid run" in err and f"pid {proc.pid}" in err
        assert not (setup["out"] / "summary.json").exists()
    finally:
        proc.kill()
        proc.wait()


def _content(folder):
    """Numeric content of every netCDF output (history and timestamps excluded)."""
    import xarray as xr

    out = {}
    for p in sorted(folder.rglob("*.nc")):
        with xr.open_dataset(p) as ds:
            out[str(p.relative_to(folder))] = {k: ds[k].values for k in ds.variables if ds[k].dtype.kind in "fiu"}
    return out


def _assert_same_content(a, b):
    """Equal outputs. Ingested runs are bit-identical; the modal stage's ARPACK solve starts from a random
    vector, so its eigenpairs agree to the solver's convergence (machine precision times the conditioning,
    ~1e-14 relative for modes separated by >10 %): compare at 1e-9 of each array's scale."""
    import numpy as np

    assert a.keys() == b.keys()
    for name in a:
        assert a[name].keys() == b[name].keys(), name
        for k in a[name]:
            x, y = a[name][k], b[name][k]
            if name.startswith("runs"):
                np.testing.assert_array_equal(x, y, err_msg=f"{name}:{k}")
            else:
                finite = np.abs(y[np.isfinite(y)])  # the law holds NaN and inf
                scale = float(finite.max()) if finite.size else 0.0
                np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-9 * scale, err_msg=f"{name}:{k}")


def test_killed_run_then_rerun_gives_identical_results_and_no_corrupt_file(setup, tmp_path):
    for i in range(4):
        _variant(setup["src"], setup["data"] / f"K{i}.csv", f"K{i}", 20 + i)
    # reference: an uninterrupted run in another folder
    ref = pipeline_process(setup["recipe"], setup["config"], "--output", str(tmp_path / "ref"))
    assert ref.wait(timeout=300) == 0, ref.stderr.read()
    t_full = json.loads((tmp_path / "ref" / "summary.json").read_text())["seconds"]
    rng = random.Random(os.getpid())
    proc = pipeline_process(setup["recipe"], setup["config"])
    time.sleep(0.6 + rng.uniform(0.0, max(t_full, 0.5)))  # 0.6 s: interpreter start-up before any output
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    again = pipeline_process(setup["recipe"], setup["config"])
    assert again.wait(timeout=300) == 0, again.stderr.read()
    s = _summary(setup)
    assert s["status"] == "pass"
    _assert_same_content(_content(setup["out"]), _content(tmp_path / "ref"))
    leftovers = [p for p in setup["out"].rglob("*.tmp")]
    # a temporary file of the killed process may remain; never a partial output under its final name
    assert all(p.name.startswith(".") for p in leftovers)
    assert s["cache"]["tasks"] == 7
