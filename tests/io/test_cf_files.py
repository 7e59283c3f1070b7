"""Every kind of netCDF file fivid writes passes the CF checker (cfchecks): no error, no warning.

The files are written once per module, as a user writes them (the CLI, small inputs: three twin runs, the coarse rig,
a 2 ms simulation); ``law.nc`` (fivid identify) is not covered yet, and the study files are checked in
tests/study/test_study.py. Also: the test conditions of a run are scalar coordinates, so runs stacked with
``open_mfdataset`` keep them and can be selected by condition.
"""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from tests.helpers import cf_checks
from fivid.cli import main

ROOT = Path(__file__).resolve().parents[2]
TWIN = ROOT / "sample_data" / "twin"
COARSE = ROOT / "configs" / "models" / "triboair_coarse.yaml"
RUNS = ("T01", "T02", "T04")  # 5 and 10 mm/s at Ra 0.4 um, 5 mm/s at Ra 1.6 um; all at 5 N


@pytest.fixture(scope="module")
def table(request):
    return cf_checks.table_or_skip(request.config)


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """``{kind: path}`` of one file of each kind, written by the CLI (and the pipeline's score stage helper)."""
    out = tmp_path_factory.mktemp("cf")
    runs = out / "runs"
    csvs = [str(next(TWIN.glob(f"{r}_*.csv"))) for r in RUNS]
    assert main(["ingest", *csvs, "-o", str(runs)]) == 0
    files = {"run": runs / "T01.nc"}
    cmds = {
        "simulated run": ["simulate", str(COARSE), "--mu", "0.3", "--duration", "2 ms"],
        "modes": ["modes", str(COARSE), "-n", "4"],
        "modes with contact": ["modes", str(COARSE), "-n", "4", "--load", "5 N"],
        "cea": ["cea", str(COARSE), "--load", "5 N", "--mu", "0", "0.6", "3", "-n", "4"],
        "psd": ["psd", str(runs / "T01.nc"), "--nperseg", "2048"],
        "scores": ["score", str(runs / "T01.nc"), str(runs / "T02.nc"), "--nperseg", "2048"],
    }
    for kind, args in cmds.items():
        files[kind] = out / (kind.replace(" ", "_") + ".nc")
        assert main([*args, "-o", str(files[kind])]) == 0, kind

    from fivid.pipeline.scoring import score_condition
    from fivid.storage import write_netcdf

    _, psd = score_condition([runs / "T01.nc"], [runs / "T02.nc"], band=(800, 5000), nperseg=2048, settle=0.0)
    files["pipeline psd"] = write_netcdf(psd, out / "condition-psd.nc")
    return files


@pytest.fixture(scope="module")
def profile_file(tmp_path_factory):
    """A surface-profile evaluation (fivid profile) of a synthetic trace: z = 1 um sin(2 pi x / 80 um)."""
    out = tmp_path_factory.mktemp("cf-profile")
    x = np.arange(0, 4e-3, 0.5e-6)
    text = "x [um],z [um]\n" + "\n".join(f"{a * 1e6:.3f},{np.sin(2 * np.pi * a / 80e-6):.6f}" for a in x)
    (out / "trace.txt").write_text(text + "\n", encoding="utf-8")
    assert main(["profile", str(out / "trace.txt"), "--cutoff", "0.8 mm", "-o", str(out / "profile.nc")]) == 0
    return out / "profile.nc"


KINDS = ["run", "simulated run", "modes", "modes with contact", "cea", "psd", "scores", "pipeline psd"]


@pytest.mark.parametrize("kind", KINDS)
def test_file_passes_the_cf_checker(kind, written, table):
    errors, warnings, out = cf_checks.cf_check(written[kind], table)
    assert (errors, warnings) == (0, 0), out[-3000:]


def test_profile_file_passes_the_cf_checker(profile_file, table):
    errors, warnings, out = cf_checks.cf_check(profile_file, table)
    assert (errors, warnings) == (0, 0), out[-3000:]


def test_run_with_several_sensors_has_no_cf_error(tmp_path, table):
    """``sensor`` stays a text dimension coordinate (``.sel(sensor="top")``, ``--sensor``): written as a char array
    it is 2-D, which the checker warns about (one warning, "possible incorrect declaration"); no error."""
    from tests.helpers.ingest import write_rig

    from fivid.io import read_rig_csv, write_run

    header = "time [s],acceleration:top [g],friction_force [N],acceleration:side [m/s^2],normal_force [N]"
    rows = ["0,0.5,1.5,1.0,5.0", "0.001,-0.25,1.6,2.0,5.1", "0.002,1,1.4,-3.0,4.9"]
    path = write_run(read_rig_csv(write_rig(tmp_path / "s.csv", rows=rows, header=header)), tmp_path / "s.nc")
    errors, warnings, out = cf_checks.cf_check(path, table)
    assert errors == 0, out[-3000:]
    assert warnings == 1 and "incorrect declaration of a coordinate variable" in out, out[-3000:]


def test_time_is_seconds_without_a_reference_date(written):
    """``time`` [s] from the start of the recording: no CF time coordinate (standard_name time / axis T need
    "s since <date>"), no _FillValue (a coordinate has no missing values); xarray leaves it float seconds."""
    import netCDF4

    for kind in ("run", "simulated run"):
        with netCDF4.Dataset(written[kind]) as nc:
            t = nc.variables["time"]
            assert t.units == "s" and t.long_name == "time since start of recording"
            assert not {"standard_name", "axis", "_FillValue"} & set(t.ncattrs()), kind
        with xr.open_dataset(written[kind]) as ds:
            assert ds["time"].dtype == np.float64


def test_rewriting_an_old_run_drops_the_time_standard_name(written, tmp_path):
    """Files written before issue 19 have standard_name/axis on time; read_run + write_run removes them."""
    from fivid.io import read_run, write_run

    old = read_run(written["run"])
    old["time"].attrs.update(standard_name="time", axis="T")
    back = read_run(write_run(old, tmp_path / "old.nc"))
    assert "standard_name" not in back["time"].attrs and "axis" not in back["time"].attrs


def test_text_is_stored_as_char_arrays(written):
    """CF has no variable-length strings: text variables are char arrays, decoded back to str by xarray."""
    import netCDF4

    with netCDF4.Dataset(written["modes"]) as nc:
        assert nc.variables["body"].dtype == np.dtype("S1") and nc.variables["component_name"].dtype == np.dtype("S1")
    with xr.open_dataset(written["modes"]) as ds:
        assert list(ds["component_name"].values) == ["x", "y"]
        assert set(ds["body"].values) == {"lower", "upper"}


def test_runs_stack_along_run_with_their_conditions_as_coordinates(written):
    """``open_mfdataset(combine="nested", concat_dim="run")`` keeps the test conditions, with units, and
    ``.where``/``.sel`` select by them (``.sel`` after ``set_xindex``, which :func:`fivid.io.open_runs` does)."""
    from fivid.io import open_runs, read_run

    paths = sorted(written["run"].parent.glob("*.nc"))
    assert [p.stem for p in paths] == list(RUNS)
    with xr.open_mfdataset(paths, combine="nested", concat_dim="run") as ds:
        assert ds.sizes["run"] == 3
        assert ds["sliding_velocity"].dims == ("run",) and ds["sliding_velocity"].attrs["units"] == "m s-1"
        assert ds["roughness_ra"].dims == ("run",) and ds["roughness_ra"].attrs["units"] == "m"
        assert ds["normal_load"].attrs["units"] == "N"  # equal in every run: open_mfdataset keeps it scalar
        assert list(ds["run_id"].values) == list(RUNS)
        np.testing.assert_allclose(ds["sliding_velocity"].values, [0.005, 0.01, 0.005], rtol=1e-12)
        rough = ds.where(ds["roughness_ra"] > 1e-6, drop=True)
        assert list(rough["run_id"].values) == ["T04"]
        slow = ds.set_xindex("sliding_velocity").sel(sliding_velocity=0.005)
        assert list(slow["run_id"].values) == ["T01", "T04"]
        np.testing.assert_array_equal(slow["acceleration"].isel(run=1).values,
                                      read_run(paths[2])["acceleration"].values)
    with open_runs(written["run"].parent / "*.nc") as ds:
        assert ds["normal_load"].dims == ("run",)  # coords="all": every condition along run
        assert float(ds.sel(run_id="T02")["sliding_velocity"]) == 0.01  # unique: the run dimension is dropped
        assert ds.sel(roughness_ra=4e-7).sizes["run"] == 2


def test_conditions_are_both_attributes_and_coordinates(written):
    """Readers of the global attributes keep working; the coordinates equal them."""
    from fivid.io import read_run

    for kind in ("run", "simulated run"):
        ds = read_run(written[kind])
        for name in ("sliding_velocity", "normal_load", "roughness_ra"):
            assert float(ds[name]) == ds.attrs[name] and ds[name].ndim == 0, (kind, name)
        assert str(ds["run_id"].values) == ds.attrs["run_id"]


def test_a_psd_keeps_the_conditions_of_its_run(written):
    with xr.open_dataset(written["psd"]) as ds:
        assert float(ds["sliding_velocity"]) == 0.005 and ds["sliding_velocity"].attrs["units"] == "m s-1"
        assert str(ds["run_id"].values) == "T01"
    with xr.open_dataset(written["pipeline psd"]) as ds:  # one test condition: its velocity, not one run's id
        assert float(ds["sliding_velocity"]) == 0.005 and "run_id" not in ds.variables
        assert list(ds["measured_run"].values) == ["T01"] and ds["psd_measured"].dims == ("measured", "frequency")


def test_law_file_has_no_cf_error(written, table, tmp_path):
    """law.nc (fivid identify): no error; its text dimension coordinates (coefficient, run, form) stay index
    coordinates that the law reader and ``fivid law show`` select by, which the checker warns about (one warning
    each, "possible incorrect declaration of a coordinate variable"); every variable has a long name."""
    runs = sorted(written["run"].parent.glob("T0*.nc"))
    law = tmp_path / "law.nc"
    assert main(["identify", *map(str, runs), "-o", str(law)]) == 0
    errors, warnings, out = cf_checks.cf_check(law, table)
    assert errors == 0, out[-3000:]
    assert "No standard_name or long_name" not in out, out[-3000:]
    assert warnings <= 4, out[-3000:]
