"""Documentation that cannot rot: every ``>>>`` example runs, every public name has a docstring.

- ``test_docstring_examples``: ``doctest`` over every module of the package (an importlib walk; ``__main__``
  modules are left out: importing one runs the CLI), ELLIPSIS | NORMALIZE_WHITESPACE, numpy's print options
  fixed to its defaults (an example must not depend on what another test set), each docstring's examples in
  their own namespace (independent of each other).
- ``test_public_names_have_docstrings``: the public names are the functions and classes named in a module's
  ``__all__`` (or, in a module without ``__all__``, the ones it defines with a name not starting with ``_``),
  in modules whose dotted path has no private part, plus the public methods and properties those classes
  define. A dataclass's generated ``Name(field, ...)`` text does not count as a docstring.

The shell and YAML examples of README.md and docs/ are run by tests/docs/test_doc_commands.py.
"""

from __future__ import annotations

import doctest
import importlib
import inspect
import pkgutil

import numpy as np
import pytest

import fivid

FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _module_names() -> list[str]:
    return sorted(m.name for m in pkgutil.walk_packages(fivid.__path__, "fivid.")
                  if not m.name.endswith("__main__"))


MODULES = ["fivid"] + _module_names()


def _doctests():
    finder = doctest.DocTestFinder(exclude_empty=True)
    out = []
    for name in MODULES:
        for test in finder.find(importlib.import_module(name)):
            if test.examples and test.name not in {t.name for t in out}:
                out.append(test)
    return out


def test_the_walk_finds_the_package():
    """The walk sees the whole package (a broken walk would make the tests below vacuous)."""
    assert len(MODULES) > 100, MODULES
    assert {"fivid.signal.welch", "fivid.solver", "fivid.units"} <= set(MODULES)


def test_docstring_examples():
    tests = _doctests()
    assert len(tests) >= 10, [t.name for t in tests]  # the package has examples; finding none is a bug here
    saved = np.get_printoptions()
    failures = []
    try:
        for test in tests:
            np.set_printoptions(**_NUMPY_DEFAULTS)
            runner = doctest.DocTestRunner(optionflags=FLAGS)
            report: list[str] = []
            result = runner.run(test, out=report.append, clear_globs=True)
            if result.failed:
                failures.append("".join(report))
    finally:
        np.set_printoptions(**saved)
    assert not failures, "\n".join(failures)


_NUMPY_DEFAULTS = {"precision": 8, "threshold": 1000, "edgeitems": 3, "linewidth": 75, "suppress": False,
                   "nanstr": "nan", "infstr": "inf", "sign": "-", "floatmode": "maxprec", "legacy": False}


def _has_doc(obj) -> bool:
    doc = obj.__doc__
    if not doc or not doc.strip():
        return False
    if inspect.isclass(obj):
        if doc.startswith(obj.__name__ + "("):  # dataclass / namedtuple generated text
            return False
        if any(doc is getattr(base, "__doc__", None) for base in obj.__mro__[1:]):  # inherited
            return False
    return True


def public_names() -> list[tuple[str, object]]:
    """``(dotted name, object)`` of every public function, class, method and property of the package."""
    seen: set[tuple[str, str]] = set()
    out = []
    for name in MODULES:
        if any(part.startswith("_") for part in name.split(".")):
            continue
        mod = importlib.import_module(name)
        names = getattr(mod, "__all__", None)
        if names is None:
            names = [n for n, o in vars(mod).items() if not n.startswith("_")
                     and (inspect.isfunction(o) or inspect.isclass(o)) and getattr(o, "__module__", None) == name]
        for n in names:
            obj = getattr(mod, n)
            if not (inspect.isfunction(obj) or inspect.isclass(obj)):
                continue  # constants: documented by a '#:' comment, they cannot carry a docstring
            key = (obj.__module__, obj.__qualname__)
            if key in seen:
                continue
            seen.add(key)
            out.append((".".join(key), obj))
            if inspect.isclass(obj):
                for attr, value in vars(obj).items():
                    if attr.startswith("_"):
                        continue
                    if isinstance(value, property):
                        value = value.fget
                    elif isinstance(value, (staticmethod, classmethod)):
                        value = value.__func__
                    if inspect.isfunction(value):
                        out.append((".".join(key) + "." + attr, value))
    return out


def test_public_names_have_docstrings():
    names = public_names()
    assert len(names) > 300, len(names)  # the package's API; far fewer means the walk broke
    missing = [name for name, obj in names if not _has_doc(obj)]
    assert not missing, f"{len(missing)} public name(s) without a docstring (one line: what it is, in its units): " \
                        + ", ".join(missing)


def test_the_docstring_check_can_fail():
    """The checker flags what it must: no docstring, a dataclass's generated text, an inherited one."""
    from dataclasses import dataclass

    def bare():
        pass

    @dataclass
    class Plain:
        x: float

    class Child(ValueError):
        pass

    assert not _has_doc(bare) and not _has_doc(Plain) and not _has_doc(Child)
    assert _has_doc(public_names)


@pytest.mark.parametrize("name", ["fivid.signal.welch"])
def test_a_module_with_examples_is_collected(name):
    """A module known to have ``>>>`` examples yields doctests (the finder is not silently excluding them)."""
    assert any(t.name.startswith(name) for t in _doctests())
