"""The reduced path by default (issue 30): the basis cache, the in-band error estimate and the automatic choice."""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.helpers.reduced_setup import COARSE, coarse, run_inputs  # noqa: F401  (shared set-up; coarse is a fixture)

ROOT = Path(__file__).resolve().parents[2]



def test_two_concurrent_simulations_build_the_basis_once(tmp_path):
    """Two ``fivid simulate`` processes started together on one model with an empty cache: one builds the basis
    (under the cache's file lock), the other waits and reads it; one cache entry, one "built"."""
    env = {**os.environ, "FIVID_CACHE_DIR": str(tmp_path / "cache"), "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "fivid", "simulate", str(COARSE), "--mu", "0.3", "--velocity", "10 mm/s", "--load",
           "5 N", "--duration", "1 ms", "--json"]
    procs = [subprocess.Popen(cmd + ["-o", str(tmp_path / f"s{i}.nc")], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for i in range(2)]
    outs = [p.communicate(timeout=600) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [o[1] for o in outs]
    summaries = [json.loads(o[0]) for o in outs]
    assert sorted(s["reduced_basis_source"] for s in summaries) == ["built", "cache"]
    assert all(s["solver_path"] == "reduced" for s in summaries)
    assert len(list((tmp_path / "cache").glob("*.npz"))) == 1
    import xarray as xr

    keys = set()
    for i in range(2):
        with xr.open_dataset(tmp_path / f"s{i}.nc") as ds:
            keys.add(ds.attrs["reduced_basis_key"])
            acc = ds.acceleration.values
        if i == 0:
            first = acc
    assert len(keys) == 1
    np.testing.assert_array_equal(acc, first)  # the cached basis is the built one, bit for bit


def test_cached_basis_is_the_built_one_and_the_key_follows_the_model(coarse, tmp_path):
    """A basis read from the cache equals the one built and stored exactly, and a fresh build (no cache) to
    round-off (the Lanczos start vector and the modes' signs are fixed); a change of material (E) changes the key."""
    from fivid.fe import load_model
    from fivid.solver.driver import prepare_run

    fresh = prepare_run(coarse, **run_inputs(1e-3, reduced="reduced", basis_cache=False)).reduced
    built = prepare_run(coarse, **run_inputs(1e-3, reduced="reduced", cache_dir=tmp_path)).reduced
    read = prepare_run(coarse, **run_inputs(1e-3, reduced="reduced", cache_dir=tmp_path)).reduced
    assert (built.basis_source, read.basis_source) == ("built", "cache")
    for name in ("T", "M", "K", "unscaled_mass", "truncation_flexibility", "mode_frequencies"):
        np.testing.assert_array_equal(getattr(read, name), getattr(built, name))
        a, b = getattr(read, name), getattr(fresh, name)
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-8 * np.abs(b).max())
    assert read.omega_max() == built.omega_max()
    text = COARSE.read_text()
    assert "E: 210 GPa" in text
    (tmp_path / "stiffer.yaml").write_text(text.replace("E: 210 GPa", "E: 212 GPa"))
    stiffer = load_model(tmp_path / "stiffer.yaml")
    other = prepare_run(stiffer, **run_inputs(1e-3, reduced="reduced", cache_dir=tmp_path)).reduced
    assert other.basis_key != read.basis_key and other.basis_source == "built"


def test_cache_command_lists_and_clears(tmp_path, capsys, coarse):
    from fivid.cli import main
    from fivid.solver.driver import prepare_run

    prepare_run(coarse, **run_inputs(1e-3, reduced="reduced", cache_dir=tmp_path))
    assert main(["cache", "info", "--cache-dir", str(tmp_path), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    kinds = {e["kind"]: e for e in info["entries"]}
    assert len(info["entries"]) == 2 and sorted(kinds) == ["basis", "preload"] and info["total_bytes"] > 0
    assert kinds["basis"]["boundary_nodes"] > 0 and kinds["preload"]["normal_load_n"] == 5.0
    assert main(["cache", "info", "--cache-dir", str(tmp_path)]) == 0
    assert "1 basis(es), 1 preload(s)" in capsys.readouterr().out
    assert main(["cache", "clear", "--cache-dir", str(tmp_path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["removed"] == 2
    assert not list(tmp_path.rglob("*.npz"))


def test_truncation_shift_predicts_the_reduced_frequency_error(coarse):
    """The first-order truncation shift ``omega_r^2 x_b^T G x_b / 2`` of the estimate against the actual error of the
    reduced natural frequencies (groups held, contact open) with 12 fixed-interface modes: the shifts of the
    modes below 10 kHz agree within 30 % (what the first-order, omega_r << omega_j, approximation leaves), and the
    reduced frequencies err high as Rayleigh-Ritz requires."""
    from fivid.fe.modal import constrained_matrices, lowest_modes
    from fivid.solver.driver import prepare_run
    from fivid.solver.reduced_error import _tied_modes

    K, M, _ = constrained_matrices(coarse, mass="lumped")
    lam, _ = lowest_modes(K, M, 6)
    full = np.sqrt(lam) / (2.0 * np.pi)
    rs = prepare_run(coarse, **run_inputs(1e-3, reduced=12)).reduced
    nf, nb2 = rs.n_free, 2 * rs.kernel["nb"]
    lam_r, x = _tied_modes(rs.K[:nf, :nf], rs.M[:nf, :nf], np.zeros((0, nf)), (2 * math.pi * 10e3) ** 2)
    n = lam_r.size
    actual = np.sqrt(lam_r) / (2.0 * math.pi) / full[:n] - 1.0
    predicted = 0.5 * lam_r * np.einsum("ir,ij,jr->r", x[:nb2], rs.truncation_flexibility, x[:nb2])
    assert n >= 2 and np.all(actual > 0.0)
    np.testing.assert_allclose(predicted, actual, rtol=0.3)


def test_auto_choice_follows_the_tolerance_and_is_recorded(coarse):
    """``reduced="auto"``: reduced when the estimate is within the tolerance, full (with the estimate and the reason
    recorded) when the tolerance is below it; ``None`` records the full path as requested."""
    from fivid.solver.driver import choice_attrs, prepare_run

    auto = prepare_run(coarse, **run_inputs(1e-3, reduced="auto"))
    est = auto.choice["estimate"]["lsd_db"]
    assert auto.reduced is not None and 0.0 < est <= 0.5
    strict = prepare_run(coarse, **run_inputs(1e-3, reduced="auto", reduced_tolerance=est / 2))
    assert strict.reduced is None and strict.choice["path"] == "full" and "tolerance" in strict.choice["reason"]
    a = choice_attrs(strict.choice)
    assert a["solver_path"] == "full" and a["reduced_error_estimate_db"] == pytest.approx(est)
    full = prepare_run(coarse, **run_inputs(1e-3, reduced=None))
    assert choice_attrs(full.choice)["solver_path"] == "full" and math.isnan(
        choice_attrs(full.choice)["reduced_error_estimate_db"])


def test_dry_run_estimates_the_run_time(tmp_path, capsys):
    from fivid.cli import main

    assert main(["simulate", str(COARSE), "--mu", "0.3", "--velocity", "10 mm/s", "--load", "5 N", "--duration",
                 "5 ms", "-o", str(tmp_path / "x.nc"), "--dry-run", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    t = j["run_time_estimate"]
    assert j["solver_path"] == "reduced" and j["memory_bytes"] > 0
    assert j["estimated_run_time_s"] == pytest.approx(t["setup_seconds"] + t["seconds_per_interval"] * t["n_intervals"])
    assert t["seconds_per_interval"] > 0 and not (tmp_path / "x.nc").exists()


def test_reduced_check_from_the_command_line(tmp_path, capsys):
    """``fivid simulate --reduced-check``: the a-posteriori Richardson pair runs, its figure and step ratio reach the
    JSON summary and the output's attrs, the history line names the flag (so the run can be repeated), and
    ``--full --reduced-check`` is refused with exit 2 (nothing to check)."""
    import xarray as xr

    from fivid.cli import main

    out = tmp_path / "x.nc"
    args = ["simulate", str(COARSE), "--mu", "0.3", "--velocity", "10 mm/s", "--load", "5 N", "--duration", "5 ms",
            "--cache-dir", str(tmp_path / "cache"), "--json"]
    assert main([*args, "--reduced-check", "-o", str(out)]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["solver_path"] == "reduced"  # the coarse rig's figure is far below 0.5 dB (docs/solver.md's table)
    assert math.isfinite(j["reduced_error_check_db"]) and j["reduced_error_check_db"] >= 0.0
    assert j["reduced_error_check_step_ratio"] == pytest.approx(0.5, rel=1e-12)  # exactly half the run's step
    with xr.open_dataset(out) as ds:
        assert ds.attrs["reduced_error_check_db"] == pytest.approx(j["reduced_error_check_db"])
        assert "--reduced-check" in ds.attrs["history"]
    assert main([*args, "--full", "--reduced-check", "-o", str(tmp_path / "y.nc")]) == 2
    err = capsys.readouterr().err
    assert "--reduced-check" in err and "--full" in err and not (tmp_path / "y.nc").exists()
