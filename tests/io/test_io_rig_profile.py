"""Rig profiles: shipped profiles, sensor sensitivities, DAQ-export features, validation with key paths."""

from pathlib import Path

import numpy as np
import pytest
import yaml
from tests.helpers.ingest import STANDARD_GRAVITY

from fivid.errors import ConfigError, FividError, SchemaError, UnitError
from fivid.io import RigProfile, load_rig_profile, read_rig_csv
from fivid.io.rig_profile import rig_profile_from_mapping
from fivid.units import sensitivity_factor

ROOT = Path(__file__).resolve().parents[2]
RTOL = 4 * 2.0**-52  # a few float roundings of exactly defined factors


def test_shipped_profiles_load():
    tribo = load_rig_profile("triboair")
    assert tribo.format == "fivid-rig-csv" and tribo.values == {"rig": "triboair"}
    # triboair is the built-in default format plus the rig name
    default = RigProfile()
    for name in ("delimiter", "decimal", "encoding", "comment", "columns", "sampling_tolerance"):
        assert getattr(tribo, name) == getattr(default, name), name
    daq = load_rig_profile("labdaq")
    assert daq.delimiter == ";" and daq.decimal == ","
    assert daq.column("acceleration").factor == pytest.approx(STANDARD_GRAVITY / 100, rel=RTOL)  # 100 mV/g
    assert daq.column("position").factor == pytest.approx(1e-3, rel=RTOL)
    assert load_rig_profile(ROOT / "configs" / "rigs" / "labdaq.yaml") == daq
    assert load_rig_profile(str(ROOT / "configs" / "rigs" / "labdaq.yaml")) == daq


@pytest.mark.parametrize("column_units, sensitivity, target, expected", [
    ("mV", "100 mV/g", "m s-2", STANDARD_GRAVITY / 100),  # 1 mV = 0.01 g
    ("V", "100 mV/g", "m s-2", 10 * STANDARD_GRAVITY),  # 1 V = 10 g
    ("mV", "10.2 mV/(m/s^2)", "m s-2", 1 / 10.2),
    ("mV", "10,2 mV/(m s-2)", "m s-2", 1 / 10.2),  # decimal comma
    ("pC", "4 pC/N", "N", 0.25),  # charge-output force sensor
    ("V", "2 mV/N", "N", 500.0),
    ("mV", "0.5 mV/um", "m", 2e-6),
])
def test_sensitivity_factor(column_units, sensitivity, target, expected):
    assert sensitivity_factor(column_units, sensitivity, target) == pytest.approx(expected, rel=RTOL)


@pytest.mark.parametrize("column_units, sensitivity, what", [
    ("mV", "100 mV", "must be"),
    ("mV", "0 mV/g", "non-zero"),
    ("N", "100 mV/g", "does not fit"),
    ("mV", "100 mV/N", "does not measure"),
    ("mV", "abc", "must be"),
])
def test_bad_sensitivity(column_units, sensitivity, what):
    with pytest.raises(UnitError, match=what):
        sensitivity_factor(column_units, sensitivity, "m s-2")


GOOD = {
    "fivid-rig-profile": 1,
    "name": "test",
    "format": "table",
    "csv": {"delimiter": ";", "decimal": ","},
    "metadata": {"values": {"run_id": "T1", "rig": "bench", "sliding_velocity": "5 mm/s", "normal_load": "10 N",
                            "roughness_ra": "1.6 um"}},
    "columns": {
        "time": {"name": "t [ms]", "units": "ms"},
        "acceleration": {"name": "acc", "units": "V", "sensitivity": "100 mV/g"},
        "friction_force": {"name": "Ft", "units": "kN"},
        "normal_force": {"name": "Fn", "units": "N", "scale": -1},
    },
}


def _with(**changes):
    raw = yaml.safe_load(yaml.safe_dump(GOOD))
    for path, value in changes.items():
        node = raw
        *parents, last = path.split("__")
        for p in parents:
            node = node.setdefault(p, {})
        if value is _DELETE:
            del node[last]
        else:
            node[last] = value
    return raw


_DELETE = object()


@pytest.mark.parametrize("changes, key, what", [
    ({"colums": {}}, "colums", "unknown key; allowed: checks, columns, csv, description, fivid-rig-profile, format, metadata, name; did you mean 'columns'?"),
    ({"fivid-rig-profile": 2}, "fivid-rig-profile", "expected 1 (the profile format version), found 2"),
    ({"format": "excel"}, "format", "expected one of 'fivid-rig-csv' or 'table', found str 'excel'"),
    ({"csv__delimiter": ","}, "csv.decimal", "cannot also be the delimiter"),
    ({"csv__decimal": "·"}, "csv.decimal", "expected one of '.' or ','"),
    ({"csv__delimiter": ";;"}, "csv.delimiter", "one character"),
    ({"csv__encoding": "klingon"}, "csv.encoding", "unknown text encoding"),
    ({"csv__encoding": "utf-16"}, "csv.encoding", "not ASCII-compatible"),
    ({"csv__header_line": 0}, "csv.header_line", ">= 1"),
    ({"columns__friction_force__units": "mm"}, "columns.friction_force.units", "not compatible"),
    ({"columns__friction_force__units": "newtonz"}, "columns.friction_force.units", "cannot parse"),
    ({"columns__acceleration__sensitivity": "100 mV/N"}, "columns.acceleration.sensitivity", "does not measure"),
    ({"columns__normal_force__scale": 0}, "columns.normal_force.scale", "non-zero"),
    ({"columns__normal_force__name": None}, "columns.normal_force.name", "missing"),
    ({"columns__normal_force": _DELETE}, "columns.normal_force", "not mapped"),
    ({"columns__strain": {"name": "e", "units": "1"}}, "columns.strain", "not a canonical variable"),
    ({"columns__friction_force__unit": "N"}, "columns.friction_force.unit", "did you mean 'units'?"),
    ({"metadata__values__sliding_velocity": "5 N"}, "metadata.values.sliding_velocity", "not compatible"),
    ({"metadata__values__history": "x"}, "metadata.values.history", "written by fivid"),
    ({"metadata__file_name": {"pattern": "(?P<run_id>R\\d+"}}, "metadata.file_name.pattern", "not a valid regular"),
    ({"metadata__file_name": {"pattern": "x", "units": {"rig": "m"}}}, "metadata.file_name.units.rig",
     "not a quantity attribute"),
    ({"metadata__in_file": {"pattern": "(?P<key>\\w+)=(.*)"}}, "metadata.in_file.pattern", "(?P<value>...)"),
    ({"checks__sampling_tolerance": 5}, "checks.sampling_tolerance", "expected a value < 1, found int 5"),
])
def test_profile_errors_name_the_key_path(changes, key, what):
    with pytest.raises(ConfigError) as info:
        rig_profile_from_mapping(_with(**changes), path="p.yaml")
    err = info.value
    assert err.key == key and what in err.message and err.file == "p.yaml"
    assert str(err).startswith(f"p.yaml: key '{key}'")


def test_all_problems_are_listed_at_once():
    raw = _with(csv__decimal="x", columns__friction_force__units="mm", checks__sampling_tolerance=-1)
    with pytest.raises(ConfigError) as info:
        rig_profile_from_mapping(raw)
    text = str(info.value)  # one error: the first problem leads, the others follow with their key paths
    assert "(and 2 more: " in text
    for key in ("csv.decimal", "columns.friction_force.units", "checks.sampling_tolerance"):
        assert f"key '{key}'" in text


def test_good_profile_and_rig_csv_rules():
    profile = rig_profile_from_mapping(GOOD)
    assert profile.column("normal_force").factor == -1.0
    assert profile.column("time").factor == pytest.approx(1e-3, rel=RTOL)
    with pytest.raises(ConfigError, match="header"):
        rig_profile_from_mapping({"fivid-rig-profile": 1, "format": "fivid-rig-csv", "columns": GOOD["columns"]})


def test_profile_not_found_lists_known(tmp_path):
    with pytest.raises(ConfigError) as info:
        load_rig_profile("no-such-rig")
    assert "labdaq" in info.value.message and "triboair" in info.value.message
    with pytest.raises(ConfigError, match="does not exist"):
        load_rig_profile(tmp_path / "missing.yaml")
    with pytest.raises(ConfigError, match="is a folder"):  # e.g. --rig configs/rigs
        load_rig_profile(tmp_path)


def test_invalid_yaml_names_the_line(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text("fivid-rig-profile: 1\ncsv:\n  delimiter: [;\n")
    with pytest.raises(ConfigError) as info:
        load_rig_profile(path)
    assert info.value.file == str(path) and info.value.line is not None and "not valid YAML" in info.value.message
    path.write_text("")
    with pytest.raises(ConfigError, match="empty"):
        load_rig_profile(path)


# ---- table exports -----------------------------------------------------------------------------

def _profile(tmp_path, **changes) -> Path:
    path = tmp_path / "p.yaml"
    path.write_text(yaml.safe_dump(_with(**changes)), encoding="utf-8")
    return path


def _daq(tmp_path, lines, name="run.csv", encoding="utf-8", newline="\n") -> Path:
    path = tmp_path / name
    path.write_bytes(newline.join(lines).encode(encoding) + newline.encode())
    return path


ROWS = ["0;1,0;0,0015;-5,0", "0,5;-2,0;0,0016;-5,1", "1;0,5;0,0014;-4,9"]


def test_table_export_is_converted(tmp_path):
    path = _daq(tmp_path, ["Export", '"t [ms]";"acc";"Ft";"Fn";"Temp"'] + [r + ";20" for r in ROWS])
    ds = read_rig_csv(path, _profile(tmp_path))
    np.testing.assert_allclose(ds["time"].values, [0, 5e-4, 1e-3], rtol=RTOL)
    np.testing.assert_allclose(ds["acceleration"].values, np.array([1.0, -2.0, 0.5]) * 10 * STANDARD_GRAVITY, rtol=RTOL)
    np.testing.assert_allclose(ds["friction_force"].values, [1.5, 1.6, 1.4], rtol=RTOL)
    np.testing.assert_allclose(ds["normal_force"].values, [5.0, 5.1, 4.9], rtol=RTOL)  # scale -1
    assert ds.attrs["roughness_ra"] == pytest.approx(1.6e-6, rel=RTOL)
    assert ds["acceleration"].attrs["sensitivity"] == "100 mV/g"
    assert ds["acceleration"].attrs["source_column"] == "acc"


def test_fixed_header_line_and_latin1_preamble(tmp_path):
    profile = _profile(tmp_path, csv__header_line=3, csv__encoding="latin-1",
                       metadata__in_file={"keys": {"Rauheit Ra": "roughness_ra"}})
    lines = ["Messung 7", "Rauheit Ra: 0,4 µm", "t [ms];acc;Ft;Fn"] + ROWS
    ds = read_rig_csv(_daq(tmp_path, lines, encoding="latin-1"), profile)
    assert ds.attrs["roughness_ra"] == pytest.approx(4e-7, rel=RTOL)  # file beats the profile's 1.6 um
    # the same file read as UTF-8 names the line of the Latin-1 byte
    with pytest.raises(SchemaError) as info:
        read_rig_csv(tmp_path / "run.csv", _profile(tmp_path, csv__header_line=3))
    assert info.value.line == 2 and "latin-1" in info.value.message


def test_metadata_from_file_name(tmp_path):
    pattern = r"^(?P<run_id>[A-Z]\d+)_v(?P<sliding_velocity>[\d,]+)_ra(?P<roughness_ra>\d+)"
    profile = _profile(tmp_path, metadata__file_name={
        "pattern": pattern, "units": {"sliding_velocity": "mm/s", "roughness_ra": "0.1 um"}})
    ds = read_rig_csv(_daq(tmp_path, ["t [ms];acc;Ft;Fn"] + ROWS, name="B7_v2,5_ra12.csv"), profile)
    assert ds.attrs["run_id"] == "B7"
    assert ds.attrs["sliding_velocity"] == pytest.approx(2.5e-3, rel=RTOL)
    assert ds.attrs["roughness_ra"] == pytest.approx(1.2e-6, rel=RTOL)


def test_file_and_file_name_must_agree(tmp_path):
    profile = _profile(tmp_path, metadata__file_name={"pattern": r"_v(?P<sliding_velocity>\d+)",
                                                       "units": {"sliding_velocity": "mm/s"}},
                       metadata__in_file={"keys": {"speed": "sliding_velocity"}})
    path = _daq(tmp_path, ["Speed; 20 mm/s", "t [ms];acc;Ft;Fn"] + ROWS, name="R1_v10.csv")
    with pytest.raises(SchemaError) as info:
        read_rig_csv(path, profile)
    assert info.value.key == "sliding_velocity" and "line 1" in info.value.message and "its name says" in info.value.message


def test_missing_metadata_mentions_unmatched_file_name(tmp_path):
    profile = _profile(tmp_path, metadata__values__run_id=_DELETE,
                       metadata__file_name={"pattern": r"^(?P<run_id>R\d+)_"})
    with pytest.raises(SchemaError) as info:
        read_rig_csv(_daq(tmp_path, ["t [ms];acc;Ft;Fn"] + ROWS, name="export.csv"), profile)
    assert info.value.key == "run_id" and "does not match" in info.value.message


def test_required_column_missing_in_export(tmp_path):
    path = _daq(tmp_path, ["t [ms];acc;Ft"] + [r.rsplit(";", 1)[0] for r in ROWS])
    with pytest.raises(SchemaError) as info:
        read_rig_csv(path, _profile(tmp_path))
    assert info.value.column == "Fn" and info.value.line == 1 and "'acc'" in info.value.message


def test_header_not_found(tmp_path):
    path = _daq(tmp_path, ["time,acc,Ft,Fn", "0,1,2,3"])
    with pytest.raises(SchemaError, match="no column header with 't \\[ms\\]'"):
        read_rig_csv(path, _profile(tmp_path))


def test_decimal_point_file_with_decimal_comma_profile(tmp_path):
    path = _daq(tmp_path, ["t [ms];acc;Ft;Fn", "0;1.5;0.001;5", "1;1.5;0.001;5"])
    with pytest.raises(SchemaError) as info:
        read_rig_csv(path, _profile(tmp_path))
    assert info.value.line == 2 and info.value.column == "acc" and "decimal comma" in info.value.message


def test_profile_object_and_missing_profile_file(tmp_path):
    profile = rig_profile_from_mapping(GOOD)
    ds = read_rig_csv(_daq(tmp_path, ["t [ms];acc;Ft;Fn"] + ROWS), profile)
    assert ds.attrs["run_id"] == "T1"
    with pytest.raises(FividError):  # the CLI's one-line, exit-2 path catches every profile error
        read_rig_csv(tmp_path / "run.csv", tmp_path / "absent.yaml")


def test_bad_value_in_file_name(tmp_path):
    profile = _profile(tmp_path, metadata__file_name={"pattern": r"_v(?P<sliding_velocity>[^_.]+)",
                                                       "units": {"sliding_velocity": "mm/s"}})
    with pytest.raises(UnitError) as info:
        read_rig_csv(_daq(tmp_path, ["t [ms];acc;Ft;Fn"] + ROWS, name="R1_vfast.csv"), profile)
    assert info.value.key == "sliding_velocity" and "from the file name ('fast')" in info.value.message
