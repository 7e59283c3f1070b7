"""Reader of generic two-column profile text files (CSV or TXT) with units in the header.

Layout::

    # optional comment lines, kept in the ``comments`` attr
    x [mm],z [um]
    0.000,0.0123
    0.001,-0.0310

The first two columns are the lateral position and the height, each headed ``name [unit]`` with
any length unit pint knows (``m``, ``mm``, ``um``, ``µm``, ``nm``, ``Å``...). The separator is
taken from the header: comma, semicolon, tab, or else white space. Further columns are ignored.
"""

from __future__ import annotations

import re

from fivid.errors import SchemaError, UnitError
from fivid.surface.profile import MIN_POINTS, make_profile
from fivid.surface.text import check_profile_rows, file_provenance, parse_rows, read_lines
from fivid.units import conversion

__all__ = ["read_profile_columns"]

_WHITE_CELLS = re.compile(r"[^\s\[\]]+\s*\[[^\[\]]+\]")  # 'x [um]  z [nm]': a cell is 'name [unit]'
_HEADER_CELL = re.compile(r"\s*(?P<name>[^\[\]]*?)\s*\[(?P<unit>[^\[\]]+)\]\s*")


def _delimiter(header: str) -> str | None:
    for sep in (",", ";", "\t"):
        if sep in header:
            return sep
    return None


def _column(cell: str, path, line: int) -> tuple[str, float]:
    """(name as written, factor to metres) of a ``name [unit]`` header cell."""
    m = _HEADER_CELL.fullmatch(cell)
    if m is None:
        raise UnitError(f"column header {cell.strip()!r} has no unit; write it as 'name [unit]', e.g. 'x [um]'",
                        file=path, line=line, column=cell.strip())
    try:
        scale, offset = conversion(m["unit"].strip(), "m")
    except UnitError as exc:
        raise UnitError(f"{exc.message}; a profile column needs a length unit such as 'mm', 'um' or 'nm'",
                        file=path, line=line, column=cell.strip()) from None
    return cell.strip(), scale


def read_profile_columns(path, *, instrument: str = "unknown"):
    """Read a two-column ``x [unit], z [unit]`` text file into a profile (metres).

    Parameters
    ----------
    path : str or path-like
        The ``.csv`` or ``.txt`` file.
    instrument : str, default "unknown"
        Recorded in the ``instrument`` attr.

    Returns
    -------
    xarray.DataArray
        The profile, with attrs ``source`` (name and sha256), ``instrument``, ``x_column``,
        ``z_column`` (the headers as written) and ``comments`` (``#`` lines before the header).

    Raises
    ------
    SchemaError, DataQualityError, UnitError
        No header, fewer than two columns, a missing or non-length unit, a non-numeric value, x not
        strictly increasing, fewer than :data:`~fivid.surface.profile.MIN_POINTS` rows: the message
        names the file, line, column and value.
    """
    lines, _ = read_lines(path)
    comments, h = [], None
    for i, line in enumerate(lines):
        text = line.strip()
        if text.startswith("#"):
            comments.append(text.lstrip("#").strip())
        elif text:
            h = i
            break
    if h is None:
        raise SchemaError("no header line; expected a header such as 'x [um],z [um]'", file=path)
    sep = _delimiter(lines[h])
    cells = lines[h].split(sep) if sep is not None else (_WHITE_CELLS.findall(lines[h]) or lines[h].split())
    if len(cells) < 2:
        raise SchemaError(f"header {lines[h].strip()!r} has {len(cells)} column(s); expected two, such as "
                          "'x [um],z [um]'", file=path, line=h + 1)
    (x_name, x_scale), (z_name, z_scale) = (_column(c, path, h + 1) for c in cells[:2])
    values, numbers = parse_rows(lines, h + 1, path=path, columns=[x_name, z_name], delimiter=sep)
    check_profile_rows(values[:, 0], numbers, path=path, column=x_name, header_line=h + 1, min_points=MIN_POINTS)
    attrs = {"source": file_provenance(path), "instrument": instrument, "x_column": x_name, "z_column": z_name,
             "comments": "\n".join(comments)}
    return make_profile(values[:, 0] * x_scale, values[:, 1] * z_scale, attrs=attrs, label=str(path))
