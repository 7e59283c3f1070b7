"""The static preload solved once per model, load and friction, and read back by every later run (issue 30).

Every simulation under a normal load starts from :func:`fivid.fe.static.preload_state` (the clamp displacement that
gives the load, and the contact state; an active-set solve on the sparse stiffness, 0.23 s on the default 0.5 mm rig
against 0.025 s on the coarse one). It depends on the model's content, the target load and the slaves' friction
coefficients during the preload only, so all the simulate tasks of a pipeline run (and repeated ``fivid simulate``
calls, Monte-Carlo samples, study points on one model and load) share one solve: it is kept in the basis cache's
folder (:mod:`fivid.solver.basis_cache`, sub-folder ``preloads/``; same file lock, atomic write and
``fivid cache info|clear``), keyed by :func:`preload_key`.

A preload read from the cache is the stored solve's arrays and scalars, bit for bit (``.npz``, float64 kept).
"""

from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np

from fivid import __version__
from fivid.fe.static import ContactGeometry, Preload, preload_state
from fivid.friction.curve import slave_coefficients
from fivid.solver.basis_cache import cached_arrays, content_key, model_key

__all__ = ["PRELOAD_FORMAT", "preload_key", "cached_preload"]

#: version of the stored preload's layout (and of the solve's method); part of the key
PRELOAD_FORMAT = 1

log = logging.getLogger("fivid")

_SCALARS = {"displacement": float, "normal_load": float, "iterations": int}


def preload_key(model, normal_load, mu) -> str:
    """sha256 (hex) of what :func:`fivid.fe.static.preload_state` solves from: the model's content
    (:func:`fivid.solver.basis_cache.model_key`), the normal load [N] (None: the model's own loads) and the slaves'
    friction coefficients ``mu`` [-] (scalar or per slave), with fivid's version and :data:`PRELOAD_FORMAT`.

    ``mu`` enters as the per-slave coefficients the solve uses (:func:`fivid.friction.curve.slave_coefficients`,
    as :func:`fivid.fe.static.preload_state` resolves it): None (each pair's own), a scalar and the equal per-slave
    array are one entry."""
    mu = np.asarray(mu if (mu is not None and np.ndim(mu) == 1) else slave_coefficients(model, mu), dtype=float)
    return content_key(f"fivid {__version__} preload format {PRELOAD_FORMAT}", model_key(model),
                       None if normal_load is None else float(normal_load), mu)


def _to_arrays(state: Preload) -> dict:
    """The preload as named arrays (geometry fields prefixed ``geometry.``; a None field left out)."""
    out = {}
    for f in dataclasses.fields(Preload):
        value = getattr(state, f.name)
        if f.name == "geometry":
            for g in dataclasses.fields(ContactGeometry):
                if getattr(value, g.name) is not None:
                    out[f"geometry.{g.name}"] = np.asarray(getattr(value, g.name))
        elif value is not None:
            out[f.name] = np.asarray(value)
    return out


def _from_arrays(arrays: dict) -> Preload:
    """The :class:`Preload` of :func:`_to_arrays`' arrays."""
    geo = ContactGeometry(**{g.name: arrays.get(f"geometry.{g.name}") for g in dataclasses.fields(ContactGeometry)})
    kw = {f.name: arrays.get(f.name) for f in dataclasses.fields(Preload) if f.name != "geometry"}
    kw.update({name: cast(arrays[name][()]) for name, cast in _SCALARS.items()})
    return Preload(**kw, geometry=geo)


def cached_preload(model, normal_load, *, mu=None, cache: bool = True, folder=None) -> tuple[Preload, str, float]:
    """:func:`fivid.fe.static.preload_state` ``(model, normal_load, mu=mu)``, solved once and stored in the cache.

    Parameters
    ----------
    model : Model
    normal_load : float or None
        Target transducer normal force [N] (None: the model's own loads press the contact).
    mu : float or ndarray (n_slave,), optional
        Friction coefficient during the preload (see :func:`fivid.fe.static.preload_state`).
    cache : bool
        Read/store the preload in the cache (False: always solve, store nothing).
    folder : path-like, optional
        Cache folder (default :func:`fivid.solver.basis_cache.cache_dir`).

    Returns
    -------
    (Preload, str, float)
        The preload, its source (``"cache"``, ``"built"`` or ``"built (not cached)"``) and the solve's wall time [s]
        (0 from the cache).

    Raises
    ------
    ConfigError
        As :func:`fivid.fe.static.preload_state` (nothing is stored then).
    """
    if not cache:
        t0 = time.perf_counter()
        state = preload_state(model, normal_load, mu=mu)
        return state, "built (not cached)", time.perf_counter() - t0
    try:
        key = preload_key(model, normal_load, mu)
    except TypeError as exc:  # a model field that cannot be hashed (content_key): solve without the cache
        log.warning("static preload not cached: %s", exc)
        return cached_preload(model, normal_load, mu=mu, cache=False)
    summary = {"model": model.describe(), "source": str(getattr(model, "source", "")),
               "normal_load_n": None if normal_load is None else float(normal_load)}
    arrays, source, seconds = cached_arrays(key, lambda: _to_arrays(preload_state(model, normal_load, mu=mu)),
                                            folder=folder, summary=summary, kind="preload")
    return _from_arrays(arrays), source, seconds
