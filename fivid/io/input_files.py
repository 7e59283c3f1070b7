"""Checks of an input file before it is read: it exists, is no symbolic-link loop, fits, and is text.

Readers that take a whole file into memory (profilometer exports, hysteresis recordings) call
:func:`check_text_input` first, so that a 2 GB file picked by mistake is refused in a millisecond
from its size, instead of after filling 4 GB of memory; and so that a UTF-16 export (Excel's
"Unicode text", some instrument software) is named as such instead of as "binary content".
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from fivid.errors import FividError, SchemaError

__all__ = ["MAX_TEXT_BYTES", "check_text_input", "stat_input", "binary_content", "format_size"]

#: Largest text recording read whole [bytes]: 256 MiB is some 10 million rows of two or three numbers,
#: far beyond a profilometer trace (10^4-10^6 points) or a hysteresis record; the parsed rows take
#: several times the file's size in memory.
MAX_TEXT_BYTES = 256 * 2**20

_BOMS = ((b"\xff\xfe\x00\x00", "UTF-32 (little-endian)"), (b"\x00\x00\xfe\xff", "UTF-32 (big-endian)"),
         (b"\xff\xfe", "UTF-16 (little-endian)"), (b"\xfe\xff", "UTF-16 (big-endian)"))


def format_size(n: int) -> str:
    """``n`` bytes as ``'2.15 GB (2147483648 bytes)'`` (decimal units, as file managers show them)."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.3g} {unit} ({n} bytes)"
    return f"{n} bytes"


def stat_input(path) -> os.stat_result:
    """``os.stat`` of an input file, with errors a person can act on.

    Raises
    ------
    FividError
        No such file; a symbolic link that points to itself through a loop; a folder or another
        non-regular file; a file that cannot be read (permissions).
    """
    path = Path(path)
    try:
        info = path.stat()
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise FividError("the path is a loop of symbolic links (too many levels: a link that leads back to "
                             "itself) and never reaches a file; point the link at the file itself", file=path) from None
        if exc.errno == errno.ENOENT:
            what = f"a symbolic link to {os.readlink(path)!r}, which does not exist" if path.is_symlink() else ""
            raise FividError(f"no such file{': ' + what if what else ''}", file=path) from None
        raise FividError(f"cannot read the file ({exc.strerror or exc})", file=path) from None
    if stat.S_ISDIR(info.st_mode):
        raise FividError("not a regular file: it is a folder; give a file", file=path)
    if not stat.S_ISREG(info.st_mode):
        raise FividError("not a regular file (a device, pipe or socket); give a file", file=path)
    return info


def binary_content(head: bytes) -> str | None:
    """Why ``head`` (a file's first bytes) is not 8-bit text, naming UTF-16/32 when it is that; or None."""
    for bom, name in _BOMS:
        if head.startswith(bom):
            return f"{name} text (byte-order mark {bom.hex(' ').upper()})"
    if b"\x00" not in head:
        return None
    even, odd = head[0::2], head[1::2]
    if even and odd.count(0) > 0.9 * len(odd) and even.count(0) < 0.1 * len(even):
        return "UTF-16 (little-endian) text without a byte-order mark (every second byte is NUL)"
    if odd and even.count(0) > 0.9 * len(even) and odd.count(0) < 0.1 * len(odd):
        return "UTF-16 (big-endian) text without a byte-order mark (every second byte is NUL)"
    return "binary content (NUL bytes)"


def check_text_input(path, *, what: str, max_bytes: int = MAX_TEXT_BYTES, text: bool = True) -> Path:
    """Refuse, before reading it, a file that is missing, a link loop, too large, or not 8-bit text.

    Parameters
    ----------
    path : str or path-like
    what : str
        What the file should be (``"profile"``, ``"hysteresis recording"``), for the messages.
    max_bytes : int
        Largest size read whole [bytes] (default :data:`MAX_TEXT_BYTES`).
    text : bool, default True
        Check that the content is 8-bit text (False for a binary format such as X3P: size only).

    Returns
    -------
    Path

    Raises
    ------
    FividError
        See :func:`stat_input`; or the file is larger than ``max_bytes`` (the size and the limit named).
    SchemaError
        The file is empty, UTF-16/UTF-32 (the encoding named, with how to convert) or binary.
    """
    path = Path(path)
    size = stat_input(path).st_size
    if size > max_bytes:
        raise FividError(f"the file is {format_size(size)}, larger than the {format_size(max_bytes)} a {what} may "
                         f"have (it is read whole into memory): is it the right file? Split or decimate it",
                         file=path)
    if size == 0:
        raise SchemaError("the file is empty", file=path, line=1)
    if not text:
        return path
    with open(path, "rb") as f:
        head = f.read(65536)
    problem = binary_content(head)
    if problem is not None:
        if "text" in problem:
            raise SchemaError(f"the {what} is {problem}, not UTF-8; save it as UTF-8 (Excel: 'CSV UTF-8'; or "
                              f"iconv -f {problem.split()[0]} -t UTF-8 {path.name} > new.csv)", file=path, line=1)
        raise SchemaError(f"not a text file ({problem}); give the {what} as text (CSV or JSON)", file=path)
    return path
