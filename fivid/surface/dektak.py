"""Reader of the CSV export of Bruker (Veeco) Dektak stylus profilometers.

Layout (CRLF lines; ``µ`` may be the latin-1 byte 0xB5)::

    Scan Parameters
    Scan Type,Standard Scan
    Length,1500.0 um
    Resolution,0.156 um/sample
    R. Cursor,Pos: 100.0 um Width: 0.0 um
    ...
    Analytical Results
    Function,R.Cur Pos,R.Cur Width,M.Cur Pos,M.Cur Width,Result
    Ra,468.0 um,0.0 um,733.0 um,0.0 um,0.00525 um
    Skew,468.0 um,0.0 um,733.0 um,0.0 um,6.96
    ...
    Scan Data
    Lateral um,Raw Micrometer,
    0.0,-0.00933,,
    0.2,-0.00760,,

The instrument's results (evaluated between the R and M cursor positions of their rows) are kept
in attrs, converted to SI, keyed by ISO symbols (``Skew`` → ``Rsk``, ``RzDin`` → ``RzDIN``) for
comparison with :func:`fivid.surface.evaluate_profile`.

Lateral positions are printed rounded (to 0.1 µm in the sample export) while the samples are
equally spaced by Length / N (1500 µm / 9600 = 0.15625 µm; the printed "Resolution" 0.156 µm is
rounded too). When every printed position equals ``i * Length / N`` to within the rounding of the
printed numbers, ``x`` is rebuilt as ``i * Length / N``; otherwise the printed positions are used.
"""

from __future__ import annotations

import re

import numpy as np

from fivid.errors import FividError, SchemaError, UnitError
from fivid.surface.profile import MIN_POINTS, make_profile
from fivid.surface.text import check_profile_rows, file_provenance, parse_rows, read_lines
from fivid.units import conversion, parse_quantity

__all__ = ["read_dektak_csv", "is_dektak_csv", "instrument_results", "ISO_SYMBOLS"]

# Dektak "Function" names -> ISO 4287 / 21920-2 symbols (others keep the instrument's name).
ISO_SYMBOLS = {"Ra": "Ra", "Rq": "Rq", "Skew": "Rsk", "Kurt": "Rku", "RzDin": "RzDIN", "Rz": "Rz", "Rt": "Rt",
               "Rp": "Rp", "Rv": "Rv", "Wa": "Wa", "Wq": "Wq"}
_TEXT_PARAMETERS = {"Scan Type": "scan_type", "Stylus": "stylus", "Force": "stylus_force", "Profile": "scan_profile"}
_SECTIONS = ("Scan Parameters", "Analytical Results", "Scan Data")
_CURSOR = re.compile(r"Pos:\s*(?P<pos>\S+\s*\S+)\s+Width:\s*(?P<width>\S+\s*\S+)")
_NUMBER_UNIT = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*")


def _section_starts(lines: list[str]) -> dict[str, int]:
    found = {}
    for i, line in enumerate(lines):
        name = line.strip().rstrip(",").strip()
        if name in _SECTIONS and name not in found:
            found[name] = i
    return found


def is_dektak_csv(lines: list[str]) -> bool:
    """Whether the lines look like a Dektak export (a ``Scan Data`` block and a ``Lateral`` header)."""
    starts = _section_starts(lines)
    return "Scan Data" in starts and any(line.startswith("Lateral") for line in lines[starts["Scan Data"]:][:5])


def _block(lines: list[str], start: int) -> list[tuple[int, str]]:
    """(0-based index, line) of the lines after ``start`` up to the next blank line."""
    out = []
    for i in range(start + 1, len(lines)):
        if not lines[i].strip():
            break
        out.append((i, lines[i]))
    return out


def _length(text: str, path, line: int, key: str) -> float:
    try:
        return parse_quantity(text, "m")
    except FividError as exc:
        raise UnitError(f"{key}: {exc.message}", file=path, line=line) from None


def _scan_parameters(lines, starts, path) -> dict:
    attrs = {}
    if "Scan Parameters" not in starts:
        return attrs
    raw = []
    for i, line in _block(lines, starts["Scan Parameters"]):
        key, _, value = line.partition(",")
        key, value = key.strip(), value.strip().rstrip(",")
        raw.append(f"{key}: {value}")
        if key == "Length":
            attrs["scan_length"] = _length(value, path, i + 1, key)
        elif key == "Resolution":
            attrs["scan_resolution_printed"] = _length(value.split("/")[0], path, i + 1, key)
        elif key in ("R. Cursor", "M. Cursor"):
            m = _CURSOR.search(value)
            if m is not None:
                attrs[f"scan_{key[0].lower()}_cursor_position"] = _length(m["pos"], path, i + 1, key)
        elif key in _TEXT_PARAMETERS:
            attrs[_TEXT_PARAMETERS[key]] = value
    attrs["scan_parameters"] = "; ".join(raw)
    return attrs


def _result_value(text: str):
    """A result as an SI float (lengths in m, bare numbers as they are), or None if not a number."""
    m = _NUMBER_UNIT.fullmatch(text)
    if m is None:
        return None
    if not m.group(2):
        return float(m.group(1))
    try:
        return parse_quantity(text, "m")
    except FividError:
        return None


def _analytical_results(lines, starts, path) -> dict:
    attrs = {}
    if "Analytical Results" not in starts:
        return attrs
    block = _block(lines, starts["Analytical Results"])
    if not block or not block[0][1].startswith("Function"):
        return attrs
    header = [h.strip() for h in block[0][1].split(",")]
    names = []
    for i, line in block[1:]:
        cells = dict(zip(header, (c.strip() for c in line.split(","))))
        function, result = cells.get("Function", ""), cells.get("Result", "")
        value = _result_value(result)
        symbol = ISO_SYMBOLS.get(function, function)
        if not function or value is None:
            attrs[f"instrument_{symbol or 'unnamed'}_text"] = result
            continue
        attrs[f"instrument_{symbol}"] = value
        names.append(f"{function}={symbol}" if function != symbol else function)
        if "instrument_window_start" not in attrs and cells.get("R.Cur Pos") and cells.get("M.Cur Pos"):
            a = _length(cells["R.Cur Pos"], path, i + 1, "R.Cur Pos")
            b = _length(cells["M.Cur Pos"], path, i + 1, "M.Cur Pos")
            attrs["instrument_window_start"], attrs["instrument_window_end"] = min(a, b), max(a, b)
    if names:
        attrs["instrument_functions"] = "; ".join(names)
    return attrs


def instrument_results(profile) -> dict[str, float]:
    """The instrument's own results stored by the reader, keyed by ISO symbol, in SI (m; Rsk, Rku: 1)."""
    skip = {"instrument_window_start", "instrument_window_end", "instrument_functions"}
    return {k[len("instrument_"):]: float(v) for k, v in profile.attrs.items()
            if k.startswith("instrument_") and k not in skip and not k.endswith("_text")}


def _column_units(header: list[str], path, line: int) -> list[tuple[str, float]]:
    out = []
    for cell in header[:2]:
        unit = cell.split()[-1] if len(cell.split()) > 1 else ""
        try:
            scale, offset = conversion(unit.lower() if unit.isalpha() else unit, "m")
        except UnitError as exc:
            raise UnitError(f"column header {cell!r}: {exc.message}; expected a length unit such as 'um'",
                            file=path, line=line, column=cell) from None
        out.append((cell, scale))
    return out


def _lateral(x_printed: np.ndarray, decimals: int, x_scale: float, attrs: dict) -> tuple[np.ndarray, str]:
    """Equally spaced x = i * Length / N when the printed positions are that, rounded; else as printed."""
    length = attrs.get("scan_length")
    n = x_printed.size
    if length is None or n < 2:
        return x_printed, "as printed"
    x = x_printed[0] + np.arange(n) * (length / n)
    half_digit = 0.5 * 10.0 ** (-decimals) * x_scale
    if np.max(np.abs(x - x_printed)) <= half_digit * (1 + 1e-9) + 1e-12 * length:
        return x, f"i * Length / N = i * {length / n:.9g} m (printed positions are rounded to {decimals} decimal(s))"
    return x_printed, "as printed"


def read_dektak_csv(path):
    """Read a Dektak CSV export into a profile (heights [m] over ``x`` [m]).

    Parameters
    ----------
    path : str or path-like
        The ``.csv`` export.

    Returns
    -------
    xarray.DataArray
        The profile (see :mod:`fivid.surface.profile`) with attrs: ``source`` (name and sha256),
        ``instrument``, ``file_encoding``, the scan parameters (``scan_length`` [m], ``scan_type``,
        ``stylus``, ``stylus_force``, ``scan_parameters`` as printed), the instrument's results
        ``instrument_<symbol>`` [m or 1] and their window ``instrument_window_start``/``_end`` [m],
        and ``x_coordinate`` (how x was obtained).

    Raises
    ------
    SchemaError, DataQualityError, UnitError
        No ``Scan Data`` block, a header without two columns, a bad unit, a non-numeric value, x not
        increasing, too few points: the message names the file, line, column and value.
    """
    lines, encoding = read_lines(path)
    starts = _section_starts(lines)
    if "Scan Data" not in starts:
        raise SchemaError("no 'Scan Data' line: not a Dektak CSV export (expected blocks 'Scan Parameters', "
                          "'Analytical Results', 'Scan Data')", file=path)
    attrs = _scan_parameters(lines, starts, path)
    attrs.update(_analytical_results(lines, starts, path))
    h = next((i for i in range(starts["Scan Data"] + 1, len(lines)) if lines[i].strip()), None)
    if h is None:
        raise SchemaError("no column header after 'Scan Data'", file=path, line=starts["Scan Data"] + 1)
    header = [c.strip() for c in lines[h].split(",") if c.strip()]
    if len(header) < 2:
        raise SchemaError(f"column header {lines[h].strip()!r} has {len(header)} column(s); expected "
                          "'Lateral um,Raw Micrometer'", file=path, line=h + 1)
    (x_name, x_scale), (z_name, z_scale) = _column_units(header, path, h + 1)
    values, numbers = parse_rows(lines, h + 1, path=path, columns=[x_name, z_name])
    check_profile_rows(values[:, 0], numbers, path=path, column=x_name, header_line=h + 1, min_points=MIN_POINTS)
    decimals = max(len(lines[k - 1].split(",")[0].strip().partition(".")[2]) for k in numbers)
    x, how = _lateral(values[:, 0] * x_scale, decimals, x_scale, attrs)
    attrs.update(source=file_provenance(path), instrument="Bruker Dektak stylus profilometer (CSV export)",
                 file_encoding=encoding, x_coordinate=how, z_column=z_name)
    return make_profile(x, values[:, 1] * z_scale, attrs=attrs, label=str(path))
