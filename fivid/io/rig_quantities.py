"""Quantities met while reading rig files: metadata values with units, sensor sensitivities."""

from __future__ import annotations

import math
import re

from fivid.errors import SchemaError, UnitError
from fivid.schema import registry
from fivid.units import conversion, parse_quantity

__all__ = ["attribute_units", "metadata_value", "sensitivity_factor", "NUMBER"]

#: A number as written in rig files, with a decimal point or a decimal comma.
NUMBER = r"[-+]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][-+]?\d+)?"


def attribute_units(name: str) -> str | None:
    """The canonical unit of RunDataset attribute ``name`` (None when it is not a quantity)."""
    att = registry().attributes.get(name)
    return None if att is None else att.units


def sensitivity_factor(column_units: str, sensitivity: str, target_units: str) -> float:
    """Factor turning a transducer signal in ``column_units`` into ``target_units``.

    Parameters
    ----------
    column_units : str
        Unit of the recorded signal (``"mV"``).
    sensitivity : str
        ``"<number> <signal unit>/<measured unit>"``, e.g. ``"100 mV/g"`` or ``"10.2 mV/(m/s^2)"``;
        ``g`` in the measured unit is standard gravity.
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


def metadata_value(name: str, value, *, default_units: str | None = None, decimal: str = "."):
    """A metadata value as stored in a RunDataset's attrs: SI float for quantity attributes, else str.

    Parameters
    ----------
    name : str
        Attribute name (``sliding_velocity``, ``run_id``, ...).
    value : str or number
        As written (``"10 mm/s"``; a bare number only with ``default_units``).
    default_units : str, optional
        Unit of a bare number (from the profile).
    decimal : str
        Decimal mark of the file (``","`` turns ``"0,8 um"`` into 0.8 µm).

    Raises
    ------
    UnitError, SchemaError
        Unknown or incompatible unit, missing unit, or an invalid ``run_id``.
    """
    units = attribute_units(name)
    if units is not None:
        text = value
        if isinstance(value, str) and decimal == ",":
            text = re.sub(r"(?<=\d),(?=\d)", ".", value)
        if isinstance(text, str) and default_units and re.fullmatch(rf"\s*{NUMBER}\s*", text):
            text = text.strip().replace(",", ".")
        return float(parse_quantity(text, units, default_units=default_units))
    if isinstance(value, (dict, list)) or value is None:
        raise SchemaError(f"{name!r} must be a single value, got {value!r}")
    text = str(value).strip()
    if name == "run_id" and not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._+-]*", text):
        raise SchemaError(
            f"run_id {text!r} cannot name a file: use letters, digits and . _ + - (starting with a letter or digit)"
        )
    if not text:
        raise SchemaError(f"{name!r} is empty")
    return text
