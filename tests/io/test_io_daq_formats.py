"""DAQ formats through rig profiles: a recording written by each format's own library (TDMS, UFF58,
MAT v5 and v7.3, LVM, MDF4) from sample_data/R002_v20_ra16.csv ingests to the CSV's RunDataset."""

import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from tests.helpers.daq_writers import CSV, MAT_NAMES, raw_recording, write_lvm, write_mat, write_mat73, write_mdf4, write_tdms, \
    write_uff58

from fivid.cli import main
from fivid.errors import FividError, SchemaError, UnitError
from fivid.io import read_rig_csv, read_run
from fivid.io.daq import read_daq_file
from fivid.io.rig_profile import rig_profile_from_mapping

ROOT = Path(__file__).resolve().parents[2]
LABDAQ = yaml.safe_load((ROOT / "configs" / "rigs" / "labdaq.yaml").read_text(encoding="utf-8"))
#: attributes that name the file or its format, and differ between the CSV and the other formats
PROVENANCE = {"source", "source_format", "history"}


def _labdaq(**change):
    raw = yaml.safe_load(yaml.safe_dump(LABDAQ))
    for key, value in change.items():
        raw[key] = value
    return rig_profile_from_mapping(raw)


def _mat_profile():
    """labdaq with MATLAB names: channels in the struct 'data', metadata keys without spaces."""
    columns = {var: dict(spec, name=f"data.{MAT_NAMES[spec['name']]}") for var, spec in LABDAQ["columns"].items()}
    metadata = dict(LABDAQ["metadata"])
    metadata["in_file"] = dict(metadata["in_file"], keys={k.replace(" ", "_"): v for k, v in
                                                           metadata["in_file"]["keys"].items()})
    return _labdaq(columns=columns, metadata=metadata)


def _uff_profile():
    """labdaq with the run metadata in the profile: UFF58 has no place for them."""
    metadata = dict(LABDAQ["metadata"])
    metadata["values"] = dict(metadata["values"], normal_load="5 N", sample_rate="51200 Hz",
                              start_time="2026-11-20 14:03:11")
    return _labdaq(metadata=metadata)


@pytest.fixture(scope="module")
def recording():
    return raw_recording()


@pytest.fixture(scope="module")
def reference():
    return read_rig_csv(CSV, "labdaq")


def _assert_same_run(ds, ref, rtol, time_atol=0.0, renamed=False):
    """Same variables, values, attributes; ``renamed``: the file's channel names are not the CSV's."""
    assert list(ds.data_vars) == list(ref.data_vars)
    assert set(ds.coords) == set(ref.coords)
    for name in ref.data_vars:
        np.testing.assert_allclose(ds[name].values, ref[name].values, rtol=rtol, atol=0)
        differ = {"source_column"} if renamed else set()
        assert {k: v for k, v in ds[name].attrs.items() if k not in differ} == \
            {k: v for k, v in ref[name].attrs.items() if k not in differ}, name
    np.testing.assert_allclose(ds["time"].values, ref["time"].values, rtol=0, atol=time_atol)
    assert {k: v for k, v in ds.attrs.items() if k not in PROVENANCE} == \
        {k: v for k, v in ref.attrs.items() if k not in PROVENANCE}


#: UFF58 time axis: start + i * increment, the increment written E13.5 (1.95312e-05 for 1/51200 s, 2.6e-6
#: low) against the CSV's times printed to 1e-7 s: off by up to 6400 x 5e-11 + 5e-8 s.
UFF_TIME_ATOL = 6400 * 5e-11 + 5e-8
# rtol: 0 for binary doubles and repr-written text; UFF58 ASCII data keep 13 significant digits
FORMATS = [
    pytest.param(write_tdms, "labdaq", "tdms", 0.0, 0.0, id="tdms"),
    pytest.param(write_uff58, _uff_profile, "uff58", 1e-12, UFF_TIME_ATOL, id="uff58"),
    pytest.param(write_mat, _mat_profile, "mat", 0.0, 0.0, id="mat-v5"),
    pytest.param(write_mat73, _mat_profile, "mat-v7.3", 0.0, 0.0, id="mat-v7.3"),
    pytest.param(write_lvm, "labdaq", "lvm", 0.0, 0.0, id="lvm"),
    pytest.param(write_mdf4, "labdaq", "mdf4", 0.0, 0.0, id="mdf4"),
]


@pytest.mark.parametrize(("write", "profile", "fmt", "rtol", "time_atol"), FORMATS)
def test_each_format_ingests_to_the_csv_run(tmp_path, recording, reference, write, profile, fmt, rtol, time_atol):
    path = write(tmp_path, *recording)
    ds = read_daq_file(path, profile if isinstance(profile, str) else profile())
    assert ds.attrs["source_format"] == fmt
    assert ds.attrs["source"].startswith(path.name + " sha256:")
    _assert_same_run(ds, reference, rtol, time_atol, renamed=profile is _mat_profile)


def test_cli_dispatches_by_suffix(tmp_path, recording, reference, capsys):
    path = write_tdms(tmp_path, *recording)
    assert main(["ingest", str(path), "-o", str(tmp_path / "out"), "--rig", "labdaq"]) == 0
    _assert_same_run(read_run(tmp_path / "out" / "R002.nc"), reference, 0.0)


def test_missing_channel_names_channel_and_exits_2(tmp_path, recording, capsys):
    channels, metadata = recording
    path = write_tdms(tmp_path, {k: v for k, v in channels.items() if k != "Fz (N)"}, metadata)
    with pytest.raises(SchemaError, match=r"required channel 'Fz \(N\)' \(normal_force\) is missing"):
        read_daq_file(path, "labdaq")
    assert main(["ingest", str(path), "-o", str(tmp_path / "out"), "--rig", "labdaq"]) == 2
    err = capsys.readouterr().err
    assert "R002_v20_ra16.tdms" in err and "'Fz (N)'" in err


def test_unit_stated_in_the_file_must_match_the_profile(tmp_path, recording):
    path = write_tdms(tmp_path, *recording)
    columns = dict(LABDAQ["columns"], friction_force={"name": "Fx (N)", "units": "kN"})
    with pytest.raises(UnitError, match=r"states the unit 'N' .* profile says 'kN'"):
        read_daq_file(path, _labdaq(columns=columns))
    columns = dict(LABDAQ["columns"], friction_force={"name": "Fx (N)", "units": "mm"})
    with pytest.raises(FividError, match="mm"):
        read_daq_file(path, _labdaq(columns=columns))


def test_bad_sample_is_named_by_its_index(tmp_path, recording):
    channels, metadata = recording
    channels = dict(channels, **{"Fx (N)": channels["Fx (N)"].copy()})
    channels["Fx (N)"][41] = np.nan
    path = write_mdf4(tmp_path, channels, metadata)
    with pytest.raises(FividError, match=r"at sample 42") as info:
        read_daq_file(path, "labdaq")
    assert info.value.column == "Fx (N)"


def test_missing_library_gives_install_hint(tmp_path, recording, monkeypatch):
    path = write_tdms(tmp_path, *recording)
    monkeypatch.setitem(sys.modules, "nptdms", None)  # import nptdms raises ImportError
    with pytest.raises(FividError, match=r"needs the npTDMS package.*pip install 'fivid\[daq\]'"):
        read_daq_file(path, "labdaq")


def test_tdms_waveform_time_when_no_time_channel(tmp_path, recording, reference):
    """NI waveforms carry wf_start_offset and wf_increment instead of a time channel."""
    from nptdms import ChannelObject, RootObject, TdmsWriter

    channels, metadata = recording
    path = tmp_path / "R002_v20_ra16.tdms"
    wave = {"wf_start_offset": 0.0, "wf_increment": 1 / 51200}
    with TdmsWriter(str(path)) as writer:
        writer.write_segment([RootObject(properties=metadata)] + [
            ChannelObject("Rig", name, values, properties=wave) for name, values in channels.items()
            if name != "Time (s)"])
    ds = read_daq_file(path, "labdaq")
    _assert_same_run(ds, reference, 0.0, time_atol=5e-8 * (1 + 1e-9))  # the CSV prints times to 1e-7 s (half up)


def test_folder_of_daq_files_is_expanded_and_uff_without_time_data_rejected(tmp_path, recording, capsys):
    from fivid.io.export import export_uff58

    write_tdms(tmp_path, *recording)
    import xarray as xr

    frf = xr.Dataset({"h": ("frequency", np.ones(4) + 1j, {"units": "m N-1"})},
                     coords={"frequency": ("frequency", np.arange(1.0, 5.0), {"units": "Hz"})})
    export_uff58(frf, tmp_path / "frf.uff")
    assert main(["ingest", str(tmp_path), "-o", str(tmp_path / "out"), "--rig", "labdaq"]) == 2
    err = capsys.readouterr().err
    assert "frf.uff" in err and "no time-response dataset 58" in err
    assert (tmp_path / "out" / "R002.nc").is_file()
