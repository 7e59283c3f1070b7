"""Every benchmark runs (``--quick``) and prints one JSON line, so none can silently break (issue 17)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BENCHMARKS = sorted(p.name for p in (ROOT / "benchmarks").glob("bench_*.py"))


def test_there_are_benchmarks():
    assert {"bench_solver.py", "bench_modes.py", "bench_damping.py", "bench_rough.py"} <= set(BENCHMARKS)


@pytest.mark.slow
@pytest.mark.parametrize("name", BENCHMARKS)
def test_benchmark_quick_run_prints_one_json_line(name):
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / name), "--quick"], cwd=ROOT,
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = [ln for ln in proc.stdout.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stdout[-3000:]
    out = json.loads(lines[0])
    assert isinstance(out, dict) and out
