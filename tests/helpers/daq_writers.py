"""Write one rig recording in each DAQ format with the formats' own libraries (for tests/io/test_io_daq_*.py).

The recording is sample_data/R002_v20_ra16.csv, the LabDAQ export read by the ``labdaq`` profile:
its raw channels (mV, N, mm; the names of its header) and its preamble metadata are written as they
are, so that ingesting the written file with the profile must give the CSV's RunDataset.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[2]
CSV = ROOT / "sample_data" / "R002_v20_ra16.csv"
STEM = "R002_v20_ra16"  # the labdaq profile reads velocity and roughness from the file name
UNITS = {"Time (s)": "s", "Accel Z (mV)": "mV", "Fx (N)": "N", "Fz (N)": "N", "Pos (mm)": "mm"}


def raw_recording(path: Path = CSV) -> tuple[dict, dict]:
    """``(channels, metadata)``: the CSV's raw columns by header name, its ``key;value`` preamble lines."""
    lines = path.read_text(encoding="utf-8").splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith('"Time (s)"'))
    metadata = dict(line.split(";", 1) for line in lines[1:header])
    metadata.pop("Comment", None)
    table = pd.read_csv(path, sep=";", decimal=",", skiprows=header, dtype=np.float64)
    return {name: table[name].to_numpy() for name in table.columns}, metadata


def write_tdms(folder: Path, channels: dict, metadata: dict) -> Path:
    from nptdms import ChannelObject, RootObject, TdmsWriter

    path = folder / f"{STEM}.tdms"
    with TdmsWriter(str(path)) as writer:
        writer.write_segment([RootObject(properties=metadata)] + [
            ChannelObject("Rig", name, values, properties={"unit_string": UNITS[name]})
            for name, values in channels.items()])
    return path


def write_uff58(folder: Path, channels: dict, metadata: dict) -> Path:
    """Dataset 58 (ASCII), one per channel, on the evenly spaced abscissa of the nominal sample rate
    (UFF58 stores the start and the increment, the latter in E13.5: 6 significant digits)."""
    import pyuff

    from fivid.io.export import uff58_set

    path = folder / f"{STEM}.uff"
    time = np.arange(len(channels["Time (s)"])) / 51200.0
    sets = [uff58_set(name, time, values, ordinate_units=UNITS[name], abscissa_units="s", node=k + 1)
            for k, (name, values) in enumerate(channels.items()) if name != "Time (s)"]
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    return path


MAT_NAMES = {"Time (s)": "Time_s", "Accel Z (mV)": "AccelZ_mV", "Fx (N)": "Fx_N", "Fz (N)": "Fz_N",
             "Pos (mm)": "Pos_mm"}


def _mat_key(key: str) -> str:
    return key.replace(" ", "_")


def write_mat(folder: Path, channels: dict, metadata: dict) -> Path:
    """A v5 .mat: channels in a struct ``data`` (``data.Time_s``), metadata as text variables."""
    import scipy.io

    path = folder / f"{STEM}.mat"
    variables = {_mat_key(k): v for k, v in metadata.items()}
    variables["data"] = {MAT_NAMES[n]: v.reshape(-1, 1) for n, v in channels.items()}
    scipy.io.savemat(str(path), variables)
    return path


def write_mat73(folder: Path, channels: dict, metadata: dict) -> Path:
    """A v7.3 .mat (HDF5 with MATLAB's 512-byte header) as MATLAB writes it: row vectors (1, n) of
    doubles and text as uint16 characters, each with its MATLAB_class."""
    import h5py

    path = folder / f"{STEM}.mat"
    with h5py.File(path, "w", userblock_size=512) as f:
        group = f.create_group("data")
        group.attrs["MATLAB_class"] = np.bytes_("struct")
        for name, values in channels.items():
            ds = group.create_dataset(MAT_NAMES[name], data=values.reshape(1, -1))
            ds.attrs["MATLAB_class"] = np.bytes_("double")
        for key, value in metadata.items():
            ds = f.create_dataset(_mat_key(key), data=np.array([ord(c) for c in value], dtype=np.uint16)[:, None])
            ds.attrs["MATLAB_class"] = np.bytes_("char")
    with open(path, "r+b") as f:
        f.write(b"MATLAB 7.3 MAT-file, written by tests/helpers/daq_writers.py".ljust(116) + b"\x00" * 8 + b"\x00\x02IM")
    return path


def write_lvm(folder: Path, channels: dict, metadata: dict) -> Path:
    """LVM text (Writer_Version 2, tab separated, one x column) with the metadata as header keys."""
    path = folder / f"{STEM}.lvm"
    names = [n for n in channels if n != "Time (s)"]
    n = len(channels["Time (s)"])
    head = ["LabVIEW Measurement\t", "Writer_Version\t2", "Reader_Version\t2", "Separator\tTab",
            "Decimal_Separator\t.", "Multi_Headings\tNo", "X_Columns\tOne", "Time_Pref\tRelative"]
    head += [f"{k}\t{v}" for k, v in metadata.items()]
    head += ["***End_of_Header***\t", "\t", f"Channels\t{len(names)}\t",
             "Samples\t" + "\t".join(str(n) for _ in names) + "\t",
             "Y_Unit_Label\t" + "\t".join(UNITS[c] for c in names) + "\t",
             "X_Dimension\t" + "\t".join("Time" for _ in names) + "\t",
             "X0\t" + "\t".join("0" for _ in names) + "\t",
             "Delta_X\t" + "\t".join("1.953125E-5" for _ in names) + "\t",
             "***End_of_Header***\t", "X_Value\t" + "\t".join(names) + "\tComment"]
    table = np.column_stack([channels["Time (s)"]] + [channels[c] for c in names])
    rows = ["\t".join(repr(float(v)) for v in row) for row in table]
    path.write_text("\n".join(head + rows) + "\n", encoding="utf-8")
    return path


def write_mdf4(folder: Path, channels: dict, metadata: dict) -> Path:
    """MDF 4.10, one channel group whose master channel is the CSV's time column."""
    from asammdf import MDF, Signal

    path = folder / f"{STEM}.mf4"
    time = channels["Time (s)"]
    mdf = MDF(version="4.10")
    mdf.append([Signal(values, time, name=name, unit=UNITS[name]) for name, values in channels.items()
                if name != "Time (s)"])
    mdf.header._common_properties.update(metadata)  # the <common_properties> of the header comment
    mdf.save(str(path), overwrite=True)
    mdf.close()
    return path
