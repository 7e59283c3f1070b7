"""constraints.txt pins every dependency fivid needs at the version the tests run with (issue 32).

The oracle is the test environment itself, what ``pip freeze`` lists (``importlib.metadata``, which
pip reads too): starting from pyproject.toml's requirements and every extra, each requirement is
followed through the installed distributions' own requirements (their markers evaluated, extras
such as ``dask[distributed]`` followed), and every distribution reached that is installed must be
pinned at its installed version. A dependency added by another change (with its own new dependencies)
is covered as soon as it is in pyproject.toml and installed; a requirement that is not installed here
(an extra left out) cannot be pinned from this environment and is skipped.
"""

from __future__ import annotations

import sys
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

ROOT = Path(__file__).resolve().parents[2]

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    tomllib = pytest.importorskip("tomli")


def _pins() -> dict:
    pins = {}
    for number, line in enumerate((ROOT / "constraints.txt").read_text().splitlines(), start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        name, sep, version = text.partition("==")
        assert sep, f"constraints.txt:{number}: {line!r} is not a 'name==version' pin"
        assert canonicalize_name(name) not in pins, f"constraints.txt:{number}: {name} is pinned twice"
        pins[canonicalize_name(name)] = version.strip()
    return pins


def _required_installed() -> dict:
    """``name -> installed version`` of every installed distribution fivid's requirements reach."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    roots = list(project["dependencies"]) + [r for reqs in project["optional-dependencies"].values() for r in reqs]
    stack = [Requirement(r) for r in roots]
    found, done = {}, set()
    while stack:
        req = stack.pop()
        name = canonicalize_name(req.name)
        if name == "fivid" or (name, frozenset(req.extras)) in done:
            continue
        done.add((name, frozenset(req.extras)))
        try:
            dist = metadata.distribution(req.name)
        except metadata.PackageNotFoundError:
            continue
        found[name] = dist.version
        environments = [{"extra": e} for e in req.extras] or [{"extra": ""}]
        for text in dist.requires or []:
            sub = Requirement(text)
            if sub.marker is None or any(sub.marker.evaluate(env) for env in environments):
                stack.append(sub)
    return found


def test_every_required_distribution_is_pinned_at_its_installed_version():
    pins, needed = _pins(), _required_installed()
    assert len(needed) > 40  # the walk reaches numpy, scipy, xarray, dask's, the DAQ readers' dependencies ...
    unpinned = sorted(f"{n}=={v}" for n, v in needed.items() if n not in pins)
    wrong = sorted(f"{n}: pinned {pins[n]}, installed {v}" for n, v in needed.items() if n in pins and pins[n] != v)
    assert not unpinned, f"constraints.txt lacks these installed dependencies: {', '.join(unpinned)}"
    assert not wrong, f"constraints.txt pins other versions than the test environment's: {'; '.join(wrong)}"


def test_no_pin_disagrees_with_the_environment():
    """A pin of an installed distribution (needed or not) that is not the installed version is stale."""
    stale = []
    for name, version in _pins().items():
        try:
            installed = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
        if installed != version:
            stale.append(f"{name}: pinned {version}, installed {installed}")
    assert not stale, "; ".join(stale)
