import numpy as np
import pytest
import xarray as xr

from fivid import schema
from fivid.errors import SchemaError


def _run(n=100, fs=1000.0):
    t = np.arange(n) / fs
    ds = xr.Dataset(
        {
            "acceleration": ("time", np.sin(t)),
            "friction_force": ("time", np.ones(n)),
            "normal_force": ("time", 2 * np.ones(n)),
        },
        coords={"time": t},
        attrs=dict(
            run_id="R1", rig="triboair", sliding_velocity=0.01, normal_load=5.0, roughness_ra=0.8e-6,
            sample_rate=fs, source="test", history=schema.new_history("made by a test"),
        ),
    )
    return schema.apply_cf_attrs(ds)


def test_valid_run_passes():
    ds = _run()
    assert schema.check_run(ds) == []
    assert ds["acceleration"].attrs["units"] == "m s-2"
    assert ds.attrs["sliding_velocity_units"] == "m s-1"


def test_every_problem_reported_at_once():
    ds = _run().drop_vars("normal_force")
    ds["friction_force"].attrs["units"] = "kN"
    ds["acceleration"][3] = np.nan
    del ds.attrs["run_id"]
    ds.attrs["sample_rate"] = "fast"
    with pytest.raises(SchemaError) as info:
        schema.validate_run(ds, name="x.nc")
    msg = str(info.value)
    for fragment in ("'normal_force'", "'kN'", "NaN", "'run_id'", "'sample_rate'", "5 problem"):
        assert fragment in msg


def test_time_must_increase():
    ds = _run()
    t = ds["time"].values.copy()
    t[10] = t[9]
    ds = ds.assign_coords(time=("time", t, {"units": "s"}))
    assert any("strictly increasing" in p for p in schema.check_run(ds))


def test_apply_cf_attrs_rewrites_wrong_units():
    ds = _run()
    ds["acceleration"] = ds["acceleration"] * 2  # arithmetic may carry or drop attrs
    ds["acceleration"].attrs["units"] = "g"
    assert schema.apply_cf_attrs(ds)["acceleration"].attrs["units"] == "m s-2"


def test_history_appends():
    ds = _run()
    schema.append_history(ds, "second step")
    lines = ds.attrs["history"].splitlines()
    assert len(lines) == 2 and lines[1].endswith("second step")


def test_unknown_variable_lists_known():
    with pytest.raises(SchemaError, match="acceleration"):
        schema.variable("acceleraton")


def test_schema_version_constant_matches_the_registry():
    """SCHEMA_VERSION is what apply_cf_attrs writes (from the YAML): the two must not drift apart."""
    from fivid.schema import SCHEMA_VERSION, registry

    assert SCHEMA_VERSION == registry().schema_version
