"""Units at the boundary: parse quantities and unit strings with pint, convert to SI.

SI inside fivid. Where data enter (CSV headers, metadata lines, configs such as
``velocity: 10 mm/s``) strings are parsed here; outputs carry CF/UDUNITS unit strings taken from
the variable registry (:mod:`fivid.schema`).

Two conventions of the field that pint does not know by itself:

* ``g`` is gram to pint but *standard gravity* (9.80665 m s-2) on an accelerometer channel. When the
  expected quantity is an acceleration, ``g`` (and ``gn``, ``g0``) mean standard gravity.
* UDUNITS writes ``m s-2``; pint wants ``m * s ** -2``. Both are accepted.

pint is imported on first use, not at ``import fivid``.
"""

from __future__ import annotations

import functools
import math
import re

from fivid.errors import UnitError

__all__ = [
    "unit_registry",
    "parse_quantity",
    "conversion",
    "convert",
    "is_compatible",
]

# UDUNITS-style exponents: "m s-2", "m2", "Hz-1" -> "m s**-2", "m**2", "Hz**-1"
_EXPONENT = re.compile(r"(?<=[A-Za-zµμΩ°%])(-?\d+)(?![\d.])")
_GRAVITY_WORDS = {"g", "gn", "g0", "g_n", "g_0", "G"}


@functools.lru_cache(maxsize=None)
def unit_registry():
    """The pint :class:`~pint.UnitRegistry` fivid uses (created once, on first use)."""
    import pint

    ureg = pint.UnitRegistry(autoconvert_offset_to_baseunit=True)
    # Typographic variants met in DAQ exports and profilometers.
    ureg.define("micron_ = micrometer = µ_m")
    return ureg


def _normalise(text: str) -> str:
    s = text.strip()
    s = s.replace("μ", "u").replace("µ", "u")  # greek mu and micro sign -> ASCII prefix
    s = s.replace("·", "*").replace("⋅", "*").replace("²", "**2").replace("³", "**3")
    s = s.replace("^", "**")
    s = _EXPONENT.sub(lambda m: "**" + m.group(1), s)
    s = re.sub(r"(?<=[\w)])\s+(?=[A-Za-z(])", " * ", s)  # "m s**-2" -> "m * s**-2"
    return s


def _is_acceleration(expected: str | None) -> bool:
    if expected is None:
        return False
    try:
        return unit_registry()(_normalise(expected)).dimensionality == {"[length]": 1, "[time]": -2}
    except Exception:
        return False


def _parse(text: str, expected: str | None):
    """Parse ``text`` into a pint Quantity; raises UnitError."""
    ureg = unit_registry()
    s = text.strip()
    if not s:
        raise UnitError("empty unit")
    if _is_acceleration(expected):
        m = re.fullmatch(r"\s*([-+0-9.eE]*)\s*(g|gn|g0|g_n|g_0|G)\s*", s)
        if m is not None:
            number = m.group(1) or "1"
            try:
                return float(number) * ureg.standard_gravity
            except ValueError:
                pass
    try:
        q = ureg.Quantity(_normalise(s))
    except Exception as exc:  # pint raises several unrelated types
        raise UnitError(f"cannot parse {text!r} as a quantity or unit ({type(exc).__name__}: {exc})") from None
    if not isinstance(q, ureg.Quantity):  # a bare number
        q = ureg.Quantity(float(q), "dimensionless")
    return q


def _check_compatible(q, text: str, expected: str):
    ureg = unit_registry()
    target = _parse(expected, None)
    if q.dimensionality != target.dimensionality:
        raise UnitError(
            f"unit {text!r} ({q.dimensionality}) is not compatible with {expected!r} "
            f"({target.dimensionality}); give a unit of that dimension"
        )
    return target


@functools.lru_cache(maxsize=256)
def conversion(from_units: str, to_units: str) -> tuple[float, float]:
    """Scale and offset turning values in ``from_units`` into ``to_units``: ``y = scale * x + offset``.

    Cached (pint parsing costs ~0.5 ms and a batch of rig files repeats the same few units);
    errors are not cached. Raises :class:`~fivid.errors.UnitError` when the units are unknown or
    incompatible.

    Examples
    --------
    >>> conversion("g", "m s-2")
    (9.80665, 0.0)
    >>> conversion("mm/s", "m s-1")
    (0.001, 0.0)
    """
    q = _parse(from_units, to_units)
    target = _check_compatible(q, from_units, to_units)
    ureg = unit_registry()
    tu = target.units
    scale_t = float(target.magnitude)
    zero = ureg.Quantity(0.0 * q.magnitude, q.units).to(tu).magnitude / scale_t
    one = ureg.Quantity(1.0 * q.magnitude, q.units).to(tu).magnitude / scale_t
    scale = float(one - zero)
    offset = float(zero)
    if not (math.isfinite(scale) and math.isfinite(offset)):
        raise UnitError(f"conversion from {from_units!r} to {to_units!r} is not finite")
    return scale, offset


def convert(values, from_units: str, to_units: str):
    """Values in ``from_units`` expressed in ``to_units`` (arrays are converted in one pass).

    The result is a new array (or float); the input is not modified.
    """
    scale, offset = conversion(from_units, to_units)
    return values * scale + offset if offset else values * scale


def parse_quantity(text, to_units: str, *, default_units: str | None = None) -> float:
    """A quantity such as ``"10 mm/s"`` as a float in ``to_units``.

    Parameters
    ----------
    text : str or float
        The quantity. A bare number is taken in ``default_units`` if given, otherwise rejected
        (ambiguous), unless ``to_units`` is dimensionless.
    to_units : str
        Target unit (usually the canonical SI unit from the registry).
    default_units : str, optional
        Unit of a bare number.

    Raises
    ------
    UnitError
        Unknown unit, incompatible dimension, or a bare number where a unit is needed.
    """
    if isinstance(text, bool):
        raise UnitError(f"expected a quantity in units compatible with {to_units!r}, got {text!r}")
    if isinstance(text, (int, float)):
        number, unit = float(text), None
    else:
        s = str(text).strip()
        m = re.fullmatch(r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*)", s)
        if m is None:
            raise UnitError(f"cannot read {text!r} as a number with a unit, e.g. '10 mm/s'")
        number, unit = float(m.group(1)), (m.group(2).strip() or None)
    if unit is None:
        target_dimless = _parse(to_units, None).dimensionless
        if default_units is not None:
            unit = default_units
        elif target_dimless:
            return number
        else:
            raise UnitError(
                f"{text!r} has no unit; write it with one, e.g. '{text} {to_units}'"
            )
    try:
        scale, offset = conversion(unit, to_units)
    except UnitError as exc:
        raise UnitError(f"{text!r}: {exc.message}") from None
    return number * scale + offset


def is_compatible(units: str, to_units: str) -> bool:
    """Whether ``units`` can be converted to ``to_units``."""
    try:
        conversion(units, to_units)
    except UnitError:
        return False
    return True
