"""Units at the boundary: parse quantities and unit strings with pint, convert to SI.

SI inside fivid. Where data enter (CSV headers, metadata lines, configs such as
``velocity: 10 mm/s``) strings are parsed here; outputs carry CF/UDUNITS unit strings taken from
the variable registry (:mod:`fivid.schema`).

Two conventions of the field that pint does not know by itself:

* ``g`` is gram to pint but *standard gravity* (9.80665 m s-2) on an accelerometer channel. When the
  expected quantity is an acceleration, ``g`` (and ``gn``, ``g0``) mean standard gravity.
* UDUNITS writes ``m s-2``; pint wants ``m * s ** -2``. Both are accepted.

This module is the one place units are parsed and converted (layer L1): quantities with a decimal point or
comma (:func:`parse_quantity`, :data:`NUMBER`), transducer sensitivities (:func:`sensitivity_factor`) and
the UDUNITS strings of spectral quantities built from their signals' units (:func:`power_units`,
:func:`product_units`, :func:`ratio_units`). :mod:`fivid.io.rig_quantities` only calls into it (the former
``fivid.signal.unit_strings`` is gone: its helpers are defined here).

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
    "sensitivity_factor",
    "power_units",
    "product_units",
    "ratio_units",
    "NUMBER",
]

#: A number as written in data files, with a decimal point or a decimal comma.
NUMBER = r"[-+]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][-+]?\d+)?"
_NUMBER_POINT = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"

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
    if "," in s:  # pint would read "1,5 mm" as 1 x 5 mm; no unit has a comma
        raise UnitError(f"{text!r} has a comma, which no unit contains; a decimal comma is read only where the "
                        "file declares it (decimal: ','); otherwise write the number with a decimal point")
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


def parse_quantity(text, to_units: str, *, default_units: str | None = None, decimal: str = ".") -> float:
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
    decimal : {".", ","}, default "."
        Decimal mark of ``text``: with ``","`` the number may be written ``"0,8 um"`` (or ``"0.8 um"``).

    Raises
    ------
    UnitError
        Unknown unit, incompatible dimension, or a bare number where a unit is needed.

    Examples
    --------
    >>> parse_quantity("10 mm/s", "m s-1"), parse_quantity("0,8 um", "m", decimal=",")
    (0.01, 8e-07)
    """
    if isinstance(text, bool):
        raise UnitError(f"expected a quantity in units compatible with {to_units!r}, got {text!r}")
    if decimal not in (".", ","):
        raise UnitError(f"decimal mark must be '.' or ',', got {decimal!r}")
    if isinstance(text, (int, float)):
        number, unit = float(text), None
    else:
        s = str(text).strip()
        m = re.fullmatch(rf"({NUMBER if decimal == ',' else _NUMBER_POINT})\s*(.*)", s)
        if m is None:
            raise UnitError(f"cannot read {text!r} as a number with a unit, e.g. '10 mm/s'")
        number, unit = float(m.group(1).replace(",", ".")), (m.group(2).strip() or None)
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


def sensitivity_factor(column_units: str, sensitivity: str, target_units: str) -> float:
    """Factor turning a transducer signal in ``column_units`` into ``target_units``.

    Parameters
    ----------
    column_units : str
        Unit of the recorded signal (``"mV"``).
    sensitivity : str
        ``"<number> <signal unit>/<measured unit>"``, e.g. ``"100 mV/g"`` or ``"10.2 mV/(m/s^2)"``
        (decimal point or comma); ``g`` in the measured unit is standard gravity.
    target_units : str
        Canonical unit of the measured quantity (``"m s-2"``).

    Returns
    -------
    float
        ``si_value = factor * signal``: for 1 mV at 100 mV/g into m s-2, 9.80665e-2.

    Raises
    ------
    UnitError
        The sensitivity is not ``number unit/unit``, is zero, or its units do not fit.
    """
    m = re.fullmatch(rf"\s*({NUMBER})\s*(.+?)\s*", str(sensitivity))
    if m is None or "/" not in m.group(2):
        raise UnitError(
            f"sensitivity {sensitivity!r} must be '<number> <signal unit>/<measured unit>', e.g. '100 mV/g'"
        )
    value = float(m.group(1).replace(",", "."))
    if value == 0 or not math.isfinite(value):
        raise UnitError(f"sensitivity {sensitivity!r} must be a finite, non-zero number")
    signal_units, measured_units = (s.strip() for s in m.group(2).split("/", 1))
    if measured_units.startswith("(") and measured_units.endswith(")"):
        measured_units = measured_units[1:-1].strip()
    try:
        to_signal, off1 = conversion(column_units, signal_units)
    except UnitError as exc:
        raise UnitError(f"the column's unit {column_units!r} does not fit sensitivity {sensitivity!r}: {exc.message}") from None
    try:
        to_target, off2 = conversion(measured_units, target_units)
    except UnitError as exc:
        raise UnitError(f"sensitivity {sensitivity!r} does not measure a quantity in {target_units!r}: {exc.message}") from None
    if off1 or off2:
        raise UnitError(f"sensitivity {sensitivity!r}: affine units (with an offset) are not allowed here")
    return to_signal / value * to_target


# ---- UDUNITS strings of derived (spectral) quantities ------------------------------------------------------
# ``m s-2`` -> PSD ``m2 s-4 Hz-1``; a force and an acceleration -> CSD ``N m s-2 Hz-1``, FRF ``m s-2 N-1``.
# Strings written as a product of powers (the registry's style) are combined symbol by symbol; any other
# form (``m/s``) is bracketed rather than guessed. Pure string algebra: pint is not needed.

_TOKEN = re.compile(r"([A-Za-z%µμ]+)(-?\d+)?")


def _exponents(units: str) -> dict[str, int] | None:
    """``"m s-2"`` -> {"m": 1, "s": -2}; None when ``units`` is not a product of powers."""
    out: dict[str, int] = {}
    text = units.strip()
    if text in ("1", ""):
        return out
    for token in text.split():
        m = _TOKEN.fullmatch(token)
        if m is None:
            return None
        out[m.group(1)] = out.get(m.group(1), 0) + int(m.group(2) or 1)
    return out


def _combine(terms: list[tuple[str, int]]) -> str:
    total: dict[str, int] = {}
    for units, sign in terms:
        exps = _exponents(units)
        if exps is None:
            exps = {f"({units})": 1}
        for s, e in exps.items():
            total[s] = total.get(s, 0) + sign * e
    return " ".join(s if e == 1 else f"{s}{e}" for s, e in total.items() if e != 0) or "1"


def product_units(*units: str) -> str:
    """Units of a cross-spectral density of signals in ``units``: ``("N", "m s-2")`` -> ``"N m s-2 Hz-1"``."""
    return _combine([(u, 1) for u in units] + [("Hz", -1)])


def power_units(units: str) -> str:
    """Units of the spectral density of a signal in ``units``: ``"m s-2"`` -> ``"m2 s-4 Hz-1"``."""
    return product_units(units, units)


def ratio_units(numerator: str, denominator: str) -> str:
    """Units of ``numerator / denominator``: ``("m s-2", "N")`` -> ``"m s-2 N-1"``."""
    return _combine([(numerator, 1), (denominator, -1)])
