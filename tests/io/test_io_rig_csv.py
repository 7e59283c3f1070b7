"""read_rig_csv: SI values checked against an independent parse (Python's csv module + CGPM constants),
accepted variants (BOM, CRLF, blank lines, no final newline), provenance, and the round trip
CSV -> Dataset -> netCDF -> Dataset."""

import csv
import hashlib
import math
import tempfile
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from tests.helpers.ingest import GOOD_META, HEADER, STANDARD_GRAVITY, rig_rows, rig_text, with_field, write_rig

from fivid.errors import DataQualityError, SchemaError
from fivid.io import read_rig_csv, read_run, write_run
from fivid.schema import check_run

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT / "sample_data"

# Exact SI factors (definitions, not fivid): 1 g_n = 9.80665 m s-2, 1 mm = 1e-3 m, 1 µm = 1e-6 m.
# Each SI value is one float multiplication of the parsed number by such a factor; fivid's factor
# comes from pint and may differ by 1 ulp, so values agree within 2 roundings: rtol 2 * 2**-52.
RTOL = 2 * 2.0**-52


def _independent_table(path, delimiter=",", decimal="."):
    """Rows of floats after the header line, parsed with the csv module (not pyarrow)."""
    with open(path, encoding="utf-8-sig", newline="") as f:
        rows = list(csv.reader(f, delimiter=delimiter))
    start = next(i for i, r in enumerate(rows) if r and r[0].strip('"').lower().startswith("time"))
    body = [r for r in rows[start + 1:] if r]
    return np.array([[float(x.replace(decimal, ".")) for x in r] for r in body])


def test_sample_rig_csv_gives_si_values():
    """The README's file: g, mm/s, mm and '0.8 µm' become m s-2, m s-1, m and m."""
    path = SAMPLES / "R001_v10_ra08.csv"
    ds = read_rig_csv(path)
    raw = _independent_table(path)
    np.testing.assert_array_equal(ds["time"].values, raw[:, 0])
    np.testing.assert_allclose(ds["acceleration"].values, raw[:, 1] * STANDARD_GRAVITY, rtol=RTOL, atol=0)
    np.testing.assert_array_equal(ds["friction_force"].values, raw[:, 2])
    np.testing.assert_array_equal(ds["normal_force"].values, raw[:, 3])
    np.testing.assert_allclose(ds["position"].values, raw[:, 4] * 1e-3, rtol=RTOL, atol=0)
    np.testing.assert_allclose(ds["velocity"].values, raw[:, 5] * 1e-3, rtol=RTOL, atol=0)
    assert ds.attrs["sliding_velocity"] == pytest.approx(0.01, rel=RTOL)  # 10 mm/s
    assert ds.attrs["roughness_ra"] == pytest.approx(8e-7, rel=RTOL)  # 0.8 µm (micro sign)
    assert ds.attrs["normal_load"] == 5.0
    assert ds.attrs["sample_rate"] == 51200.0  # stated '51.2 kHz', consistent with the time column
    assert ds["acceleration"].attrs["units"] == "m s-2"
    assert ds["acceleration"].attrs["source_units"] == "g"
    assert check_run(ds) == []


def test_sample_daq_export_gives_si_values():
    """The labdaq export: decimal comma, mV at 100 mV/g, velocity and Ra from the file name."""
    path = SAMPLES / "R002_v20_ra16.csv"
    ds = read_rig_csv(path, "labdaq")
    raw = _independent_table(path, delimiter=";", decimal=",")
    np.testing.assert_array_equal(ds["time"].values, raw[:, 0])
    # 1 mV at 100 mV/g is 0.01 g: two roundings here, up to three in fivid (mV->V->g->m s-2 folded into one factor)
    np.testing.assert_allclose(ds["acceleration"].values, raw[:, 1] / 100 * STANDARD_GRAVITY, rtol=3 * 2.0**-52, atol=0)
    np.testing.assert_array_equal(ds["friction_force"].values, raw[:, 2])
    np.testing.assert_allclose(ds["position"].values, raw[:, 4] * 1e-3, rtol=RTOL, atol=0)
    assert ds.attrs["run_id"] == "R002"
    assert ds.attrs["sliding_velocity"] == pytest.approx(0.02, rel=RTOL)  # v20 -> 20 mm/s
    assert ds.attrs["roughness_ra"] == pytest.approx(1.6e-6, rel=RTOL)  # ra16 -> 16 x 0.1 µm
    assert ds.attrs["rig"] == "triboair"  # from the profile
    assert ds.attrs["start_time"] == "2026-11-20 14:03:11"  # kept from the preamble
    assert "velocity" not in ds


def test_units_are_converted(tmp_path):
    """ms, m/s^2, kN, mN, µm (micro sign and greek mu) and unit spellings in the header."""
    rows = ["0,0.5,0.0015,5000,1", "0.5,-0.25,0.0016,5001,2", "1,0,0.0014,4999,3"]
    header = "time [ms],acceleration [m/s^2],friction_force [kN],normal_force [mN],position [µm]"
    meta = dict(GOOD_META, roughness_ra="0.8 μm", sliding_velocity="0.6 m/min", normal_load="0.005 kN")
    ds = read_rig_csv(write_rig(tmp_path / "u.csv", rows=rows, header=header, meta=meta))
    np.testing.assert_allclose(ds["time"].values, [0, 5e-4, 1e-3], rtol=RTOL)
    np.testing.assert_allclose(ds["acceleration"].values, [0.5, -0.25, 0], rtol=RTOL)
    np.testing.assert_allclose(ds["friction_force"].values, [1.5, 1.6, 1.4], rtol=RTOL)
    np.testing.assert_allclose(ds["normal_force"].values, [5.0, 5.001, 4.999], rtol=RTOL)
    np.testing.assert_allclose(ds["position"].values, [1e-6, 2e-6, 3e-6], rtol=RTOL)
    assert ds.attrs["sliding_velocity"] == pytest.approx(0.01, rel=RTOL)
    assert ds.attrs["normal_load"] == pytest.approx(5.0, rel=RTOL)
    assert ds.attrs["roughness_ra"] == pytest.approx(8e-7, rel=RTOL)
    assert ds.attrs["sample_rate"] == pytest.approx(2000.0, rel=RTOL)


def test_bom_and_crlf_are_accepted(tmp_path):
    plain = read_rig_csv(write_rig(tmp_path / "lf.csv"))
    text = "\ufeff" + rig_text().replace("\n", "\r\n")
    path = tmp_path / "crlf.csv"
    path.write_bytes(text.encode("utf-8"))
    ds = read_rig_csv(path)
    for name in plain.variables:
        np.testing.assert_array_equal(ds[name].values, plain[name].values)
    assert ds.attrs["run_id"] == "R001"


def test_crlf_error_lines_are_file_lines(tmp_path):
    rows = rig_rows(20)
    rows[12] = with_field(rows[12], 2, "1.5x")
    path = tmp_path / "bad.csv"
    path.write_bytes(("\ufeff" + rig_text(rows)).replace("\n", "\r\n").encode())
    with pytest.raises(SchemaError) as info:
        read_rig_csv(path)
    assert info.value.line == 7 + 12 + 1  # 6 metadata lines, header line 7, row 12 on line 20
    assert info.value.column == "friction_force"


def test_blank_lines_and_missing_final_newline(tmp_path):
    rows = rig_rows(10)
    text = rig_text(rows[:5] + ["", ""] + rows[5:]) + "\n\n"
    ds = read_rig_csv(write_rig(tmp_path / "blank.csv", text=text))
    assert ds.sizes["time"] == 10
    ds = read_rig_csv(write_rig(tmp_path / "nonl.csv", text=rig_text(rows).rstrip("\n")))
    assert ds.sizes["time"] == 10


def test_line_numbers_count_blank_lines(tmp_path):
    rows = rig_rows(10)
    rows[8] = with_field(rows[8], 3, "nan")
    text = rig_text(rows[:3] + ["", ""] + rows[3:])
    with pytest.raises(DataQualityError) as info:
        read_rig_csv(write_rig(tmp_path / "b.csv", text=text))
    assert info.value.line == 7 + 2 + 8 + 1  # header line 7, two blank lines, data row 8
    assert info.value.column == "normal_force"


def test_provenance(tmp_path):
    path = write_rig(tmp_path / "p.csv", extra_meta=["# operator: A. Smith", "# a comment without key"])
    ds = read_rig_csv(path)
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    assert ds.attrs["source"] == f"p.csv sha256:{digest}"
    assert digest in ds.attrs["history"] and "ingest p.csv" in ds.attrs["history"]
    assert ds.attrs["operator"] == "A. Smith"
    assert ds.attrs["schema_version"] == 1 and "fivid_version" in ds.attrs


def test_unknown_columns_are_left_out(tmp_path):
    rows = [r + ",21.5" for r in rig_rows(5)]
    ds = read_rig_csv(write_rig(tmp_path / "x.csv", rows=rows, header=HEADER + ",temperature [degC]"))
    assert "temperature" not in ds
    assert list(ds.data_vars) == ["acceleration", "friction_force", "normal_force", "position"]


def test_stated_sample_rate_must_match(tmp_path):
    path = write_rig(tmp_path / "fs.csv", extra_meta=["# sample_rate: 50 kHz"])
    with pytest.raises(DataQualityError) as info:
        read_rig_csv(path)
    assert info.value.key == "sample_rate" and "51200" in str(info.value)


def test_profile_by_name_and_default_rig(tmp_path):
    meta = {k: v for k, v in GOOD_META.items() if k != "rig"}
    path = write_rig(tmp_path / "norig.csv", meta=meta)
    assert read_rig_csv(path, "triboair").attrs["rig"] == "triboair"


# ---- round trip: CSV -> Dataset -> netCDF -> Dataset ----------------------------------------------

finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False, allow_subnormal=False)
# forces in the plausible range (fivid.io.plausibility): |F| <= 1e5 N and a normal force that is not reversed
force = st.floats(min_value=-1e5, max_value=1e5, allow_nan=False, allow_infinity=False, allow_subnormal=False)
# within 10x of the file's normal_load (5 N): a larger gap is an implausibility error (fivid.io.plausibility)
normal = st.floats(min_value=0.5, max_value=49.9, allow_nan=False, allow_infinity=False, allow_subnormal=False)


@settings(max_examples=25, deadline=None)
@given(
    n=st.integers(min_value=2, max_value=40),
    sample_rate=st.sampled_from([1000.0, 25600.0, 51200.0, 1e5 / 3]),
    t0=st.floats(min_value=0.0, max_value=100.0),
    data=st.data(),
)
def test_round_trip_csv_dataset_netcdf(n, sample_rate, t0, data):
    """Values written with repr() are read back bit for bit, and netCDF gives the identical Dataset."""
    columns = [data.draw(st.lists(values, min_size=n, max_size=n)) for values in (finite, force, normal)]
    time = [t0 + i / sample_rate for i in range(n)]
    assume(all(b > a for a, b in zip(time, time[1:])))  # else steps vanish in float resolution
    rows = [",".join(repr(v) for v in row) for row in zip(time, *columns)]
    header = "time [s],acceleration [m s-2],friction_force [N],normal_force [N]"
    with tempfile.TemporaryDirectory() as tmp:
        path = write_rig(Path(tmp) / "rt.csv", rows=rows, header=header)
        ds = read_rig_csv(path)
        np.testing.assert_array_equal(ds["time"].values, time)
        for name, col in zip(["acceleration", "friction_force", "normal_force"], columns):
            np.testing.assert_array_equal(ds[name].values, col)
        out = write_run(ds, Path(tmp) / "rt.nc")
        back = read_run(out)
        xr.testing.assert_identical(back, ds)
    assert math.isclose(ds.attrs["sample_rate"], (n - 1) / (time[-1] - time[0]), rel_tol=1e-12)


def test_round_trip_with_conversions(tmp_path):
    ds = read_rig_csv(SAMPLES / "R001_v10_ra08.csv")
    back = read_run(write_run(ds, tmp_path / "R001.nc"))
    xr.testing.assert_identical(back, ds)


def test_trailing_delimiter_only_rows_are_not_samples(tmp_path):
    """Spreadsheets save trailing ',,,,' rows; they are dropped, a trailing delimiter on real rows is kept."""
    plain = read_rig_csv(write_rig(tmp_path / "plain.csv"))
    text = rig_text() + ",,,,\n , ,,,\r\n,,,,"
    ds = read_rig_csv(write_rig(tmp_path / "excel.csv", text=text))
    np.testing.assert_array_equal(ds["acceleration"].values, plain["acceleration"].values)
    rows = [r + "," for r in rig_rows()]  # every row ends with a delimiter: a 6th, empty field
    header = HEADER + ","
    with pytest.raises(SchemaError, match="column header '' must be written"):
        read_rig_csv(write_rig(tmp_path / "t.csv", rows=rows, header=header))
    only_junk = rig_text(rows=[]) + ",,,,\n,,,,\n"
    with pytest.raises(SchemaError, match="no data rows"):
        read_rig_csv(write_rig(tmp_path / "j.csv", text=only_junk))


def test_multi_block_file_agrees_with_pandas_bit_for_bit(tmp_path):
    """A 10 MB file (three 4 MiB pyarrow blocks, parsed in parallel) against pandas' C parser:
    every value identical and in order (SI units in the header: factor 1, no rounding)."""
    import pandas as pd

    rng = np.random.default_rng(7)
    n = 150_000
    values = rng.standard_normal((n, 4)) * np.array([1.0, 1e3, 1e-3, 1e6])
    time = np.arange(n) / 51200.0
    header = "time [s],acceleration [m s-2],friction_force [N],normal_force [N],position [m]"
    import io

    import pyarrow as pa
    import pyarrow.csv as pcsv

    columns = {f"c{k}": col for k, col in enumerate(np.column_stack([time, values]).T)}
    sink = io.BytesIO()  # pyarrow writes shortest round-trip decimals, fast
    pcsv.write_csv(pa.table(columns), sink, pcsv.WriteOptions(include_header=False))
    path = write_rig(tmp_path / "big.csv", text=rig_text(rows=[], header=header) + sink.getvalue().decode())
    assert path.stat().st_size > 2 * (1 << 22)
    ds = read_rig_csv(path, allow_implausible=True)  # a normal force of 1 mN against 5 N: parsing is tested here
    ref = pd.read_csv(path, skiprows=6).to_numpy()  # pandas 3 parses floats correctly rounded by default
    np.testing.assert_array_equal(ds["time"].values, ref[:, 0])
    for k, name in enumerate(["acceleration", "friction_force", "normal_force", "position"], start=1):
        np.testing.assert_array_equal(ds[name].values, ref[:, k])
    np.testing.assert_array_equal(ds["acceleration"].values, values[:, 0])  # shortest repr round-trips


def test_same_record_in_both_formats_gives_the_same_dataset(tmp_path):
    """R001 rewritten by hand as a labdaq export (g -> mV at 100 mV/g by shifting the decimal point,
    ';' and ',' decimals, CRLF, metadata split between preamble and file name) reads back the same.

    The two acceleration paths are x_g * 9.80665 and x_mV * 0.0980665 with x_mV = 100 x_g exactly in
    decimal: each side has <= 2 roundings of relative size 2**-53, so they agree within 4 * 2**-53.
    """
    from decimal import Decimal

    src = SAMPLES / "R001_v10_ra08.csv"
    rows = [line.split(",") for line in src.read_text(encoding="utf-8").splitlines() if line[:1].isdigit()]
    daq = ["LabDAQ Export;v3.2", "Run;R001", "Normal load;5 N", "Sample rate;51200 Hz",
           '"Time (s)";"Accel Z (mV)";"Fx (N)";"Fz (N)";"Pos (mm)"']
    for t, a, ft, fn, x, _ in rows:
        mv = format(Decimal(a).scaleb(2), "f")
        daq.append(";".join([t, mv, ft, fn, x]).replace(".", ","))
    path = tmp_path / "R001_v10_ra08.csv"
    path.write_bytes(("\r\n".join(daq) + "\r\n").encode())
    a, b = read_rig_csv(src), read_rig_csv(path, "labdaq")
    np.testing.assert_allclose(b["acceleration"].values, a["acceleration"].values, rtol=4 * 2.0**-53, atol=0)
    for name in ("time", "friction_force", "normal_force", "position"):
        np.testing.assert_array_equal(b[name].values, a[name].values)
    for key in ("run_id", "rig"):  # text: equal (pytest.approx takes no strings since pytest 9.2)
        assert b.attrs[key] == a.attrs[key], key
    for key in ("sliding_velocity", "normal_load", "roughness_ra", "sample_rate"):
        assert b.attrs[key] == pytest.approx(a.attrs[key], rel=2.0**-52), key


def test_two_ingests_of_one_csv_are_byte_identical(tmp_path, root):
    """Issue 18: the run dataset holds no wall-clock time (HDF5 writes none), so its sha256 — what the
    pipeline's cache hashes — depends on the CSV only; the time is in the cache manifest and the log."""
    import time

    from fivid.cli import main

    src = root / "sample_data" / "R001_v10_ra08.csv"
    assert main(["ingest", str(src), "-o", str(tmp_path / "a")]) == 0
    time.sleep(1.1)  # history stamps had a resolution of 1 s
    assert main(["ingest", str(src), "-o", str(tmp_path / "b")]) == 0
    a, b = (tmp_path / d / "R001.nc" for d in "ab")
    assert a.read_bytes() == b.read_bytes()
