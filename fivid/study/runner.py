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
import os
import time
from pathlib import Path

import numpy as np

from fivid.errors import FividError
from fivid.study.config import AXES

__all__ = ["run_study", "open_study", "point_key"]

#: per-point results of a roughness-noise point (fivid.study.roughness) copied into summary.json
ROUGHNESS_KEYS = ("vibration_level", "velocity_rms", "shock_rate", "shock_impulse", "shock_count", "dissipated_power",
                  "mean_normal_force", "mean_friction_force", "open_fraction", "friction_coefficient",
                  "friction_coefficient_rms", "profile_rsm_target", "profile_Ra", "profile_Rq",
                  "profile_Rz", "profile_Rsm", "simulation_seconds", "dof_updates_per_second", "n_dof", "time_step")

log = logging.getLogger("fivid")


def point_key(study, conditions: dict) -> str:
    """sha256 (hex) of a point: the study's digest and the point's conditions."""
    text = json.dumps({"study": study.digest, "conditions": {k: float(v) for k, v in conditions.items()}},
                      sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _system(study) -> dict:
    """What a worker needs to build the system (plain data), with the study-wide coupling bounds when modes are
    computed on a model with contacts (computed once here, not at every point)."""
    if study.lumped is not None:
        return {"lumped": study.lumped}
    out = {"model_path": str(study.model_path)}
    if "modes" in study.points:
        from fivid.study.tasks import refined_model

        bounds = {}
        for factor in np.unique(study.axes.get("mesh", [1.0])):  # per mesh of the sweep
            model = refined_model(study.model_path, float(factor))
            if model.contacts:
                from fivid.study.coupling import coupling_bounds

                f0, fi = coupling_bounds(model, study.points["modes"]["n_modes"])
                bounds[repr(float(factor))] = (f0.tolist(), fi.tolist())
        if bounds:
            out["coupling_bounds"] = bounds
    return out


def _safe_evaluate(system, tasks, conditions):
    """Evaluate one point; a failure comes back as ``(None, message)`` so that the other points go on."""
    from fivid.study.tasks import evaluate_point

    try:
        return evaluate_point(system, tasks, conditions), None
    except Exception as exc:  # noqa: BLE001 - any failure of one point is reported, the study goes on
        return None, f"{type(exc).__name__}: {exc}"


def _in_process(items: dict):
    for name, args in items.items():
        t0 = time.perf_counter()
        out = _safe_evaluate(*args)
        yield name, out, time.perf_counter() - t0, os.getpid()


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

    from fivid.pipeline.lock import OutputLock
    from fivid.storage import write_json, write_netcdf

    if scheduler is not None:  # before any work or output
        from fivid.pipeline.sweep import check_scheduler_address

        check_scheduler_address(scheduler)
    outdir = Path(outdir)
    started = time.perf_counter()
    with OutputLock(outdir):
        pdir = outdir / "points"
        pdir.mkdir(parents=True, exist_ok=True)
        table = study.point_table()
        files = [pdir / f"p{i:04d}-{point_key(study, c)[:16]}.nc" for i, c in enumerate(table)]
        missing = [i for i, f in enumerate(files) if not f.exists()]
        system = _system(study) if missing and study.points else None
        todo = {i: (system, study.points, table[i]) for i in missing}
        log.info("study %s: %d points, %d to compute", study.name, len(table), len(todo))
        timing, failed = {}, {}
        if todo and study.points:
            if workers == 0 and scheduler is None:
                results = _in_process(todo)
            else:
                from fivid.pipeline.sweep import map_tasks

                results = map_tasks(_safe_evaluate, todo, workers=max(workers, 1), scheduler=scheduler)
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
        from fivid.study.convergence import convergence_summary

        conv = convergence_summary(ds, table, done)
        if conv is not None:
            summary["convergence"] = conv
        write_json(outdir / "summary.json", summary)
        from fivid.study.report import render_study_report

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
    if study.lumped is not None:
        from fivid.study.lumped import HoffmannSystem

        res = HoffmannSystem(**study.lumped["parameters"]).cea(mu)
    else:
        from fivid.fe import load_model
        from fivid.fe.cea import complex_eigenvalue_analysis

        from fivid.study.tasks import refined_model

        load = study.cea.get("normal_load")
        meshes = np.unique(study.axes.get("mesh", [1.0]))  # one mesh swept: the CEA on it too
        model = refined_model(study.model_path, float(meshes[0])) if meshes.size == 1 else load_model(study.model_path)
        ds = complex_eigenvalue_analysis(model, mu, normal_load=load)
        lam = ds["real_part"].transpose("mu", "mode").values + 2j * np.pi * ds["frequency"].transpose("mu", "mode").values
        p = ds["partner"].values  # mode numbers (1-based), -1 for none
        res = {"eigenvalues": lam, "critical_mu": ds["critical_mu"].values, "partner": np.where(p > 0, p - 1, -1)}
    return {"mu": mu, **{k: res[k] for k in ("eigenvalues", "critical_mu", "partner")}}


def _assemble(study, table, files, done, cea):
    import xarray as xr

    from fivid.study.config import AXES

    parts = []
    for i in done:
        with xr.open_dataset(files[i]) as d:
            part = d.load()
        for name in ("regime", "coupling"):  # concat would truncate strings to the first point's width
            if name in part:
                part[name] = part[name].astype(object)
        parts.append(part.assign_coords(point=i))
    if parts:
        ds = xr.concat(parts, dim="point", coords="minimal", compat="override", join="outer",
                       combine_attrs="override")  # keeps the variables' units and long names (the first point's)
        ds.attrs = {}
        for name in ("regime", "coupling"):  # netCDF gives fixed-width strings back: keep them whole
            if name in ds:
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
    from fivid import __version__
    from fivid.schema import new_history

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
    from fivid import __version__

    points = []
    for i, cond in enumerate(table):
        p = {k: (int(v) if k == "seed" else float(v)) for k, v in cond.items()}
        if i in done:
            p["status"] = "done"
            for name, key in (("regime", "regime"), ("growth_rate", "growth_rate"), ("response_frequency", "frequency"),
                              ("onset_time", "onset_time"), ("rms", "rms"), ("level_db", "level_db"),
                              ("stick_fraction", "stick_fraction"), ("narrowband_fraction", "narrowband_fraction"),
                              ("coupling_indicator", "coupling_indicator"), ("coupling", "coupling"),
                              ("perturbation_gain_db", "perturbation_gain_db"),
                              *((n, n) for n in ROUGHNESS_KEYS)):
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
    out = {"study": study.name, "description": study.description, "source": study.source,
           "fivid_version": __version__, "quick": study.quick, "n_points": len(table), "n_done": len(done),
           "failed": [{"point": i, **{k: float(v) for k, v in table[i].items()}, "error": e}
                      for i, e in sorted(failed.items())],
           "points": points}
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
    out.update(_transitions(points))
    from fivid.study.fits import power_law_fit

    fit = power_law_fit(points, "rms")
    if fit is not None:
        out["fits"] = {"rms": fit}
    if any("vibration_level" in p for p in points):
        from fivid.study.fits import roughness_noise_fits
        from fivid.study.roughness import roughness_settings

        rn = roughness_noise_fits(points)
        out.setdefault("fits", {}).update(rn.pop("fits"))
        out.update(rn)
        out["roughness_settings"] = roughness_settings(study)
    seconds = list(timing.values())
    out["timing"] = {"wall_s": round(wall, 3), "computed_points": len(seconds),
                     "mean_point_s": round(float(np.mean(seconds)), 3) if seconds else None}
    if seconds and workers:
        out["timing"]["workers"] = workers
        out["timing"]["parallel_efficiency"] = round(float(np.sum(seconds) / (wall * workers)), 3)
    return out


def _transitions(points) -> dict:
    """``transition_load`` (the first group's, see :func:`_transition_load`) and, when other conditions vary,
    ``transition_loads``: one per combination of them (the contact's compliance follows roughness, say)."""
    transition = _transition_load(points)
    if transition is None:
        return {}
    out = {"transition_load": transition}
    others = sorted({k for p in points for k in p if k in AXES and k not in ("normal_load", "seed")
                     and len({q.get(k) for q in points}) > 1})
    if others:
        groups = {}
        for p in points:
            groups.setdefault(tuple(p.get(k) for k in others), []).append(p)
        out["transition_loads"] = [{**dict(zip(others, key)), **(_transition_load(grp) or {})}
                                   for key, grp in groups.items()]
    return out


def _transition_load(points) -> dict | None:
    """Where the coupling indicator first crosses the weak/strong threshold along the normal load.

    ``{"value" [N], "bracket": [lo, hi] [N], "threshold"}``: kappa interpolated linearly in log load between the two
    swept loads that bracket the crossing (other axes: the first point of each load, in sweep order; the summary's
    ``transition_loads`` repeats this per combination of the other swept conditions). None without a load sweep
    or an indicator; ``value`` null when kappa stays on one side over the swept loads.
    """
    from fivid.study.coupling import WEAK_STRONG_THRESHOLD

    by_load = {}
    for p in points:
        if "normal_load" in p and "coupling_indicator" in p:
            by_load.setdefault(p["normal_load"], p["coupling_indicator"])
    if len(by_load) < 2:
        return None
    loads = np.array(sorted(by_load))
    kappa = np.array([by_load[f] for f in loads])
    above = kappa >= WEAK_STRONG_THRESHOLD
    k = np.flatnonzero(~above[:-1] & above[1:])
    if k.size == 0:
        return {"value": None, "bracket": None, "threshold": WEAK_STRONG_THRESHOLD,
                "note": "strong at every swept load" if above.all() else "weak at every swept load"
                if not above.any() else "kappa does not rise through the threshold"}
    i = int(k[0])
    w = (WEAK_STRONG_THRESHOLD - kappa[i]) / (kappa[i + 1] - kappa[i])
    value = float(np.exp(np.log(loads[i]) + w * (np.log(loads[i + 1]) - np.log(loads[i]))))
    return {"value": value, "bracket": [float(loads[i]), float(loads[i + 1])], "threshold": WEAK_STRONG_THRESHOLD}


def _cea_at(cea, mu: float) -> dict:
    """CEA's most unstable eigenvalue at ``mu`` (linear interpolation on the sweep): growth rate, frequency."""
    m = np.asarray(cea["mu"])
    lam = np.asarray(cea["eigenvalues"])
    if not m[0] <= mu <= m[-1]:
        return {}
    re = np.array([np.interp(mu, m, lam[:, k].real) for k in range(lam.shape[1])])
    k = int(np.argmax(re))
    return {"cea_growth_rate": float(re[k]), "cea_frequency": float(np.interp(mu, m, np.abs(lam[:, k].imag)) / (2 * np.pi))}
