"""UDUNITS strings of spectral quantities built from their signals' units.

``m s-2`` → PSD ``m2 s-4 Hz-1``; a force and an acceleration → CSD ``N m s-2 Hz-1``, FRF ``m s-2 N-1``.
Strings written as a product of powers (the registry's style) are combined symbol by symbol; any
other form (``m/s``) is bracketed rather than guessed.
"""

from __future__ import annotations

import re

__all__ = ["power_units", "product_units", "ratio_units"]

_TOKEN = re.compile(r"([A-Za-z%µμ]+)(-?\d+)?")


def _exponents(units: str) -> dict[str, int] | None:
    """``"m s-2"`` → {"m": 1, "s": -2}; None when ``units`` is not a product of powers."""
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


def _format(exps: dict[str, int]) -> str:
    return " ".join(s if e == 1 else f"{s}{e}" for s, e in exps.items() if e != 0) or "1"


def _combine(terms: list[tuple[str, int]]) -> str:
    total: dict[str, int] = {}
    for units, sign in terms:
        exps = _exponents(units)
        if exps is None:
            exps = {f"({units})": 1}
        for s, e in exps.items():
            total[s] = total.get(s, 0) + sign * e
    return _format(total)


def product_units(*units: str) -> str:
    """Units of a cross-spectral density of signals in ``units``: ``("N", "m s-2")`` → ``"N m s-2 Hz-1"``."""
    return _combine([(u, 1) for u in units] + [("Hz", -1)])


def power_units(units: str) -> str:
    """Units of the spectral density of a signal in ``units``: ``"m s-2"`` → ``"m2 s-4 Hz-1"``."""
    return product_units(units, units)


def ratio_units(numerator: str, denominator: str) -> str:
    """Units of ``numerator / denominator``: ``("m s-2", "N")`` → ``"m s-2 N-1"``."""
    return _combine([(numerator, 1), (denominator, -1)])
