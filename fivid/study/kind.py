"""Study kinds as plug-ins: one protocol and one registry (STYLE rule 9; xarray's backend entry points are the
model).

A *kind* is what a study does at each point and with all of them: its typed config section, the plain data its
workers need, ``evaluate`` (one point -> a small Dataset), the study-level CEA where it has one, ``summarise``
(its own keys of ``summary.json``) and its report section. The runner (:mod:`fivid.study.runner`), the config
loader (:mod:`fivid.study.config`) and the report (:mod:`fivid.study.report`) call these methods and know no
kind by name. The shipped kinds are registered by :mod:`fivid.study.kinds`; another package adds one with
:func:`register_study_kind` or, without importing fivid first, with an entry point in the group
:data:`ENTRY_POINT_GROUP` whose object is the kind (docs/studies.md, "Adding a study kind").
"""

from __future__ import annotations

import logging
from typing import Any, Protocol, runtime_checkable

from fivid.errors import ConfigError

__all__ = ["StudyKind", "ENTRY_POINT_GROUP", "register_study_kind", "unregister_study_kind", "registered_kinds",
           "study_kind", "guess_kind"]

log = logging.getLogger("fivid")

#: entry-point group of third-party study kinds (``[project.entry-points."fivid.study_kinds"]``)
ENTRY_POINT_GROUP = "fivid.study_kinds"


@runtime_checkable
class StudyKind(Protocol):
    """What a study kind provides (attributes and methods; see the shipped kinds in :mod:`fivid.study.kinds`).

    Attributes
    ----------
    name : str
        The registry key: the study config's ``kind:`` (and, for a lumped kind, ``system.lumped:``).
    description : str
        One line for listings and errors.
    lumped : bool
        The system is the kind's own model, parametrised by its config section (``system.parameters``), not an FE
        model file (``system.model``).
    section : tuple of (str, str) or None
        Where its typed config section lives in the study file, e.g. ``("points", "roughness")`` or
        ``("system", "parameters")``; None: the kind has none.
    config : type or None
        The pydantic model (:class:`fivid.config_layer.ConfigModel`) of that section.
    point_keys : tuple of (str, str)
        ``(variable of a point Dataset, key in summary.json's points)`` copied into the summary per point.
    """

    name: str
    description: str
    lumped: bool
    section: tuple[str, str] | None
    config: type | None
    point_keys: tuple[tuple[str, str], ...]

    def guess(self, data: dict) -> bool:
        """Whether a study config without ``kind:`` (the raw mapping) is one of this kind."""

    def check(self, cfg) -> list[tuple[str, str]]:
        """Problems ``(key path, message)`` of a validated :class:`fivid.study.config.StudyConfig` for this kind."""

    def settings(self, section) -> dict:
        """The validated section (an instance of ``config``, or None) as plain SI data for the workers; may raise
        :class:`~fivid.errors.ConfigError` (its key relative to the section)."""

    def system(self, study) -> dict:
        """Plain (picklable) data the workers need besides the point's tasks, computed once per study."""

    def evaluate(self, system: dict, tasks: dict, conditions: dict):
        """One point: an :class:`xarray.Dataset` without a ``point`` dimension (``conditions``: ``{axis: SI}``)."""

    def cea(self, study, mu) -> dict:
        """The study-level CEA at the friction coefficients ``mu``: ``{"eigenvalues" (mu, mode), "critical_mu"
        (mode), "partner" (mode, 0-based, -1 none)}``."""

    def summarise(self, study, ds, points: list[dict]) -> dict:
        """The kind's own keys of ``summary.json`` from the assembled Dataset and the summary's point dicts."""

    def report(self, page, ds, summary: dict) -> None:
        """Add the kind's report section to ``page`` (:class:`fivid.report.html.Page`)."""


_KINDS: dict[str, Any] = {}
_entry_points_loaded = False

_REQUIRED = ("name", "description", "lumped", "section", "config", "point_keys", "guess", "check", "settings",
             "system", "evaluate", "cea", "summarise", "report")


def register_study_kind(kind, *, replace: bool = False):
    """Add ``kind`` to the registry (after those already there: :func:`guess_kind` asks in this order); returns it.

    Raises ValueError when an attribute of :class:`StudyKind` is missing or the name is taken (unless ``replace``).
    """
    missing = [a for a in _REQUIRED if not hasattr(kind, a)]
    if missing:
        raise ValueError(f"study kind {kind!r} lacks {', '.join(missing)} (see fivid.study.kind.StudyKind)")
    if kind.name in _KINDS and not replace and _KINDS[kind.name] is not kind:
        raise ValueError(f"a study kind named {kind.name!r} is registered already ({_KINDS[kind.name]!r})")
    _KINDS[kind.name] = kind
    return kind


def unregister_study_kind(name: str) -> None:
    """Remove a kind from the registry (a test's toy kind, say)."""
    _KINDS.pop(name, None)


def _load_entry_points() -> None:
    global _entry_points_loaded
    if _entry_points_loaded:
        return
    _entry_points_loaded = True
    from importlib.metadata import entry_points

    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in _KINDS:
            continue
        try:
            register_study_kind(ep.load())
        except Exception as exc:  # noqa: BLE001 - a broken third-party kind must not break the others
            log.warning("study kind %r from entry point %s could not be loaded: %s", ep.name, ep.value, exc)


def registered_kinds() -> dict[str, Any]:
    """Name -> kind, shipped kinds first, then those of entry points and :func:`register_study_kind`."""
    _load_entry_points()
    return dict(_KINDS)


def study_kind(name: str, *, key: str = "kind"):
    """The kind registered as ``name``; :class:`ConfigError` naming ``key`` and the kinds there are otherwise."""
    kinds = registered_kinds()
    if name not in kinds:
        raise ConfigError(f"unknown study kind {name!r}; registered kinds: {', '.join(kinds)}", key=key)
    return kinds[name]


def guess_kind(data: dict):
    """The first registered kind whose ``guess`` accepts a study config without ``kind:`` (xarray's
    ``guess_can_open``), None if none does."""
    for kind in registered_kinds().values():
        if not kind.lumped and kind.guess(data):
            return kind
    return None
