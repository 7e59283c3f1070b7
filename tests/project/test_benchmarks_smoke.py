"""Every benchmark runs (``--quick --force``) and prints one JSON line with real content, so none can silently break
(issue 17); every benchmark shares the load guard (issue 30): ``load_average_1min`` in its line, and a refusal to run
on a machine loaded above its core count unless ``--force``."""

import argparse
import importlib.util
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BENCHMARKS = sorted(p.name for p in (ROOT / "benchmarks").glob("bench_*.py"))

#: what each benchmark's line must hold: keys whose values are finite numbers > 0, and keys with a required value
#: or range (a benchmark missing here is checked for its load and for at least one measured positive figure)
POSITIVE = {
    "bench_solver.py": ["dofs", "steps", "dof_updates_per_s", "ns_per_element_cycle", "scipy_csr_dof_updates_per_s",
                        "scipy_csr_ns_per_element_cycle", "speedup_vs_scipy_csr", "bare_stencil_dof_updates_per_s",
                        "bare_stencil_ns_per_element_cycle", "fraction_of_bare_stencil",
                        "curved_fraction_of_bare_stencil", "curved_stencil_fraction_of_bare_stencil",
                        "rough_fraction_of_bare_stencil", "rough_no_contact_fraction_of_bare_stencil",
                        "rough_no_contact_stencil_fraction_of_bare_stencil", "reduced_speedup", "reduced_setup_s",
                        "parallel_1thread_dof_updates_per_s", "reduced_fine_vs_coarse_step_cost_ratio",
                        "reduced_fine_vs_coarse_loop_ratio"],
    "bench_modes.py": ["n_dofs", "modes_s", "lu_s", "cea_s", "full_order_point_s", "cea_speedup"],
    "bench_damping.py": ["rayleigh_wall_s", "band_limited_wall_s", "rayleigh_steps_per_s", "fast_speedup",
                         "fast_rms_ratio"],
    "bench_rough.py": ["rough_dofs", "rough_dof_updates_per_s", "default_dof_updates_per_s", "rough_over_default",
                       "full_scale_slave_nodes", "full_scale_fraction_of_bare_stencil"],
    "bench_psd.py": ["samples", "speedup_vs_scipy_welch"],
    "bench_frf.py": ["hbm_frf_s", "arclength_points", "time_domain_s"],
    "bench_ingest.py": ["rows", "rows_per_s", "fivid_ingest_s", "pandas_pyarrow_s", "time_ratio_vs_pandas_pyarrow",
                        "fivid_read_s", "fivid_write_s"],
    "bench_update.py": ["update_params", "update_evaluations", "update_s", "ema_s"],
    "bench_pipeline.py": ["fine_wall_s", "coarse_wall_s", "fine_vs_coarse_wall_ratio", "fine_cold_wall_s",
                          "coarse_cold_wall_s", "fine_cpu_s", "fine_cold_cpu_s", "fine_vs_coarse_simulate_stage_ratio",
                          "fine_sim_task_mean_s", "coarse_sim_task_mean_s", "fine_vs_coarse_sim_task_ratio",
                          "fine_sim_steps", "coarse_sim_steps", "fine_reduced_boundary_nodes", "fine_wall_min_s",
                          "fine_wall_max_s", "coarse_wall_min_s", "coarse_wall_max_s"],
    "bench_prestress.py": ["ring_dofs", "rig_dofs", "steps", "step_s", "prestress_step_s", "steps_rig", "step_s_rig",
                           "prestress_step_s_rig", "cpu_step_s", "prestress_cpu_step_s", "cpu_step_s_rig",
                           "prestress_cpu_step_s_rig", "sample_seconds"],
}
#: values that are fixed by the benchmark's set-up
EXACT = {
    "bench_solver.py": {"benchmark": "solver", "quick": True, "contact_active": True,
                        "curved_model": "configs/models/ring_pressure.yaml", "curved_mapped_node_share": 1.0},
    "bench_modes.py": {"cea_points": 51},
    "bench_damping.py": {"quick": True},
    "bench_rough.py": {"benchmark": "rough", "quick": True},
    "bench_ingest.py": {"benchmark": "ingest", "rows": 300_000, "columns": 5},
    "bench_update.py": {"benchmark": "update", "quick": True, "update_converged": True},
    "bench_prestress.py": {"benchmark": "prestress", "quick": True, "rounds": 2, "target_max_overhead": 0.2},
    "bench_pipeline.py": {"benchmark": "pipeline", "quick": True, "repeats": 2},
}


def _load_guard():
    spec = importlib.util.spec_from_file_location("_load_guard", ROOT / "benchmarks" / "_load_guard.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_there_are_benchmarks():
    assert {"bench_solver.py", "bench_modes.py", "bench_damping.py", "bench_rough.py"} <= set(BENCHMARKS)


def test_load_guard_refuses_above_the_core_count(capsys):
    guard = _load_guard()
    with pytest.raises(SystemExit) as exc:
        guard.check_load(False, load=2.5, cores=2)
    assert exc.value.code == guard.LOADED_EXIT_STATUS != 0
    err = capsys.readouterr().err
    assert "2.50" in err and "2 cores" in err and "--force" in err
    assert guard.check_load(True, load=2.5, cores=2) == 2.5  # forced: runs, and reports the load
    assert guard.check_load(False, load=2.0, cores=2) == 2.0  # at the core count: runs
    assert guard.check_load(False, load=0.123, cores=1) == 0.12


def test_parse_guarded_adds_force_and_returns_the_load():
    guard = _load_guard()
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    args, load = guard.parse_guarded(parser, ["--quick", "--force"])
    assert args.quick and args.force and load >= 0.0


@pytest.mark.slow
@pytest.mark.parametrize("name", BENCHMARKS)
def test_benchmark_quick_run_prints_one_json_line(name):
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / name), "--quick", "--force"], cwd=ROOT,
                          capture_output=True, text=True, timeout=1200)
    assert proc.returncode == 0, proc.stderr[-3000:]
    lines = [ln for ln in proc.stdout.splitlines() if ln.strip()]
    assert len(lines) == 1, proc.stdout[-3000:]
    out = json.loads(lines[0])
    load = out["load_average_1min"]
    assert isinstance(load, float) and 0.0 <= load < 1000.0
    positive = POSITIVE.get(name) or [k for k, v in out.items() if k != "load_average_1min"
                                      and isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0][:1]
    assert positive, f"{name} reports no measured figure: {out}"
    for key in positive:
        value = out[key]
        assert isinstance(value, (int, float)) and not isinstance(value, bool), (key, value)
        assert math.isfinite(value) and value > 0.0, (key, value)
    for key, value in EXACT.get(name, {}).items():
        assert out[key] == value, (key, out[key], value)
    if name == "bench_pipeline.py":  # the repeats: medians, ranges and per-repeat ratios of the interleaved jobs
        import statistics

        for model in ("fine", "coarse"):
            walls = out[f"{model}_walls_s"]
            assert len(walls) == out["repeats"] and out[f"{model}_wall_s"] == statistics.median(walls)
            assert out[f"{model}_wall_min_s"] == min(walls) and out[f"{model}_wall_max_s"] == max(walls)
        assert out["fine_vs_coarse_wall_ratio"] == out["fine_wall_s"] / out["coarse_wall_s"]
        assert out["wall_ratios"] == [f / c for f, c in zip(out["fine_walls_s"], out["coarse_walls_s"])]
        assert 0.0 <= out["load_average_1min_end"] < 1000.0
