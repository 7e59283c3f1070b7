"""UDUNITS strings of spectral quantities: kept as an import path; the definitions live in :mod:`fivid.units`
(the one home of unit parsing and conversion)."""

from fivid.units import power_units, product_units, ratio_units

__all__ = ["power_units", "product_units", "ratio_units"]
