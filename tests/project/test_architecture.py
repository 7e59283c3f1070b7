"""Imports flow down the layers of DESIGN §1 and form no cycle; kernels import nothing from fivid; import fivid is
light."""

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[2] / "fivid"

# DESIGN §1. A module may import from its own layer or below.
LAYERS = {
    "cli": 5,
    "pipeline": 4, "study": 4, "verify": 4,
    "identify": 3, "score": 3, "solver": 3, "report": 3, "damper": 3, "ema": 3, "updating": 3, "execution": 3,
    "io": 2, "signal": 2, "friction": 2, "fe": 2, "surface": 2, "contact": 2,
    "schema": 1, "units": 1, "errors": 1, "storage": 1, "builtin": 1, "config_layer": 1,
    "__init__": 1, "__main__": 5,
}


def _layer(module_parts: tuple[str, ...]) -> int:
    if module_parts[-1] == "_kernels" or module_parts[-1].endswith("_kernels"):
        return 0
    top = module_parts[0]
    if top not in LAYERS:
        raise AssertionError(f"fivid.{top} has no layer in tests/project/test_architecture.py: add it (DESIGN §1)")
    return LAYERS[top]


def _modules():
    for path in sorted(PKG.rglob("*.py")):
        rel = path.relative_to(PKG).with_suffix("")
        parts = rel.parts
        if parts[-1] == "__init__" and len(parts) > 1:
            parts = parts[:-1]
        yield path, parts


def _fivid_imports(path: Path, parts: tuple[str, ...]):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name == "fivid" or alias.name.startswith("fivid."):
                    yield node.lineno, tuple(alias.name.split(".")[1:])
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                raise AssertionError(f"{path}:{node.lineno}: relative import; use absolute imports (STYLE)")
            mod = node.module or ""
            if mod == "fivid":
                for alias in node.names:
                    yield node.lineno, (alias.name,)
            elif mod.startswith("fivid."):
                base = tuple(mod.split(".")[1:])
                # ``from fivid.solver import _kernels``: the module imported is the kernel module itself
                kernels = [a.name for a in node.names if a.name.endswith("_kernels")]
                for name in kernels:
                    yield node.lineno, base + (name,)
                if len(kernels) < len(node.names):
                    yield node.lineno, base


def test_imports_flow_down_the_layers():
    bad = []
    for path, parts in _modules():
        own = _layer(parts)
        for lineno, target in _fivid_imports(path, parts):
            if not target:
                continue
            if own == 0 and not target[-1].endswith("_kernels"):  # kernels may call other kernels only
                bad.append(f"{path.relative_to(PKG.parent)}:{lineno}: a kernel module imports fivid.{'.'.join(target)}")
                continue
            if target[0] == "__version__":
                continue
            if target[0] == parts[0]:
                continue  # same package
            their = _layer(target)
            if their > own:
                bad.append(
                    f"{path.relative_to(PKG.parent)}:{lineno}: fivid.{'.'.join(parts)} (L{own}) imports "
                    f"fivid.{'.'.join(target)} (L{their})"
                )
    assert not bad, "imports against the layers of DESIGN §1:\n" + "\n".join(bad)


def _imported_names(path: Path):
    """(line, ("a", "b", "name")) for every ``import fivid.a.b`` / ``from fivid.a.b import name`` anywhere."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "fivid":
                    yield node.lineno, tuple(alias.name.split(".")[1:])
        elif isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").split(".")[0] == "fivid":
            for alias in node.names:
                yield node.lineno, tuple(node.module.split(".")[1:]) + (alias.name,)


def _import_graph() -> dict[tuple[str, ...], dict[tuple[str, ...], list[int]]]:
    """Every fivid module -> the fivid modules it imports, with the lines: module level, class and function bodies
    alike (a function-level import is an edge too: it runs, later), inside a package as well as across packages.
    ``from fivid.a import b`` is an edge to the module ``a.b`` when it is one, else to ``a``; importing ``a.b``
    also runs the ``__init__`` of ``a`` (an edge to ``a``) unless the importer is inside ``a`` already."""
    modules = dict((parts, path) for path, parts in _modules())
    graph = {}
    for parts, path in modules.items():
        edges = graph.setdefault(parts, {})
        for lineno, target in _imported_names(path):
            while target and target not in modules:  # ``from fivid.a.b import name``: the module a.b
                target = target[:-1]
            if not target or target == parts:
                continue
            for i in range(1, len(target) + 1):
                pkg = target[:i]
                if i < len(target) and parts[:i] == pkg:
                    continue  # the importer's own enclosing package is initialised already
                if pkg != parts:
                    edges.setdefault(pkg, []).append(lineno)
    return graph


def _cycles(graph) -> list[list]:
    """The strongly connected components of more than one module (Tarjan), each in a stable order."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


@pytest.mark.parametrize("graph, n", [
    ({("a",): {("b",): [1]}, ("b",): {("a",): [2]}}, 1),
    ({("a",): {("b",): [1]}, ("b",): {("c",): [1]}, ("c",): {("a",): [1]}, ("d",): {("a",): [1]}}, 1),
    ({("a",): {("b",): [1], ("c",): [1]}, ("b",): {("c",): [1]}, ("c",): {}}, 0),
    ({("a",): {("b",): [1]}, ("b",): {("a",): [1]}, ("c",): {("d",): [1]}, ("d",): {("c",): [1]}}, 2),
])
def test_the_cycle_finder_finds_cycles(graph, n):
    """The cycle check below is an oracle only if it finds a cycle of any length and nothing in a DAG."""
    assert len(_cycles(graph)) == n


def test_the_import_graph_sees_function_bodies_and_packages():
    """The graph has the edges that hid the old cycles: a function-level import (fe.contact's of fe.static), an
    import inside a package, and ``__init__`` edges (importing fivid.study.runner runs fivid/study/__init__.py)."""
    graph = _import_graph()
    assert ("fe", "static") in graph[("fe", "contact")]
    assert ("study",) in graph[("pipeline", "discretisation")]
    assert ("study", "runner") in graph[("study",)]


def test_no_import_cycles():
    """fivid's modules import each other without a cycle: every import (module level or in a function), every
    package's ``__init__``, inside a package and across packages. A cycle is broken by moving the shared piece
    down into a module both sides import (docs/architecture.md), never by hiding the import in a function."""
    graph = _import_graph()
    lines = []
    for comp in _cycles(graph):
        members = set(comp)
        lines.append("cycle: " + ", ".join("fivid." + ".".join(m) for m in comp))
        for m in comp:
            for t, linenos in sorted(graph[m].items()):
                if t in members:
                    lines.append(f"    fivid/{'/'.join(m)}.py lines {linenos} -> fivid.{'.'.join(t)}")
    assert not lines, "import cycles:\n" + "\n".join(lines)


def test_docs_package_graph_matches_the_code():
    """docs/architecture.md's package graph (which package imports which) is the import graph of the code."""
    import re

    graph = _import_graph()
    actual = {}
    for m, targets in graph.items():
        if len(m) == 1 and not (PKG / m[0]).is_dir():
            continue  # top-level modules (errors, units, ...): the layer table places them
        deps = {t[0] for t in targets if t[0] != m[0] and (PKG / t[0]).is_dir()}
        actual.setdefault(m[0], set()).update(deps)
    text = (PKG.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    documented = {pkg: set(re.findall(r"`(\w+)`", deps))
                  for pkg, deps in re.findall(r"^\| `(\w+)` \| (.*) \|$", text, flags=re.M)}
    assert documented == actual, "redraw the package graph of docs/architecture.md:\n" + "\n".join(
        f"| `{p}` | {', '.join(f'`{d}`' for d in sorted(actual[p])) or '-'} |" for p in sorted(actual))


def _kernel_modules():
    return [(path, parts) for path, parts in _modules() if _layer(parts) == 0]


def test_kernel_modules_are_found():
    """The kernel checks below see the solver's kernel modules (one per concern): a rename cannot empty them."""
    names = {".".join(parts) for _, parts in _kernel_modules()}
    assert {"solver._kernels", "solver._stencil_kernels", "solver._contact_kernels", "solver._loop_kernels",
            "solver._reduced_kernels", "contact._kernels"} <= names, names


def test_kernels_import_only_numpy_and_numba():
    """Kernel modules (``_kernels.py``, ``_*_kernels.py``) import numpy, numba, math and, for the kernels' argument
    groups, collections (namedtuple); from fivid only other kernel modules. fivid/_cache_kernels.py also reads the
    kernel sources to key numba's cache on them (hashlib, os, pathlib)."""
    bad = []
    for path, parts in _kernel_modules():
        allowed = {"numpy", "numba", "math", "collections", "__future__"}
        if parts == ("_cache_kernels",):
            allowed |= {"hashlib", "os", "pathlib"}
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [node.module or ""]
            for n in names:
                if n.split(".")[0] not in allowed and not (
                        n.startswith("fivid.") and n.endswith("_kernels")):
                    bad.append(f"{path}:{node.lineno}: imports {n}")
    assert not bad, "\n".join(bad)


#: kernel modules passing their own fastmath/parallel options (none: every kernel uses the shared decorators)
_OWN_JIT_OPTIONS: set[str] = set()


def test_kernel_compilation_setting_is_defined_once():
    """fastmath and parallel are chosen once, by the decorators of fivid/solver/_kernels.py; no other kernel module
    passes them to numba itself (STYLE: no fastmath flags scattered per function)."""
    bad = []
    for path, parts in _kernel_modules():
        name = ".".join(parts)
        if name == "solver._kernels" or name in _OWN_JIT_OPTIONS:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call):
                for kw in node.keywords:
                    if kw.arg in {"fastmath", "parallel"}:
                        bad.append(f"{path}:{node.lineno}: {kw.arg}= (use the decorators of fivid.solver._kernels)")
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("heavy", ["numba", "dask", "distributed", "matplotlib", "pyfftw"])
def test_import_fivid_is_light(heavy):
    code = f"import sys, fivid, fivid.cli; fivid.cli.build_parser(); print({heavy!r} in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False", f"import fivid / fivid --help imports {heavy}"


def test_docs_layer_table_matches_the_code():
    """docs/architecture.md's layer table is the layer map above, and its L0 row names exactly the kernel modules
    that exist -- so the documented architecture cannot drift from the code."""
    import re

    text = (PKG.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    rows = dict(re.findall(r"^\| L(\d) \| (.+) \|$", text, flags=re.M))
    documented = {name: int(layer) for layer, cells in rows.items() if layer != "0"
                  for name in re.findall(r"`([\w]+)`", cells)}
    assert documented == LAYERS
    kernels = set(re.findall(r"`([\w/]+\.py)`", rows["0"]))
    actual = {str(p.relative_to(PKG)) for p in PKG.rglob("*_kernels.py")}
    assert kernels == actual


#: the Welch estimators of scipy.signal that fivid.signal wraps (one home for spectra: issue 29 item 1)
_SPECTRAL = {"welch", "csd"}
_SCIPY_SIGNAL = {"scipy.signal", "scipy.signal.spectral", "scipy.signal._spectral_py"}


def _scipy_welch_uses(source: str) -> list[tuple[int, str]]:
    """Lines of ``source`` that import or call ``scipy.signal.welch``/``csd`` in any spelling (module level and
    function bodies): ``from scipy.signal import welch [as w]``, ``scipy.signal.welch(...)``,
    ``import scipy.signal as ss; ss.csd(...)``, ``from scipy import signal; signal.welch(...)``, or the
    function fetched with ``getattr(module, "welch")``."""
    tree = ast.parse(source)
    modules = set()  # names bound to scipy.signal
    roots = set()  # names bound to scipy
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name in _SCIPY_SIGNAL and a.asname:
                    modules.add(a.asname)
                elif a.name == "scipy" or a.name.startswith("scipy."):
                    roots.add(a.asname or "scipy")
        elif isinstance(node, ast.ImportFrom) and node.module == "scipy":
            modules.update(a.asname or a.name for a in node.names if a.name == "signal")

    def is_scipy_signal(expr) -> bool:
        if isinstance(expr, ast.Name):
            return expr.id in modules
        return (isinstance(expr, ast.Attribute) and expr.attr in {"signal", "spectral", "_spectral_py"}
                and (is_scipy_signal(expr.value) or isinstance(expr.value, ast.Name) and expr.value.id in roots))

    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module in _SCIPY_SIGNAL:
            found += [(node.lineno, f"from {node.module} import {a.name}") for a in node.names
                      if a.name in _SPECTRAL or a.name == "*"]
        elif isinstance(node, ast.Attribute) and node.attr in _SPECTRAL and is_scipy_signal(node.value):
            found.append((node.lineno, f"{ast.unparse(node)}"))
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "getattr"
              and len(node.args) >= 2 and is_scipy_signal(node.args[0]) and isinstance(node.args[1], ast.Constant)
              and node.args[1].value in _SPECTRAL):
            found.append((node.lineno, ast.unparse(node)))
    return found


@pytest.mark.parametrize("source, n", [
    ("def f(x):\n    from scipy.signal import welch\n    return welch(x)\n", 1),
    ("import scipy.signal\ndef f(x):\n    return scipy.signal.csd(x, x)\n", 1),
    ("import scipy.signal as ss\nclass A:\n    def f(self, x):\n        return ss.welch(x)\n", 1),
    ("from scipy import signal as sig\nf = lambda x: sig.welch(x)\n", 1),
    ("import scipy\ny = scipy.signal.welch\n", 1),
    ("from scipy.signal import csd as c, welch\n", 2),
    ("import scipy.signal\nw = getattr(scipy.signal, 'welch')\n", 1),
    ("from scipy.signal import find_peaks, get_window\nimport scipy.signal\nscipy.signal.spectrogram\n", 0),
    ("from fivid.signal import csd, welch_psd\ncsd(a, b)\n", 0),
])
def test_the_welch_detector_sees_every_spelling(source, n):
    """The checker below is an oracle only if it finds the call however it is written (and nothing else)."""
    assert len(_scipy_welch_uses(source)) == n, _scipy_welch_uses(source)


def test_spectra_have_one_home():
    """No scipy.signal.welch/csd call or import outside fivid/signal/ (module level or in a function body): every
    PSD and cross-spectrum goes through fivid.signal (welch_psd, csd, welch_density), so its settings are the ones
    recorded and one estimator serves the scores, the studies, the solver checks and the surface statistics."""
    bad = []
    for path, parts in _modules():
        if parts[0] == "signal":
            continue
        if parts[:3] == ("verify", "cases", "signal_welch"):  # the case comparing fivid.signal with scipy's welch
            continue
        for lineno, what in _scipy_welch_uses(path.read_text(encoding="utf-8")):
            bad.append(f"{path.relative_to(PKG.parent)}:{lineno}: {what} (use fivid.signal)")
    assert not bad, "spectral estimators outside fivid/signal/:\n" + "\n".join(bad)


#: the most parameters a public function takes (issue 29 item 4): more travel as frozen dataclasses (the groups of
#: fivid.solver.simulate, EnvelopeSpectrum, ...); the numba kernels (``_*kernels.py``) take arrays and scalars only
MAX_PARAMETERS = 10


def _parameter_counts(source: str) -> list[tuple[int, str, int]]:
    """``(line, name, parameters)`` of every public function of a module's ``source``: a module-level function or a
    method of a module-level class, neither named with a leading underscore (a public class's ``__init__`` counts:
    it is the constructor's signature). Parameters are all of them (positional-only, positional, ``*args``,
    keyword-only, ``**kwargs``) but a method's ``self``/``cls``."""
    functions = (ast.FunctionDef, ast.AsyncFunctionDef)
    found = []
    for node in ast.parse(source).body:
        if isinstance(node, functions):
            members = [(node, node.name, False)]
        elif isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
            members = [(f, f"{node.name}.{f.name}", True) for f in node.body if isinstance(f, functions)]
        else:
            continue
        for f, name, method in members:
            if f.name.startswith("_") and f.name != "__init__":
                continue
            a = f.args
            names = [p.arg for p in a.posonlyargs + a.args + a.kwonlyargs]
            names += [p.arg for p in (a.vararg, a.kwarg) if p is not None]
            static = any(isinstance(d, ast.Name) and d.id == "staticmethod" for d in f.decorator_list)
            if method and not static and names and names[0] in ("self", "cls"):
                names = names[1:]
            found.append((f.lineno, name, len(names)))
    return found


@pytest.mark.parametrize("source, counts", [
    ("def f(a, b=1, *c, d, e=2, **f): pass\n", [6]),
    ("def f(a, /, b, *, c): pass\nasync def g(x): pass\n", [3, 1]),
    ("class A:\n    def __init__(self, a, b): pass\n    def m(self, x): pass\n    @classmethod\n"
     "    def k(cls, y): pass\n    @staticmethod\n    def s(self, z): pass\n", [2, 1, 1, 2]),
    ("def _private(" + ", ".join(f"a{i}" for i in range(20)) + "): pass\nclass _P:\n    def m(self, a): pass\n"
     "class A:\n    def _m(self, a): pass\ndef outer():\n    def inner(a, b): pass\n", [0]),
])
def test_the_parameter_counter_counts_what_a_caller_passes(source, counts):
    """The checker below is an oracle only if it counts every kind of parameter and skips exactly the private."""
    assert [n for _, _, n in _parameter_counts(source)] == counts


def test_public_functions_take_at_most_ten_parameters():
    """No public function outside the numba kernel modules takes more than :data:`MAX_PARAMETERS` parameters:
    related inputs travel together as frozen dataclasses (``simulate(model, condition, friction, *, schedule,
    integration, output)``), not as long keyword lists passed from layer to layer."""
    bad = []
    for path, parts in _modules():
        if parts[-1].startswith("_") and parts[-1].endswith("kernels"):
            continue
        for lineno, name, n in _parameter_counts(path.read_text(encoding="utf-8")):
            if n > MAX_PARAMETERS:
                bad.append(f"{path.relative_to(PKG.parent)}:{lineno}: {name} takes {n} parameters")
    assert not bad, f"public functions with more than {MAX_PARAMETERS} parameters (group them in dataclasses):\n" + \
        "\n".join(bad)


#: The fivid modules a function body may import (issue 29 item 6, STYLE 7): each defers a heavy third-party module
#: that ``import fivid`` and ``fivid --help`` must not pay for, and the importer does not load at module level
#: (test_lazy_imports_defer_what_they_say below checks both in a fresh interpreter). Every kernel module
#: (``_kernels.py``, ``_*_kernels.py``) is one too: importing it compiles or loads numba. All other fivid imports
#: sit at module top, so the import graph shows the architecture; the command modules of ``cli/commands/`` are
#: exempt (``fivid --help`` imports them all to build the parser).
_LAZY_TARGETS = {
    "config_layer": "pydantic",  # the typed-config base: pydantic models
    "io.netcdf": "pydantic",  # runs fivid/io/__init__.py, whose rig-profile and DAQ-channel configs are pydantic
    "solver.timestep": "pydantic",  # runs fivid/solver/__init__.py (the solver's typed options are pydantic)
    "solver.output": "numba",  # the run dataset is unpacked with the kernels' record layout
}


def _is_kernel_module(target: tuple[str, ...]) -> bool:
    return target[-1] == "_kernels" or (target[-1].startswith("_") and target[-1].endswith("_kernels"))


def _lazy_reason(target: tuple[str, ...]) -> str | None:
    """The heavy module a function-level import of fivid.``target`` may defer, or None: it belongs at module top."""
    return "numba" if _is_kernel_module(target) else _LAZY_TARGETS.get(".".join(target))


def _function_level_imports(source: str, modules) -> list[tuple[int, tuple[str, ...], str]]:
    """``(line, module, line text)`` of every fivid import in a function or method body of ``source`` (nested
    functions, branches and ``try`` blocks too; module level and ``if TYPE_CHECKING:`` are not function level).
    ``from fivid.a import b`` imports the module ``a.b`` when ``modules`` has it, else (a name of) ``a``; the line
    text is the statement's first line and the one above, where a ``# lazy: pulls X`` comment may stand."""
    lines = source.splitlines()
    found = []

    def visit(node, in_function):
        for child in ast.iter_child_nodes(node):
            inside = in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
            if in_function and isinstance(child, (ast.Import, ast.ImportFrom)):
                targets = []
                if isinstance(child, ast.Import):
                    targets = [tuple(a.name.split(".")[1:]) for a in child.names if a.name.split(".")[0] == "fivid"]
                elif not child.level and (child.module or "").split(".")[0] == "fivid":
                    base = tuple(child.module.split(".")[1:])
                    targets = [base + (a.name,) if base + (a.name,) in modules else base for a in child.names]
                text = "\n".join(lines[max(child.lineno - 2, 0):child.lineno])
                found.extend((child.lineno, t, text) for t in dict.fromkeys(targets))
            visit(child, inside)

    visit(ast.parse(source), False)
    return found


def _misplaced_imports(source: str, modules) -> list[str]:
    """The function-level fivid imports of ``source`` that belong at module top: the target defers nothing heavy
    (:func:`_lazy_reason`), or the line lacks its ``# lazy: pulls X`` comment naming what it defers."""
    bad = []
    for lineno, target, text in _function_level_imports(source, modules):
        reason = _lazy_reason(target) if target else None
        if reason is None:
            bad.append(f"{lineno}: fivid.{'.'.join(target)} (move it to module top)")
        elif f"# lazy: pulls {reason}" not in text:
            bad.append(f"{lineno}: fivid.{'.'.join(target)} (mark it '# lazy: pulls {reason}')")
    return bad


_FAKE_MODULES = {("fe",), ("fe", "model"), ("solver",), ("solver", "_kernels"), ("config_layer",), ("signal",),
                 ("signal", "welch")}


@pytest.mark.parametrize("source, n", [
    ("def f():\n    from fivid.fe import model\n", 1),
    ("class A:\n    def m(self):\n        import fivid.signal.welch\n", 1),
    ("def f():\n    def g():\n        from fivid.signal import welch_psd\n    return g\n", 1),
    ("def f():\n    try:\n        from fivid.fe import model\n    except ImportError:\n        pass\n", 1),
    ("def f(x):\n    if x:\n        from fivid import fe\n", 1),
    ("def f():\n    from fivid.solver import _kernels as K\n", 1),  # lazy, but not marked
    ("def f():\n    from fivid.config_layer import read_yaml  # lazy: pulls numba\n", 1),  # the wrong reason
    ("def f():\n    from fivid.config_layer import read_yaml  # lazy: pulls pydantic\n"
     "    from fivid.fe.model import Model  # lazy: pulls pydantic\n", 1),  # fe.model defers nothing
    ("def f():\n    from fivid.solver import _kernels as K, simulate  # lazy: pulls numba\n", 1),
    ("def f():\n    from fivid.solver import _kernels as K  # lazy: pulls numba\n", 0),
    ("def f():\n    # lazy: pulls pydantic\n    from fivid.config_layer import read_yaml\n", 0),
    ("from fivid.fe import model\nimport fivid.signal\ndef f():\n    return model\n", 0),
    ("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from fivid.fe.model import Model\n", 0),
    ("def f():\n    import numpy as np\n    from scipy import signal\n    return np, signal\n", 0),
])
def test_the_lazy_import_checker_sees_every_function_level_import(source, n):
    """The checker below is an oracle only if it finds a misplaced fivid import wherever a function hides it (method,
    nested function, branch, try), accepts a lazy one only with its reason, and flags nothing at module level."""
    assert len(_misplaced_imports(source, _FAKE_MODULES)) == n, _misplaced_imports(source, _FAKE_MODULES)


def test_fivid_imports_are_at_module_top():
    """Every fivid-internal import sits at module top, except those in :data:`_LAZY_TARGETS` (and kernel modules),
    each marked ``# lazy: pulls X``, and those of the command modules (cli/commands/). A new one in a function
    body either moves up (the cycle test then proves the move safe) or, if it defers a heavy library, joins the
    table with its reason."""
    modules = {parts for _, parts in _modules()}
    bad = []
    for path, parts in _modules():
        if parts[:2] == ("cli", "commands"):
            continue
        bad += [f"{path.relative_to(PKG.parent)}:{line}" for line in
                _misplaced_imports(path.read_text(encoding="utf-8"), modules)]
    assert not bad, "fivid imports in function bodies (STYLE 7: module top):\n" + "\n".join(bad)


_PROBE = """\
import importlib, json, os, sys
HEAVY = {heavy!r}
for name in ("numpy", "scipy.linalg", "scipy.sparse.linalg", "scipy.signal", "scipy.optimize", "scipy.stats",
             "scipy.interpolate", "pandas", "xarray", "yaml"):  # loaded once, before the forks (none is heavy)
    importlib.import_module(name)
assert not [h for h in HEAVY if h in sys.modules], "a preloaded library brings a heavy one: the probe would be void"
out = {{}}
for name in {names!r}:
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # a fresh sys.modules per module: the child imports it and reports what came with it
        os.close(r)
        importlib.import_module(name)
        os.write(w, json.dumps([h for h in HEAVY if h in sys.modules]).encode())
        os._exit(0)
    os.close(w)
    data = b""
    while chunk := os.read(r, 4096):
        data += chunk
    os.waitpid(pid, 0)
    out[name] = json.loads(data or b"null")
print(json.dumps(out))
"""


def test_lazy_imports_defer_what_they_say():
    """Each function-level import left defers what its comment says: the target, imported alone, loads the heavy
    module, and the importer, imported alone, does not (else the import gains nothing and belongs at module top)."""
    modules = {parts for _, parts in _modules()}
    pairs = set()
    for path, parts in _modules():
        if parts[:2] == ("cli", "commands"):
            continue
        for _, target, _ in _function_level_imports(path.read_text(encoding="utf-8"), modules):
            if _lazy_reason(target):
                pairs.add((parts, target, _lazy_reason(target)))
    assert pairs, "no lazy import found: the checker no longer sees them"
    bad = []
    for _, target, _ in pairs:  # a kernel module is numba code: it imports numba or another kernel module
        if _is_kernel_module(target):
            source = (PKG / Path(*target)).with_suffix(".py").read_text(encoding="utf-8")
            if not any(isinstance(n, (ast.Import, ast.ImportFrom)) and any(
                    "numba" in name.split(".") or name.endswith("_kernels")
                    for name in ([a.name for a in n.names] if isinstance(n, ast.Import) else
                                 [n.module or ""] + [a.name for a in n.names]))
                       for n in ast.walk(ast.parse(source))):
                bad.append(f"fivid.{'.'.join(target)} imports no numba: a plain import at module top will do")
    names = sorted({"fivid." + ".".join(m) for a, b, _ in pairs for m in (a, b)
                    if not (m == b and _is_kernel_module(b))})  # the importers, and the table's targets
    code = _PROBE.format(heavy=sorted({h for *_, h in pairs}), names=names)
    loaded = __import__("json").loads(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                                     check=True).stdout)
    for importer, target, heavy in sorted(pairs):
        a, b = "fivid." + ".".join(importer), "fivid." + ".".join(target)
        if b in loaded and heavy not in loaded[b]:
            bad.append(f"{b} does not load {heavy}: {a} may import it at module top")
        if heavy in loaded[a]:
            bad.append(f"{a} loads {heavy} already: its import of {b} belongs at module top")
    assert not bad, "\n".join(bad)
