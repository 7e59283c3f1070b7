"""Built-in rig profiles and example models by name, in a checkout and from an installed wheel (issue 19)."""

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from fivid.builtin import builtin_folders, builtin_names, find_builtin

ROOT = Path(__file__).resolve().parents[2]
DAQ_CSV = ROOT / "sample_data" / "twin_daq" / "T01_v5_ra04.csv"


def test_every_built_in_config_is_found_by_name():
    assert builtin_folders("rigs")[0] == ROOT / "configs" / "rigs"  # the checkout first
    assert set(builtin_names("rigs")) == {p.stem for p in (ROOT / "configs" / "rigs").glob("*.yaml")}
    assert set(builtin_names("models")) == {p.stem for p in (ROOT / "configs" / "models").glob("*.yaml")}
    assert set(builtin_names("dampers")) == {p.stem for p in (ROOT / "configs" / "dampers").glob("*.yaml")} != set()
    assert find_builtin("models", "triboair_coarse") == ROOT / "configs" / "models" / "triboair_coarse.yaml"
    assert find_builtin("models", "triboair_coarse.yaml") == find_builtin("models", "triboair_coarse")
    assert find_builtin("rigs", "nonexistent") is None and find_builtin("rigs", "../rigs/labdaq") is None


def test_rig_and_model_names_work_from_another_folder(tmp_path, monkeypatch):
    from fivid.fe import load_model
    from fivid.io import load_rig_profile

    monkeypatch.chdir(tmp_path)  # no ./configs here
    assert load_rig_profile("labdaq").name == "labdaq"
    model = load_model("rough_pair")  # its profile data (profiles/*.csv) is found beside the YAML
    assert model.describe() == load_model(ROOT / "configs" / "models" / "rough_pair.yaml").describe()


def test_damper_models_are_found_by_name(tmp_path, monkeypatch):
    """configs/dampers/ is a built-in kind like rigs and models (issue 19, packaging leftover)."""
    from fivid.damper.model import load_damper_model

    monkeypatch.chdir(tmp_path)
    by_name = load_damper_model("seed004_model1")
    assert by_name.source == str(ROOT / "configs" / "dampers" / "seed004_model1.yaml")
    assert (by_name.friction_coefficient, by_name.contact_stiffness) == (0.45, 3.9e5)


def test_setup_and_manifest_ship_every_built_in_kind():
    """The wheel's build hook (setup.py) and the sdist (MANIFEST.in) carry every kind fivid.builtin looks up."""
    import ast

    from fivid.builtin import KINDS

    tree = ast.parse((ROOT / "setup.py").read_text(encoding="utf-8"))
    shipped = next(ast.literal_eval(n.value) for n in ast.walk(tree)
                   if isinstance(n, ast.Assign) and getattr(n.targets[0], "id", "") == "SHIPPED")
    assert set(shipped) == set(KINDS)
    manifest = (ROOT / "MANIFEST.in").read_text(encoding="utf-8")
    assert all(f"recursive-include configs/{kind} *.yaml" in manifest for kind in KINDS)


def test_an_unknown_model_name_lists_the_built_in_ones(tmp_path, monkeypatch, capsys):
    from fivid.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["modes", "triboair_corse"]) == 2
    err = capsys.readouterr().err
    assert "'triboair_corse'" in err and "triboair_coarse" in err


def test_the_lock_is_portable():
    """The output-folder lock goes through filelock (flock on POSIX, msvcrt on Windows), not fcntl."""
    source = (ROOT / "fivid" / "execution" / "lock.py").read_text(encoding="utf-8")
    assert "fcntl" not in source and "from filelock import" in source


@pytest.fixture
def own_tmp():
    """A temporary folder outside pytest's numbered tmp folders: those are pruned to the last three runs, and
    other pytest runs on a shared machine prune them during this test's minutes of pip install."""
    with tempfile.TemporaryDirectory(prefix="fivid-wheel-") as folder:
        yield Path(folder)


@pytest.mark.slow
def test_a_wheel_installed_in_a_fresh_venv_ingests_with_a_built_in_rig_profile(own_tmp):
    """Build the wheel, install it (dependencies from the package index: minutes), ingest outside the checkout;
    ``fivid verify --quick --json`` passes from the wheel alone (issue 28)."""
    tmp_path = own_tmp
    src, wheels, venv, work = tmp_path / "src", tmp_path / "whl", tmp_path / "venv", tmp_path / "work"
    # the checkout must not be on the path: pip would take its fivid for installed and skip the wheel
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    # build from a copy: an in-tree build leaves build/ and fivid.egg-info/ in the checkout
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(".git", "build", "*.egg-info", "__pycache__", "out",
                                                             ".pytest_cache", ".hypothesis", "benchmarks"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "-w", str(wheels), "-q"],
                   check=True, cwd=tmp_path, env=env)
    (wheel,) = wheels.glob("fivid-*.whl")
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, env=env)
    bin_ = venv / ("Scripts" if os.name == "nt" else "bin")
    subprocess.run([str(bin_ / "python"), "-m", "pip", "install", "-q", str(wheel)], check=True, env=env)
    work.mkdir()
    shutil.copy(DAQ_CSV, work / DAQ_CSV.name)
    out = subprocess.run([str(bin_ / "fivid"), "ingest", DAQ_CSV.name, "--rig", "labdaq", "-o", "runs", "--json"],
                         cwd=work, env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    (record,) = json.loads(out.stdout)["written"]
    assert (work / record["output"]).is_file() or Path(record["output"]).is_file()
    where = subprocess.run([str(bin_ / "python"), "-c", "import fivid.builtin as b; print(b.builtin_folders('rigs'))"],
                           cwd=work, env=env, capture_output=True, text=True, check=True).stdout
    assert str(ROOT) not in where and "site-packages" in where
    models = subprocess.run([str(bin_ / "fivid"), "modes", "triboair_coarse", "-n", "2", "--json"],
                            cwd=work, env=env, capture_output=True, text=True)
    assert models.returncode == 0, models.stderr
    assert len(json.loads(models.stdout)["frequencies_hz"]) == 2
    # issue 28: the verification cases ship in the wheel; a plain install (no dask, no matplotlib) verifies itself
    verify = subprocess.run([str(bin_ / "fivid"), "verify", "--quick", "--json", "--no-progress", "-o", "verification"],
                            cwd=work, env=env, capture_output=True, text=True)
    assert verify.returncode == 0, verify.stderr
    doc = json.loads(verify.stdout)
    assert doc["passed"] is True and len(doc["cases"]) >= 15
    assert all(c["source"] and c["reference"] is not None for c in doc["cases"] if c["status"] != "skipped")
    assert {c["name"]: c["status"] for c in doc["cases"]}["dektak_ra"] == "passed"  # the shipped measured profile
    assert (work / "verification" / "verification.html").is_file()
    damper = subprocess.run([str(bin_ / "python"), "-c", "from fivid.damper.model import load_damper_model as l; "
                             "print(l('seed004_model2').source)"], cwd=work, env=env, capture_output=True, text=True)
    assert damper.returncode == 0 and "site-packages" in damper.stdout, damper.stderr
