"""ASAM MDF 4 (and 3) measurement files through asammdf."""

from __future__ import annotations

import numpy as np

from fivid.errors import SchemaError
from fivid.io.daq.channels import ChannelFile, require

__all__ = ["read_mdf"]


def read_mdf(path) -> ChannelFile:
    """The channels of an MDF file.

    A channel is named by its channel name (the master channels are not listed: they are the
    time); its unit is the channel's unit. Metadata: the header's common properties
    (``<e name="Run">R002</e>`` in its comment) and author, project, subject, department. Implicit
    time: the master channel [s], which every mapped channel must share.
    """
    asammdf = require("asammdf", "asammdf", "ASAM MDF files (.mf4, .mdf)")
    data = ChannelFile("mdf4")
    with asammdf.MDF(str(path)) as mdf:
        header = mdf.header
        for key in ("author", "project", "subject", "department"):
            value = getattr(header, key, "")
            if value:
                data.metadata[key] = (str(value), f"header {key}")
        for key, value in getattr(header, "_common_properties", {}).items():
            if isinstance(value, str) and value:
                data.metadata.setdefault(key, (value, f"header property {key!r}"))
        for signal in mdf.iter_channels():
            if not np.issubdtype(signal.samples.dtype, np.number):
                continue
            if signal.name in data.channels:
                raise SchemaError(f"the file has two channels named {signal.name!r}; give each its own name",
                                  file=path, column=signal.name)
            timestamps = np.asarray(signal.timestamps, dtype=np.float64)
            if data.time is None:
                data.time = timestamps
            elif timestamps.shape != data.time.shape or not np.array_equal(timestamps, data.time):
                raise SchemaError("this channel's time stamps differ from the first channel's; every channel of a "
                                  "run must share one time axis (resample the file in the MDF tool)",
                                  file=path, column=signal.name)
            data.channels[signal.name] = np.asarray(signal.samples)
            if signal.unit:
                data.units[signal.name] = str(signal.unit)
    return data
