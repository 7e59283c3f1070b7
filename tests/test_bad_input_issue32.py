"""Bad inputs of issue 32 ("Bad inputs that still get through"): each ends in one line naming the file, line,
key or value and what is allowed, exit 2, no traceback, nothing half-written."""

import pytest
from cli_helpers import fails
from ingest_helpers import GOOD_META, write_rig

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
