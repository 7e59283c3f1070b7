"""``read_profile``: one entry point that picks the reader from the file's content and extension.

* Dektak CSV exports (a ``Scan Data`` block): :func:`fivid.surface.dektak.read_dektak_csv`;
* ``.x3p`` (ISO 25178-72 / ISO 5436-2): :func:`fivid.surface.x3p.read_x3p` (optional ``x3pio``);
* any other ``.csv``/``.txt``/``.dat``: :func:`fivid.surface.columns.read_profile_columns`
  (``x [unit], z [unit]`` header).
"""

from __future__ import annotations

from pathlib import Path

from fivid.errors import FividError
from fivid.io.input_files import check_text_input
from fivid.surface.columns import read_profile_columns
from fivid.surface.dektak import is_dektak_csv, read_dektak_csv
from fivid.surface.text import read_lines
from fivid.surface.x3p import read_x3p

__all__ = ["read_profile", "read_dektak_csv", "read_profile_columns", "read_x3p"]


def read_profile(path):
    """Read a surface profile from ``path`` (heights [m] over ``x`` [m]); the format is detected.

    Raises
    ------
    FividError
        The file does not exist, is a loop of symbolic links, is larger than
        :data:`fivid.io.input_files.MAX_TEXT_BYTES` or cannot be read; or any error of the chosen
        reader, naming the file, line, column and value.
    SchemaError
        A UTF-16/UTF-32 or binary file (the encoding named).
    """
    path = Path(path)
    if not path.exists() and not path.is_symlink():
        raise FividError("profile file not found", file=path)
    # size, link loops and encoding before the file is read whole (a 2 GB file took 4 GB of memory first)
    check_text_input(path, what="profile", text=path.suffix.lower() != ".x3p")
    if path.suffix.lower() == ".x3p":
        return read_x3p(path)
    lines, _ = read_lines(path)
    if is_dektak_csv(lines):
        return read_dektak_csv(path)
    return read_profile_columns(path)
