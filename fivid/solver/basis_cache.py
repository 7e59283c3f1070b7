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
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import time
from pathlib import Path

import numpy as np

from fivid import __version__
from fivid.errors import FividError
from fivid.storage import atomic_path, write_json

__all__ = ["CACHE_ENV", "BASIS_FORMAT", "cache_dir", "basis_key", "cached_basis", "cache_info", "clear_cache"]

log = logging.getLogger("fivid")

#: environment variable that overrides the cache folder
CACHE_ENV = "FIVID_CACHE_DIR"
#: version of the stored arrays' layout; part of the key, so a new layout never reads an old file
BASIS_FORMAT = 1
#: how long a process waits for another one building the same basis [s]
LOCK_TIMEOUT = 3600.0


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


def basis_key(*parts) -> str:
    """sha256 (hex) of ``parts``: numpy arrays by dtype, shape and bytes; scipy sparse matrices by their CSR arrays;
    other values by ``repr``; fivid's version and :data:`BASIS_FORMAT` included."""
    import scipy.sparse as sp

    h = hashlib.sha256(f"fivid {__version__} basis format {BASIS_FORMAT}".encode())

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
        else:
            h.update(repr(value).encode())

    for p in parts:
        add(p)
    return h.hexdigest()


def cached_basis(key: str, build, *, folder=None, summary: dict | None = None):
    """The basis stored under ``key``, or ``build()``'s (a dict of numpy arrays and scalars) stored there first.

    Returns ``(arrays, source, seconds)``: ``source`` is ``"cache"`` or ``"built"``, ``seconds`` the build time
    (0 from the cache). Without a writable cache folder the basis is built and not stored (logged).
    """
    from filelock import FileLock, Timeout

    root = cache_dir(folder)
    try:
        root.mkdir(parents=True, exist_ok=True)
        lock = FileLock(str(root / f"{key}.lock"), timeout=LOCK_TIMEOUT)
        lock.acquire()
    except (OSError, Timeout) as exc:
        log.warning("reduced-basis cache %s not usable (%s): building without caching", root, exc)
        t0 = time.perf_counter()
        return build(), "built", time.perf_counter() - t0
    try:
        path = root / f"{key}.npz"
        if path.is_file():
            try:
                with np.load(path, allow_pickle=False) as f:
                    arrays = {k: f[k] for k in f.files}
                log.info("reduced basis %s read from the cache %s", key[:12], root)
                return arrays, "cache", 0.0
            except (OSError, ValueError) as exc:  # an unreadable entry is rebuilt, not trusted
                log.warning("reduced-basis cache entry %s unreadable (%s): rebuilding it", path, exc)
        t0 = time.perf_counter()
        arrays = build()
        seconds = time.perf_counter() - t0
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as f:
                np.savez(f, **arrays)
        write_json(root / f"{key}.json", {**(summary or {}), "key": key, "fivid_version": __version__,
                                          "format": BASIS_FORMAT, "build_seconds": seconds, "built_by_pid": os.getpid(),
                                          "built": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())})
        log.info("reduced basis %s built in %.3g s and stored in %s", key[:12], seconds, root)
        return arrays, "built", seconds
    finally:
        lock.release()


def cache_info(folder=None) -> dict:
    """The cache folder, its entries (their JSON summaries, file sizes) and total size [bytes]."""
    root = cache_dir(folder)
    entries = []
    for path in sorted(root.glob("*.npz")) if root.is_dir() else []:
        meta_path = path.with_suffix(".json")
        try:
            meta = json.loads(meta_path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            meta = {"key": path.stem}
        entries.append({**meta, "bytes": path.stat().st_size, "path": str(path)})
    return {"folder": str(root), "override": f"${CACHE_ENV} or --cache-dir", "entries": entries,
            "total_bytes": int(sum(e["bytes"] for e in entries))}


def clear_cache(folder=None) -> int:
    """Remove every basis from the cache folder (an entry being built by another process is waited for);
    returns the number removed. The empty ``.lock`` files stay (removing one under a waiting process would let
    a third one lock a new file of the same name)."""
    from filelock import FileLock, Timeout

    root = cache_dir(folder)
    if not root.is_dir():
        return 0
    n = 0
    for path in sorted(root.glob("*.npz")):
        try:
            with FileLock(str(path.with_suffix(".lock")), timeout=LOCK_TIMEOUT):
                path.unlink(missing_ok=True)
                path.with_suffix(".json").unlink(missing_ok=True)
        except Timeout:
            raise FividError(f"cache entry {path} is locked by a process building it; try again later") from None
        n += 1  # the empty .lock file stays: a process waiting on it holds that very inode
    return n
