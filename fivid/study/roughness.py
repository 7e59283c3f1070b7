"""Seed 003's rough sliding pair: a model config from two profiles, and what a run tells about roughness noise.

Builder (plain data; :mod:`fivid.surface` stays below the FE layers):

* :func:`synthetic_rough_profiles` -- two Gaussian profiles of a given Ra (``Rq = sqrt(pi/2) Ra``), fixed
  correlation length and seeds (:func:`fivid.surface.gaussian_random_profile`), closed to cover the body;
* :func:`rough_pair_config` -- a rough_pair-style model config (a mapping for :func:`fivid.fe.load_model`) with
  the two profiles on the facing edges, the upper body lifted so that its lowest point touches the lower body's
  highest one (zero gap at the first touching node pair), and velocity sensors on the back-face nodes.

Run metrics (:func:`roughness_metrics`, over the steady part of a RunDataset):

* ``vibration_level`` Lv [dB] = 20 log10(V_RMS / 1e-9 m s-1), V_RMS the RMS over time and back-face nodes of the
  normal velocity (each node's mean removed) -- seed 003's definition;
* shocks (:func:`detect_shocks`): closing events of the contact, with rate [s-1] and mean impulse [N s];
* ``dissipated_power`` [W]: slope of ``friction_dissipation`` (least squares) over the steady part.
"""

from __future__ import annotations

import copy

import numpy as np

from fivid.signal.steady import steady_part

__all__ = ["LV_REFERENCE", "synthetic_rough_profiles", "rough_pair_config", "vibration_level", "detect_shocks",
           "dissipated_power", "friction_coefficient_statistics", "roughness_metrics", "identification_run",
           "build_point_model", "simulate_rough_run",
           "point_profiles_design", "RSM_LEVELS", "RSM_PER_CORRELATION_LENGTH"]

#: seed 003's velocity reference of the vibration level [m s-1]
LV_REFERENCE = 1e-9
#: Rq / Ra of a Gaussian height distribution
RQ_PER_RA = float(np.sqrt(np.pi / 2.0))


def synthetic_rough_profiles(ra: float, length: float, *, correlation_length: float = 1e-3, step: float = 50e-6,
                             seeds=(3, 4), acf: str = "gaussian"):
    """Two Gaussian random profiles (lower, upper) of expected ``Rq = sqrt(pi/2) ra`` over ``[0, length]`` [m].

    The profiles are periodic (spectral synthesis); the first sample is repeated at ``x = length`` so that they
    cover the body. ``ra = 0`` gives flat (zero) profiles.
    """
    from fivid.surface import gaussian_random_profile, make_profile

    out = []
    for seed in seeds:
        p = gaussian_random_profile(RQ_PER_RA * float(ra), correlation_length, length, step, acf=acf, seed=int(seed))
        x = np.append(p["x"].values, length)
        z = np.append(p.values, p.values[0])
        out.append(make_profile(x, z, attrs=dict(p.attrs), label="synthetic profile"))
    return tuple(out)


def _si(ctx, value, key, units="m") -> float:
    from fivid.config_layer import quantity_at

    return quantity_at(ctx, value, key, units)


def rough_pair_config(base, lower, upper, *, sensor_every: int = 1, normal_load: float | None = None):
    """A rough-pair model config: ``base`` (path or mapping of a rough_pair-style config) with the profiles.

    Parameters
    ----------
    base : path-like or mapping
        A model config with two rectangular bodies whose facing edges carry ``profile:`` keys (the one with a
        ``top`` profile is the lower body, the ``bottom`` one the upper body) and one contact pair.
    lower, upper : xarray.DataArray
        Height profiles [m] over ``x`` [m] from the bodies' left ends (a reader's or a synthesis's output),
        covering the body length.
    sensor_every : int
        A velocity sensor (direction y) on every ``sensor_every``-th node of the lower body's back face
        (``bottom`` edge), both end nodes included when the division count allows; replaces the config's sensors.
    normal_load : float, optional
        Dead load [N] on the upper body: its ``top``-edge pressure loads are scaled to sum to it (pressure x
        length x thickness). None: as configured.

    Returns
    -------
    (dict, dict)
        The config mapping, and a record: ``lift`` [m] (the upper body is lifted by ``max(z_lower - z_upper)``
        over the contact's slave nodes, so the highest asperity pair touches with zero gap), the bodies' names,
        ``back_face_sensors``, ``sensor_every`` and the base config's source.
    """
    from fivid.fe.config import read_config

    data, ctx, origin = read_config(base)
    data = copy.deepcopy(data)
    bodies = data["bodies"]
    edges = {b["profile"]["edge"]: name for name, b in bodies.items() if isinstance(b.get("profile"), dict)}
    if set(edges) != {"top", "bottom"}:
        from fivid.errors import ConfigError

        raise ConfigError(f"{origin}: a rough pair needs one body with a 'top' profile and one with a 'bottom' "
                          f"profile; profiled edges found: {sorted(edges) or 'none'}", key="bodies")
    lo_name, up_name = edges["top"], edges["bottom"]
    lo, up = bodies[lo_name], bodies[up_name]
    lc = np.array([[_si(ctx, v, f"bodies.{lo_name}.corners") for v in c] for c in lo["corners"]])
    uc = np.array([[_si(ctx, v, f"bodies.{up_name}.corners") for v in c] for c in up["corners"]])
    length = lc[1, 0] - lc[0, 0]
    nx = int(lo["divisions"][0])
    xn = np.linspace(0.0, length, nx + 1)  # back-face nodes (uniform along x; grading is through the depth)
    nu = int(up["divisions"][0])
    xs = np.linspace(uc[0, 0], uc[1, 0], nu + 1)[1:-1]  # the interface's slave nodes, end nodes excluded (below)
    zl = np.interp(xs - lc[0, 0], lower["x"].values, lower.values)
    zu = np.interp(xs - uc[0, 0], upper["x"].values, upper.values)
    lift = float(np.max(zl - zu))
    top = lc[2, 1]
    up_corners_y0 = up["corners"][0][1]
    depth_up = uc[2, 1] - uc[1, 1]
    uc[:, 1] = [top + lift, top + lift, top + lift + depth_up, top + lift + depth_up]
    for body, prof, edge in ((lo, lower, "top"), (up, upper, "bottom")):
        body["profile"] = {"edge": edge, "x": np.asarray(prof["x"].values, float),
                           "z": np.asarray(prof.values, float)}
    up["corners"] = [[f"{float(x)!r} m", f"{float(y)!r} m"] for x, y in uc]
    # whatever rides with the upper body (a carriage block, transducer springs, point masses) rises with it
    dy = top + lift - _si(ctx, up_corners_y0, f"bodies.{up_name}.corners")
    for name, b in bodies.items():
        if name not in (lo_name, up_name) and "corners" in b:
            b["corners"] = [[c[0], f"{float(_si(ctx, c[1], f'bodies.{name}.corners') + dy)!r} m"] for c in b["corners"]]
    for group in ("springs", "point_masses"):
        for item in data.get(group) or []:
            for end in ("a", "b", None):
                ref = item if end is None else item.get(end)
                if isinstance(ref, dict) and ref.get("body") not in (None, lo_name) and "at" in ref:
                    y = _si(ctx, ref["at"][1], f"{group}.{item.get('name')}.at") + dy
                    ref["at"] = [ref["at"][0], f"{float(y)!r} m"]
    # the slave edge without its two end nodes: the carriage-held one (prescribed dofs) and the one facing the lower
    # body's clamped corner would tie prescribed dofs through the rigid contact (a flat pair diverges with them)
    h = (uc[1, 0] - uc[0, 0]) / nu
    for c in data["contacts"]:
        if c["slave"]["body"] == up_name:
            c["slave"] = {**c["slave"], "x": [f"{float(uc[0, 0] + h / 2)!r} m", f"{float(uc[1, 0] - h / 2)!r} m"]}
    if normal_load is not None:
        weights = [ld for ld in data.get("loads") or [] if ld.get("body") == up_name and ld.get("edge") == "top"]
        if not weights:
            from fivid.errors import ConfigError

            raise ConfigError(f"{origin}: normal_load needs a pressure load on the top edge of {up_name!r}",
                              key="loads")
        area = (uc[1, 0] - uc[0, 0]) * _si(ctx, up["thickness"], f"bodies.{up_name}.thickness")
        total = sum(_si(ctx, ld["pressure"], "loads.pressure", "Pa") for ld in weights)
        for ld in weights:
            p = _si(ctx, ld["pressure"], "loads.pressure", "Pa") / total * normal_load / area
            ld["pressure"] = f"{float(p)!r} Pa"
    k = max(1, int(sensor_every))
    y0 = lc[0, 1]
    data["sensors"] = [{"name": f"back_{i:04d}", "body": lo_name, "direction": "y",
                        "at": [f"{float(xn[i] + lc[0, 0])!r} m", f"{float(y0)!r} m"]} for i in range(0, nx + 1, k)]
    data["name"] = f"{data.get('name', 'rough_pair')} (profiles: {lower.attrs.get('source', 'given')})"
    return data, {"lift": lift, "lower_body": lo_name, "upper_body": up_name,
                  "back_face_sensors": len(data["sensors"]), "sensor_every": k, "base": origin}


def _steady(ds, start=None):
    """The run from ``start`` [s], by default its steady part (:func:`fivid.signal.steady_part`)."""
    return steady_part(ds) if start is None else ds.sel(time=slice(float(start), None))


def vibration_level(ds, *, start=None, reference: float = LV_REFERENCE) -> tuple[float, float]:
    """(Lv [dB], V_RMS [m s-1]): RMS over the steady time and every sensor of ``sensor_velocity``, each sensor's
    mean removed; ``Lv = 20 log10(V_RMS / reference)`` (seed 003: reference 1e-9 m s-1, back-face nodes)."""
    v = np.asarray(_steady(ds, start)["sensor_velocity"].values, float)
    v = v.reshape(v.shape[0], -1)
    v = v - v.mean(axis=0)
    vrms = float(np.sqrt(np.mean(v * v)))
    return (20.0 * np.log10(vrms / reference) if vrms > 0 else -np.inf), vrms


#: shock detector defaults: closed-node rise and baseline window (docs/roughness.md)
SHOCK_MIN_CLOSING = 0.1
SHOCK_BASELINE = 0.5e-3


def detect_shocks(time, contact_normal_force, open_fraction, n_slave: int, *, min_closing: float = SHOCK_MIN_CLOSING,
                  baseline_time: float = SHOCK_BASELINE) -> dict:
    """Closing events of a node-to-segment contact (shocks between asperities) from its per-sample records.

    A shock is a run of consecutive samples over which the number of closed slave nodes,
    ``n_closed = (1 - open_fraction) n_slave``, rises by at least ``min_closing`` nodes in total (the records
    are averages over each output period, so one node closing mid-period shows as two partial rises). Its
    impulse is the excess of the contact normal force over its running median (window ``baseline_time`` [s])
    summed over the run and the sample after it, times the sample period [N s].

    Returns
    -------
    dict
        ``count``, ``rate`` [s-1] (count / record duration), ``mean_impulse`` [N s] (NaN without shocks),
        ``start_times`` [s] and ``impulses`` [N s] (arrays), and the thresholds used.
    """
    from scipy.ndimage import median_filter

    t = np.asarray(time, float)
    fc = np.asarray(contact_normal_force, float)
    closed = (1.0 - np.asarray(open_fraction, float)) * int(n_slave)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    w = max(3, int(round(baseline_time / dt)) | 1) if dt > 0 else 3
    excess = fc - median_filter(fc, size=w, mode="nearest")
    d = np.diff(closed)
    starts, impulses = [], []
    i = 0
    while i < d.size:
        if d[i] <= 0:
            i += 1
            continue
        j = i
        while j + 1 < d.size and d[j + 1] > 0:
            j += 1
        if closed[j + 1] - closed[i] >= min_closing:
            starts.append(t[i + 1])
            impulses.append(float(np.sum(np.clip(excess[i + 1:j + 3], 0.0, None)) * dt))
        i = j + 1
    duration = t[-1] - t[0] + dt if t.size else 0.0
    imp = np.array(impulses)
    return {"count": len(starts), "rate": len(starts) / duration if duration > 0 else np.nan,
            "mean_impulse": float(imp.mean()) if imp.size else np.nan, "start_times": np.array(starts),
            "impulses": imp, "min_closing": float(min_closing), "baseline_time": float(baseline_time)}


def dissipated_power(ds, *, start=None) -> float:
    """Mean friction power [W]: least-squares slope of ``friction_dissipation`` over the steady part."""
    part = _steady(ds, start)
    t, e = part["time"].values, part["friction_dissipation"].values
    return float(np.polyfit(t - t[0], e, 1)[0]) if t.size > 1 else np.nan


def roughness_metrics(ds, n_slave: int, *, start=None, **shock_options) -> dict:
    """Lv, V_RMS, shocks, dissipated power and mean forces of a rough-pair run (steady part)."""
    part = _steady(ds, start)
    lv, vrms = vibration_level(ds, start=start)
    sh = detect_shocks(part["time"].values, part["contact_normal_force"].values, part["open_fraction"].values,
                       n_slave, **shock_options)
    return {"vibration_level": lv, "velocity_rms": vrms, "shock_rate": sh["rate"], "shock_impulse": sh["mean_impulse"],
            "shock_count": sh["count"], "dissipated_power": dissipated_power(ds, start=start),
            "mean_normal_force": float(np.mean(part["contact_normal_force"].values)),
            "mean_friction_force": float(np.mean(part["friction_force"].values)),
            "open_fraction": float(np.mean(part["open_fraction"].values)), "shocks": sh,
            **friction_coefficient_statistics(ds, start=start)}


def friction_coefficient_statistics(ds, *, start=None) -> dict:
    """mu(t) = |friction_force(t)| / mean normal force over the steady part: the transducer's force over the
    dead load as the interface carries it (the mean of ``contact_normal_force``; momentary losses of contact,
    frequent on rough surfaces at a few cm/s, would make a pointwise Ft/Fn diverge). ``friction_coefficient``:
    its mean; ``friction_coefficient_rms``: RMS of mu - mean (the perturbation's amplitude over all frequencies
    up to the output Nyquist). The same mu(t) as :func:`identification_run` hands to ``fivid identify``. NaN
    without a transducer (a zero friction_force)."""
    part = _steady(ds, start)
    ft = np.abs(np.asarray(part["friction_force"].values, float))
    fn = float(np.mean(np.asarray(part["contact_normal_force"].values, float))) if part.sizes["time"] else 0.0
    if not np.any(ft) or not fn > 0:
        return {"friction_coefficient": np.nan, "friction_coefficient_rms": np.nan}
    mu = ft / fn
    return {"friction_coefficient": float(np.mean(mu)), "friction_coefficient_rms": float(np.std(mu))}


def identification_run(ds):
    """The run as ``fivid identify`` reads it: its steady part (``time >= transient_end``) with the carriage
    ``velocity`` [m s-1], the imposed sliding velocity, which a simulation does not record as an encoder would.
    A model whose transducer measures along x only (rough_pair_graded.yaml: the carriage's spring) gets the
    dead load as the interface carries it (the steady mean of ``contact_normal_force``) as a constant
    ``normal_force`` and ``|friction_force|`` (:func:`friction_coefficient_statistics`); a model without
    a force transducer (a dead-loaded slider, zero ``friction_force``) gets the interface's
    ``contact_tangential_force`` and ``contact_normal_force`` as ``friction_force`` and ``normal_force``: then
    ``Ft = mu Fn`` holds exactly at sliding Coulomb nodes and mu(t) carries no dynamics.

    ``mu(t) = friction_force / normal_force`` of this dataset is what identify turns into mu0 and the
    perturbation's spectrum and amplitude (docs/roughness.md, "From a profile to a friction law").
    """
    import xarray as xr

    out = _steady(ds)
    scale = float(np.mean(np.abs(out["contact_normal_force"].values))) if "contact_normal_force" in out else 0.0

    def negligible(name):  # a transducer that does not measure this component reads round-off
        return not np.any(np.abs(out[name].values) > 1e-6 * scale)

    if negligible("friction_force") and "contact_normal_force" in out:  # no transducer in the model
        out["friction_force"] = out["contact_tangential_force"].copy()
        out["normal_force"] = out["contact_normal_force"].copy()
        out.attrs["force_note"] = "friction_force, normal_force: the interface's contact forces (no transducer)"
        out.attrs["normal_load"] = float(np.mean(out["normal_force"].values))
    elif negligible("normal_force") and "contact_normal_force" in out:  # transducer along x only
        w = float(np.mean(out["contact_normal_force"].values))
        out["normal_force"] = xr.full_like(out["contact_normal_force"], w)
        out["normal_force"].attrs.update({"units": "N", "long_name": "normal force (the dead load as the interface "
                                                                     "carries it: mean contact normal force)"})
        out["friction_force"] = np.abs(out["friction_force"])
        out["friction_force"].attrs.update({"units": "N", "long_name": "friction force (transducer spring)"})
        out.attrs["force_note"] = ("friction_force: |the transducer spring's force| (the carriage reaction); "
                                   "normal_force: the dead load as the interface carries it (mean contact normal "
                                   "force), as friction_coefficient_statistics")
        out.attrs["normal_load"] = w
    v = np.full(out.sizes["time"], float(ds.attrs["sliding_velocity"]))
    out["velocity"] = (("time",), v, {"units": "m s-1", "long_name": "sliding velocity (encoder)",
                                      "description": "imposed carriage velocity (the simulation's base motion)"})
    out.attrs["history"] = str(ds.attrs.get("history", "")) + "\nidentification_run: steady part, carriage velocity"
    return out


#: Rsm levels [m] of the study's profiles, one per replicate (sweep axis ``seed``: replicate r takes level
#: r mod 2): inside seed 003's Table 1 range (92-516 um) and resolved by >= 8 elements of rough_pair_graded.yaml
RSM_LEVELS = (200e-6, 300e-6)
#: Rsm / correlation length of a Gaussian-ACF profile (ACF exp(-x^2/xi^2)): an element is a peak and a valley,
#: twice the mean zero-crossing spacing pi sqrt(-R(0)/R''(0)) = pi xi / sqrt(2) (Rice 1944)
RSM_PER_CORRELATION_LENGTH = float(np.sqrt(2.0) * np.pi)

#: study task defaults (``points: roughness:``; docs/roughness.md). ``correlation_length`` None: from the
#: replicate's Rsm level (``rsm``, read with this default until the study config accepts the key)
ROUGHNESS_TASK = {"correlation_length": None, "rsm": RSM_LEVELS, "profile_step": 5e-6, "seeds": (3, 4),
                  "sensor_every": 4, "gs_tolerance": 1e-6, "gs_max_iterations": 30, "settle_time": 0.05e-3}


def point_profiles_design(spec: dict, conditions: dict) -> dict:
    """The profile synthesis of a study point: ``replicate`` (the ``seed`` condition, default 0), its target
    ``rsm`` [m] (``spec["rsm"][replicate mod len]``), ``correlation_length`` [m] (``rsm /`` :data:`RSM_PER_CORRELATION_LENGTH`,
    or ``spec["correlation_length"]`` when given) and the two profile ``seeds`` (``spec["seeds"] + 100 replicate``:
    each replicate its own realisation)."""
    r = int(round(float(conditions.get("seed", 0))))
    levels = tuple(spec.get("rsm") or RSM_LEVELS)
    rsm = float(levels[r % len(levels)])
    xi = spec.get("correlation_length")
    xi = float(xi) if xi else rsm / RSM_PER_CORRELATION_LENGTH
    return {"replicate": r, "rsm": rsm if not spec.get("correlation_length") else xi * RSM_PER_CORRELATION_LENGTH,
            "correlation_length": xi, "seeds": tuple(int(v) + 100 * r for v in spec["seeds"])}


def build_point_model(model_path, spec: dict, conditions: dict):
    """The rough pair of a study point: ``(model, lower profile, rough_pair_config record, profile design)``
    for ``conditions`` (``roughness_ra`` [m], ``seed`` (replicate), ``normal_load`` [N]) and the task settings
    ``spec`` (:data:`ROUGHNESS_TASK` keys). The profiles cover the lower (top-profiled) body's length."""
    from fivid.fe import load_model
    from fivid.fe.config import read_config

    spec = {**ROUGHNESS_TASK, **spec}
    base, ctx, _ = read_config(model_path)
    corners = next(b["corners"] for b in base["bodies"].values()
                   if isinstance(b.get("profile"), dict) and b["profile"].get("edge") == "top")
    length = _si(ctx, corners[1][0], "corners") - _si(ctx, corners[0][0], "corners")
    design = point_profiles_design(spec, conditions)
    lower, upper = synthetic_rough_profiles(float(conditions.get("roughness_ra", 0.0)), length,
                                            correlation_length=design["correlation_length"],
                                            step=spec["profile_step"], seeds=design["seeds"])
    load = float(conditions["normal_load"]) if "normal_load" in conditions else None
    cfg, info = rough_pair_config(model_path, lower, upper, sensor_every=spec["sensor_every"], normal_load=load)
    return load_model(cfg), lower, info, design


def simulate_rough_run(model_path, conditions: dict, *, duration: float, sample_rate: float, run_id: str,
                       **spec):
    """A rough-pair run as a rig records it, ready for ``fivid identify`` (:func:`identification_run`): the pair
    of :func:`build_point_model` for ``conditions`` (``roughness_ra`` [m], ``sliding_velocity`` [m s-1],
    ``normal_load`` [N], ``seed``), simulated for ``duration`` [s] at ``sample_rate`` [Hz]; ``spec`` overrides
    :data:`ROUGHNESS_TASK`. identify's steady-window search smooths the velocity over 0.05 s, so ``duration``
    must exceed 0.1 s plus the start-up; the slider must stay on the lower body meanwhile (rough_pair_graded*:
    ``sliding_velocity x duration`` below about 1 mm, i.e. <= ~9 mm/s for 0.1 s)."""
    from fivid.solver import simulate

    spec = {**ROUGHNESS_TASK, **spec}
    model, _, _, design = build_point_model(model_path, spec, conditions)
    kw = {"sliding_velocity": float(conditions["sliding_velocity"])} if "sliding_velocity" in conditions else {}
    ds = simulate(model, duration=duration, sample_rate=sample_rate, progress=False, run_id=run_id,
                  roughness_ra=float(conditions.get("roughness_ra", 0.0)), settle_time=spec["settle_time"],
                  gs_tolerance=spec["gs_tolerance"], gs_max_iterations=spec["gs_max_iterations"], **kw)
    out = identification_run(ds)
    out.attrs["profile_rsm_target"] = design["rsm"]
    out.attrs["profile_seeds"] = " ".join(map(str, design["seeds"]))
    return out


def evaluate_roughness_point(model_path, tasks: dict, conditions: dict) -> dict:
    """One roughness-noise study point: synthesise the point's profiles (``roughness_ra``; Rsm level and seeds from
    the replicate, :func:`point_profiles_design`), build the pair, run it for ``tasks["transient"]`` (duration,
    sample rate) at the point's ``sliding_velocity``, and measure it.

    Returns ``{name: (dims, value, attrs)}`` for the point Dataset: Lv, V_RMS, shock rate and impulse, dissipated
    power, mean forces, the transducer's friction coefficient (mean and RMS fluctuation), open fraction, and the
    generated profiles' Ra, Rq, Rz, Rsm (lower body, :func:`fivid.surface.evaluate_profile`, line form removed, no
    filter, the body's length) with the run's cost.
    """
    import time

    from fivid.solver import simulate
    from fivid.surface import evaluate_profile

    spec = {**ROUGHNESS_TASK, **tasks["roughness"]}
    tr = tasks["transient"]
    ra = float(conditions.get("roughness_ra", 0.0))
    model, lower, info, design = build_point_model(model_path, spec, conditions)
    n_slave = int(sum(c.slave_nodes.size for c in model.contacts))
    kw = {"sliding_velocity": float(conditions["sliding_velocity"])} if "sliding_velocity" in conditions else {}
    t0 = time.perf_counter()
    ds = simulate(model, duration=tr["duration"], sample_rate=tr["sample_rate"], progress=False, roughness_ra=ra,
                  settle_time=spec["settle_time"], gs_tolerance=spec["gs_tolerance"],
                  gs_max_iterations=spec["gs_max_iterations"], **kw)
    seconds = time.perf_counter() - t0
    r = roughness_metrics(ds, n_slave)
    ev = evaluate_profile(lower, form="line").parameters if ra > 0 else {}
    sh = r["shocks"]
    out = {
        "vibration_level": ((), r["vibration_level"], {"units": "dB", "long_name": "vibration level Lv re 1e-9 m s-1 "
                                                       "(RMS normal velocity over the back-face nodes)"}),
        "velocity_rms": ((), r["velocity_rms"], {"units": "m s-1", "long_name": "RMS back-face normal velocity"}),
        "shock_rate": ((), r["shock_rate"], {"units": "s-1", "long_name": "contact closing events per second",
                                             "min_closing": sh["min_closing"], "baseline_time": sh["baseline_time"]}),
        "shock_impulse": ((), r["shock_impulse"], {"units": "N s", "long_name": "mean impulse per shock"}),
        "shock_count": ((), r["shock_count"], {"units": "1", "long_name": "shocks in the steady record"}),
        "dissipated_power": ((), r["dissipated_power"], {"units": "W", "long_name": "friction power (slope of "
                                                         "friction_dissipation)"}),
        "mean_normal_force": ((), r["mean_normal_force"], {"units": "N", "long_name": "mean contact normal force"}),
        "mean_friction_force": ((), r["mean_friction_force"], {"units": "N", "long_name": "mean friction force "
                                                               "(transducer)"}),
        "open_fraction": ((), r["open_fraction"], {"units": "1", "long_name": "mean share of open slave nodes"}),
        "friction_coefficient": ((), r["friction_coefficient"], {"units": "1", "long_name": "mean of mu(t) = "
                                                                 "|transducer force| / mean contact normal force"}),
        "friction_coefficient_rms": ((), r["friction_coefficient_rms"], {
            "units": "1", "long_name": "RMS fluctuation of mu(t) (the perturbation amplitude, all frequencies)"}),
        "profile_rsm_target": ((), design["rsm"], {"units": "m", "long_name": "Rsm level of the point's profiles "
                                                   "(replicate)", "replicate": design["replicate"]}),
        "simulation_seconds": ((), seconds, {"units": "s", "long_name": "wall time of the simulation"}),
        "dof_updates_per_second": ((), model.coords.size * ds.attrs["steps"] / seconds,
                                   {"units": "s-1", "long_name": "degrees of freedom x steps / wall time"}),
        "n_dof": ((), int(model.coords.size), {"units": "1", "long_name": "degrees of freedom"}),
        "time_step": ((), float(ds.attrs["time_step"]), {"units": "s", "long_name": "solver time step"}),
    }
    for key in ("Ra", "Rq", "Rz", "Rsm"):
        if key in ev:
            out[f"profile_{key}"] = ((), float(ev[key]) if ev[key] is not None else np.nan,
                                     {"units": "m", "long_name": f"{key} of the lower body's profile (line removed, "
                                                                 "no filter, whole length)"})
    out["upper_lift"] = ((), info["lift"], {"units": "m", "long_name": "upper body lift to first touch",
                                            "back_face_sensors": info["back_face_sensors"],
                                            "sensor_every": info["sensor_every"],
                                            "correlation_length": design["correlation_length"],
                                            "profile_seeds": " ".join(map(str, design["seeds"]))})
    return out


def roughness_settings(study) -> dict:
    """What a roughness-noise study's numbers depend on (summary.json ``roughness_settings``): the model and
    its mesh, the profiles' synthesis, the record and the analysis window, the detector's thresholds."""
    from fivid.fe.config import read_config

    spec = {**ROUGHNESS_TASK, **study.points["roughness"]}
    data, _, origin = read_config(study.model_path)
    return {
        "model": origin,
        "mesh": {name: {"divisions": list(b["divisions"]), "grading": b.get("grading")}
                 for name, b in data["bodies"].items()},
        "profiles": {"generator": "fivid.surface.gaussian_random_profile", "acf": "gaussian",
                     "rq_per_ra": RQ_PER_RA,
                     "rsm_levels": list(spec["rsm"]) if not spec["correlation_length"] else None,
                     "correlation_length": (spec["correlation_length"] or
                                            [float(v) / RSM_PER_CORRELATION_LENGTH for v in spec["rsm"]]),
                     "rsm_per_correlation_length": RSM_PER_CORRELATION_LENGTH,
                     "replicates": "sweep axis seed: replicate r takes Rsm level r mod len(levels) and profile seeds "
                                   "(lower, upper) + 100 r",
                     "step": spec["profile_step"], "seeds": {"lower": spec["seeds"][0], "upper": spec["seeds"][1]},
                     "metrology": "lower profile, line removed, no filter, the body's length "
                                  "(fivid.surface.evaluate_profile)"},
        "record": {"duration": study.points["transient"]["duration"],
                   "sample_rate": study.points["transient"]["sample_rate"],
                   "window": "steady part: time >= transient_end (preload ramp, settle_time, base ramp excluded)",
                   "settle_time": spec["settle_time"]},
        "friction_coefficient": "mu(t) = |friction_force (transducer)| / mean contact_normal_force, steady part",
        "sensors": f"velocity (y) on every {spec['sensor_every']}th node of the lower body's back face",
        "lv_reference": LV_REFERENCE,
        "shock_detector": {"min_closing_nodes": SHOCK_MIN_CLOSING, "baseline_time": SHOCK_BASELINE},
        "contact_gauss_seidel": {"tolerance": spec["gs_tolerance"], "max_iterations": spec["gs_max_iterations"]},
    }
