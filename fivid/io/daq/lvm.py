"""LabVIEW Measurement (.lvm) text files through lvm_read."""

from __future__ import annotations

import numpy as np

from fivid.errors import SchemaError
from fivid.io.daq.channels import ChannelFile, require

__all__ = ["read_lvm"]

#: File-header keys that describe the layout, not the run.
_LAYOUT = frozenset({"Writer_Version", "Reader_Version", "Separator", "Decimal_Separator", "Multi_Headings",
                     "X_Columns", "Time_Pref", "Segments", ""})


def read_lvm(path) -> ChannelFile:
    """The channels of an LVM file (one segment).

    A channel is named by its column name in the segment's header (``X_Value`` for the x column);
    its unit is its ``Y_Unit_Label``. Metadata: the file header's ``key<TAB>value`` lines other
    than the layout keys (``Operator``, ``Description``, ``Date``, and any other). Implicit time:
    the x column (``X_Value``), else ``X0 + i * Delta_X`` of the first channel.
    """
    lvm_read = require("lvm_read", "lvm_read", "LabVIEW Measurement files (.lvm)")
    lvm = lvm_read.read(str(path), read_from_pickle=False, dump_file=False)  # no pickle next to the file
    if lvm.get("Segments", 0) != 1:
        raise SchemaError(f"the file has {lvm.get('Segments', 0)} segments; fivid reads LVM files of one segment "
                          "(one run)", file=path)
    data = ChannelFile("lvm")
    for key, value in lvm.items():
        if isinstance(key, str) and key not in _LAYOUT:
            data.metadata[key] = (str(value), f"header key {key!r}")
    segment = lvm[0]
    names = list(segment["Channel names"])
    table = np.atleast_2d(np.asarray(segment["data"], dtype=np.float64))
    units = list(segment.get("Y_Unit_Label", []))
    y_names = [n for n in names if n != "X_Value"]
    for k, name in enumerate(names):
        data.channels[name] = table[:, k]
    for name, unit in zip(y_names, units, strict=False):
        if unit:
            data.units[name] = unit
    if "X_Value" in names:
        data.time = data.channels["X_Value"]
    elif segment.get("Delta_X"):
        data.time = segment["X0"][0] + segment["Delta_X"][0] * np.arange(table.shape[0])
    return data
