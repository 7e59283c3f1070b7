"""NI TDMS files (LabVIEW, DIAdem, NI DAQ) through npTDMS."""

from __future__ import annotations

from collections import Counter

import numpy as np

from fivid.io.daq.channels import ChannelFile, require

__all__ = ["read_tdms"]


def read_tdms(path) -> ChannelFile:
    """The channels of a TDMS file.

    A channel is named ``"group/channel"``, and by its channel name alone when no other group has
    one of that name. Its unit is its ``unit_string`` property. Metadata: the file's (root)
    properties, then each group's. Implicit time: the waveform of the first channel with a
    ``wf_increment`` property (``wf_start_offset + i * wf_increment`` [s]). Non-numeric channels
    (strings, timestamps) are left out.
    """
    nptdms = require("nptdms", "npTDMS", "TDMS files (.tdms)")
    tdms = nptdms.TdmsFile.read(str(path))
    data = ChannelFile("tdms")
    for key, value in tdms.properties.items():
        data.metadata[key] = (str(value), f"file property {key!r}")
    for group in tdms.groups():
        for key, value in group.properties.items():
            data.metadata.setdefault(key, (str(value), f"group {group.name!r} property {key!r}"))
    numeric = [(g, c) for g in tdms.groups() for c in g.channels() if np.issubdtype(c.dtype, np.number)]
    count = Counter(c.name for _, c in numeric)
    for group, channel in numeric:
        values = channel[:]
        names = [f"{group.name}/{channel.name}"] + ([channel.name] if count[channel.name] == 1 else [])
        for name in names:
            data.channels[name] = values
            unit = channel.properties.get("unit_string")
            if unit:
                data.units[name] = str(unit)
        if data.time is None and "wf_increment" in channel.properties:
            data.time = channel.time_track()
    return data
