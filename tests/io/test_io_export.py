"""fivid export: UFF58 and CSV with units of runs, PSDs and FRFs, read back by pyuff and fivid ingest."""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from fivid.cli import main
from fivid.io import read_rig_csv
from fivid.io.export import export_csv, export_uff58

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def run():
    return read_rig_csv(ROOT / "sample_data" / "R001_v10_ra08.csv")


def test_run_csv_export_ingests_back_to_the_same_run(tmp_path, run):
    path = tmp_path / "R001.csv"
    export_csv(run, path)
    back = read_rig_csv(path)  # the fivid-rig-csv format: %.17g keeps every bit
    for name in [*run.data_vars, "time"]:
        np.testing.assert_array_equal(back[name].values, run[name].values)
    for key in ("run_id", "sliding_velocity", "normal_load", "roughness_ra", "sample_rate", "rig"):
        assert back.attrs[key] == run.attrs[key]


def test_run_uff58_export_reads_back_with_pyuff(tmp_path, run):
    pyuff = pytest.importorskip("pyuff")
    path = tmp_path / "R001.uff"
    assert export_uff58(run, path) == len(run.data_vars)
    sets = pyuff.UFF(str(path)).read_sets()
    by_name = {s["id1"].strip(): s for s in sets}
    assert set(by_name) == set(run.data_vars)
    for name, s in by_name.items():
        assert s["func_type"] == 1 and s["ordinate_axis_units_lab"].strip() == run[name].attrs["units"]
        np.testing.assert_allclose(s["data"], run[name].values, rtol=1e-12, atol=1e-300)
        # the E13.5 increment: 6 significant digits over the record
        np.testing.assert_allclose(s["x"], run["time"].values, rtol=0, atol=run.sizes["time"] * 5e-6 / 51200)


def test_frf_uff58_is_complex_function_type_4_and_csv_has_real_imag(tmp_path):
    pyuff = pytest.importorskip("pyuff")
    f = np.linspace(10.0, 1000.0, 100)
    h = 1.0 / (1e6 - (2 * np.pi * f) ** 2 + 2j * 0.02 * 1e3 * 2 * np.pi * f)  # a 1-dof receptance [m N-1]
    ds = xr.Dataset({"receptance": ("frequency", h, {"units": "m N-1"})},
                    coords={"frequency": ("frequency", f, {"units": "Hz"})})
    export_uff58(ds, tmp_path / "frf.uff")
    s = pyuff.UFF(str(tmp_path / "frf.uff")).read_sets()
    s = s[0] if isinstance(s, list) else s
    assert s["func_type"] == 4
    np.testing.assert_allclose(s["data"], h, rtol=1e-11)
    export_csv(ds, tmp_path / "frf.csv")
    lines = (tmp_path / "frf.csv").read_text().splitlines()
    assert lines[0] == "frequency [Hz],receptance.real [m N-1],receptance.imag [m N-1]"
    table = np.loadtxt(tmp_path / "frf.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(table[:, 1] + 1j * table[:, 2], h)


def test_cli_exports_a_psd(tmp_path, run):
    nc = tmp_path / "R001.nc"
    run.to_netcdf(nc)
    psd = tmp_path / "psd.nc"
    assert main(["psd", str(nc), "--nperseg", "512", "-o", str(psd)]) == 0
    assert main(["export", str(psd), "--format", "csv", "-o", str(tmp_path / "psd.csv")]) == 0
    header = next(line for line in (tmp_path / "psd.csv").read_text().splitlines() if not line.startswith("#"))
    assert header.startswith("frequency [Hz],psd_acceleration [m2 s-4 Hz-1]")
    assert main(["export", str(psd), "--format", "csv", "-o", str(tmp_path / "psd.csv")]) == 2  # exists
