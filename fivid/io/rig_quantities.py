"""Quantities met while reading rig files: metadata values as RunDataset attributes.

Parsing and conversion are :mod:`fivid.units` (:func:`~fivid.units.parse_quantity`,
:func:`~fivid.units.sensitivity_factor`, :data:`~fivid.units.NUMBER`, re-exported here for the readers);
this module only knows which attribute is a quantity (the registry) and checks the text ones.
"""

from __future__ import annotations

import re

from fivid.errors import SchemaError
from fivid.schema import registry
from fivid.units import NUMBER, parse_quantity, sensitivity_factor

__all__ = ["attribute_units", "metadata_value", "sensitivity_factor", "NUMBER"]


def attribute_units(name: str) -> str | None:
    """The canonical unit of RunDataset attribute ``name`` (None when it is not a quantity)."""
    att = registry().attributes.get(name)
    return None if att is None else att.units


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
        if isinstance(value, str) and default_units and re.fullmatch(rf"\s*{NUMBER}\s*", value):
            decimal = ","  # a bare number (a file name's "v2,5") may use either mark, whatever the file's
        return float(parse_quantity(value, units, default_units=default_units, decimal=decimal))
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
