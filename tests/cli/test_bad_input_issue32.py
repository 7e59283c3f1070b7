"""Bad inputs of issue 32 ("Bad inputs that still get through"): each ends in one line naming the file, line,
key or value and what is allowed, exit 2, no traceback, nothing half-written."""

import pytest
from tests.helpers.cli import fails
from tests.helpers.ingest import GOOD_META, write_rig

from fivid.cli import main





# --- ingest -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("rate", ["0 Hz", "1e-320 Hz"])
def test_zero_sample_rate_does_not_stop_the_batch(tmp_path, capsys, rate):
    """A file with sample_rate 0 Hz (a ZeroDivisionError before) is reported; the good file is written."""
    bad = write_rig(tmp_path / "bad.csv", meta={**GOOD_META, "run_id": "R009"}, extra_meta=[f"# sample_rate: {rate}"])
    good = write_rig(tmp_path / "good.csv")
    out = tmp_path / "out"
    err = fails(capsys, ["ingest", str(bad), str(good), "-o", str(out)])
    assert f"{bad}:7: key 'sample_rate'" in err and "1 file(s) written, 1 rejected" in err
    assert sorted(p.name for p in out.iterdir()) == ["R001.nc"]


def test_allow_implausible_is_recorded_in_the_file(tmp_path, capsys):
    from fivid.io import read_run

    path = write_rig(tmp_path / "kn.csv", meta={**GOOD_META, "normal_load": "5 kN"})
    out = tmp_path / "out"
    err = fails(capsys, ["ingest", str(path), "-o", str(out)])
    assert "normal_force" in err and "--allow-implausible" in err and not out.joinpath("R001.nc").exists()
    assert main(["ingest", str(path), "-o", str(out), "--allow-implausible"]) == 0
    ds = read_run(out / "R001.nc")
    assert ds.attrs["allow_implausible"] == "yes"
    assert "allowed (--allow-implausible): normal_force: " in ds.attrs["quality_report"]


# --- export -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("file_format", ["csv", "uff58"])
def test_export_of_a_netcdf_fivid_did_not_write(tmp_path, capsys, file_format):
    """A netCDF without units used to become a CSV with empty units ('a []'): refused, nothing written."""
    import numpy as np
    import xarray as xr

    if file_format == "uff58":
        pytest.importorskip("pyuff")
    path = tmp_path / "other.nc"
    xr.Dataset({"a": ("time", np.arange(4.0)), "b": ("time", np.ones(4), {"units": "N"})},
               coords={"time": np.arange(4) * 1e-3}).to_netcdf(path)
    out = tmp_path / "out.csv"
    err = fails(capsys, ["export", str(path), "--format", file_format, "-o", str(out)])
    assert f"{path}: key 'units': cannot export: 2 variable(s) have no 'units' attribute ('time', 'a')" in err
    assert "not a fivid dataset" in err and not out.exists() and not list(tmp_path.glob(".*tmp"))


# --- built-in names with every option ------------------------------------------------------------------


@pytest.mark.parametrize("options", [["--json"], ["--points", "3"], ["--points", "3", "--json"],
                                     ["--arclength", "--json"]])
def test_damper_frf_by_built_in_name_with_every_option(tmp_path, monkeypatch, capsys, options):
    """`fivid damper frf seed004_model1 --normal-load 1N --json` hashed the name as a path (FileNotFoundError);
    the JSON names the file the name resolved to, byte for byte the shipped YAML."""
    import hashlib
    import json

    from fivid.builtin import find_builtin

    monkeypatch.chdir(tmp_path)  # no ./configs: the name is resolved by fivid.builtin
    load = "5N" if "--arclength" in options else "1N"  # at 1 N the arclength continuation stalls (a path too)
    status = main(["damper", "frf", "seed004_model1", "--normal-load", load, *options])
    out, err = capsys.readouterr()
    assert status == 0 and "Traceback" not in err, err
    if "--json" in options:
        shipped = find_builtin("dampers", "seed004_model1")
        sha = hashlib.sha256(shipped.read_bytes()).hexdigest()
        assert json.loads(out)["model_source"] == f"seed004_model1.yaml sha256:{sha}"


# --- reproducible modes ---------------------------------------------------------------------------------


def test_modes_are_bit_reproducible():
    """ARPACK started from its own random vector: the frequencies changed in the last digits from call to
    call (issue 32). With a fixed start vector two analyses of a sparse-sized model are identical."""
    import numpy as np

    from fivid.fe import load_model
    from fivid.fe.modal import DENSE_LIMIT, modal_analysis

    model = load_model("triboair_coarse")
    first, second = modal_analysis(model, 6), modal_analysis(model, 6)
    assert first.attrs["n_free_dofs"] > DENSE_LIMIT  # the eigsh path, not the dense one
    for name in first.data_vars:
        np.testing.assert_array_equal(first[name].values, second[name].values)


# --- files read whole: size, content, links ----------------------------------------------------------------


def _utf16(path):
    path.write_bytes("x [um],z [um]\n0,1\n1,2\n2,3\n".encode("utf-16"))  # with its byte-order mark
    return path


def _loop(path):
    other = path.with_name("other.csv")
    other.symlink_to(path.name)
    path.symlink_to(other.name)
    return path


def _huge(path):
    with open(path, "wb") as f:  # a sparse 2 GB file: its size is checked before a byte is read
        f.truncate(2 * 10**9)
    return path


@pytest.mark.parametrize("command", [["profile"], ["damper", "fit"]])
@pytest.mark.parametrize("make, expected", [
    (_huge, "the file is 2 GB (2000000000 bytes), larger than the 268 MB"),
    (_loop, "loop of symbolic links"),
    (_utf16, "UTF-16 (little-endian) text (byte-order mark FF FE), not UTF-8; save it as UTF-8"),
])
def test_files_read_whole_are_checked_first(tmp_path, capsys, command, make, expected):
    import resource

    path = make(tmp_path / "input.csv")
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    err = fails(capsys, [*command, str(path)])
    assert f"{path}" in err and expected in err
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 100_000  # KiB: nothing read whole


def test_utf16_rig_csv_names_its_encoding(tmp_path, capsys):
    path = tmp_path / "run.csv"
    path.write_bytes("# fivid-rig-csv: 1\n".encode("utf-16-le"))  # no byte-order mark
    err = fails(capsys, ["ingest", str(path), "-o", str(tmp_path / "out")])
    assert "UTF-16 (little-endian) text without a byte-order mark" in err and "binary" not in err
    assert "loop of symbolic links" in fails(capsys, ["ingest", str(_loop(tmp_path / "l.csv")), "-o",
                                                      str(tmp_path / "out")])


# --- summary.json agrees with the exit status ---------------------------------------------------------------


@pytest.mark.parametrize("raised, expected", [
    (MemoryError("8 EiB requested"), 2),  # was exit_code 1 in summary.json, exit status 2
    (RuntimeError("a bug"), 1),
    (KeyboardInterrupt(), 130),
])
def test_summary_exit_code_is_the_exit_status(tmp_path, root, monkeypatch, capsys, raised, expected):
    import json

    import fivid.pipeline.stages

    data = tmp_path / "data"
    data.mkdir()
    (data / "R001.csv").write_bytes((root / "sample_data" / "R001_v10_ra08.csv").read_bytes())
    (tmp_path / "recipe.yaml").write_text("fivid-pipeline: 1\nstages: [ingest]\n")
    model = root / "configs" / "models" / "triboair_coarse.yaml"
    (tmp_path / "run.yaml").write_text(f"inputs: {{folder: {data}}}\nmodel: {model}\noutput: {tmp_path / 'out'}\n")

    def read(*args, **kwargs):
        raise raised

    monkeypatch.setattr(fivid.pipeline.stages, "read_rig_csv", read)  # where the ingest stage looks it up
    status = main(["run", str(tmp_path / "recipe.yaml"), "--config", str(tmp_path / "run.yaml"), "--no-progress"])
    err = capsys.readouterr().err
    assert status == expected, err
    assert ("Traceback" in err) == (expected == 1)
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["exit_code"] == status


# --- study --quick validates the base config too -----------------------------------------------------------


def test_study_quick_reports_a_wrong_type_the_quick_block_overrides(tmp_path, root, capsys):
    text = (root / "configs" / "studies" / "weak_strong.yaml").read_text()
    text = text.replace("../models/", f"{root}/configs/models/").replace("../laws/", f"{root}/configs/laws/")
    text = text.replace("  modes: {n_modes: 6}", '  modes: {n_modes: "6"}')  # a string where an integer is typed
    text = text.replace("  points: {transient: {duration: 0.02 s}}",
                        "  points: {transient: {duration: 0.02 s}, modes: {n_modes: 4}}")  # quick overrides it
    study = tmp_path / "study.yaml"
    study.write_text(text)
    line = text.splitlines().index('  modes: {n_modes: "6"}') + 1
    err = fails(capsys, ["study", str(study), "--quick", "-o", str(tmp_path / "out")])
    assert f"{study}:{line}: key 'points.modes.n_modes': expected an integer, found str '6'" in err
    assert not (tmp_path / "out").exists()


# --- sizes checked before work -------------------------------------------------------------------------------


def test_simulate_of_a_billion_seconds_is_refused_before_work(root, tmp_path, capsys):
    model = root / "configs" / "models" / "triboair_coarse.yaml"
    err = fails(capsys, ["simulate", str(model), "--duration", "1e9 s", "-o", str(tmp_path / "x.nc"), "--dry-run"])
    assert "key '--duration':" in err and "may be planned" in err  # memory, the first limit met


def test_simulate_beyond_the_time_cap_is_refused(root, tmp_path, capsys, monkeypatch):
    """On a machine with memory to spare, the solver work itself is capped (MAX_DOF_STEPS, about 4 days)."""
    from fivid.execution import resources

    monkeypatch.setattr(resources, "available_memory", lambda: (1 << 62, "test"))
    model = root / "configs" / "models" / "triboair_coarse.yaml"
    err = fails(capsys, ["simulate", str(model), "--duration", "1e6 s", "-o", str(tmp_path / "x.nc"), "--dry-run"])
    assert "key '--duration': this simulation would take 1 run(s) x" in err and "at most 1e+15 may be planned" in err


def test_monte_carlo_samples_are_refused_before_work(root, tmp_path, capsys):
    model = root / "configs" / "models" / "triboair_coarse.yaml"
    law = root / "configs" / "laws" / "sample_truth.nc"
    out = tmp_path / "env.nc"
    err = fails(capsys, ["simulate", str(model), "--law", str(law), "--roughness", "1.6 um", "--samples", "100000000",
                         "-o", str(out)])
    assert "key '--samples': 100,000,000 samples" in err and not out.exists()


def test_run_plan_refuses_a_simulate_stage_that_cannot_fit(tmp_path, root, capsys):
    text = (root / "configs" / "runs" / "sample.yaml").read_text()
    text = text.replace("../../", f"{root}/").replace("../models/", f"{root}/configs/models/")
    text = text.replace("  duration: 0.3 s ", "  duration: 1e9 s ")
    config = tmp_path / "run.yaml"
    config.write_text(text)
    line = next(i for i, t in enumerate(text.splitlines(), 1) if t.startswith("  duration: 1e9 s"))
    out = tmp_path / "out"
    err = fails(capsys, ["run", str(root / "pipelines" / "calibration.yaml"), "--config", str(config), "-o", str(out),
                         "--dry-run"])
    assert f"{config}:{line}: key 'simulate.duration':" in err and "Shorten simulate.duration" in err
    assert not out.exists()  # refused at the plan check: nothing ingested, identified or written


@pytest.mark.parametrize("command", [["modes"], ["cea", "--load", "5 N", "--mu", "0", "1", "3"]])
def test_modal_analysis_of_a_huge_mesh_is_refused_before_assembly(tmp_path, root, capsys, command):
    """50 000 x 5 000 divisions: killed by the OOM killer before (issue 32); refused from the divisions now."""
    import resource

    text = (root / "configs" / "models" / "triboair_coarse.yaml").read_text()
    model = tmp_path / "huge.yaml"
    model.write_text(text.replace("divisions: [50, 5]", "divisions: [50000, 5000]"))
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    err = fails(capsys, [command[0], str(model), *command[1:]])
    assert f"{model}: key 'bodies': this model has 250,055,187 nodes" in err and "Lower the bodies' divisions" in err
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 200_000  # KiB: no mesh was built


# --- physically impossible simulations ---------------------------------------------------------------------


@pytest.mark.parametrize("option, key", [(["--load", "1e30 N"], "normal_load"),
                                         (["--velocity", "1e30 m/s"], "sliding_velocity"),
                                         (["--mu", "1e6"], "mu")])
def test_impossible_simulation_inputs_are_refused(root, tmp_path, capsys, option, key):
    model = root / "configs" / "models" / "triboair_coarse.yaml"
    out = tmp_path / "sim.nc"
    err = fails(capsys, ["simulate", str(model), *option, "--duration", "1 ms", "-o", str(out)])
    assert f"key '{key}': {key} = 1e+" in err and "plausible range" in err and not out.exists()


def test_energy_balance_beyond_its_bound_fails_the_run():
    """The closure error against the run's energy scale: round-off (1e-14 on the shipped models) passes,
    an error of 1e-3 of the scale (or a NaN) is no result."""
    import numpy as np
    import xarray as xr

    from fivid.solver.inputs import ENERGY_BALANCE_TOLERANCE, EnergyBalanceError, check_energy_balance

    t = np.linspace(0, 1e-3, 11)
    work = 2e-3 * t / t[-1]  # [J]
    base = {"external_work": ("time", work), "kinetic_energy": ("time", work / 2),
            "friction_dissipation": ("time", work / 2)}
    ok = xr.Dataset({**base, "energy_balance_error": ("time", 1e-14 * work)}, coords={"time": t})
    check_energy_balance(ok)
    for error in (1e3 * ENERGY_BALANCE_TOLERANCE * work, np.where(t > 5e-4, np.nan, 0.0)):
        bad = xr.Dataset({**base, "energy_balance_error": ("time", error)}, coords={"time": t})
        with pytest.raises(EnergyBalanceError, match="does not close"):
            check_energy_balance(bad)


# --- identify: mu = +-12 ---------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def runs_mu_12(tmp_path_factory):
    """Two SYNTHETIC runs (tests/helpers/synthetic_friction_runs.py) whose friction force is scaled to mean Ft/Fn = +12
    and -12: the identification took |mu| of both, mu0 11.98, the sign lost (issue 32)."""
    from tests.helpers.synthetic_friction_runs import synthetic_run, true_law

    from fivid.io import write_run

    folder = tmp_path_factory.mktemp("mu12")
    paths = []
    for k, sign in enumerate((1, -1)):
        ds = synthetic_run(true_law(), velocity=0.01, roughness=0.4e-6, normal_load=5.0, seed=k, run_id=f"M{k}",
                           duration=2.0)
        ds["friction_force"] = ds["friction_force"] * (sign * 12.0 / 0.3)  # the law's mu0 is 0.3
        paths.append(write_run(ds, folder / f"M{k}.nc"))
    return paths


def test_identify_refuses_mu_beyond_two_and_records_an_override(runs_mu_12, tmp_path, capsys):
    import xarray as xr

    out = tmp_path / "law.nc"
    err = fails(capsys, ["identify", *map(str, runs_mu_12), "-o", str(out)])
    assert "run M0: mean friction coefficient Ft/Fn = +12" in err and "key 'friction_force'" in err
    assert "--allow-implausible" in err and not out.exists()
    assert main(["identify", *map(str, runs_mu_12), "-o", str(out), "--allow-implausible"]) == 0
    assert "negative: taken as the opposite sign convention" in capsys.readouterr().err  # the sign is said
    with xr.open_dataset(out) as law:
        recorded = "\n".join(f"{k}={v}" for k, v in law.attrs.items())
    assert "allow_implausible" in recorded, recorded
