"""Run a study: points on dask (or in-process), incrementally and atomically; assemble, summarise, report.

Layout of the output folder ``DIR``:

``points/p0007-<key>.nc``
    one file per finished point, written atomically; ``key`` hashes the point's conditions and everything it
    depends on (model file, task settings). A re-run skips the points whose file exists, so a killed study
    resumes where it stopped and a changed setting recomputes only what it changes. A failing point is
    reported and written nowhere (the next run tries it again); the other points finish.
``study.nc``
    all points along a ``point`` dimension, the swept conditions as ``point`` coordinates with units (open it
    with :func:`open_study` to select by condition: ``open_study(p).sel(normal_load=5.0)``), and the study-level
    CEA on ``cea_mu``.
``summary.json``
    the output contract (docs/studies.md): provenance, ``points`` (conditions in SI, ``regime``, ``growth_rate``,
    ``frequency``, ``onset_time`` where they apply, ``status``), ``critical_mu`` (null if stable over the CEA's
    range), failures, timing (wall time per point and parallel efficiency).
``report.html``
    the report section: the summary table and figures.
"""

from __future__ import annotations

import hashlib
import json
import logging
import time
from pathlib import Path

import numpy as np

from fivid import __version__
from fivid.errors import FividError
from fivid.execution.cluster import check_scheduler_address, map_tasks
from fivid.execution.lock import OutputLock
from fivid.schema import new_history
from fivid.storage import write_json, write_netcdf
from fivid.study.axes import AXES
from fivid.study.report import render_study_report

__all__ = ["run_study", "open_study", "point_key"]

log = logging.getLogger("fivid")


def point_key(study, conditions: dict) -> str:
    """sha256 (hex) of a point: the study's digest and the point's conditions."""
    text = json.dumps({"study": study.digest, "conditions": {k: float(v) for k, v in conditions.items()}},
                      sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _safe_evaluate(kind, system, tasks, conditions):
    """Evaluate one point with the study's kind; a failure comes back as ``(None, message)`` so that the other
    points go on."""
    try:
        return kind.evaluate(system, tasks, conditions), None
    except Exception as exc:  # noqa: BLE001 - any failure of one point is reported, the study goes on
        return None, f"{type(exc).__name__}: {exc}"


def run_study(study, outdir, *, workers: int = 2, scheduler: str | None = None, progress=None) -> dict:
    """Run ``study`` into ``outdir``; returns the summary (also written to ``outdir/summary.json``).

    Parameters
    ----------
    study : Study
        From :func:`fivid.study.load_study`.
    outdir : path-like
        Output folder (created; locked while the study runs).
    workers : int
        Worker processes of the dask LocalCluster; 0 runs the points in this process (no dask).
    scheduler : str, optional
        ``tcp://host:port`` of a running dask scheduler (then ``workers`` is ignored).
    progress : bool, optional
        Progress bar (default: when the terminal is interactive).
    """
    from tqdm.auto import tqdm

    if scheduler is not None:  # before any work or output
        check_scheduler_address(scheduler)
    outdir = Path(outdir)
    started = time.perf_counter()
    with OutputLock(outdir):
        pdir = outdir / "points"
        pdir.mkdir(parents=True, exist_ok=True)
        table = study.point_table()
        files = [pdir / f"p{i:04d}-{point_key(study, c)[:16]}.nc" for i, c in enumerate(table)]
        missing = [i for i, f in enumerate(files) if not f.exists()]
        # a point has work when the study asks for tasks, or its kind has a section of its own (its settings are
        # what the points compute); a CEA-only study of a kind without one computes no points
        busy = bool(study.points) or study.kind.section is not None
        system = study.kind.system(study) if missing and busy else None
        todo = {i: (study.kind, system, study.points, table[i]) for i in missing} if busy else {}
        log.info("study %s: %d points, %d to compute", study.name, len(table), len(todo))
        timing, failed = {}, {}
        if todo:
            results = map_tasks(_safe_evaluate, todo, workers=workers, scheduler=scheduler)
            with tqdm(total=len(todo), desc=f"study {study.name}", unit="point", leave=False,
                      disable=None if progress is None else not progress) as bar:
                for i, (ds, error), seconds, pid in results:
                    timing[i] = seconds
                    if error is not None:
                        failed[i] = error
                        log.warning("study %s: point %d %s failed: %s", study.name, i, table[i], error)
                    else:
                        ds.attrs.update({"Conventions": "CF-1.8", "point": i, "seconds": seconds, "worker_pid": pid,
                                         "study_digest": study.digest,
                                         **{f"condition_{k}": float(v) for k, v in table[i].items()}})
                        write_netcdf(ds, files[i])
                    bar.update(1)
        wall = time.perf_counter() - started
        done = [i for i, f in enumerate(files) if f.exists()]
        cea = _study_cea(study)
        ds = _assemble(study, table, files, done, cea)
        write_netcdf(ds, outdir / "study.nc")  # text as char arrays: fivid.storage.cf_encoding
        summary = _summary(study, table, ds, done, failed, cea, timing, wall, workers if scheduler is None else None)
        write_json(outdir / "summary.json", summary)
        render_study_report(outdir / "report.html", study, ds, summary)
    return summary


def _study_cea(study):
    """The study-level CEA: ``{"mu", "eigenvalues", "critical_mu", "partner"}`` or None."""
    if study.cea is None:
        return None
    mu = study.cea["mu"]
    if "mu" in study.axes:  # evaluate exactly at the transients' mu too (near a threshold Re(lambda) ~ sqrt)
        swept = study.axes["mu"]
        mu = np.union1d(mu, swept[(swept >= mu[0]) & (swept <= mu[-1])])
    res = study.kind.cea(study, mu)
    return {"mu": mu, **{k: res[k] for k in ("eigenvalues", "critical_mu", "partner")}}


def _text_variables(ds) -> list[str]:
    """The data variables holding text (a regime, a coupling class): netCDF gives them back fixed-width."""
    return [str(n) for n, v in ds.data_vars.items() if v.dtype.kind in "OSU"]


def _assemble(study, table, files, done, cea):
    import xarray as xr

    parts = []
    for i in done:
        with xr.open_dataset(files[i]) as d:
            part = d.load()
        for name in _text_variables(part):  # concat would truncate strings to the first point's width
            part[name] = part[name].astype(object)
        parts.append(part.assign_coords(point=i))
    if parts:
        ds = xr.concat(parts, dim="point", coords="minimal", compat="override", join="outer",
                       combine_attrs="override")  # keeps the variables' units and long names (the first point's)
        ds.attrs = {}
        for name in _text_variables(ds):  # netCDF gives fixed-width strings back: keep them whole
            ds[name] = ds[name].astype(object)
    else:
        ds = xr.Dataset(coords={"point": ("point", np.array([], dtype=np.int64))})
    for name in study.axes:
        units, long = AXES[name]
        vals = np.array([table[i][name] for i in ds["point"].values.astype(int)])
        ds = ds.assign_coords({name: ("point", vals, {"units": units, "long_name": long})})
    ds["point"].attrs.update(long_name="sweep point index", units="1")
    for name, long in (("mode", "mode number, by frequency"), ("frequency", "frequency")):
        if name in ds.coords:
            ds[name].attrs.setdefault("long_name", long)
    if "mode" in ds.coords:
        ds["mode"].attrs.setdefault("units", "1")
    if cea is not None:
        lam = np.asarray(cea["eigenvalues"])
        ds = ds.assign_coords(cea_mu=("cea_mu", cea["mu"], {"units": "1", "long_name": "friction coefficient (CEA)"}),
                              cea_mode=("cea_mode", np.arange(1, lam.shape[1] + 1),
                                        {"units": "1", "long_name": "CEA mode number, by frequency at the first mu"}))
        ds["cea_real_part"] = (("cea_mu", "cea_mode"), lam.real,
                               {"units": "s-1", "long_name": "real part of the eigenvalue (> 0: unstable)"})
        ds["cea_frequency"] = (("cea_mu", "cea_mode"), np.abs(lam.imag) / (2 * np.pi),
                               {"units": "Hz", "long_name": "damped frequency of the CEA mode"})
        ds["cea_critical_mu"] = (("cea_mode",), np.asarray(cea["critical_mu"], dtype=float),
                                 {"units": "1", "long_name": "friction coefficient at which the mode turns unstable"})

    ds.attrs.update({"Conventions": "CF-1.8", "title": f"fivid study {study.name}", "study": study.name, "description": study.description,
                     "source": study.source, "quick": int(study.quick), "fivid_version": __version__,
                     "history": new_history(f"study {study.name}: {len(done)}/{len(table)} points")})
    return ds


def open_study(path):
    """Open ``study.nc`` with an index on every swept condition, so ``.sel(normal_load=...)`` works."""
    import xarray as xr

    ds = xr.open_dataset(path)
    for name in [c for c in ds.coords if ds[c].dims == ("point",) and c != "point"]:
        ds = ds.set_xindex(name)
    return ds


def _scalar(ds, name, i):
    if name not in ds:
        return None
    v = ds[name].sel(point=i).values
    v = v.item() if hasattr(v, "item") else v
    if isinstance(v, float) and not np.isfinite(v):
        return None
    return v


def _summary(study, table, ds, done, failed, cea, timing, wall, workers) -> dict:
    points = []
    for i, cond in enumerate(table):
        p = {k: (int(v) if k == "seed" else float(v)) for k, v in cond.items()}
        if i in done:
            p["status"] = "done"
            for name, key in study.kind.point_keys:
                val = _scalar(ds, name, i)
                if val is not None:
                    p[key] = val
            if cea is not None and "mu" in cond and "regime" in p:
                p.update(_cea_at(cea, float(cond["mu"])))
        else:
            p["status"] = "failed" if i in failed else "missing"
            if i in failed:
                p["error"] = failed[i]
        points.append(p)
    out = {"study": study.name, "kind": study.kind.name, "description": study.description, "source": study.source,
           "fivid_version": __version__, "quick": study.quick, "n_points": len(table), "n_done": len(done),
           "failed": [{"point": i, **{k: float(v) for k, v in table[i].items()}, "error": e}
                      for i, e in sorted(failed.items())],
           "points": points, "units": _point_units(study, table, ds)}
    if cea is not None:
        crit = np.asarray(cea["critical_mu"], dtype=float)
        if np.isfinite(crit).any():
            k = int(np.nanargmin(crit))
            partner = int(cea["partner"][k]) if cea["partner"] is not None else -1
            j = int(np.searchsorted(cea["mu"], crit[k]))
            lam = np.asarray(cea["eigenvalues"])[min(j, len(cea["mu"]) - 1)]
            out["critical_mu"] = {"value": float(crit[k]), "mode": k + 1,
                                  "partner_mode": partner + 1 if partner >= 0 else None,
                                  "frequency": float(abs(lam[k].imag) / (2 * np.pi)),
                                  "cea_mu_range": [float(cea["mu"][0]), float(cea["mu"][-1])]}
        else:
            out["critical_mu"] = None
    for key, value in study.kind.summarise(study, ds, points).items():  # the kind's own keys
        if key == "fits":
            out.setdefault("fits", {}).update(value)
        else:
            out[key] = value
    seconds = list(timing.values())
    out["timing"] = {"wall_s": round(wall, 3), "computed_points": len(seconds),
                     "mean_point_s": round(float(np.mean(seconds)), 3) if seconds else None}
    if seconds and workers:
        out["timing"]["workers"] = workers
        out["timing"]["parallel_efficiency"] = round(float(np.sum(seconds) / (wall * workers)), 3)
    return out


def _point_units(study, table, ds) -> dict:
    """CF units of every per-point key of the summary (condition and result keys; ``"1"`` dimensionless), from the
    study dataset's attrs: the summary's keys stay plain names (its contract), their units stand beside them."""
    names = {k: k for cond in table[:1] for k in cond} | {key: name for name, key in study.kind.point_keys}
    units = {key: str(ds[name].attrs["units"]) for key, name in names.items()
             if name in ds.variables and "units" in ds[name].attrs}
    if "cea_frequency" in ds.variables:  # the CEA interpolated at each point's mu (_cea_at)
        units |= {"cea_growth_rate": "s-1", "cea_frequency": "Hz"}
    return units


def _cea_at(cea, mu: float) -> dict:
    """CEA's most unstable eigenvalue at ``mu`` (linear interpolation on the sweep): growth rate, frequency."""
    m = np.asarray(cea["mu"])
    lam = np.asarray(cea["eigenvalues"])
    if not m[0] <= mu <= m[-1]:
        return {}
    re = np.array([np.interp(mu, m, lam[:, k].real) for k in range(lam.shape[1])])
    k = int(np.argmax(re))
    return {"cea_growth_rate": float(re[k]), "cea_frequency": float(np.interp(mu, m, np.abs(lam[:, k].imag)) / (2 * np.pi))}
