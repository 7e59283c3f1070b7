"""The one registry of verification cases.

Cases come from three places, all through :func:`register_case`:

- the modules of :mod:`fivid.verify.cases` (each defines ``CASES``, a tuple of :class:`~fivid.verify.case.Case`),
  discovered, so adding a case touches no other file;
- installed plug-ins: an entry point in the group ``fivid.verification_cases`` whose object is a Case or a
  sequence of them (as xarray finds its backends);
- a caller's own case, registered at run time (a lab's check of its own rig model; the tests' toy cases).

The runner, the manual and the command line ask this module for cases and know none by name (STYLE rule 9).
"""

from __future__ import annotations

import importlib
import pkgutil
from importlib import metadata

from fivid.errors import ConfigError
from fivid.verify import cases as _cases_package
from fivid.verify.case import Case

__all__ = ["register_case", "unregister_case", "registered_cases", "select_cases", "ENTRY_POINT_GROUP"]

#: entry-point group of installed verification-case plug-ins
ENTRY_POINT_GROUP = "fivid.verification_cases"

_REGISTRY: dict[str, Case] = {}
_DISCOVERED = False


def register_case(case: Case, *, replace: bool = False) -> Case:
    """Add ``case`` to the catalogue; returns it.

    Raises
    ------
    ValueError
        Not a :class:`Case`, or its name is taken (and ``replace`` is false).
    """
    if not isinstance(case, Case):
        raise ValueError(f"register_case expects a fivid.verify.Case, got {type(case).__name__}")
    if case.name in _REGISTRY and not replace and _REGISTRY[case.name] is not case:
        raise ValueError(f"a verification case named {case.name!r} is already registered "
                         f"({_REGISTRY[case.name].title!r}); choose another name")
    _REGISTRY[case.name] = case
    return case


def unregister_case(name: str) -> None:
    """Remove the case ``name`` from the catalogue (no error when absent)."""
    _REGISTRY.pop(name, None)


def _discover() -> None:
    global _DISCOVERED
    if _DISCOVERED:
        return
    _DISCOVERED = True
    for info in sorted(pkgutil.iter_modules(_cases_package.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{_cases_package.__name__}.{info.name}")
        for case in module.CASES:
            register_case(case)
    for ep in metadata.entry_points(group=ENTRY_POINT_GROUP):
        obj = ep.load()
        for case in (obj if isinstance(obj, (list, tuple)) else (obj,)):
            register_case(case)


def registered_cases() -> list[Case]:
    """Every case of the catalogue, in catalogue order (shipped modules by name, then plug-ins, then run-time)."""
    _discover()
    return list(_REGISTRY.values())


def select_cases(names=None) -> list[Case]:
    """The cases called ``names`` (all when None or empty), in catalogue order.

    Raises
    ------
    ConfigError
        A name is not in the catalogue (the message lists the catalogue).
    """
    cases = registered_cases()
    if not names:
        return cases
    known = {c.name for c in cases}
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ConfigError(f"no verification case named {', '.join(repr(n) for n in unknown)}; the catalogue has: "
                          f"{', '.join(sorted(known))} (list them with 'fivid verify --list')", key="--case")
    wanted = set(names)
    return [c for c in cases if c.name in wanted]
