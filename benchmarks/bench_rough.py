"""Cost of one roughness-noise study point (issue 15), next to the default rig, measured in one run.

    python benchmarks/bench_rough.py [--quick]

Prints one JSON line. The rough model is the study's (``configs/studies/roughness_noise.yaml``): the pair of
``configs/models/rough_pair_graded.yaml`` built by :func:`fivid.study.roughness.build_point_model` for one point
(Ra 4.5 um, Rsm level 200 um, 1 N dead load, 10 cm/s), or ``rough_pair_graded_quick.yaml`` with ``--quick``
(the study's ``--quick`` model). Both it and the default rig (``configs/models/triboair.yaml``, the run of
``benchmarks/bench_solver.py``: 5 N, 1 cm/s) run a short preload-and-slide record, interleaved, best of the
rounds (the machine is shared): ``rough_dof_updates_per_s`` and ``default_dof_updates_per_s`` (dofs x steps / wall
time of the whole run), their ratio ``rough_over_default``, the rough model's ``rough_dofs``,
``rough_time_step_s`` (the stable step of its smallest element), ``rough_steps_per_point`` (the study's 4.2 ms
record, or the quick study's 1.2 ms, over that step) and ``rough_point_projected_s`` (those steps at the measured
rate: the simulation time of one study point; ``rough_point_projected_cpu_s`` the same from the process's CPU
time, which a shared machine's load does not inflate, as are the ``*_cpu_dof_updates_per_s`` and
``rough_over_default_cpu``), with the contact's mean Gauss-Seidel sweeps per step.

The contact at the paper's size (issue 26 item 5): ``full_scale_*``, the two 120 x 8 mm blocks of
``configs/models/rough_pair.yaml`` with the surface spacing at Rsm/8 of Table 1's finest surface (Ra 1 um, Rsm
92 um: 10 435 divisions along x, the base config's 12 graded layers through the depth) and synthetic Gaussian
profiles of that Ra and Rsm (:func:`fivid.surface.rough_pair.synthetic_rough_profiles`, seeds 3 and 4; the upper
body lifted to first touch by :func:`fivid.fe.rough_pair.rough_pair_config`), built here until the study's own
full-scale model config exists: ``full_scale_slave_nodes``, ``full_scale_dofs``,
``full_scale_fraction_of_bare_stencil`` (its full step against the bare rectangular stencil + update on the same
node count, measured in this run, as ``bench_solver.py``'s ``rough_fraction_of_bare_stencil``), the same without its
contact pair (``full_scale_no_contact_fraction_of_bare_stencil``: the mapped stencil's own cost), the contact's
share of the step ``full_scale_contact_share`` (the same three from the process's CPU time, ``full_scale_cpu_*``,
for a loaded machine) and ``full_scale_steps`` of a short preload-and-slide record
(30 mm/s) at the paper-scale study's recording rate (``configs/studies/roughness_paper.yaml``: 2 MHz, recorded
internally at 4x, ``full_scale_steps_per_record`` steps per record, each record one extra stencil pass for the
energies) and with its model's damping (``rough_pair_paper.yaml``: no mass term, band-limited stiffness term), so
the step is the study's (before the 2026-11-27 afternoon session: rough_pair.yaml's classic Rayleigh damping and a
record every 4 steps, whose energy pass -- one stencil pass, ~0.9 ms, per 4 steps of ~2.3 ms -- was ~10 % of the
step, which the study pays once per ~40 steps). With ``--quick`` the full-scale figures come from a 12 mm cut at
the same spacing (the smoke run).
With ``--transition`` the full-scale pair coarsens along x with depth (:mod:`fivid.fe.transition`, as the
paper-scale study's ``transition: true``) instead: only its surface level has the Rsm/8 columns
(``full_scale_mesh`` names which), and its surface levels are mass-scaled as the paper-scale study's
(``points.roughness.surface_added_mass``, or ``--surface-added-mass``; :mod:`fivid.fe.mass_scaling`): printed are
the step used ``full_scale_time_step_s`` (0.9 of the stable step) and the unscaled model's
``full_scale_unscaled_time_step_s``, the cap ``full_scale_surface_added_mass`` and per block its density factor and
added mass fraction ``full_scale_mass_scaling``, the CPU time per step ``full_scale_cpu_us_per_step`` and the
study's 1.25 ms record at that step and cost, ``full_scale_point_projected_cpu_s`` (set-up not included).

Idle full-scale figures (issue 26)::

    python benchmarks/bench_rough.py --full-scale-only --transition
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from _load_guard import parse_guarded  # benchmarks/, this script's folder

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="the quick study's model and shorter runs (noisier)")
    ap.add_argument("--full-scale-only", action="store_true", help="only the full-scale contact figures")
    ap.add_argument("--transition", action="store_true",
                    help="the full-scale pair coarsening along x with depth (fivid.fe.transition)")
    ap.add_argument("--surface-added-mass", type=float, default=None,
                    help="with --transition: mass-scale the surface levels, adding at most this fraction of each "
                         "body's mass (fivid.fe.mass_scaling; default: the paper-scale study's "
                         "points.roughness.surface_added_mass; 0: none)")
    args, load = parse_guarded(ap, argv)
    out = {"benchmark": "rough", "quick": bool(args.quick)}
    from fivid.study.config import load_study

    paper = load_study(ROOT / "configs/studies/roughness_paper.yaml")
    added = args.surface_added_mass
    if added is None:
        added = paper.points["roughness"].get("surface_added_mass")
    out.update(_full_scale(2 if args.quick else 3, 60 if args.quick else 300, 0.012 if args.quick else 0.12,
                           transition=args.transition, added_mass=float(added or 0.0) if args.transition else 0.0,
                           study=paper))
    if args.full_scale_only:
        out["load_average_1min"] = load
        print(json.dumps(out))
        return 0

    from fivid.fe import load_model
    from fivid.solver import FrictionInput, IntegrationOptions, OperatingCondition, RunSchedule
    from fivid.solver.driver import prepare_run
    from fivid.study.config import load_study
    from fivid.study.roughness import ROUGHNESS_TASK, build_point_model

    study = load_study(ROOT / "configs/studies/roughness_noise.yaml", quick=args.quick)
    spec = {**ROUGHNESS_TASK, **study.points["roughness"]}
    conditions = {"roughness_ra": 4.5e-6, "sliding_velocity": 0.1, "normal_load": 1.0, "seed": 0}
    rough, _, _, _ = build_point_model(study.model_path, spec, conditions)
    default = load_model(ROOT / "configs/models/triboair.yaml")

    duration = 0.3e-3 if args.quick else 1e-3  # the rough record; the start-up ramps are 0.2 ms
    rough_prep = prepare_run(rough, OperatingCondition(sliding_velocity=conditions["sliding_velocity"],
                                                       roughness_ra=conditions["roughness_ra"]),
                             schedule=RunSchedule(duration=duration,
                                                  sample_rate=study.points["transient"]["sample_rate"],
                                                  settle_time=spec["settle_time"]),
                             integration=IntegrationOptions(gs_tolerance=spec["gs_tolerance"],
                                                            gs_max_iterations=spec["gs_max_iterations"]))
    default_prep = prepare_run(default, OperatingCondition(sliding_velocity=0.01, normal_load=5.0),
                               FrictionInput(mu=0.3),
                               schedule=RunSchedule(duration=1e-4 if args.quick else 5e-4, sample_rate=51200.0,
                                                    preload_time=2e-4, settle_time=0.0, base_ramp_time=1e-4))
    rough_prep.run(progress=False)  # warm-up: load the cached kernels
    t_rough = t_default = c_rough = c_default = float("inf")
    for _ in range(2 if args.quick else 3):
        t0, c0 = time.perf_counter(), time.process_time()
        ds = rough_prep.run(progress=False)
        t_rough = min(t_rough, time.perf_counter() - t0)
        c_rough = min(c_rough, time.process_time() - c0)
        t0, c0 = time.perf_counter(), time.process_time()
        default_prep.run(progress=False)
        t_default = min(t_default, time.perf_counter() - t0)
        c_default = min(c_default, time.process_time() - c0)
    rs, ds_ = rough_prep.settings, default_prep.settings
    rough_steps = rs.n_intervals * rs.steps_per_interval
    default_steps = ds_.n_intervals * ds_.steps_per_interval
    rough_rate = rough.n_dofs * rough_steps / t_rough
    default_rate = default.n_dofs * default_steps / t_default
    point_steps = int(round(study.points["transient"]["duration"] / rs.time_step))
    out.update({
        "rough_model": str(Path(study.model_path).relative_to(ROOT)),
        "rough_conditions": conditions,
        "rough_dofs": int(rough.n_dofs),
        "rough_slave_nodes": int(sum(c.slave_nodes.size for c in rough.contacts)),
        "rough_time_step_s": rs.time_step,
        "rough_steps_measured": rough_steps,
        "rough_contact_gs_mean_sweeps": ds.attrs.get("contact_gs_mean_sweeps"),
        "rough_dof_updates_per_s": rough_rate,
        "rough_steps_per_point": point_steps,
        "rough_point_record_s": study.points["transient"]["duration"],
        "rough_point_projected_s": point_steps * t_rough / rough_steps,
        "rough_point_projected_cpu_s": point_steps * c_rough / rough_steps,
        "default_model": "configs/models/triboair.yaml",
        "default_dofs": int(default.n_dofs),
        "default_dof_updates_per_s": default_rate,
        "rough_over_default": rough_rate / default_rate,
        "rough_cpu_dof_updates_per_s": rough.n_dofs * rough_steps / c_rough,
        "default_cpu_dof_updates_per_s": default.n_dofs * default_steps / c_default,
        "rough_over_default_cpu": (rough.n_dofs * rough_steps / c_rough) / (default.n_dofs * default_steps / c_default),
        "load_average_1min": load,
    })
    print(json.dumps(out))
    return 0


def _full_scale_pair(rsm=92e-6, ra=1e-6, per_rsm=8, length=0.12, transition=False, damping=None):
    """The full-scale rough pair (see the module docstring): ``configs/models/rough_pair.yaml`` with
    ``ceil(length / (rsm / per_rsm))`` divisions along x over ``length`` [m] (0.12: the paper's blocks) and
    Gaussian profiles of ``ra``, ``rsm`` [m]; ``transition``: coarsening along x with depth; ``damping``: a model
    config's ``damping`` mapping instead of the file's."""
    import math

    import yaml

    from fivid.fe import load_model
    from fivid.fe.rough_pair import rough_pair_config
    from fivid.fe.transition import transition_model
    from fivid.surface.rough_pair import RSM_PER_CORRELATION_LENGTH, synthetic_rough_profiles

    data = yaml.safe_load((ROOT / "configs/models/rough_pair.yaml").read_text())
    if damping is not None:
        data["damping"] = damping
    nx = math.ceil(length / (rsm / per_rsm))
    for body in data["bodies"].values():
        body["divisions"] = [nx, body["divisions"][1]]
        # the corners in the file's units: scale x to ``length`` (120 mm in the file; --quick cuts it)
        body["corners"] = [[f"{float(str(x).split()[0]) * length / 0.12:.9g} mm", y] for x, y in body["corners"]]
    lower, upper = synthetic_rough_profiles(ra, length, correlation_length=rsm / RSM_PER_CORRELATION_LENGTH,
                                            step=rsm / (2 * per_rsm), seeds=(3, 4))
    if transition:
        cfg, info = rough_pair_config(data, lower, upper, sensor_every=64, mesh_step=rsm / per_rsm, transition=True)
        return transition_model(load_model(cfg), info["transition"])
    cfg, _ = rough_pair_config(data, lower, upper, sensor_every=64)
    return load_model(cfg)


def _full_scale(rounds, steps, length=0.12, transition=False, added_mass=0.0, study=None):
    """``full_scale_*`` figures (module docstring): about ``steps`` time steps per run (at least two of the study's
    records), best of ``rounds``, on blocks ``length`` [m] long (``--quick``: a 12 mm cut at the same surface
    spacing, so the smoke run stays short); ``added_mass``: the surface levels' mass scaling
    (:func:`fivid.fe.mass_scaling.surface_mass_scaling`); ``study``: the paper-scale study (its model's damping,
    its recording rate)."""
    import yaml
    import dataclasses

    import numpy as np
    from bench_solver import _bare_kernels  # benchmarks/, this script's folder

    from fivid.fe import load_model
    from fivid.solver import OperatingCondition, RunSchedule
    from fivid.solver.stencil import block_stencils
    from fivid.solver.timestep import stable_step

    from fivid.fe.mass_scaling import surface_mass_scaling

    damping = yaml.safe_load(Path(study.model_path).read_text())["damping"]
    rate = float(study.points["transient"]["sample_rate"])
    model = _full_scale_pair(length=length, transition=transition, damping=damping)
    dt_unscaled = 0.9 * stable_step(model).critical_time_step
    model, scaling = surface_mass_scaling(model, max_added_mass=added_mass)
    st = block_stencils(load_model(ROOT / "configs/models/triboair.yaml"))
    c_rect = st.c_uni[int(st.blocks[np.flatnonzero(st.blocks[:, 4] == 1)[0], 5])]  # the rig's interior stencil
    bare = _bare_kernels()[0]
    dt = 0.9 * stable_step(model).critical_time_step
    kw = dict(condition=OperatingCondition(sliding_velocity=0.03),
              schedule=RunSchedule(duration=max(steps * dt, 2.0 / rate), sample_rate=rate, preload_time=2 * dt,
                                   settle_time=0.0, base_ramp_time=2 * dt))
    out = {"full_scale_model": f"configs/models/rough_pair.yaml at Rsm/8 (Ra 1 um, Rsm 92 um), {length * 1e3:g} mm long, "
                               f"the damping of {Path(study.model_path).name}",
           "full_scale_mesh": "transition" if transition else "graded",
           "full_scale_slave_nodes": int(sum(c.slave_nodes.size for c in model.contacts)),
           "full_scale_dofs": int(model.n_dofs), "full_scale_time_step_s": dt,
           "full_scale_unscaled_time_step_s": dt_unscaled, "full_scale_surface_added_mass": added_mass,
           "full_scale_mass_scaling": {k: {"density_factor": r["factor"], "added_mass_fraction": r["added_mass_fraction"]}
                                       for k, r in scaling.items()}}
    frac, cpu, sweeps, step_cpu, (n_steps, per_record) = _step_fraction(model, c_rect, bare, kw, rounds)
    frac0, cpu0, _, _, _ = _step_fraction(dataclasses.replace(model, contacts=()), c_rect, bare, kw, rounds)
    out.update({"full_scale_fraction_of_bare_stencil": frac, "full_scale_no_contact_fraction_of_bare_stencil": frac0,
                "full_scale_contact_share": 1.0 - frac / frac0, "full_scale_cpu_fraction_of_bare_stencil": cpu,
                "full_scale_cpu_no_contact_fraction_of_bare_stencil": cpu0, "full_scale_cpu_contact_share": 1.0 - cpu / cpu0,
                "full_scale_contact_gs_mean_sweeps": sweeps, "full_scale_steps": n_steps,
                "full_scale_steps_per_record": per_record, "full_scale_record_rate_hz": rate,
                "full_scale_cpu_us_per_step": 1e6 * step_cpu,
                # the paper-scale study's 1.25 ms record at this step and per-step CPU (the run's setup not included)
                "full_scale_point_projected_cpu_s": step_cpu * 1.25e-3 / dt})
    return out


def _step_fraction(model, c_rect, bare, kw, rounds):
    """``(wall, cpu, mean Gauss-Seidel sweeps, CPU seconds per step of the model, (steps, steps per recorded
    interval))``: the bare rectangular stencil + update on a ghost-padded grid of the
    model's node count per block (``bench_solver.py``'s reference) over the model's full step
    (:meth:`fivid.solver.driver.PreparedRun.run` per step), by wall time and by the process's CPU time (which the
    shared machine's load inflates less), interleaved rounds, best of each."""
    import numpy as np
    from bench_solver import _bare_arguments  # benchmarks/, this script's folder

    from fivid.solver.driver import prepare_run

    prep = prepare_run(model, **kw)
    steps = prep.settings.n_intervals * prep.settings.steps_per_interval
    bare_args = _bare_arguments(model, prep, c_rect, bare)
    ds = prep.run(progress=False)  # compile/load the kernels for this model's argument types
    best = {k: np.inf for k in ("run", "bare", "run_cpu", "bare_cpu")}
    for _ in range(rounds):
        for key, call in (("run", lambda: prep.run(progress=False)),
                          ("bare", lambda: bare(steps, *bare_args))):
            t0, c0 = time.perf_counter(), time.process_time()
            call()
            best[key] = min(best[key], time.perf_counter() - t0)
            best[key + "_cpu"] = min(best[key + "_cpu"], time.process_time() - c0)
    return (best["bare"] / best["run"], best["bare_cpu"] / best["run_cpu"], ds.attrs.get("contact_gs_mean_sweeps"),
            best["run_cpu"] / steps, (steps, prep.settings.steps_per_interval))


if __name__ == "__main__":
    raise SystemExit(main())
