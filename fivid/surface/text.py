"""Text of profilometer exports: decoded bytes split into numbered lines.

Instrument exports mix encodings (a Dektak writes ``µ`` as the latin-1 byte 0xB5 inside an otherwise
ASCII file) and line ends (``\\r\\n`` and stray ``\\r``). Lines are numbered as editors and ``grep -n``
number them: 1-based, split at ``\\n``; carriage returns are dropped.
"""

from __future__ import annotations

import hashlib
import math
from pathlib import Path

import numpy as np

from fivid.errors import DataQualityError, FividError, SchemaError

__all__ = ["read_lines", "file_provenance", "parse_rows", "check_profile_rows"]


def read_lines(path) -> tuple[list[str], str]:
    """The lines of a text file (without line ends) and the encoding they were decoded with.

    UTF-8 is tried first; a file that is not valid UTF-8 is decoded as latin-1 (every byte is a
    character there, so decoding cannot fail). Raises :class:`~fivid.errors.FividError` naming the
    file when it cannot be read.
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise FividError(f"cannot read profile file: {exc.strerror or exc}", file=path) from None
    try:
        text, encoding = data.decode("utf-8"), "utf-8"
    except UnicodeDecodeError:
        text, encoding = data.decode("latin-1"), "latin-1"
    if text.startswith("\ufeff"):
        text = text[1:]
    return [line.replace("\r", "") for line in text.split("\n")], encoding


def file_provenance(path) -> str:
    """``"name sha256:<hex>"``: the ``source`` attr of a profile read from ``path``."""
    path = Path(path)
    return f"{path.name} sha256:{hashlib.sha256(path.read_bytes()).hexdigest()}"


def parse_rows(lines: list[str], first: int, *, path, columns: list[str], delimiter: str | None = ","):
    """Numeric rows of a data block: the first ``len(columns)`` fields of each non-blank line.

    Parameters
    ----------
    lines : list of str
        The file's lines (:func:`read_lines`).
    first : int
        0-based index of the first data line.
    path : path-like
        The file, for error messages.
    columns : list of str
        Names of the columns to read (as in the file's header), for error messages.
    delimiter : str or None
        Field separator; ``None`` splits at runs of white space.

    Returns
    -------
    values : ndarray, shape (n, len(columns))
    line_numbers : ndarray of int, shape (n,)
        1-based line number of each row.

    Raises
    ------
    SchemaError
        A row with fewer fields than columns (file and line named).
    DataQualityError
        A value that is not a finite number (file, line, column and value named).
    """
    rows, numbers = [], []
    for i in range(first, len(lines)):
        text = lines[i].strip()
        if not text:
            continue
        fields = text.split(delimiter)
        if len(fields) < len(columns):
            raise SchemaError(
                f"row has {len(fields)} field(s) ({text!r}); expected {len(columns)}: {', '.join(columns)}",
                file=path, line=i + 1,
            )
        row = []
        for name, field in zip(columns, fields):
            try:
                value = float(field)
            except ValueError:
                raise DataQualityError(f"value {field.strip()!r} is not a number", file=path, line=i + 1,
                                       column=name) from None
            if not math.isfinite(value):
                raise DataQualityError(f"value {field.strip()!r} is not a finite number", file=path, line=i + 1,
                                       column=name)
            row.append(value)
        rows.append(row)
        numbers.append(i + 1)
    return np.asarray(rows, dtype=np.float64).reshape(-1, len(columns)), np.asarray(numbers, dtype=int)


def check_profile_rows(x: np.ndarray, line_numbers: np.ndarray, *, path, column: str, header_line: int,
                       min_points: int) -> None:
    """Enough rows, and ``x`` strictly increasing; errors name the file, line, column and value."""
    if x.size < min_points:
        raise DataQualityError(f"{x.size} data row(s) after the header; a profile needs at least {min_points}",
                               file=path, line=header_line)
    bad = ~(np.diff(x) > 0)
    if bad.any():
        i = int(np.argmax(bad)) + 1
        raise DataQualityError(
            f"x is not strictly increasing: {float(x[i])!r} after {float(x[i - 1])!r} (line {int(line_numbers[i - 1])}); "
            "rows must be sorted by x with no repeated position",
            file=path, line=int(line_numbers[i]), column=column,
        )
