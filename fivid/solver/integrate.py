"""Allocate the state and records of a run and advance it by chunks of the jitted time loop.

The kernel runs a whole number of output intervals per call (a chunk of ~0.2 s of wall time), so the
Python side only updates the progress bar and checks the guard status between chunks.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.contact._layout_kernels import N_CNODE, N_GEO
from fivid.errors import SimulationDiverged

__all__ = ["RawRecords", "integrate", "loop_arguments", "loop_state", "velocity_filter_gain", "chunked",
           "massive_ranges", "shortest_master_segment", "RUNAWAY_FACTOR"]

#: guard: the stiffness-damping loss inferred as W_int - U may not fall below -RUNAWAY_FACTOR x (KE + U)
RUNAWAY_FACTOR = 2.0


@dataclass
class RawRecords:
    """Per-interval records at the oversampled rate (see :func:`fivid.solver._loop_kernels.run_steps`)."""

    rec: np.ndarray
    sens_v: np.ndarray
    sens_v0: np.ndarray
    contact: np.ndarray
    u: np.ndarray
    v: np.ndarray
    ke0: float
    acc: np.ndarray
    steps: int


def velocity_filter_gain(cutoff: float, dt: float) -> float:
    """Gain ``1 - exp(-2 pi cutoff dt)`` of the band-limited damping's velocity filter per step [-].

    ``cutoff`` [Hz] inf gives 1: classic Rayleigh (the kernel then uses ``v`` itself, bit for bit).
    """
    import math

    if not math.isfinite(cutoff):
        return 1.0
    return float(-math.expm1(-2.0 * math.pi * cutoff * dt))


def massive_ranges(mass: np.ndarray) -> np.ndarray:
    """The ranges ``[start, end)`` (n_ranges, 2) int64 of the consecutive entries of ``mass`` [kg] (kernel layout)
    that are > 0: the dofs the time loop's predictor integrates (tied nodes and the padding are massless). A mesh
    coarsening in levels gives a few dozen ranges (the 120 mm rough pair: 24, over 58 % of the entries)."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], (np.asarray(mass) > 0).astype(np.int8), [0]])))
    return np.ascontiguousarray(edges.reshape(-1, 2), dtype=np.int64)


def loop_arguments(model, st, ka, fric, dt: float, gs_max_iterations: int, gs_tol: float) -> tuple:
    """The argument groups of :func:`fivid.solver._loop_kernels.run_steps` that describe the model and stay
    fixed over a run: ``(stencil, structure, motions, loads, contact, friction)`` (the motions' and loads'
    scratch arrays are allocated here). ``gs_tol`` [m] is the absolute Gauss-Seidel tolerance."""
    from fivid.solver import _loop_kernels as L  # lazy: pulls numba

    structure = L.Structure(ka.mass, ka.minv, massive_ranges(ka.mass), ka.spr_dof, ka.spr_kc,
                            float(model.rayleigh_alpha), float(model.rayleigh_beta),
                            velocity_filter_gain(model.damping_cutoff, dt))
    motions = L.Motions(ka.con_dof, ka.con_grp, ka.grp_par, ka.con_react, np.zeros((ka.grp_par.shape[0], 2)),
                        ka.con_cnode)
    loads = L.Loads(ka.ld_dof, ka.ld_force, ka.ld_grp, ka.ld_par, np.zeros(ka.ld_par.shape[0]),
                    np.zeros(ka.ld_dof.size))
    contact = L.ContactSet(ka.X, ka.slave_node, ka.slave_pair, ka.master_ptr, ka.master_nodes, ka.pair_sign,
                           ka.pair_par, ka.law_tab, ka.s_area, ka.minv_c, ka.cnodes, ka.cnode_slot,
                           int(gs_max_iterations), float(gs_tol))
    friction = L.MuSeries(np.ascontiguousarray(fric.mu), float(fric.rate))
    return st.kernel_args, structure, motions, loads, contact, friction


def loop_state(st, ka, u, v, beta: float):
    """The state groups of :func:`fivid.solver._loop_kernels.run_steps` at displacement ``u`` and velocity ``v``
    (kernel layout; updated in place by the loop): ``(contact state, state)``; ``vf = v``, ``w = u + beta v``."""
    from fivid.solver import _kernels as K  # lazy: pulls numba
    from fivid.solver import _loop_kernels as L  # lazy: pulls numba

    ns = ka.slave_node.size
    cs = L.ContactState(ka.seg.copy(), np.zeros((ns, N_GEO)), np.zeros((ns, 2)), np.zeros(ns, dtype=np.int64),
                        np.zeros(ns), np.zeros((ka.cnodes.size, N_CNODE)))
    # the filtered velocity of band-limited damping starts at the initial velocity
    state = L.State(u, v, u + beta * v, v.copy(), np.zeros_like(u), np.zeros_like(u), np.zeros(K.N_ACC), np.zeros(2))
    return cs, state


def integrate(model, st, ka, fric, settings, *, progress=None) -> RawRecords:
    """Run the time loop of ``settings.n_intervals`` output intervals; :class:`SimulationDiverged` on failure."""
    from fivid.solver import _kernels as K  # lazy: pulls numba
    from fivid.solver import _loop_kernels as L  # lazy: pulls numba

    dt = settings.time_step
    n_sub = settings.steps_per_interval
    n_int = settings.n_intervals
    u = np.zeros(2 * st.npd)
    v = st.to_kernel(model.initial_velocity())
    # constrained dofs start at their prescribed velocity at t = -dt/2 (zero for clamps and ramps)
    for c, d in enumerate(ka.con_dof):
        p = ka.grp_par[ka.con_grp[c]]
        v[d] = K.constrained_velocity(int(p[0]), p[1], p[2], p[3], -dt, dt)
    n_pairs = ka.master_ptr.size - 1
    diag = np.zeros(2, dtype=np.int64)
    rec = np.full((n_int, K.N_REC), np.nan)
    sens_v = np.full((n_int, ka.sens_node.size, 2), np.nan)
    contact = np.full((n_int, n_pairs, 5), np.nan)
    sens_v0 = ka.sens_dir[:, 0] * v[ka.sens_node] + ka.sens_dir[:, 1] * v[ka.sens_node + st.npd]
    ke0 = float(0.5 * np.sum(ka.mass * v * v))
    # chunk: about 3e7 dof-steps (~0.1-0.3 s of wall time) per kernel call
    chunk = max(1, int(3e7 // max(1, 2 * st.npd * n_sub)))
    # Gauss-Seidel tolerance: relative to the shortest master segment [m]
    gs_tol = settings.gs_tolerance * shortest_master_segment(ka.X, st.npd, ka.master_ptr, ka.master_nodes,
                                                             ka.slave_node, ka.slave_pair)
    fixed = loop_arguments(model, st, ka, fric, dt, settings.gs_max_iterations, gs_tol)
    cs, state = loop_state(st, ka, u, v, float(model.rayleigh_beta))

    def advance(r0, nr):
        records = L.Records(rec[r0:r0 + nr], sens_v[r0:r0 + nr], contact[r0:r0 + nr], diag, ka.sens_node,
                            ka.sens_dir)
        status, _ = L.run_steps(r0 * n_sub, nr * n_sub, dt, n_sub, RUNAWAY_FACTOR, *fixed, cs, state, records)
        if status != K.OK:
            raise SimulationDiverged(_diagnosis(model, st, status, diag, dt, settings, u, v))

    chunked(advance, n_int, chunk, progress, settings.oversample)
    return RawRecords(rec, sens_v, sens_v0, contact, st.to_global(u), st.to_global(v), ke0, state.acc, n_int * n_sub)


def chunked(advance, n_int, chunk, progress, oversample: int = 1):
    """Call ``advance(r0, nr)`` over ``n_int`` output intervals in chunks of ``chunk``, with a progress bar that
    counts output samples (the ``n_int`` records at the oversampled rate are decimated by ``oversample``)."""
    from tqdm.auto import tqdm

    q = max(1, int(oversample))
    with tqdm(total=n_int // q, disable=None if progress is None else not progress, unit="sample",
              desc="fivid simulate", leave=False) as bar:
        r0 = 0
        while r0 < n_int:
            nr = min(chunk, n_int - r0)
            advance(r0, nr)
            bar.update((r0 + nr) // q - r0 // q)
            r0 += nr


def shortest_master_segment(X, npd, master_ptr, master_nodes, slave_node, slave_pair) -> float:
    """Shortest master segment [m] over the contact pairs (a rigid master: its slave edge's node spacing); 1 if
    there is none. Nodes by x-index in the layout ``X`` (x part, then y part at ``+ npd``)."""
    best = np.inf
    for p in range(master_ptr.size - 1):
        nodes = master_nodes[master_ptr[p]:master_ptr[p + 1]]
        if nodes.size < 2:  # a rigid master: the slave edge's spacing
            nodes = slave_node[slave_pair == p]
            if nodes.size < 2:
                continue
        best = min(best, float(np.hypot(np.diff(X[nodes]), np.diff(X[nodes + npd])).min()))
    return best if np.isfinite(best) else 1.0


def _diagnosis(model, st, status, diag, dt, settings, u, v) -> str:
    step = int(diag[0])
    node = int(diag[1]) - st.pad
    what = "NaN or infinite values" if status == 1 else "runaway energy (inferred stiffness-damping loss < -2 x energy)"
    where = f"node {node}"
    if 0 <= node < model.n_nodes:
        b = model.block_of_node(node)
        loc = node - b.node_offset
        x, y = model.coords[node]
        where += (f" (body {b.name!r}, local i={loc % b.n_cols}, j={loc // b.n_cols}, at x={x:.4g} m, y={y:.4g} m;"
                  f" |v| = {float(np.hypot(v[st.pad + node], v[st.npd + st.pad + node])):.3g} m/s)")
    return (f"the simulation diverged at step {step} (t = {step * dt:.6g} s): {what}; largest speed at {where}. "
            f"Time step {dt:.4g} s, critical {settings.critical_time_step:.4g} s. Check the model (contact geometry, "
            f"springs, masses) or lower the step (time_step=...)")
