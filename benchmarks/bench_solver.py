"""Speed of the explicit contact solver (issue 5), as ratios measured in one run.

    python benchmarks/bench_solver.py [--quick] [--force]

Refuses to run when the 1-minute load average exceeds the core count, unless ``--force``
(``benchmarks/_load_guard.py``); the load at the start is ``load_average_1min`` (and at the end
``load_average_1min_end``). Prints one JSON line: ``dofs``, ``steps``, ``dof_updates_per_s`` and
``ns_per_element_cycle`` (wall time of one step per element) of fivid's full step on the default rig (stencil K(u + beta v), central-difference update, constraints, contact with
Coulomb friction, energy bookkeeping, records) during a preload-and-slide run; ``speedup_vs_scipy_csr``
against a plain scipy loop doing the same arithmetic (``K @ (u + beta v)`` and the lumped-mass update) on the
same model; ``fraction_of_bare_stencil`` against the fastest bare stencil + update kernel written here for
the same mesh (every node of every block with one interior stencil on ghost-padded arrays, the
rectangular-element sparsity (13 terms per force), unsigned indices, no contact or constraints), whose own ``bare_stencil_dof_updates_per_s`` is printed too, with a
``prange`` variant (``bare_stencil_parallel_dof_updates_per_s``) to show whether two threads pay at this size.
Also the wall time to simulate 0.1 s of the coarse and of the default rig: measured (coarse, full mode) or
projected from the measured step rate (``*_projected``).

Mapped blocks (DESIGN §7/§11: rotated patches for rings, per-node stencils for profiled blocks,
``fivid.solver.stencil``): the same ``fraction_of_bare_stencil`` for a curved model
(``configs/models/ring_pressure.yaml``: a periodic annular ring under pressure, no contact) as
``curved_fraction_of_bare_stencil``, and for a rough-edged model (``configs/models/rough_pair.yaml``: two
profiled, graded blocks in sliding contact) as ``rough_fraction_of_bare_stencil``; each against the bare
rectangular stencil on a ghost-padded grid of the same node count per block (the speed the model would have
if its blocks were uniform rectangles). ``rough_no_contact_*`` is the rough model with its contact pair removed:
the mapped stencil's own cost, separated from the contact solve over its 481 slave nodes; and
``*_stencil_fraction_of_bare_stencil``: fivid's stencil pass alone (``block_forces``) against the bare stencil alone,
separating the stencil from the rest of the step. The same ns-per-element-cycle figure is printed for the scipy loop
and the bare stencil (``scipy_csr_ns_per_element_cycle``, ``bare_stencil_ns_per_element_cycle``), and the scipy loop
against the bare stencil as ``scipy_csr_fraction_of_bare_stencil``.

Two cores: ``parallel_efficiency_2_cores = t_1 / (2 t_2)`` of the ``prange`` stencil + update kernel with numba's
threads set to 1 and 2 in the same run, and ``parallel_forkjoin_us_per_step`` (one empty two-iteration parallel
region with 2 threads: what a parallel kernel pays per region and step). Reduced-order path (issue 17):
``reduced_speedup`` (time-loop wall time of the full over the Craig-Bampton reduced run, interleaved, best of;
set-up time apart as ``reduced_setup_s``) and ``reduced_band_lsd_db`` (acceleration PSDs of the two runs,
200 Hz - 10 kHz, same damping scheme) for the mass-scaled reduction (modes and scaling at ``--mass-scaling`` x the
band top), ``reduced_plain_*`` for ``reduced=True``, and ``full_vs_full_band_lsd_db`` (the full model at 0.97 x its
step: the paired comparison's floor), on the default rig (0.05 s of sliding), or on the coarse rig with
``--quick`` (0.03 s).

The reduced path by default (issue 30, :func:`_auto_path`): ``auto_speedup_warm`` and ``auto_speedup_cold``, the
end-to-end wall time of ``fivid simulate`` with its defaults (the automatic choice; warm and empty basis cache)
over ``fivid simulate --full``, ``auto_band_lsd_db`` (their PSDs), ``reduced_setup_s`` (the basis build of the
cold run; this key replaces the reduced comparison's set-up time above), on the default rig for 0.1 s (coarse rig,
0.03 s with ``--quick``). The automatic path's reduced loop on the default (fine) against the coarse rig
(:func:`_reduced_fine_vs_coarse`, 0.05 s, 0.01 s with ``--quick``): ``reduced_fine_us_per_step``,
``reduced_coarse_us_per_step`` (CPU time), ``reduced_fine_vs_coarse_step_cost_ratio`` and
``reduced_fine_vs_coarse_loop_ratio`` (the same simulated time), sweeps per step of each.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time
from pathlib import Path

import numpy as np
from _load_guard import parse_guarded  # benchmarks/, this script's folder

ROOT = Path(__file__).resolve().parents[1]


def _bare_kernels():
    """The bare stencil + update loop, compiled serial and with ``prange`` (same body; prange runs as range
    in the serial compilation)."""
    from numba import njit, prange

    from fivid.solver._stencil_kernels import _rect_component

    def steps(nsteps, dt, alpha, beta, npd, blocks, c_uni, minv, u, v, w, f):
        n = u.shape[0]
        for _ in range(nsteps):
            wx = w[:npd]
            wy = w[npd:]
            for b in range(blocks.shape[0]):
                for a in prange(2):
                    _rect_component(wx, wy, f[a * npd:(a + 1) * npd], c_uni[b], a, blocks[b, 0], blocks[b, 1],
                                    blocks[b, 2], blocks[b, 3])
            for d in prange(n):
                vn = v[d] + dt * (-minv[d] * f[d] - alpha * v[d])
                v[d] = vn
                ud = u[d] + dt * vn
                u[d] = ud
                w[d] = ud + beta * vn

    return njit(cache=False)(steps), njit(cache=False, parallel=True)(steps)


def _bare_layout(model, c_rect):
    """Ghost-padded copy of every block: one rectangular-element stencil ``c_rect`` (36,) covers all its real nodes."""
    rows, off = [], 0
    for block in model.blocks:
        stride = block.n_cols + 2
        rows.append((off + stride + 1, block.n_cols, block.ny + 1, stride))
        off += stride * (block.ny + 3)
    blocks = np.array(rows, dtype=np.int64)
    c_uni = np.ascontiguousarray(np.tile(c_rect, (len(model.blocks), 1)))
    return off, blocks, c_uni


def _stencil_loops():
    """``(bare, fivid)``: ``nsteps`` passes of the bare rectangular stencil alone (no update) and of fivid's
    :func:`fivid.solver._stencil_kernels.block_forces` alone, to separate the stencil's cost from the rest of the step."""
    from numba import njit

    from fivid.solver._stencil_kernels import _rect_component, block_forces

    def bare_stencil(nsteps, npd, blocks, c_uni, w, f):
        wx = w[:npd]
        wy = w[npd:]
        for _ in range(nsteps):
            for b in range(blocks.shape[0]):
                for a in range(2):
                    _rect_component(wx, wy, f[a * npd:(a + 1) * npd], c_uni[b], a, blocks[b, 0], blocks[b, 1],
                                    blocks[b, 2], blocks[b, 3])

    def fivid_stencil(nsteps, w, f, stencil):
        for _ in range(nsteps):
            block_forces(w, f, stencil)

    return njit(cache=False)(bare_stencil), njit(cache=False)(fivid_stencil)


def _bare_arguments(model, prep, c_rect, bare) -> tuple:
    """The arguments after ``nsteps`` of the ``bare`` loop (:func:`_bare_kernels`) for ``model``'s node count per
    block (:func:`_bare_layout`) at the step, damping and mean mass of the prepared run ``prep``; the loop is run
    10 steps (compiled)."""
    npd, blocks, c_uni = _bare_layout(model, c_rect)
    arrays = [np.zeros(2 * npd) for _ in range(4)]
    mb = np.full(2 * npd, 1.0 / float(np.mean(prep.arrays.mass[prep.arrays.mass > 0])))
    args = (prep.settings.time_step, model.rayleigh_alpha, model.rayleigh_beta, npd, blocks, c_uni, mb, *arrays)
    bare(10, *args)
    return args


def _mapped_fraction(model, c_rect, bare, kw, duration, rounds):
    """``(fraction_of_bare_stencil, dof_updates_per_s, mapped node share, mean Gauss-Seidel sweeps or None,
    stencil_fraction_of_bare_stencil)`` of a model with mapped blocks: its full step against the bare stencil + update
    on a ghost-padded grid of the same node count per block, and its stencil pass alone (``block_forces``) against the
    bare stencil alone (interleaved rounds, best of each)."""
    from fivid.solver.driver import prepare_run

    prep = prepare_run(model, **_lasting(kw, duration))
    s = prep.settings
    steps = s.n_intervals * s.steps_per_interval
    bare_args = _bare_arguments(model, prep, c_rect, bare)
    npd, blocks, c_uni = bare_args[3:6]
    bare_stencil, fivid_stencil = _stencil_loops()
    st = prep.stencils
    rng = np.random.default_rng(0)
    w_st = np.zeros(2 * st.npd)
    w_st[st.dof_index(np.arange(model.n_dofs))] = rng.standard_normal(model.n_dofs)
    f_st = np.zeros_like(w_st)
    w_bare = rng.standard_normal(2 * npd)
    f_bare = np.zeros_like(w_bare)
    bare_stencil(2, npd, blocks, c_uni, w_bare, f_bare)
    fivid_stencil(2, w_st, f_st, st.kernel_args)
    prep.run(progress=False)  # compile/load the kernels for this model's argument types
    t_run = t_bare = t_st = t_bare_st = np.inf
    for _ in range(rounds):
        t0 = time.perf_counter()
        ds = prep.run(progress=False)
        t_run = min(t_run, (time.perf_counter() - t0) / steps)
        t_bare = min(t_bare, _time(bare, steps, *bare_args, repeat=1) / steps)
        t_st = min(t_st, _time(fivid_stencil, steps, w_st, f_st, st.kernel_args, repeat=1) / steps)
        t_bare_st = min(t_bare_st, _time(bare_stencil, steps, npd, blocks, c_uni, w_bare, f_bare, repeat=1) / steps)
    mapped = int(st.blocks[st.blocks[:, 4] >= 2][:, 1:3].prod(axis=1).sum() + st.lst_idx.size)  # per-node, rotated
    return (t_bare / t_run, model.n_dofs / t_run, mapped / model.n_nodes, ds.attrs.get("contact_gs_mean_sweeps"),
            t_bare_st / t_st)


def _lasting(kw, duration, **integration) -> dict:
    """The benchmark's inputs ``kw`` of :func:`fivid.solver.driver.prepare_run` with ``duration`` [s] of steady
    sliding and ``integration`` (:class:`fivid.solver.IntegrationOptions` fields)."""
    from fivid.solver import IntegrationOptions

    return {**kw, "schedule": dataclasses.replace(kw["schedule"], duration=duration),
            "integration": IntegrationOptions(**integration)}


def _time(fn, *args, repeat=3):
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn(*args)
        best = min(best, time.perf_counter() - t0)
    return best


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="shorter runs (noisier numbers)")
    ap.add_argument("--mass-scaling", type=float, default=None, metavar="FACTOR",
                    help="fast reduced path: fixed-interface modes and selective mass scaling at FACTOR x the band top "
                         "(sample_rate / 2; default 18 on the default rig: 460.8 kHz, 6 with --quick: 153.6 kHz)")
    args, load = parse_guarded(ap, argv)
    import tempfile  # reduced set-up times are builds: an empty basis cache for this run (fivid.solver.basis_cache)

    os.environ["FIVID_CACHE_DIR"] = tempfile.mkdtemp(prefix="fivid-bench-bases-")

    from fivid.fe import load_model
    from fivid.solver import FrictionInput, OperatingCondition, RunSchedule
    from fivid.solver.driver import prepare_run

    default = load_model(ROOT / "configs/models/triboair.yaml")
    coarse = load_model(ROOT / "configs/models/triboair_coarse.yaml")
    kw = dict(condition=OperatingCondition(sliding_velocity=0.01, normal_load=5.0), friction=FrictionInput(mu=0.3),
              schedule=RunSchedule(duration=1e-4, sample_rate=51200.0, preload_time=2e-4, settle_time=0.0,
                                   base_ramp_time=1e-4))
    # warm-up: load the cached kernels
    prepare_run(coarse, **_lasting(kw, 1e-4)).run(progress=False)
    out = {"benchmark": "solver", "quick": bool(args.quick), "load_average_1min": load}
    rounds = 2 if args.quick else 3
    duration = 1e-4 if args.quick else 5e-4
    bare, bare_par = _bare_kernels()
    throughput, timing = _full_path_throughput(default, kw, duration, rounds, args.quick, bare, bare_par)
    out.update(throughput)
    out.update(_mapped_blocks(kw, duration / 2, rounds, timing["c_rect"], bare))
    out.update(_coarse_wall(coarse, kw, args.quick))
    # ---- two cores: the prange stencil with 1 and 2 threads, same run (numba.set_num_threads)
    steps = timing["steps"]
    eff, t1, t2, tfj = _parallel_efficiency(bare_par, steps, timing["bare_args"], rounds)
    out["parallel_efficiency_2_cores"] = eff
    out["parallel_forkjoin_us_per_step"] = tfj * 1e6  # two parallel regions per bare step (stencil, update)
    out["parallel_1thread_us_per_step"] = t1 / steps * 1e6
    out["parallel_1thread_dof_updates_per_s"] = default.n_dofs * steps / t1
    out["parallel_2thread_dof_updates_per_s"] = default.n_dofs * steps / t2
    # ---- reduced-order path (Craig-Bampton) against the full model: default rig, coarse rig in --quick
    rmodel, rpath = (coarse, "configs/models/triboair_coarse.yaml") if args.quick else \
        (default, "configs/models/triboair.yaml")
    out["reduced_model"] = rpath
    factor = args.mass_scaling if args.mass_scaling is not None else 6.0 if args.quick else 18.0
    out.update(_reduced_comparison(rmodel, kw, 0.03 if args.quick else 0.05, rounds, factor))
    out.update(_auto_path(rpath, "0.03 s" if args.quick else "0.1 s"))  # the reduced path by default (issue 30)
    out.update(_reduced_fine_vs_coarse(default, coarse, kw, 0.01 if args.quick else 0.05, rounds))
    out["load_average_1min_end"] = round(os.getloadavg()[0], 2)
    print(json.dumps(out))
    return 0


def _full_path_throughput(model, kw, duration, rounds, quick, bare, bare_par):
    """The three loops on the default rig, interleaved in rounds (best of each): fivid's full step, a plain scipy CSR
    loop doing the same arithmetic (``K @ (u + beta v)`` and the lumped-mass update), the bare stencil + update
    (serial and ``prange``). Returns ``(JSON entries, timing)``; ``timing`` holds what the other parts reuse: the
    rig's interior rectangular stencil ``c_rect``, the bare kernel's arguments ``bare_args`` and ``steps``."""
    from fivid.fe import lumped_mass, stiffness_matrix
    from fivid.solver.driver import prepare_run
    from fivid.solver.stencil import block_stencils

    prep = prepare_run(model, **_lasting(kw, duration))
    s = prep.settings
    steps = s.n_intervals * s.steps_per_interval
    n_dofs = model.n_dofs
    n_el = sum(b.n_elements for b in model.blocks)
    K = stiffness_matrix(model).tocsr()
    minv = 1.0 / lumped_mass(model)
    minv[model.fixed_dofs] = 0.0
    dt, a, b = s.time_step, model.rayleigh_alpha, model.rayleigh_beta
    n_scipy = min(steps, 3000 if quick else 20000)

    def scipy_loop(n):
        # the same arithmetic as a plain scipy program: K @ (u + beta v), lumped-mass central difference
        u = np.zeros(n_dofs)
        v = np.zeros(n_dofs)
        for _ in range(n):
            f = K @ (u + b * v)
            v += dt * (-minv * f - a * v)
            u += dt * v

    st = block_stencils(model)
    c_rect = st.c_uni[int(st.blocks[np.flatnonzero(st.blocks[:, 4] == 1)[0], 5])]  # the rig's interior stencil
    npd, blocks, c_uni = _bare_layout(model, c_rect)
    arrays = [np.zeros(2 * npd) for _ in range(4)]
    mb = np.full(2 * npd, minv[minv > 0].mean())
    bare_args = (dt, a, b, npd, blocks, c_uni, mb, *arrays)
    bare(10, *bare_args)
    bare_par(10, *bare_args)
    t_fivid = t_scipy = t_bare = t_par = np.inf
    for _ in range(rounds):
        t0 = time.perf_counter()
        ds = prep.run(progress=False)
        t_fivid = min(t_fivid, (time.perf_counter() - t0) / steps)
        t_bare = min(t_bare, _time(bare, steps, *bare_args, repeat=1) / steps)
        t_scipy = min(t_scipy, _time(scipy_loop, n_scipy, repeat=1) / n_scipy)
        t_par = min(t_par, _time(bare_par, steps, *bare_args, repeat=1) / steps)
    out = {
        "model": "configs/models/triboair.yaml",
        "dofs": n_dofs,
        "elements": n_el,
        "steps": steps,
        "time_step_s": dt,
        "contact_active": float(ds.contact_normal_force.max()) > 0.0,
        "contact_gs_mean_sweeps": ds.attrs["contact_gs_mean_sweeps"],
        "dof_updates_per_s": n_dofs / t_fivid,
        "ns_per_element_cycle": t_fivid / n_el * 1e9,
        "scipy_csr_dof_updates_per_s": n_dofs / t_scipy,
        "scipy_csr_ns_per_element_cycle": t_scipy / n_el * 1e9,
        "speedup_vs_scipy_csr": t_scipy / t_fivid,
        "bare_stencil_dof_updates_per_s": n_dofs / t_bare,
        "bare_stencil_ns_per_element_cycle": t_bare / n_el * 1e9,
        "bare_stencil_parallel_dof_updates_per_s": n_dofs / t_par,
        "fraction_of_bare_stencil": t_bare / t_fivid,
        "scipy_csr_fraction_of_bare_stencil": t_bare / t_scipy,
        "wall_0p1s_default_projected_s": 0.1 / dt * t_fivid,
    }
    return out, {"c_rect": c_rect, "bare_args": bare_args, "steps": steps}


def _mapped_blocks(kw, duration, rounds, c_rect, bare):
    """Mapped blocks: a curved (annular, periodic) and a rough-edged (profiled, graded, contact) model, and the rough
    one without its contact pair, each against the bare rectangular stencil (:func:`_mapped_fraction`)."""
    from fivid.fe import load_model

    out = {}
    from fivid.solver import FrictionInput, OperatingCondition

    for key, path, velocity in (("curved", "configs/models/ring_pressure.yaml", None),
                                ("rough", "configs/models/rough_pair.yaml", 0.03),
                                ("rough_no_contact", "configs/models/rough_pair.yaml", 0.03)):
        # no target load, the models' own friction coefficients
        mkw = dict(kw, condition=OperatingCondition(sliding_velocity=velocity), friction=FrictionInput())
        model = load_model(ROOT / path)
        if key == "rough_no_contact":  # the same mapped mesh without its contact pair: the stencil's own cost
            model = dataclasses.replace(model, contacts=())
        frac, rate, share, sweeps, stencil_frac = _mapped_fraction(model, c_rect, bare, mkw, duration, rounds)
        out[f"{key}_model"] = path
        out[f"{key}_fraction_of_bare_stencil"] = frac
        out[f"{key}_stencil_fraction_of_bare_stencil"] = stencil_frac
        out[f"{key}_dof_updates_per_s"] = rate
        out[f"{key}_mapped_node_share"] = share
        if sweeps is not None:
            out[f"{key}_contact_gs_mean_sweeps"] = sweeps
    return out


def _coarse_wall(coarse, kw, quick):
    """Wall time to simulate 0.1 s of the coarse rig: measured (full mode) or projected from the step rate
    (``--quick``)."""
    from fivid.solver.driver import prepare_run

    cprep = prepare_run(coarse, **_lasting(kw, 1e-3 if quick else 0.1 - (2e-4 + 1e-4)))
    t0 = time.perf_counter()
    cprep.run(progress=False)
    cwall = time.perf_counter() - t0
    csteps = cprep.settings.n_intervals * cprep.settings.steps_per_interval
    ctotal = csteps * cprep.settings.time_step
    out = {"wall_0p1s_coarse_projected_s": cwall * 0.1 / ctotal} if quick else {"wall_0p1s_coarse_s": cwall}
    out["coarse_dofs"] = coarse.n_dofs
    out["coarse_dof_updates_per_s"] = coarse.n_dofs * csteps / cwall
    return out


def _reduced_comparison(model, kw, duration, rounds, scaling_factor):
    """Full vs Craig-Bampton reduced runs of ``model`` (issue 17), same schedule and damping scheme: the plain
    reduction (``reduced=True``: modes to 3 x the band top, no mass scaling) and the fast one (modes and selective
    mass scaling both at ``scaling_factor`` x the band top, :func:`fivid.solver.reduced.prepare_reduced`).
    Wall times of the time loop (best of interleaved rounds), set-up times, and the log-spectral distance of the
    acceleration PSDs over 200 Hz - 10 kHz (Welch, Hann, nperseg 256, 50 % overlap, steady part). The floor to
    read it against: the full model against itself at 0.97 x its step (``full_vs_full_band_lsd_db``): the runs share
    their deterministic forcing, so a distance above that floor is the reduction's, not the estimator's."""
    from fivid.solver.driver import prepare_run
    from fivid.solver.reduced import prepare_reduced
    from fivid.signal.compare import band_distance, steady_psds

    full = prepare_run(model, **_lasting(kw, duration))
    t0 = time.perf_counter()
    plain = prepare_run(model, **_lasting(kw, duration, reduced=True))
    t_plain_setup = time.perf_counter() - t0
    f_s = scaling_factor * kw["schedule"].sample_rate / 2.0
    t0 = time.perf_counter()
    fast = prepare_reduced(full, cutoff=f_s, mass_scaling=f_s)
    t_setup = time.perf_counter() - t0
    walls = {"full": np.inf, "plain": np.inf, "fast": np.inf}
    runs = {}
    for _ in range(rounds):
        for key, prep in (("full", full), ("plain", plain), ("fast", fast)):
            t0 = time.perf_counter()
            runs[key] = prep.run(progress=False)
            walls[key] = min(walls[key], time.perf_counter() - t0)
    runs["ref"] = prepare_run(model, **_lasting(kw, duration, time_step=0.97 * full.settings.time_step)).run(
        progress=False)
    f, psd, nperseg = steady_psds([runs[k] for k in ("full", "plain", "fast", "ref")], nperseg=256)
    dist = {k: band_distance(f, psd[0], p, (200.0, 10e3))[:2] for k, p in zip(("plain", "fast", "ref"), psd[1:])}
    a = runs["fast"].attrs
    out = {
        "reduced_speedup": walls["full"] / walls["fast"],
        "reduced_band_lsd_db": dist["fast"][0],
        "reduced_band_level_diff_db": dist["fast"][1],
        "reduced_mass_scaling_hz": f_s,
        "reduced_plain_speedup": walls["full"] / walls["plain"],
        "reduced_plain_band_lsd_db": dist["plain"][0],
        "reduced_plain_band_level_diff_db": dist["plain"][1],
        "full_vs_full_band_lsd_db": dist["ref"][0],
        "reduced_psd_nperseg": nperseg,
        "reduced_wall_s": walls["fast"],
        "reduced_plain_wall_s": walls["plain"],
        "reduced_full_wall_s": walls["full"],
        "reduced_setup_s": t_setup,
        "reduced_plain_setup_s": t_plain_setup,
        "reduced_simulated_s": float(full.settings.n_intervals / (full.settings.oversample * kw["schedule"].sample_rate)),
        "reduced_size": a["reduced_size"],
        "reduced_plain_size": runs["plain"].attrs["reduced_size"],
        "reduced_boundary_nodes": a["reduced_boundary_nodes"],
        "reduced_modes": a["reduced_modes"],
        "reduced_plain_modes": runs["plain"].attrs["reduced_modes"],
        "reduced_mass_scaled_modes": a["reduced_mass_scaled_modes"],
        "reduced_added_mass_fraction": a["reduced_added_mass_fraction"],
        "reduced_first_truncated_frequency_hz": a["reduced_first_truncated_frequency"],
        "reduced_time_step_s": a["time_step"],
        "reduced_plain_time_step_s": runs["plain"].attrs["time_step"],
        "full_time_step_s": runs["full"].attrs["time_step"],
        "reduced_energy_balance_error_j": float(np.abs(runs["fast"].energy_balance_error).max()),
        "reduced_mean_friction_n": _steady_mean(runs["fast"], "friction_force"),
        "full_mean_friction_n": _steady_mean(runs["full"], "friction_force"),
    }
    return out


def _reduced_fine_vs_coarse(default, coarse, kw, duration, rounds):
    """The reduced time loop of the default (fine) and of the coarse rig as the automatic path runs them (issue 30:
    the pipeline's simulate stage on the fine rig against the coarse one), interleaved in this process, best of
    ``rounds``: CPU time per step (``reduced_fine_us_per_step``, ``reduced_coarse_us_per_step``; the loop is serial,
    so CPU time is its cost even on a loaded machine), their ratio ``reduced_fine_vs_coarse_step_cost_ratio``, the
    loops' ratio over the same simulated time ``reduced_fine_vs_coarse_loop_ratio`` (the fine rig takes fewer,
    longer steps) and the contact solve's Gauss-Seidel sweeps per step."""
    from fivid.solver import _kernels as K
    from fivid.solver.driver import prepare_run
    from fivid.solver.reduced import integrate_reduced

    best = {}
    preps = {name: prepare_run(m, **_lasting(kw, duration, reduced="auto")) for name, m in (("fine", default),
                                                                                         ("coarse", coarse))}
    for _ in range(rounds):
        for name, prep in preps.items():
            if prep.reduced is None:
                raise SystemExit(f"the automatic path chose the full model for the {name} rig: {prep.choice}")
            t0 = time.process_time()
            raw = integrate_reduced(prep.model, prep.reduced, prep.friction, prep.settings)
            cpu = time.process_time() - t0
            steps = prep.settings.n_intervals * prep.settings.steps_per_interval
            if cpu < best.get(name, (np.inf,))[0]:
                best[name] = (cpu, steps, raw.acc[K.GS_SWEEPS] / steps)
    (fc, fs, fsw), (cc, cs, csw) = best["fine"], best["coarse"]
    return {"reduced_fine_us_per_step": fc / fs * 1e6, "reduced_coarse_us_per_step": cc / cs * 1e6,
            "reduced_fine_vs_coarse_step_cost_ratio": (fc / fs) / (cc / cs),
            "reduced_fine_vs_coarse_loop_ratio": fc / cc, "reduced_fine_sweeps_per_step": fsw,
            "reduced_coarse_sweeps_per_step": csw, "reduced_fine_vs_coarse_simulated_s": duration}


def _auto_path(model_path, duration):
    """End-to-end wall time of ``fivid simulate MODEL --mu 0.3 --velocity '10 mm/s' --load '5 N' --duration D``
    with the defaults (the automatic path choice, issue 30) in a fresh process each: cold (empty basis cache: the
    set-up is paid), warm (the same cache again) and ``--full``, after one untimed short run of each path (numba's
    compilation cache filled; its basis in another cache folder). ``auto_speedup_warm``/``_cold`` = full / auto;
    ``auto_band_lsd_db``: the warm auto run's acceleration PSD against the full one's (200 Hz - 10 kHz, Welch Hann
    256 / 50 %, steady part); ``reduced_setup_s``: the cold run's basis build time (its ``reduced_setup_time``)."""
    import subprocess
    import sys
    import tempfile

    import xarray as xr

    from fivid.signal.compare import band_distance, steady_psds

    cmd = [sys.executable, "-m", "fivid", "simulate", str(ROOT / model_path), "--mu", "0.3", "--velocity", "10 mm/s",
           "--load", "5 N"]
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)

        def run(name, cache, *extra, duration=duration):
            env = {**os.environ, "FIVID_CACHE_DIR": str(tmp / cache)}
            t0 = time.perf_counter()
            subprocess.run(cmd + ["--duration", duration, "-o", str(tmp / f"{name}.nc"), *extra], env=env, check=True,
                           stdout=subprocess.DEVNULL)
            return time.perf_counter() - t0

        run("warmup-auto", "warmup", duration="1 ms")
        run("warmup-full", "warmup", "--full", duration="1 ms")
        t_cold = run("cold", "bases")
        t_warm = run("warm", "bases")
        t_full = run("full", "bases", "--full")
        runs = [xr.load_dataset(tmp / f"{n}.nc") for n in ("full", "warm", "cold")]
    f, psd, _ = steady_psds(runs, nperseg=256)
    lsd, level = band_distance(f, psd[0], psd[1], (200.0, 10e3))
    a, c = runs[1].attrs, runs[2].attrs
    return {"auto_model": model_path, "auto_duration": duration, "auto_solver_path": a["solver_path"],
            "auto_speedup_warm": t_full / t_warm, "auto_speedup_cold": t_full / t_cold, "auto_band_lsd_db": lsd,
            "auto_band_level_diff_db": level, "auto_error_estimate_db": float(a["reduced_error_estimate_db"]),
            "auto_wall_warm_s": t_warm, "auto_wall_cold_s": t_cold, "auto_wall_full_s": t_full,
            "auto_basis_sources": [c.get("reduced_basis_source"), a.get("reduced_basis_source")],
            "reduced_setup_s": float(c.get("reduced_setup_time", float("nan"))),
            "auto_load_average_1min": os.getloadavg()[0]}


def _steady_mean(ds, name):
    """Mean of ``ds[name]`` over steady sliding [its unit]."""
    return float(ds[name].where(ds.time >= ds.attrs["transient_end"]).mean())


def _forkjoin_kernel():
    """``nsteps`` parallel regions of two trivial iterations: the per-step price of a fork/join."""
    from numba import njit, prange

    def forkjoin(nsteps, x):
        for _ in range(nsteps):
            for k in prange(2):
                x[k] += 1.0

    return njit(cache=False, parallel=True)(forkjoin)


def _parallel_efficiency(bare_par, steps, args, rounds):
    """``(t_1 / (2 t_2), t_1, t_2, fork/join time per step [s])`` of the ``prange`` stencil + update kernel with 1 and
    2 numba threads (interleaved, best of), and of an empty two-iteration parallel region with 2 threads."""
    import numba

    forkjoin = _forkjoin_kernel()
    x = np.zeros(2)
    n0 = numba.get_num_threads()
    t1 = t2 = tf = np.inf
    try:
        forkjoin(10, x)
        for _ in range(rounds):
            numba.set_num_threads(1)
            t1 = min(t1, _time(bare_par, steps, *args, repeat=1))
            numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
            t2 = min(t2, _time(bare_par, steps, *args, repeat=1))
            tf = min(tf, _time(forkjoin, steps, x, repeat=1) / steps)
    finally:
        numba.set_num_threads(n0)
    return t1 / (2.0 * t2), t1, t2, tf


if __name__ == "__main__":
    raise SystemExit(main())
