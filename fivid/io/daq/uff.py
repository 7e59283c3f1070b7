"""Universal File Format dataset 58 (time data) through pyuff."""

from __future__ import annotations

import numpy as np

from fivid.errors import SchemaError
from fivid.io.daq.channels import ChannelFile, require

__all__ = ["read_uff58"]

#: UFF58 function type of a time response (1 = time response; 4 = FRF, 12 = spectrum, ...).
TIME_RESPONSE = 1


def read_uff58(path) -> ChannelFile:
    """The time-response channels (dataset 58, function type 1) of a UFF file.

    A channel is named by its ID line 1 (``id1``, stripped); its unit is the ordinate axis units
    label. Its abscissa (``abscissa_min + i * abscissa_inc``, or the stored values when uneven) is
    the implicit time [s]; every channel must share it. Datasets of other types or function types
    (FRFs, spectra) are left out. UFF58 carries no run metadata: give it in the file name or the
    profile's ``metadata.values``.
    """
    pyuff = require("pyuff", "pyuff", "Universal File Format files (.uff, .unv)")
    sets = pyuff.UFF(str(path)).read_sets()
    sets = [sets] if isinstance(sets, dict) else list(sets)
    data = ChannelFile("uff58")
    for s in sets:
        if s.get("type") != 58 or s.get("func_type") != TIME_RESPONSE:
            continue
        name = str(s.get("id1", "")).strip()
        if name in data.channels:
            raise SchemaError(f"two time-response datasets have the ID line 1 {name!r}; give each channel its own "
                              "name", file=path, column=name)
        x = np.asarray(s["x"], dtype=np.float64)
        if data.time is None:
            data.time = x
        elif x.shape != data.time.shape or not np.array_equal(x, data.time):
            raise SchemaError("this channel's abscissa differs from the first channel's; every channel of a run "
                              "must share one time axis", file=path, column=name)
        data.channels[name] = np.real(np.asarray(s["data"]))
        unit = str(s.get("ordinate_axis_units_lab", "")).strip()
        if unit and unit.upper() != "NONE":
            data.units[name] = unit
    if not data.channels:
        raise SchemaError("the file holds no time-response dataset 58 (function type 1); UFF FRFs and spectra "
                          "are not runs", file=path)
    return data
