"""argparse ``type=`` factories shared by every sub-command: a value is checked before any work starts.

A refused value ends the command through argparse: exit 2 and one line on stderr,
``fivid COMMAND: error: argument OPTION: <what was wrong, the value, what is allowed>``.
"""

from __future__ import annotations

import argparse
import math
import re

from fivid.errors import FividError
from fivid.units import parse_quantity

__all__ = ["integer_at_least", "quantity", "QuantityArgument", "in_si"]

# canonical SI unit -> (the physical quantity it measures, units usual on a rig, for the messages)
_DIMENSIONS = {
    "Hz": ("frequency", ("Hz", "kHz")),
    "s": ("time", ("s", "ms")),
    "N": ("force", ("N", "mN")),
    "m s-1": ("velocity", ("mm/s", "m/s")),
    "m": ("length", ("um", "mm")),
    "Pa": ("pressure", ("MPa", "kPa")),
}
_BARE_NUMBER = re.compile(r"\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s*")


def integer_at_least(minimum: int):
    """An argparse ``type``: an integer >= ``minimum``, refused (exit 2, option and value named) before any work."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = None
        if value is None or value < minimum:
            raise argparse.ArgumentTypeError(f"must be an integer >= {minimum}, got {text!r}")
        return value

    parse.__name__ = f"integer >= {minimum}"
    return parse


class QuantityArgument(float):
    """A parsed command-line quantity: the value in SI units (a float) that remembers how it was written.

    ``text`` is the user's spelling (``"10 mm/s"``), kept for the ``history`` line, so that the command
    recorded in an output file is the command that was typed.
    """

    text: str

    def __new__(cls, value: float, text: str):
        self = super().__new__(cls, value)
        self.text = text
        return self

    def __reduce__(self):  # pickle (dask) as the pair it was built from
        return (QuantityArgument, (float(self), self.text))


def quantity(units: str, *, bare_numbers: bool = True, positive: bool = False, nonnegative: bool = False):
    """An argparse ``type``: a pint quantity such as ``'5 kHz'``, returned in ``units`` (SI) as a :class:`QuantityArgument`.

    Parameters
    ----------
    units : str
        The SI unit the value is returned in, one of ``Hz, s, N, m s-1, m, Pa``.
    bare_numbers : bool
        Whether a number without a unit is accepted, in ``units`` (default). False where a bare
        number is more likely a slip than SI (profile lengths, written in um on the instrument).
    positive, nonnegative : bool
        Refuse values <= 0 (``positive``) or < 0 (``nonnegative``).

    The value must be finite. A wrong dimension, an unknown unit, a missing unit (when
    ``bare_numbers`` is False) or a value out of range raises :class:`argparse.ArgumentTypeError`
    naming the value and the expected quantity; argparse adds the option and exits with status 2.
    """
    name, usual = _DIMENSIONS[units]
    allowed = (f"give a {name} with a unit such as {usual[0]} or {usual[1]}"
               + (f" (a bare number is in {units})" if bare_numbers else ""))

    def parse(text: str) -> QuantityArgument:
        if not bare_numbers and _BARE_NUMBER.fullmatch(text):
            raise argparse.ArgumentTypeError(f"{text!r} has no unit; write the {name} with one, e.g. "
                                             f"'{text} {usual[0]}' or '{text} {usual[1]}'")
        try:
            value = parse_quantity(text, units, default_units=units if bare_numbers else None)
        except FividError as exc:
            detail = exc.message.removeprefix(f"{text!r}: ").removesuffix("; give a unit of that dimension")
            if detail.startswith("cannot read"):
                detail = "not a number with a unit"
            raise argparse.ArgumentTypeError(f"{text!r} is not a {name} ({detail}); {allowed}") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{text!r} is not finite; {allowed}")
        if positive and not value > 0:
            raise argparse.ArgumentTypeError(f"must be a positive {name}, got {text!r}")
        if nonnegative and not value >= 0:
            raise argparse.ArgumentTypeError(f"must be a {name} >= 0, got {text!r}")
        return QuantityArgument(value, str(text))

    parse.__name__ = name  # argparse's fallback message says "invalid <name> value"
    return parse


def in_si(value) -> float | None:
    """A parsed :func:`quantity` argument (a :class:`QuantityArgument`, already in SI units) as a plain float;
    None (an option not given) stays None."""
    return None if value is None else float(value)
