"""On-disk cache of Craig-Bampton bases (issue 30 item 1): built once per model, shared by every process.

A basis (:class:`fivid.solver.reduced.ReducedBasis`: the transformation, reduced matrices, kept modes, the
truncation's flexibility and the mass-scaled mass) depends only on the model's content and the reduction's
settings, not on the run (load, velocity, law, seed, duration within the sliding range). It is stored as
``<key>.npz`` (with a ``<key>.json`` summary) in the cache folder, the key being the sha256 of everything it is
built from (:func:`basis_key`): the assembled stiffness and lumped mass (mesh, materials, springs), the
boundary nodes (contact nodes within the sliding range, sensors), the constrained and grouped dofs, the Rayleigh
damping, the cut-off or number of modes, the mass-scaling target, fivid's version and the basis format.

Concurrency: :func:`cached_basis` takes an OS file lock (``filelock``) on ``<key>.lock`` before looking; the
first process builds and writes atomically (:func:`fivid.storage.atomic_path`) while the others wait on the
lock, then read. A killed builder leaves no partial entry (the lock dies with its process).

Location: ``$FIVID_CACHE_DIR`` if set, else ``fivid/bases`` in the user cache folder
(``platformdirs.user_cache_dir``: ``~/.cache/fivid/bases`` on Linux). ``fivid cache info|clear`` shows and empties it.

The same store keeps other set-up results that depend only on the model's content and a few settings, each kind in
a sub-folder of its own with its own key prefix (:data:`KINDS`): the static preloads of
:mod:`fivid.solver.preload_cache` in ``preloads/``. :func:`cached_arrays` is the store, :func:`content_key` the key.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import pickle
import time
from pathlib import Path

import numpy as np

from fivid import __version__
from fivid.errors import FividError
from fivid.storage import atomic_path, write_json

__all__ = ["CACHE_ENV", "BASIS_FORMAT", "KINDS", "cache_dir", "content_key", "model_key", "basis_key", "cached_arrays",
           "cached_basis", "cache_info", "clear_cache"]

log = logging.getLogger("fivid")

#: environment variable that overrides the cache folder
CACHE_ENV = "FIVID_CACHE_DIR"
#: version of the stored arrays' layout; part of the key, so a new layout never reads an old file
BASIS_FORMAT = 1
#: how long a process waits for another one building the same basis [s]
LOCK_TIMEOUT = 3600.0
#: the kinds of entries the cache holds and their sub-folders of the cache folder ("" : the folder itself)
KINDS = {"basis": "", "preload": "preloads"}


def cache_dir(folder: str | os.PathLike | None = None) -> Path:
    """The basis cache folder: ``folder`` if given, else ``$FIVID_CACHE_DIR``, else the user cache folder's
    ``fivid/bases`` (not created here)."""
    if folder is not None:
        return Path(folder)
    env = os.environ.get(CACHE_ENV)
    if env:
        return Path(env)
    import platformdirs

    return Path(platformdirs.user_cache_dir("fivid", appauthor=False)) / "bases"


def content_key(prefix: str, *parts) -> str:
    """sha256 (hex) of ``prefix`` and ``parts``: numpy arrays by dtype, shape and bytes; scipy sparse matrices by
    their CSR arrays; sequences and mappings element by element (mappings in key order, sets sorted); dataclass
    instances by their class name and every field; numbers, strings and None by ``repr``; any other object by its
    pickle (TypeError if it has none).

    Two values that differ in any array element or field give different keys (a cached result is never taken for
    another input's); equal content built another way gives the same key."""
    import dataclasses

    import scipy.sparse as sp

    h = hashlib.sha256(prefix.encode())

    def add(value):
        if sp.issparse(value):
            csr = value.tocsr()
            csr.sort_indices()
            for a in (csr.data, csr.indices, csr.indptr, np.asarray(csr.shape)):
                add(a)
        elif isinstance(value, np.ndarray):
            a = np.ascontiguousarray(value)
            h.update(f"{a.dtype.str}{a.shape}".encode())
            h.update(a.tobytes())
        elif isinstance(value, (list, tuple)):
            h.update(f"seq{len(value)}".encode())
            for v in value:
                add(v)
        elif isinstance(value, dict):
            h.update(f"map{len(value)}".encode())
            for k in sorted(value, key=repr):
                add(k)
                add(value[k])
        elif isinstance(value, (set, frozenset)):
            add(sorted(value, key=repr))
        elif dataclasses.is_dataclass(value) and not isinstance(value, type):
            h.update(f"{type(value).__module__}.{type(value).__qualname__}".encode())
            for f in dataclasses.fields(value):
                add(f.name)
                add(getattr(value, f.name))
        elif value is None or isinstance(value, (str, bytes, bool, int, float, complex, np.generic)):
            h.update(repr(value).encode())
        else:  # any other object by its pickle (a default repr names only its address); unpicklable: TypeError
            try:
                h.update(pickle.dumps(value, protocol=4))
            except Exception as exc:
                raise TypeError(f"content_key cannot hash a {type(value).__qualname__}: {exc}") from exc

    for p in parts:
        add(p)
    return h.hexdigest()


def model_key(model) -> str:
    """sha256 (hex) of a :class:`fivid.fe.model.Model`'s content (:func:`content_key` of every field but ``source``,
    the config's path): the same model read from another path or rebuilt in another process has the same key, any
    change of mesh, material, contact, motion, load or damping another."""
    import dataclasses

    fields = [(f.name, getattr(model, f.name)) for f in dataclasses.fields(model) if f.name != "source"]
    return content_key(f"fivid {__version__} model", fields)


def basis_key(*parts) -> str:
    """sha256 (hex) of ``parts`` (:func:`content_key`), fivid's version and :data:`BASIS_FORMAT` included."""
    return content_key(f"fivid {__version__} basis format {BASIS_FORMAT}", *parts)


def cached_basis(key: str, build, *, folder=None, summary: dict | None = None):
    """The basis stored under ``key``, or ``build()``'s (a dict of numpy arrays and scalars) stored there first.

    Returns ``(arrays, source, seconds)``: ``source`` is ``"cache"`` or ``"built"``, ``seconds`` the build time
    (0 from the cache). Without a writable cache folder the basis is built and not stored (logged).
    """
    return cached_arrays(key, build, folder=folder, summary=summary, kind="basis")


def cached_arrays(key: str, build, *, folder=None, summary: dict | None = None, kind: str = "basis"):
    """The arrays stored under ``key`` in the ``kind`` part of the cache (:data:`KINDS`), or ``build()``'s (a dict
    of numpy arrays and scalars) stored there first, under the entry's file lock (one process builds, the others
    wait and read).

    Returns ``(arrays, source, seconds)``: ``source`` is ``"cache"`` or ``"built"``, ``seconds`` the build time
    (0 from the cache). Without a writable cache folder the arrays are built and not stored (logged). An unreadable
    entry is rebuilt, never trusted.
    """
    from filelock import FileLock, Timeout

    what = "reduced basis" if kind == "basis" else kind
    root = cache_dir(folder) / KINDS[kind]
    try:
        root.mkdir(parents=True, exist_ok=True)
        lock = FileLock(str(root / f"{key}.lock"), timeout=LOCK_TIMEOUT)
        lock.acquire()
    except (OSError, Timeout) as exc:
        log.warning("%s cache %s not usable (%s): building without caching", what, root, exc)
        t0 = time.perf_counter()
        return build(), "built", time.perf_counter() - t0
    try:
        path = root / f"{key}.npz"
        if path.is_file():
            try:
                with np.load(path, allow_pickle=False) as f:
                    arrays = {k: f[k] for k in f.files}
                log.info("%s %s read from the cache %s", what, key[:12], root)
                return arrays, "cache", 0.0
            except (OSError, ValueError) as exc:  # an unreadable entry is rebuilt, not trusted
                log.warning("%s cache entry %s unreadable (%s): rebuilding it", what, path, exc)
        t0 = time.perf_counter()
        arrays = build()
        seconds = time.perf_counter() - t0
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as f:
                np.savez(f, **arrays)
        write_json(root / f"{key}.json", {**(summary or {}), "kind": kind, "key": key, "fivid_version": __version__,
                                          "format": BASIS_FORMAT, "build_seconds": seconds, "built_by_pid": os.getpid(),
                                          "built": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())})
        log.info("%s %s built in %.3g s and stored in %s", what, key[:12], seconds, root)
        return arrays, "built", seconds
    finally:
        lock.release()


def _entries(root: Path):
    """``(kind, path)`` of every stored entry under the cache folder ``root``, kind by kind."""
    for kind, sub in KINDS.items():
        folder = root / sub
        for path in sorted(folder.glob("*.npz")) if folder.is_dir() else []:
            yield kind, path


def cache_info(folder=None) -> dict:
    """The cache folder, its entries (their JSON summaries with ``kind``: ``"basis"`` or ``"preload"``, file sizes)
    and total size [bytes]."""
    root = cache_dir(folder)
    entries = []
    for kind, path in _entries(root):
        meta_path = path.with_suffix(".json")
        try:
            meta = json.loads(meta_path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            meta = {"key": path.stem}
        entries.append({"kind": kind, **meta, "bytes": path.stat().st_size, "path": str(path)})
    return {"folder": str(root), "override": f"${CACHE_ENV} or --cache-dir", "entries": entries,
            "total_bytes": int(sum(e["bytes"] for e in entries))}


def clear_cache(folder=None) -> int:
    """Remove every entry (bases and preloads) from the cache folder (an entry being built by another process is
    waited for); returns the number removed. The empty ``.lock`` files stay (removing one under a waiting process
    would let a third one lock a new file of the same name)."""
    from filelock import FileLock, Timeout

    root = cache_dir(folder)
    if not root.is_dir():
        return 0
    n = 0
    for _kind, path in list(_entries(root)):
        try:
            with FileLock(str(path.with_suffix(".lock")), timeout=LOCK_TIMEOUT):
                path.unlink(missing_ok=True)
                path.with_suffix(".json").unlink(missing_ok=True)
        except Timeout:
            raise FividError(f"cache entry {path} is locked by a process building it; try again later") from None
        n += 1  # the empty .lock file stays: a process waiting on it holds that very inode
    return n
