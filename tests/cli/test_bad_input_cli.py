"""Bad inputs of issue 18 that used to end in a traceback: each is now exit 2 with one line naming the
file, key or value and the fix, and nothing half-written is left behind."""

import numpy as np
import pytest
from tests.helpers.cli import fails
from tests.helpers.ingest import data_line, rig_rows, with_field, write_rig
from tests.helpers.synthetic_friction_runs import synthetic_run, true_law

from fivid.cli import main
from fivid.errors import DataQualityError
from fivid.io import read_rig_csv, write_run





# --- A1: degenerate time columns -------------------------------------------------------------------


def test_time_column_all_equal(tmp_path):
    rows = [with_field(r, 0, "0.000000000") for r in rig_rows()]
    path = write_rig(tmp_path / "flat.csv", rows=rows)
    with pytest.raises(DataQualityError) as info:
        read_rig_csv(path)
    err = info.value
    assert err.file == str(path) and err.column == "time"
    assert "all 50 time values are 0 s" in err.message
    assert "time column" in err.message


def test_time_written_with_too_few_decimals(tmp_path):
    rows = [with_field(r, 0, f"{i / 51200:.4f}") for i, r in enumerate(rig_rows(200))]
    path = write_rig(tmp_path / "coarse.csv", rows=rows)
    with pytest.raises(DataQualityError) as info:
        read_rig_csv(path)
    err = info.value
    assert err.column == "time" and err.line == data_line(1)
    # the resolution of the stamps (1e-4 s) against the step the record implies (19.5 us)
    assert "resolution 0.0001 s" in err.message
    assert "at least 7 decimals" in err.message


def test_ingest_cli_reports_flat_time(tmp_path, capsys):
    rows = [with_field(r, 0, "1.5") for r in rig_rows()]
    path = write_rig(tmp_path / "flat.csv", rows=rows)
    err = fails(capsys, ["ingest", str(path), "-o", str(tmp_path / "out")])
    assert str(path) in err and "time" in err
    assert not list((tmp_path / "out").glob("*.nc"))


# --- A2: the same run twice -------------------------------------------------------------------------


@pytest.fixture(scope="module")
def one_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("runs")
    ds = synthetic_run(true_law(), velocity=0.01, roughness=0.4e-6, normal_load=5.0, seed=0, run_id="D1",
                       duration=2.0)
    return write_run(ds, folder / "D1.nc")


def test_identify_same_run_twice(one_run, tmp_path, capsys):
    out = tmp_path / "law.nc"
    err = fails(capsys, ["identify", str(one_run), str(one_run), "-o", str(out)])
    assert "run_id 'D1'" in err and str(one_run) in err and "once" in err
    assert not out.exists()


def test_identify_two_files_of_one_run(one_run, tmp_path, capsys):
    copy = tmp_path / "copy.nc"
    copy.write_bytes(one_run.read_bytes())
    out = tmp_path / "law.nc"
    err = fails(capsys, ["identify", str(one_run), str(copy), "-o", str(out)])
    assert str(copy) in err and str(one_run) in err
    assert not out.exists()


# --- A3: Welch segment length ----------------------------------------------------------------------


@pytest.mark.parametrize("command", ["score", "psd", "identify"])
@pytest.mark.parametrize("value", ["0", "1", "-3"])
def test_nperseg_below_two(one_run, tmp_path, capsys, command, value):
    argv = {"score": ["score", str(one_run), str(one_run)],
            "psd": ["psd", str(one_run), "-o", str(tmp_path / "p.nc")],
            "identify": ["identify", str(one_run), "-o", str(tmp_path / "law.nc")]}[command]
    assert main(argv + ["--nperseg", value]) == 2  # refused by argparse: the option and the value named
    err = capsys.readouterr().err
    assert "--nperseg" in err and value in err and ">= 2" in err
    assert not list(tmp_path.iterdir())


def test_score_runs_nperseg_zero(one_run):
    from fivid.errors import ConfigError
    from fivid.io import read_run
    from fivid.score import score_runs

    ds = read_run(one_run)
    with pytest.raises(ConfigError, match="nperseg must be an integer >= 2, got 0"):
        score_runs(ds, ds, nperseg=0)


# --- A7: a run dataset given as a law file ---------------------------------------------------------


def test_law_file_that_is_a_run(one_run):
    from fivid.errors import SchemaError
    from fivid.friction import load_law

    with pytest.raises(SchemaError) as info:
        load_law(one_run)
    msg = str(info.value)
    assert msg.startswith(str(one_run))
    assert "None" not in msg
    assert "RunDataset" in msg and "run 'D1'" in msg and "fivid identify" in msg


def test_law_file_that_is_other_netcdf(tmp_path):
    import xarray as xr

    from fivid.errors import SchemaError
    from fivid.friction import load_law

    path = tmp_path / "other.nc"
    xr.Dataset({"x": ("i", np.arange(3.0))}, attrs={"title": "something else"}).to_netcdf(path)
    with pytest.raises(SchemaError, match="not a fivid friction-law file") as info:
        load_law(path)
    assert "law_file_version" in str(info.value) and "None" not in str(info.value)
