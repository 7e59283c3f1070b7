"""Several accelerometers: ``acceleration:<sensor> [unit]`` columns (or a list in a rig profile)
become ``acceleration(time, sensor)``."""

import numpy as np
import pytest
import xarray as xr
from tests.helpers.ingest import STANDARD_GRAVITY, write_rig

from fivid.errors import ConfigError, SchemaError
from fivid.io import read_rig_csv, read_run, write_run
from fivid.io.rig_profile import rig_profile_from_mapping
from fivid.schema import check_run

RTOL = 2 * 2.0**-52  # one multiplication by an exactly defined factor, which pint may give to 1 ulp

HEADER = "time [s],acceleration:top [g],friction_force [N],acceleration:side [m/s^2],normal_force [N]"
ROWS = ["0,0.5,1.5,1.0,5.0", "0.001,-0.25,1.6,2.0,5.1", "0.002,1,1.4,-3.0,4.9"]


def test_sensor_columns_make_a_sensor_dimension(tmp_path):
    ds = read_rig_csv(write_rig(tmp_path / "s.csv", rows=ROWS, header=HEADER))
    assert ds["acceleration"].dims == ("time", "sensor")
    assert list(ds["sensor"].values) == ["top", "side"]
    np.testing.assert_allclose(ds["acceleration"].sel(sensor="top").values,
                               np.array([0.5, -0.25, 1.0]) * STANDARD_GRAVITY, rtol=RTOL)
    np.testing.assert_array_equal(ds["acceleration"].sel(sensor="side").values, [1.0, 2.0, -3.0])
    np.testing.assert_array_equal(ds["friction_force"].values, [1.5, 1.6, 1.4])
    assert ds["acceleration"].attrs["source_column"] == "acceleration:top, acceleration:side"
    assert ds["acceleration"].attrs["source_units"] == "g, m/s^2"
    assert check_run(ds) == []
    back = read_run(write_run(ds, tmp_path / "s.nc"))
    xr.testing.assert_identical(back, ds)


def test_bad_value_in_a_sensor_column_names_it(tmp_path):
    rows = ROWS[:2] + ["0.002,1,1.4,nan,4.9"]
    with pytest.raises(Exception) as info:
        read_rig_csv(write_rig(tmp_path / "s.csv", rows=rows, header=HEADER))
    assert info.value.column == "acceleration:side" and info.value.line == 10  # header on line 7


@pytest.mark.parametrize("header, what", [
    ("time [s],acceleration [g],friction_force [N],acceleration:side [g],normal_force [N]", "name each one's sensor"),
    ("time [s],acceleration [g],friction_force:x [N],normal_force [N],position [m]", "no sensor dimension"),
    ("time [s],acceleration:a [g],friction_force [N],acceleration:a [g],normal_force [N]", "appears twice"),
])
def test_sensor_header_errors(tmp_path, header, what):
    with pytest.raises(SchemaError, match=what):
        read_rig_csv(write_rig(tmp_path / "s.csv", rows=ROWS, header=header))


PROFILE = {
    "fivid-rig-profile": 1,
    "format": "table",
    "metadata": {"values": {"run_id": "S1", "rig": "r", "sliding_velocity": "1 mm/s", "normal_load": "5 N",
                            "roughness_ra": "1 um"}},
    "columns": {
        "time": {"name": "t", "units": "s"},
        "acceleration": [
            {"name": "A1", "units": "mV", "sensitivity": "100 mV/g", "sensor": "upper"},
            {"name": "A2", "units": "mV", "sensitivity": "10.2 mV/(m/s^2)", "sensor": "lower"},
        ],
        "friction_force": {"name": "Ft", "units": "N"},
        "normal_force": {"name": "Fn", "units": "N"},
    },
}


def test_profile_with_two_accelerometers(tmp_path):
    path = tmp_path / "d.csv"
    path.write_text("t,A2,Ft,Fn,A1\n0,10.2,1.5,5,100\n0.001,20.4,1.5,5,-50\n0.002,0,1.5,5,0\n")
    ds = read_rig_csv(path, rig_profile_from_mapping(PROFILE))
    assert list(ds["sensor"].values) == ["lower", "upper"]  # header order
    np.testing.assert_allclose(ds["acceleration"].sel(sensor="upper").values,
                               np.array([1.0, -0.5, 0.0]) * STANDARD_GRAVITY, rtol=RTOL)
    np.testing.assert_allclose(ds["acceleration"].sel(sensor="lower").values, [1.0, 2.0, 0.0], rtol=RTOL)
    assert ds["acceleration"].attrs["sensitivity"] == "10.2 mV/(m/s^2), 100 mV/g"


@pytest.mark.parametrize("columns, key", [
    ({"acceleration": [{"name": "A1", "units": "g"}]}, "columns.acceleration[0].sensor"),
    ({"acceleration": [{"name": "A1", "units": "g", "sensor": "a"}, {"name": "A2", "units": "g", "sensor": "a"}]},
     "columns.acceleration[1].sensor"),
    ({"friction_force": [{"name": "F", "units": "N", "sensor": "a"}]}, "columns.friction_force"),
    ({"friction_force": {"name": "F", "units": "N", "sensor": "a"}}, "columns.friction_force.sensor"),
    ({"acceleration": [{"name": "A1", "units": "g", "sensor": "a b"}]}, "columns.acceleration[0].sensor"),
])
def test_sensor_profile_errors(columns, key):
    raw = {**PROFILE, "columns": {**PROFILE["columns"], **columns}}
    with pytest.raises(ConfigError) as info:
        rig_profile_from_mapping(raw)
    assert info.value.key == key
