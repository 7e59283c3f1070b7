"""Export runs, PSDs and FRFs for modal and test software: UFF dataset 58 (pyuff) and CSV with units.

A dataset with one dimension, ``time`` (a RunDataset, ingested or simulated) or ``frequency`` (a
PSD from ``fivid psd``, an FRF), is written channel by channel: each data variable, and each
coordinate along that dimension (PSD confidence bounds), with its CF ``units``. A variable with a
``sensor`` dimension gives one channel per sensor, named ``variable:sensor``.

* **UFF58** (``export_uff58``): one dataset 58 per channel, ASCII (13 significant digits), the
  abscissa stored as given (start and increment when even). Function type: 1 (time response) along ``time``; 4 (frequency response
  function) for complex values along ``frequency``; 2 (auto spectrum) for real ones (PSDs). ID
  line 1 is the channel name; the axis unit labels are the CF units.
* **CSV** (``export_csv``): ``# key: value`` metadata lines, a header ``name [units]``, one row per
  sample; complex values as ``name.real`` and ``name.imag`` columns. A RunDataset is written in the
  ``fivid-rig-csv: 1`` format, so ``fivid ingest`` reads it back.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import SchemaError
from fivid.io.daq.channels import require
from fivid.io.rig_profile import RESERVED_ATTRIBUTES

__all__ = ["EXPORT_FORMATS", "check_exportable", "export_csv", "export_dataset", "export_uff58", "uff58_set"]

EXPORT_FORMATS = ("uff58", "csv")
#: UFF58 function types (dataset 58, record 6 field 1).
_TIME_RESPONSE, _AUTO_SPECTRUM, _FRF = 1, 2, 4
#: UFF58 abscissa specific data types (record 8 field 1).
_ABSCISSA_TYPE = {"time": 17, "frequency": 18}


def uff58_set(name: str, x, values, *, ordinate_units: str, abscissa_units: str, node: int = 1,
              func_type: int = _TIME_RESPONSE, abscissa: str = "time", description: str = "") -> dict:
    """A complete pyuff dataset-58 dictionary for one channel (ASCII, double precision).

    ASCII, because pyuff 2.5 writes binary 58 files it cannot read back (``58b``); its ASCII keeps
    13 significant digits (relative round-off 1e-12).

    Parameters
    ----------
    name : str
        Channel name, written as ID line 1 (at most 80 characters).
    x, values : array_like
        Abscissa [``abscissa_units``] and ordinate [``ordinate_units``], same length; complex
        ``values`` are written as complex doubles.
    node : int
        Response node number (one per channel, so tools tell channels apart).
    func_type : int
        1 time response, 2 auto spectrum, 4 FRF.
    """
    values = np.asarray(values)
    x = np.asarray(x, dtype=np.float64)
    complex_values = np.iscomplexobj(values)
    step = np.diff(x)
    even = x.size > 1 and np.allclose(step, step[0], rtol=1e-9, atol=0)
    return {
        "type": 58, "binary": 0, "id1": name[:80], "id2": description[:80], "id3": "", "id4": "", "id5": "",
        "func_type": func_type, "func_id": node, "ver_num": 0, "load_case_id": 0,
        "rsp_ent_name": "fivid", "rsp_node": node, "rsp_dir": 0, "ref_ent_name": "fivid", "ref_node": 0,
        "ref_dir": 0, "ord_data_type": 6 if complex_values else 4, "num_pts": int(values.size),
        "abscissa_spacing": 1 if even else 0, "abscissa_min": float(x[0]) if x.size else 0.0,
        "abscissa_inc": float((x[-1] - x[0]) / (x.size - 1)) if even else 0.0, "z_axis_value": 0.0,
        "abscissa_spec_data_type": _ABSCISSA_TYPE.get(abscissa, 0), "abscissa_len_unit_exp": 0,
        "abscissa_force_unit_exp": 0, "abscissa_temp_unit_exp": 0, "abscissa_axis_lab": abscissa,
        "abscissa_axis_units_lab": abscissa_units,
        "ordinate_spec_data_type": 0, "ordinate_len_unit_exp": 0, "ordinate_force_unit_exp": 0,
        "ordinate_temp_unit_exp": 0, "ordinate_axis_lab": name[:20], "ordinate_axis_units_lab": ordinate_units,
        "orddenom_spec_data_type": 0, "orddenom_len_unit_exp": 0, "orddenom_force_unit_exp": 0,
        "orddenom_temp_unit_exp": 0, "orddenom_axis_lab": "", "orddenom_axis_units_lab": "",
        "z_axis_spec_data_type": 0, "z_axis_len_unit_exp": 0, "z_axis_force_unit_exp": 0,
        "z_axis_temp_unit_exp": 0, "z_axis_axis_lab": "", "z_axis_axis_units_lab": "",
        "data": values.astype(np.complex128 if complex_values else np.float64), "x": x,
    }


def _axis(ds) -> str:
    for dim in ("time", "frequency"):
        if dim in ds.dims:
            return dim
    raise SchemaError(f"cannot export a dataset with dimensions {dict(ds.sizes)}: expected a run (time) or a "
                      "spectrum/FRF (frequency)")


def _channels(ds, axis: str):
    """``(name, values, units)`` for every variable and non-index coordinate along ``axis``."""
    out = []
    for name, var in [*ds.data_vars.items(), *((n, c) for n, c in ds.coords.items() if n != axis)]:
        if axis not in var.dims:
            continue
        units = str(var.attrs.get("units", ""))
        if var.ndim == 1:
            out.append((str(name), var.values, units))
        elif var.ndim == 2:
            other = next(d for d in var.dims if d != axis)
            for label in var[other].values:
                out.append((f"{name}:{label}", var.sel({other: label}).transpose(axis).values, units))
        else:
            raise SchemaError(f"variable {name!r} has dimensions {var.dims}; export writes 1-D channels along "
                              f"{axis!r} (and one extra dimension such as sensor)")
    if not out:
        raise SchemaError(f"the dataset has no variable along {axis!r} to export")
    return out


def export_uff58(ds, path) -> int:
    """Write ``ds`` as UFF dataset-58 channels to ``path`` (replaced); returns the number of channels."""
    pyuff = require("pyuff", "pyuff", "UFF58 export")
    axis = _axis(ds)
    x = ds[axis].values
    x_units = str(ds[axis].attrs.get("units", "s" if axis == "time" else "Hz"))
    description = str(ds.attrs.get("run_id", ds.attrs.get("title", "")))
    sets = []
    for k, (name, values, units) in enumerate(_channels(ds, axis)):
        func = _TIME_RESPONSE if axis == "time" else (_FRF if np.iscomplexobj(values) else _AUTO_SPECTRUM)
        sets.append(uff58_set(name, x, values, ordinate_units=units, abscissa_units=x_units, node=k + 1,
                              func_type=func, abscissa=axis, description=description))
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    return len(sets)


def _metadata_lines(ds, is_run: bool) -> list[str]:
    lines = ["# fivid-rig-csv: 1"] if is_run else []
    for key, value in ds.attrs.items():
        if key.endswith("_units") or (is_run and key in RESERVED_ATTRIBUTES):
            continue
        text = f"{value} {ds.attrs[key + '_units']}" if f"{key}_units" in ds.attrs else str(value)
        if "\n" not in text:
            lines.append(f"# {key}: {text}")
    if is_run and "source" in ds.attrs:
        lines.append(f"# exported by fivid from {ds.attrs['source']}")
    return lines


def export_csv(ds, path) -> int:
    """Write ``ds`` as CSV with units to ``path``; returns the number of channels (see the module doc)."""
    axis = _axis(ds)
    columns = [(axis, ds[axis].values, str(ds[axis].attrs.get("units", "")))]
    for name, values, units in _channels(ds, axis):
        if np.iscomplexobj(values):
            columns += [(f"{name}.real", values.real, units), (f"{name}.imag", values.imag, units)]
        else:
            columns.append((name, values, units))
    is_run = axis == "time" and "run_id" in ds.attrs
    header = ",".join(f"{name} [{units}]" for name, _, units in columns)
    table = np.column_stack([np.asarray(v, dtype=np.float64) for _, v, _ in columns])
    with open(path, "w", encoding="utf-8", newline="\n") as f:
        f.write("\n".join([*_metadata_lines(ds, is_run), header]) + "\n")
        np.savetxt(f, table, delimiter=",", fmt="%.17g")
    return len(columns) - 1


def check_exportable(ds) -> None:
    """Refuse a dataset whose axis or channels carry no CF ``units`` (a netCDF file fivid did not write).

    Export writes a unit into every header and axis label; an empty one would pass silently into the
    CSV or UFF file. Datasets written by fivid carry ``fivid_version`` and units on every variable.

    Raises
    ------
    SchemaError
        Naming the variables without units, and whether the file was written by fivid.
    """
    axis = _axis(ds)
    names = [axis] if not str(ds[axis].attrs.get("units", "")).strip() else []
    names += [name.split(":")[0] for name, _, units in _channels(ds, axis) if not units.strip()]
    if not names:
        return
    names = list(dict.fromkeys(names))
    origin = ("it was written by fivid " + str(ds.attrs["fivid_version"]) if "fivid_version" in ds.attrs else
              "it is not a fivid dataset (no 'fivid_version' attribute: fivid ingest, simulate, psd and frf write one)")
    raise SchemaError(f"cannot export: {len(names)} variable(s) have no 'units' attribute ({', '.join(map(repr, names))}) "
                      f"and {origin}; export writes the unit of every column: give a file written by fivid, or add "
                      "CF 'units' attributes to those variables", key="units")


def export_dataset(ds, path, file_format: str) -> int:
    """Write ``ds`` to ``path`` in ``file_format`` (``"uff58"`` or ``"csv"``); returns the number of channels.

    Raises
    ------
    SchemaError
        An unknown format, or a dataset without units (:func:`check_exportable`), before anything is written.
    """
    writers = {"uff58": export_uff58, "csv": export_csv}
    if file_format not in writers:
        raise SchemaError(f"unknown export format {file_format!r}; choose one of {', '.join(EXPORT_FORMATS)}")
    check_exportable(ds)
    return writers[file_format](ds, path)
