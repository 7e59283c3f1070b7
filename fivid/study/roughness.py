"""Seed 003's rough sliding pair as a study: a point's profiles, model and run, and what the study records.

The physics lives below the study layer: the synthetic profiles in :mod:`fivid.surface.rough_pair`, the pair's
model config in :mod:`fivid.fe.rough_pair`, the run's metrics (Lv, shocks, friction power, the transducer's
friction coefficient) in :mod:`fivid.score.roughness`. Here: a study point's profile design
(:func:`point_profiles_design`: the replicate's Rsm level and seeds), its model (:func:`build_point_model`), its
evaluation (:func:`evaluate_roughness_point`, the ``roughness`` kind's), a run ready for ``fivid identify``
(:func:`identification_run`, :func:`simulate_rough_run`) and the settings a roughness study's numbers depend on
(:func:`roughness_settings`).
"""

from __future__ import annotations

import time

import numpy as np

from fivid.fe import load_model
from fivid.fe.config import read_config
from fivid.fe.mass_scaling import surface_mass_scaling
from fivid.fe.rough_pair import profiled_length, rough_pair_config
from fivid.fe.transition import transition_model
from fivid.score.roughness import (
    LV_BAND,
    LV_REFERENCE,
    SHOCK_BASELINE,
    SHOCK_MIN_CLOSING,
    friction_coefficient_statistics,
    roughness_metrics,
)
from fivid.signal.steady import steady_part
from fivid.solver import IntegrationOptions, OperatingCondition, OutputOptions, RunSchedule, simulate
from fivid.surface import evaluate_profile
from fivid.surface.rough_pair import (
    RQ_PER_RA,
    RSM_PER_CORRELATION_LENGTH,
    iso_cutoff,
    measured_rough_profiles,
    synthetic_rough_profiles,
    table1_profiles,
    table1_row,
)

__all__ = ["identification_run", "build_point_model", "simulate_rough_run", "point_profiles_design",
           "evaluate_roughness_point", "roughness_settings", "RSM_LEVELS", "ROUGHNESS_TASK"]


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

    out = steady_part(ds)
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
#: Table 1 surfaces are synthesised at Rsm / this, whatever the mesh (``nodes_per_rsm``): the random draws of a
#: spectral synthesis depend on its sample count, so a step that followed the mesh gave every resolution its own
#: surface, and a convergence check compared two realisations, not two resolutions; 24 samples per Rsm are the
#: nodes of the finest mesh checked (Rsm/12) and twice those of the study's Rsm/8
TABLE1_SYNTHESIS_PER_RSM = 24
#: study task defaults (``points: roughness:``; docs/roughness.md). ``correlation_length`` None: from the
#: replicate's Rsm level (``rsm``, read with this default until the study config accepts the key)
ROUGHNESS_TASK = {"correlation_length": None, "rsm": RSM_LEVELS, "profile_step": 5e-6, "seeds": (3, 4),
                  "sensor_every": 4, "gs_tolerance": 1e-6, "gs_max_iterations": 30, "settle_time": 0.05e-3,
                  "surfaces": "rsm_levels", "nodes_per_rsm": None, "sensor_spacing": None, "profile_files": None,
                  "seat": False, "transition": False, "surface_added_mass": None}


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


def _point_profiles(spec: dict, conditions: dict, length: float, design: dict):
    """The point's two profiles and their Rsm [m] (the mesh step's reference): ``surfaces`` "table1" (seed 003's
    Table 1 surface of the point's Ra, :func:`fivid.surface.rough_pair.table1_profiles`), "measured"
    (``profile_files``: lower, upper; their ISO Rsm) or "rsm_levels" (the replicate's Rsm level)."""
    ra = float(conditions.get("roughness_ra", 0.0))
    kind = spec.get("surfaces") or "rsm_levels"
    if kind == "table1":
        rsm = table1_row(ra)["Rsm"]
        return table1_profiles(ra, length, seeds=design["seeds"], step=rsm / TABLE1_SYNTHESIS_PER_RSM), rsm
    if kind == "measured":
        lower, upper = measured_rough_profiles(*spec["profile_files"], length)
        rsm = evaluate_profile(lower, form="line").parameters["Rsm"]
        rsm = evaluate_profile(lower, form="line", cutoff=iso_cutoff(rsm)).parameters["Rsm"]
        return (lower, upper), float(rsm)
    profiles = synthetic_rough_profiles(ra, length, correlation_length=design["correlation_length"],
                                        step=spec["profile_step"], seeds=design["seeds"])
    return profiles, design["rsm"]


def build_point_model(model_path, spec: dict, conditions: dict):
    """The rough pair of a study point: ``(model, lower profile, rough_pair_config record, profile design)``
    for ``conditions`` (``roughness_ra`` [m], ``seed`` (replicate), ``normal_load`` [N]) and the task settings
    ``spec`` (:data:`ROUGHNESS_TASK` keys). The profiles cover the lower (top-profiled) body's length.

    With ``nodes_per_rsm`` both blocks are re-divided at ``Rsm / nodes_per_rsm`` (the point's surface Rsm:
    :func:`fivid.fe.rough_pair.rough_pair_config`'s ``mesh_step``); with ``sensor_spacing`` [m] the back-face
    sensors sit on every ``round(sensor_spacing / mesh step)``-th node (``sensor_every`` otherwise); with ``seat``
    the upper block starts seated on its two supporting asperities (``rough_pair_config``'s ``seat``); with
    ``transition`` (and ``nodes_per_rsm``) both blocks coarsen along x with depth
    (:func:`fivid.fe.transition.transition_model`: only the surface level has columns of the mesh step); with
    ``surface_added_mass`` (a fraction of each body's mass) their surface levels are mass-scaled
    (:func:`fivid.fe.mass_scaling.surface_mass_scaling`; the record's ``mass_scaling``)."""
    spec = {**ROUGHNESS_TASK, **spec}
    length = profiled_length(model_path)
    design = point_profiles_design(spec, conditions)
    (lower, upper), rsm = _point_profiles(spec, conditions, length, design)
    design = {**design, "rsm": rsm, "surfaces": spec.get("surfaces") or "rsm_levels"}
    mesh_step = rsm / float(spec["nodes_per_rsm"]) if spec.get("nodes_per_rsm") else None
    every = spec["sensor_every"]
    if spec.get("sensor_spacing") and mesh_step:
        every = max(1, int(round(float(spec["sensor_spacing"]) / mesh_step)))
    design["mesh_step"] = mesh_step
    load = float(conditions["normal_load"]) if "normal_load" in conditions else None
    cfg, info = rough_pair_config(model_path, lower, upper, sensor_every=every, normal_load=load,
                                  mesh_step=mesh_step, seat=bool(spec.get("seat")),
                                  transition=bool(spec.get("transition")))
    model = load_model(cfg)
    if info["transition"]:
        model = transition_model(model, info["transition"])
    info["mass_scaling"] = {}
    if spec.get("surface_added_mass"):
        model, info["mass_scaling"] = surface_mass_scaling(model, max_added_mass=float(spec["surface_added_mass"]))
    return model, lower, info, design


def _point_condition(conditions: dict, roughness_ra: float) -> OperatingCondition:
    """The point's sliding velocity [m s-1] (as configured when not a condition) and Ra [m]."""
    v = float(conditions["sliding_velocity"]) if "sliding_velocity" in conditions else None
    return OperatingCondition(sliding_velocity=v, roughness_ra=roughness_ra)


def _contact_iterations(spec: dict) -> IntegrationOptions:
    """The contact Gauss-Seidel limits of a roughness task (``gs_tolerance``, ``gs_max_iterations``)."""
    return IntegrationOptions(gs_tolerance=spec["gs_tolerance"], gs_max_iterations=spec["gs_max_iterations"])


def simulate_rough_run(model_path, conditions: dict, *, duration: float, sample_rate: float, run_id: str,
                       **spec):
    """A rough-pair run as a rig records it, ready for ``fivid identify`` (:func:`identification_run`): the pair
    of :func:`build_point_model` for ``conditions`` (``roughness_ra`` [m], ``sliding_velocity`` [m s-1],
    ``normal_load`` [N], ``seed``), simulated for ``duration`` [s] at ``sample_rate`` [Hz]; ``spec`` overrides
    :data:`ROUGHNESS_TASK`. identify's steady-window search smooths the velocity over 0.05 s, so ``duration``
    must exceed 0.1 s plus the start-up; the slider must stay on the lower body meanwhile (rough_pair_graded*:
    ``sliding_velocity x duration`` below about 1 mm, i.e. <= ~9 mm/s for 0.1 s)."""
    spec = {**ROUGHNESS_TASK, **spec}
    model, _, _, design = build_point_model(model_path, spec, conditions)
    ds = simulate(model, _point_condition(conditions, float(conditions.get("roughness_ra", 0.0))),
                  schedule=RunSchedule(duration=duration, sample_rate=sample_rate, settle_time=spec["settle_time"]),
                  integration=_contact_iterations(spec), output=OutputOptions(run_id=run_id, progress=False))
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
    spec = {**ROUGHNESS_TASK, **tasks["roughness"]}
    tr = tasks["transient"]
    ra = float(conditions.get("roughness_ra", 0.0))
    model, lower, info, design = build_point_model(model_path, spec, conditions)
    n_slave = int(sum(c.slave_nodes.size for c in model.contacts))
    t0, c0 = time.perf_counter(), time.process_time()
    ds = simulate(model, _point_condition(conditions, ra),
                  schedule=RunSchedule(duration=tr["duration"], sample_rate=tr["sample_rate"],
                                       settle_time=spec["settle_time"]),
                  integration=_contact_iterations(spec), output=OutputOptions(progress=False))
    seconds, cpu = time.perf_counter() - t0, time.process_time() - c0
    r = roughness_metrics(ds, n_slave)
    cutoff = iso_cutoff(design["rsm"]) if design["surfaces"] != "rsm_levels" else None  # Table 1's ISO metrology
    ev = evaluate_profile(lower, form="line", cutoff=cutoff).parameters if ra > 0 or cutoff else {}
    sh = r["shocks"]
    out = {
        "vibration_level": ((), r["vibration_level"], {"units": "dB", "long_name": "vibration level Lv re 1e-9 m s-1 "
                                                       "(RMS normal velocity over the back-face nodes)"}),
        "velocity_rms": ((), r["velocity_rms"], {"units": "m s-1", "long_name": "RMS back-face normal velocity"}),
        "band_vibration_level": ((), r["band_vibration_level"], {
            "units": "dB", "long_name": f"vibration level Lv re 1e-9 m s-1 in {LV_BAND[0]:g}-{LV_BAND[1]:g} Hz "
                                        "(fivid.score.roughness.band_vibration_level)", "band": list(LV_BAND)}),
        "band_velocity_rms": ((), r["band_velocity_rms"], {
            "units": "m s-1", "long_name": f"RMS back-face normal velocity in {LV_BAND[0]:g}-{LV_BAND[1]:g} Hz"}),
        "shock_rate": ((), r["shock_rate"], {"units": "s-1", "long_name": "contact closing events per second",
                                             "min_closing": sh["min_closing"], "baseline_time": sh["baseline_time"]}),
        "shock_impulse": ((), r["shock_impulse"], {"units": "N s", "long_name": "mean impulse per shock"}),
        "shock_count": ((), r["shock_count"], {"units": "1", "long_name": "shocks in the steady record"}),
        "friction_power": ((), r["friction_power"], {"units": "W", "long_name": "friction power (slope of "
                                                     "friction_dissipation)"}),
        "vibratory_power": ((), r["vibratory_power"], {"units": "W", "long_name": "vibratory power (slope of "
                                                       "damping_dissipation: dissipated by the N shocks' vibration)"}),
        "shock_energy": ((), r["shock_energy"], {"units": "J", "long_name": "shock intensity: vibratory energy "
                                                 "per shock (vibratory power / shock rate)"}),
        "impact_power": ((), r["impact_power"], {"units": "W", "long_name": "impact dissipation rate (slope of "
                                                 "impact_dissipation)"}),
        "mean_normal_force": ((), r["mean_normal_force"], {"units": "N", "long_name": "mean contact normal force"}),
        "mean_friction_force": ((), r["mean_friction_force"], {"units": "N", "long_name": "mean friction force "
                                                               "(transducer)"}),
        "open_fraction": ((), r["open_fraction"], {"units": "1", "long_name": "mean share of open slave nodes"}),
        "friction_coefficient": ((), r["friction_coefficient"], {"units": "1", "long_name": "mean of mu(t) = "
                                                                 "|transducer force| / mean contact normal force"}),
        "friction_coefficient_rms": ((), r["friction_coefficient_rms"], {
            "units": "1", "long_name": "RMS fluctuation of mu(t) (the perturbation amplitude, all frequencies)"}),
        "profile_rsm_target": ((), design["rsm"], {"units": "m", "long_name": "target Rsm of the point's profiles "
                                                   f"({design['surfaces']})", "replicate": design["replicate"]}),
        "simulation_seconds": ((), seconds, {"units": "s", "long_name": "wall time of the simulation"}),
        "simulation_cpu_seconds": ((), cpu, {"units": "s", "long_name": "CPU time of the simulation (process)"}),
        "mesh_step": ((), design["mesh_step"] if design["mesh_step"] else np.nan,
                      {"units": "m", "long_name": "element length along the contact (Rsm / nodes_per_rsm)"}),
        "dof_updates_per_second": ((), model.coords.size * ds.attrs["steps"] / seconds,
                                   {"units": "s-1", "long_name": "degrees of freedom x steps / wall time"}),
        "n_dof": ((), int(model.coords.size), {"units": "1", "long_name": "degrees of freedom"}),
        "time_step": ((), float(ds.attrs["time_step"]), {"units": "s", "long_name": "solver time step"}),
        "added_mass_fraction": ((), max([r["added_mass_fraction"] for r in info["mass_scaling"].values()], default=0.0),
                                {"units": "1", "long_name": "mass added by the surface levels' mass scaling, largest "
                                                            "fraction of a body's mass (fivid.fe.mass_scaling)",
                                 "density_factors": " ".join(f"{k}:{r['factor']:.4g}"
                                                             for k, r in info["mass_scaling"].items())}),
    }
    for key in ("Ra", "Rq", "Rz", "Rsm"):
        if key in ev:
            out[f"profile_{key}"] = ((), float(ev[key]) if ev[key] is not None else np.nan,
                                     {"units": "m", "long_name": f"{key} of the lower body's profile (line removed, "
                                                                 "whole length, filter: ISO 4288 cut-off for "
                                                                 "Table 1 / measured surfaces, none otherwise)"})
    out["upper_lift"] = ((), info["lift"], {"units": "m", "long_name": "upper body lift to first touch",
                                            "back_face_sensors": info["back_face_sensors"],
                                            "sensor_every": info["sensor_every"],
                                            "correlation_length": design["correlation_length"],
                                            "profile_seeds": " ".join(map(str, design["seeds"]))})
    return out


def roughness_settings(study) -> dict:
    """What a roughness-noise study's numbers depend on (summary.json ``roughness_settings``): the model and
    its mesh, the profiles' synthesis, the record and the analysis window, the detector's thresholds."""
    spec = {**ROUGHNESS_TASK, **study.points["roughness"]}
    data, _, origin = read_config(study.model_path)
    return {
        "model": origin,
        "mesh": {name: {"divisions": list(b["divisions"]), "grading": b.get("grading")}
                 for name, b in data["bodies"].items()},
        "surfaces": spec.get("surfaces") or "rsm_levels",
        "nodes_per_rsm": spec.get("nodes_per_rsm"), "sensor_spacing": spec.get("sensor_spacing"),
        "seat": bool(spec.get("seat")), "transition": bool(spec.get("transition")),
        "surface_added_mass": spec.get("surface_added_mass"),
        "profile_files": spec.get("profile_files"),
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
        "lv_band": {"band": list(LV_BAND), "estimator": "mean over sensors of the mean square times the band's share "
                                                      "of the Hann periodogram (fivid.score.roughness."
                                                      "band_vibration_level)"},
        "shock_detector": {"min_closing_nodes": SHOCK_MIN_CLOSING, "baseline_time": SHOCK_BASELINE},
        "contact_gauss_seidel": {"tolerance": spec["gs_tolerance"], "max_iterations": spec["gs_max_iterations"]},
    }
