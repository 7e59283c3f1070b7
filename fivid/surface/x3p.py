"""Reader of ISO 25178-72 (ISO 5436-2) X3P profile files, through the optional package ``x3pio``.

``x3pio`` (MIT, PyPI) reads and writes x3p files of ISO 25178-72:2017 and Amd 1:2020 (profiles,
surfaces, point clouds, checksums); it is maintained and depends only on numpy and defusedxml, so
fivid uses it rather than parsing the zipped XML itself. Install it with ``pip install x3pio``;
without it, reading an ``.x3p`` file raises a :class:`~fivid.errors.FividError` saying so.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import DataQualityError, FividError, SchemaError
from fivid.surface.profile import make_profile
from fivid.surface.text import file_provenance

__all__ = ["read_x3p"]


def _x3pio():
    try:
        import x3pio
    except ImportError:
        raise FividError("reading .x3p files needs the optional package 'x3pio' (ISO 25178-72 reader, MIT): "
                         "pip install x3pio") from None
    return x3pio


def read_x3p(path, *, layer: int = 0, row: int | None = None):
    """Read a profile from an X3P file (heights and x in metres, as x3pio gives them).

    Parameters
    ----------
    path : str or path-like
        The ``.x3p`` file.
    layer : int, default 0
        Which layer of a multi-layer file.
    row : int, optional
        For an areal (surface) file, the row (profile along x) to take; required there.

    Raises
    ------
    FividError
        x3pio is not installed, or the file is not a valid x3p file (x3pio's message).
    SchemaError
        A point cloud, an absolute x axis, or a surface file without ``row``.
    DataQualityError
        Points that were not measured (NaN) in the chosen profile.
    """
    x3pio = _x3pio()
    try:
        data = x3pio.read(path)
    except (OSError, x3pio.X3pError) as exc:
        raise FividError(f"cannot read x3p file: {exc}", file=path) from None
    kind = type(data).__name__
    if kind not in ("Profile", "Surface"):
        raise SchemaError(f"x3p file holds a {kind}; a profile or a surface on a grid is needed", file=path)
    if not 0 <= layer < len(data.layers):
        raise SchemaError(f"layer {layer} requested; the file has {len(data.layers)}", file=path)
    lay = data.layers[layer]
    if not data.header.x.is_incremental:
        raise SchemaError("x3p x axis is absolute (irregular); only incremental axes are read", file=path)
    z = np.asarray(lay.z, dtype=np.float64)
    if kind == "Surface":
        if row is None:
            raise SchemaError(f"x3p file is an areal surface of {z.shape[0]} x {z.shape[1]} points; choose a "
                              "profile with row=", file=path)
        if not 0 <= row < z.shape[0]:
            raise SchemaError(f"row {row} requested; the surface has {z.shape[0]} rows", file=path)
        z = z[row]
    z = z.reshape(-1)
    if np.isnan(z).any():
        i = int(np.argmax(np.isnan(z)))
        raise DataQualityError(f"point {i} of the profile was not measured (NaN); crop or fill it first", file=path)
    x = np.arange(z.size) * float(data.header.x.increment)
    meta = data.metadata
    instrument = "unknown"
    if meta is not None and meta.instrument is not None:
        instrument = " ".join(s for s in (meta.instrument.manufacturer, meta.instrument.model) if s) or instrument
    attrs = {"source": file_provenance(path), "instrument": instrument, "x3p_feature": kind,
             "x3p_layer": layer}
    if row is not None:
        attrs["x3p_row"] = row
    return make_profile(x, z, attrs=attrs, label=str(path))
