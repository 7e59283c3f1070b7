"""Every bad input of issue 2 gets its own error, naming the file's real line and the column or key."""

import re

import numpy as np
import pytest
from tests.helpers.ingest import GOOD_META, HEADER, N_META_LINES, data_line, rig_rows, rig_text, with_field, write_rig

from fivid.errors import DataQualityError, FividError, SchemaError, UnitError
from fivid.io import read_rig_csv

HEADER_LINE = N_META_LINES + 1


def _error(tmp_path, text=None, name="bad.csv", data: bytes | None = None, profile=None, **kw) -> FividError:
    path = tmp_path / name
    if data is not None:
        path.write_bytes(data)
    else:
        write_rig(path, text, **kw)
    with pytest.raises(FividError) as info:
        read_rig_csv(path, profile)
    err = info.value
    assert err.file == str(path)
    assert str(err).startswith(str(path))
    assert "\n" not in str(err)  # one line on stderr
    return err


def test_empty_file(tmp_path):
    err = _error(tmp_path, data=b"")
    assert isinstance(err, SchemaError) and "empty" in err.message and err.line == 1


def test_only_blank_lines(tmp_path):
    err = _error(tmp_path, data=b"\n\r\n\n")
    assert "blank" in err.message


def test_header_only(tmp_path):
    err = _error(tmp_path, rows=[])
    assert isinstance(err, SchemaError) and "no data rows" in err.message and err.line == HEADER_LINE


def test_single_row(tmp_path):
    err = _error(tmp_path, rows=rig_rows(1))
    assert "only one data row" in err.message


def test_metadata_only(tmp_path):
    err = _error(tmp_path, text="# fivid-rig-csv: 1\n# run_id: R1\n")
    assert "no column header" in err.message


def test_missing_required_column(tmp_path):
    rows = [r.rsplit(",", 2)[0] + "," + r.rsplit(",", 1)[1] for r in rig_rows()]
    err = _error(tmp_path, rows=rows, header="time [s],acceleration [g],friction_force [N],position [mm]")
    assert isinstance(err, SchemaError) and err.column == "normal_force" and err.line == HEADER_LINE


def test_missing_time_column(tmp_path):
    rows = [r.split(",", 1)[1] for r in rig_rows()]
    err = _error(tmp_path, rows=rows, header=HEADER.split(",", 1)[1])
    assert err.column == "time"


@pytest.mark.parametrize("key", ["run_id", "rig", "sliding_velocity", "normal_load", "roughness_ra"])
def test_missing_metadata(tmp_path, key):
    meta = {k: v for k, v in GOOD_META.items() if k != key}
    err = _error(tmp_path, meta=meta)
    assert isinstance(err, SchemaError) and err.key == key and "missing metadata" in err.message
    assert f"# {key}:" in err.message  # says how to fix it


@pytest.mark.parametrize("bad", ["1.5x", "abc", "1,5", "0x10", "1.2.3", "--1"])
def test_unparseable_number(tmp_path, bad):
    rows = rig_rows(30)
    rows[17] = with_field(rows[17], 2, bad)
    err = _error(tmp_path, rows=rows)
    if bad == "1,5":  # an extra comma makes an extra field
        assert "6 field(s) but the header has 5" in err.message
    else:
        assert isinstance(err, SchemaError) and err.column == "friction_force" and repr(bad) in err.message
    assert err.line == data_line(17)


def test_unparseable_number_far_into_a_multi_block_file(tmp_path):
    """pyarrow parses blocks in parallel without row numbers: the line is still the file's."""
    rows = rig_rows(150_000)
    rows[123_456] = with_field(rows[123_456], 1, "0.0o1")
    err = _error(tmp_path, rows=rows)
    assert err.line == data_line(123_456) and err.column == "acceleration" and "'0.0o1'" in err.message


@pytest.mark.parametrize("bad", ["nan", "NaN", "inf", "-inf", "1e400"])
def test_non_finite_values(tmp_path, bad):
    rows = rig_rows(30)
    rows[9] = with_field(rows[9], 3, bad)
    rows[20] = with_field(rows[20], 3, bad)
    err = _error(tmp_path, rows=rows)
    assert isinstance(err, DataQualityError) and err.column == "normal_force" and err.line == data_line(9)
    assert "2 non-finite" in err.message


def test_empty_value(tmp_path):
    rows = rig_rows(30)
    rows[4] = with_field(rows[4], 1, "")
    err = _error(tmp_path, rows=rows)
    assert isinstance(err, DataQualityError) and err.column == "acceleration" and err.line == data_line(4)
    assert "empty value" in err.message


def test_time_duplicated(tmp_path):
    rows = rig_rows(30)
    rows[11] = with_field(rows[11], 0, rows[10].split(",")[0])
    err = _error(tmp_path, rows=rows)
    assert isinstance(err, DataQualityError) and err.column == "time" and err.line == data_line(11)
    assert "duplicated" in err.message and f"line {data_line(10)}" in err.message


def test_time_going_backwards(tmp_path):
    rows = rig_rows(30)
    rows[20], rows[21] = rows[21], rows[20]
    err = _error(tmp_path, rows=rows)
    assert err.line == data_line(21) and "goes backwards" in err.message


def test_time_in_ms_written_as_seconds_is_not_uniform_when_a_sample_is_dropped(tmp_path):
    rows = rig_rows(200)
    del rows[120]  # a dropped sample: one step twice as long
    err = _error(tmp_path, rows=rows)
    assert isinstance(err, DataQualityError) and err.column == "time" and err.line == data_line(120)
    t = np.array([float(r.split(",")[0]) for r in rows])
    dt = 1 / 51200.0  # the nominal (median) step; times written to 1e-9 s, so steps are off by <= 1e-9 s
    expected = 100 * abs((t[120] - t[119]) - dt) / dt  # 100 %: the deviation is reported
    reported = float(re.search(r"([\d.]+) % off", err.message).group(1))
    # printed with 3 significant digits (rel 5e-3); the steps' rounding adds <= 2e-9 / 1.95e-5 = 1e-4
    assert reported == pytest.approx(expected, rel=5e-3)
    assert "1 step(s) exceed" in err.message and "tolerance 1 %" in err.message


def test_rounding_jitter_within_tolerance_is_accepted_and_beyond_it_rejected(tmp_path):
    """Times of a 51.2 kHz DAQ written with 7 decimals: steps of 1.95e-5 or 1.96e-5 s (true 1.953125e-5).

    The median step is 1.95e-5 s, so the worst step deviates by 1e-7 / 1.95e-5 = 0.513 %: inside the
    default 1 % tolerance, outside a 0.4 % one.
    """
    rows = [f"{i / 51200.0:.7f},0.0,1.5,5.0,0.0" for i in range(1000)]
    ds = read_rig_csv(write_rig(tmp_path / "ok.csv", rows=rows))
    assert ds.sizes["time"] == 1000
    strict = tmp_path / "strict.yaml"
    strict.write_text("fivid-rig-profile: 1\nformat: fivid-rig-csv\nchecks: {sampling_tolerance: 0.004}\n")
    err = _error(tmp_path, rows=rows, profile=strict)
    assert "not uniform" in err.message and "tolerance 0.4 %" in err.message
    reported = float(re.search(r"([\d.]+) % off", err.message).group(1))
    assert reported == pytest.approx(100 * 1e-7 / 1.95e-5, rel=5e-3)  # 3 significant digits


@pytest.mark.parametrize("header_unit, column", [("furlongs", "acceleration"), ("N/", "acceleration")])
def test_unknown_unit(tmp_path, header_unit, column):
    err = _error(tmp_path, header=HEADER.replace("[g]", f"[{header_unit}]"))
    assert isinstance(err, UnitError) and err.column == column and err.line == HEADER_LINE


@pytest.mark.parametrize("header_unit", ["mm", "s", "kg"])
def test_incompatible_unit(tmp_path, header_unit):
    err = _error(tmp_path, header=HEADER.replace("friction_force [N]", f"friction_force [{header_unit}]"))
    assert isinstance(err, UnitError) and err.column == "friction_force" and "not compatible" in err.message


def test_empty_unit_and_missing_brackets(tmp_path):
    assert "empty unit" in _error(tmp_path, header=HEADER.replace("[N]", "[]", 1)).message
    err = _error(tmp_path, header=HEADER.replace("time [s]", "time"))
    assert "'name [unit]'" in err.message and err.column == "time"


@pytest.mark.parametrize("key, value, what", [
    ("sliding_velocity", "10 N", "not compatible"),
    ("normal_load", "5", "has no unit"),
    ("roughness_ra", "0.8 microfoo", "cannot parse"),
])
def test_bad_metadata_units(tmp_path, key, value, what):
    err = _error(tmp_path, meta=dict(GOOD_META, **{key: value}))
    assert isinstance(err, UnitError) and err.key == key and what in err.message
    assert err.line == 2 + list(GOOD_META).index(key)


def test_truncated_last_line(tmp_path):
    text = rig_text(rig_rows(30)).rstrip("\n")
    text = text[: text.rfind(",") - 2]  # cut inside the last line, no newline
    err = _error(tmp_path, text=text)
    assert isinstance(err, SchemaError) and err.line == data_line(29)
    assert "truncated" in err.message and "header has 5" in err.message


def test_row_with_extra_field(tmp_path):
    rows = rig_rows(30)
    rows[3] += ",1.0"
    err = _error(tmp_path, rows=rows)
    assert err.line == data_line(3) and "6 field(s)" in err.message and "truncated" not in err.message


@pytest.mark.parametrize("data, what", [
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "not a CSV text file"),
    (b"PK\x03\x04\x14\x00\x06\x00\x08\x00\x00\x00!\x00", "not a CSV text file"),  # .xlsx (zip)
    (b"CDF\x01\x00\x00\x00\x00", "not a CSV text file"),  # netCDF-3
    (b"Dear colleague,\nplease find the data attached.\n", "not a fivid-rig-csv file"),
    ("# fivid-rig-csv: 1\n# run_id: R\xe9\n".encode("latin-1"), "not utf-8 text"),
])
def test_not_a_csv(tmp_path, data, what):
    err = _error(tmp_path, data=data)
    assert isinstance(err, SchemaError) and what in err.message


def test_wrong_format_version(tmp_path):
    err = _error(tmp_path, magic="# fivid-rig-csv: 2")
    assert "unsupported fivid-rig-csv version '2'" in err.message and err.line == 1


def test_duplicate_column_and_metadata(tmp_path):
    err = _error(tmp_path, header=HEADER.replace("position [mm]", "acceleration [g]"))
    assert "appears twice" in err.message and err.column == "acceleration"
    err = _error(tmp_path, extra_meta=["# run_id: R002"])
    assert "given twice" in err.message and err.key == "run_id" and err.line == N_META_LINES + 1


@pytest.mark.parametrize("run_id", ["R 1", "../R1", ".hidden", "R1/2"])
def test_run_id_must_name_a_file(tmp_path, run_id):
    err = _error(tmp_path, meta=dict(GOOD_META, run_id=run_id))
    assert err.key == "run_id" and "cannot name a file" in err.message


def test_reserved_metadata(tmp_path):
    err = _error(tmp_path, extra_meta=["# history: made up"])
    assert err.key == "history" and "written by fivid" in err.message


def test_text_between_metadata_and_header(tmp_path):
    err = _error(tmp_path, extra_meta=["Operator: A. Smith"])
    assert err.line == N_META_LINES + 1 and "'name [unit]'" in err.message  # taken as the header


def test_missing_file(tmp_path):
    with pytest.raises(FividError, match="no such file"):
        read_rig_csv(tmp_path / "nope.csv")


def test_read_run_of_a_folder_says_folder(tmp_path):
    from fivid.io import read_run

    with pytest.raises(FividError, match="is a folder"):
        read_run(tmp_path)
    with pytest.raises(FividError, match="no such file"):
        read_run(tmp_path / "nope.nc")


def test_misspelt_optional_column_is_not_dropped_silently(tmp_path, caplog):
    """'positon' is no variable: the run is read without it, but a warning names the likely one."""
    header = HEADER.replace("position [mm]", "positon [mm]")
    path = write_rig(tmp_path / "typo.csv", header=header)
    with caplog.at_level("WARNING", logger="fivid"):
        ds = read_rig_csv(path)
    assert "position" not in ds
    warned = [r.getMessage() for r in caplog.records if r.levelname == "WARNING"]
    assert any(f"{path}:{HEADER_LINE}: column 'positon'" in m and "did you mean 'position'?" in m for m in warned)
