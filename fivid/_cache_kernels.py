"""Where numba caches fivid's kernels on disk: a folder keyed on every kernel source of the package (layer L0).

numba keys a cached function on its own file only, so a kernel whose callee (or a constant it reads) lives in
another file would load stale machine code after that file changes (numba issue 1833: e.g. an edit of
``fivid/contact/_kernels.py`` left ``run_steps`` of ``fivid/solver/_loop_kernels.py`` cached with the old contact
law). :class:`KernelSourcesLocator` puts the cache of every function defined in the fivid package in a subfolder
``kernels-<digest>`` of numba's own choice of folder (``__pycache__`` next to the source; numba's user-wide
cache folder for a read-only installation; ``NUMBA_CACHE_DIR`` when set), the digest being the sha256 of every
``_*kernels.py`` source of the package (:func:`kernel_sources_digest`, computed once per process: about a
millisecond). An edit of any kernel file therefore recompiles every kernel once; an unchanged tree loads them
all from the cache. Older ``kernels-*`` folders are left in place (``__pycache__`` is disposable).

Importing this module registers the locator with numba (first in ``numba.core.caching.CacheImpl``'s list of
locators; it answers only for files inside the package): the kernel modules import it before they decorate
(:mod:`fivid.solver._kernels` does for the solver's). ``NUMBA_CACHE_LOCATOR_CLASSES`` overrides it as it overrides
numba's own.
"""

import hashlib
import os
from pathlib import Path

from numba.core.caching import CacheImpl, _CacheLocator

__all__ = ["KernelSourcesLocator", "kernel_sources_digest"]


def kernel_sources_digest(root) -> str:
    """sha256 (hex, 16 characters) of the paths and contents of every ``_*kernels.py`` file below ``root``."""
    root = Path(root)
    h = hashlib.sha256()
    for path in sorted(root.rglob("_*kernels.py")):
        h.update(path.relative_to(root).as_posix().encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


class KernelSourcesLocator(_CacheLocator):
    """numba cache locator of the functions defined below :attr:`root`: the folder numba's own locators choose
    for the file, plus ``kernels-<digest of root's kernel sources>`` (see the module docstring).

    numba asks each class of ``CacheImpl._locator_classes`` in turn (:meth:`from_function`); this one answers only
    for files below :attr:`root` and leaves every other function to numba's own locators.
    """

    #: package folder whose functions this locator keys (the fivid package)
    root = str(Path(__file__).resolve().parent)
    #: :func:`kernel_sources_digest` of :attr:`root`, computed when the class is created
    digest = kernel_sources_digest(root)

    def __init__(self, inner):
        self._inner = inner
        self._py_file = getattr(inner, "_py_file", None)
        self._cache_path = os.path.join(inner.get_cache_path(), f"kernels-{self.digest}")

    def get_cache_path(self):
        return self._cache_path

    def get_source_stamp(self):
        return self._inner.get_source_stamp()

    def get_disambiguator(self):
        return self._inner.get_disambiguator()

    @classmethod
    def for_package(cls, root) -> type:
        """A locator class keying the functions below ``root`` on ``root``'s kernel sources (tests, other
        packages)."""
        root = str(Path(root).resolve())
        return type(cls.__name__, (cls,), {"root": root, "digest": kernel_sources_digest(root)})

    @classmethod
    def register(cls) -> None:
        """Put this locator first in numba's list (once per root)."""
        classes = CacheImpl._locator_classes
        if not any(getattr(c, "root", None) == cls.root for c in classes):
            classes.insert(0, cls)

    @classmethod
    def from_function(cls, py_func, py_file):
        try:
            inside = os.path.commonpath([os.path.abspath(py_file), cls.root]) == cls.root
        except ValueError:  # another drive (Windows)
            inside = False
        if not inside:
            return None
        for other in CacheImpl._locator_classes:
            if isinstance(other, type) and issubclass(other, KernelSourcesLocator):
                continue
            inner = other.from_function(py_func, py_file)
            if inner is None:
                continue
            self = cls(inner)
            try:
                self.ensure_cache_path()
            except OSError:  # that folder is writable but not our subfolder: try numba's next choice
                continue
            return self
        return None


KernelSourcesLocator.register()
