"""The kernels' on-disk cache is keyed on every kernel source (fivid._cache_kernels.KernelSourcesLocator).

numba keys a cached function on its own file only: a caller whose callee lives in another file keeps its stale
machine code after the callee's file changes (numba issue 1833). Oracle: a two-file package in a temporary folder,
run in fresh interpreters -- after an edit of the callee's file the caller returns the new value (it was
recompiled), and with the sources unchanged it is loaded from the cache, not compiled again.
"""

import os
import subprocess
import sys
import textwrap

import pytest

from fivid._cache_kernels import KernelSourcesLocator, kernel_sources_digest

pytestmark = pytest.mark.skipif(os.environ.get("NUMBA_DISABLE_JIT") == "1", reason="needs numba's compiler and cache")

_CALLER = """
from numba import njit

from kpkg._callee_kernels import value


@njit(cache=True)
def caller():
    return value() + 100
"""

_RUN = """
import sys
from fivid._cache_kernels import KernelSourcesLocator
KernelSourcesLocator.for_package(sys.argv[1] + "/kpkg").register()
sys.path.insert(0, sys.argv[1])
from kpkg._caller_kernels import caller
print(caller(), sum(caller.stats.cache_hits.values()),
      caller._cache.cache_path)
"""


def _write_callee(pkg, value):
    (pkg / "_callee_kernels.py").write_text(textwrap.dedent(f"""
        from numba import njit


        @njit(cache=True)
        def value():
            return {value}
        """), encoding="utf-8")


def _run(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    out = subprocess.run([sys.executable, "-c", _RUN, str(tmp_path)], env=env, capture_output=True, text=True,
                         check=True).stdout.split()
    return int(out[0]), int(out[1]), out[2]


def test_editing_a_callee_in_another_file_recompiles_the_caller(tmp_path):
    pkg = tmp_path / "kpkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("", encoding="utf-8")
    (pkg / "_caller_kernels.py").write_text(_CALLER, encoding="utf-8")
    _write_callee(pkg, 1)
    first, hits, folder = _run(tmp_path)
    assert (first, hits) == (101, 0)  # compiled
    again, hits, same = _run(tmp_path)
    assert (again, hits, same) == (101, 1, folder)  # unchanged sources: loaded from the cache
    _write_callee(pkg, 2)  # the caller's own file is untouched
    edited, hits, moved = _run(tmp_path)
    assert edited == 102 and hits == 0  # recompiled against the new callee, not the stale cached 101
    assert moved != folder and moved.startswith(str(pkg / "__pycache__"))


def test_the_cache_folder_is_keyed_on_every_kernel_source(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "_x_kernels.py").write_text("X = 1\n", encoding="utf-8")
    (tmp_path / "notes.py").write_text("", encoding="utf-8")
    before = kernel_sources_digest(tmp_path)
    (tmp_path / "notes.py").write_text("changed = True\n", encoding="utf-8")  # not a kernel source
    assert kernel_sources_digest(tmp_path) == before
    (tmp_path / "a" / "_x_kernels.py").write_text("X = 2\n", encoding="utf-8")
    assert kernel_sources_digest(tmp_path) != before


def test_fivid_kernels_are_cached_under_the_digest_of_fivid_kernel_sources():
    from fivid.solver._reduced_kernels import run_modal_steps

    path = run_modal_steps._cache.cache_path
    assert os.path.basename(path) == f"kernels-{KernelSourcesLocator.digest}"
