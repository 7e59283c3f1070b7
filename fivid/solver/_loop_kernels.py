"""The explicit solver's time loop (layer L0): the central-difference step of the full model, its energy
bookkeeping, output records and guards.

:func:`run_steps` takes its arrays in a few named groups (typed tuples: numba compiles one specialisation and
caches it, as for plain arguments); the record, guard and work helpers are shared with the reduced system's
loop (:mod:`fivid.solver._reduced_kernels`). Layout: :mod:`fivid.solver._kernels`.
"""

import math
from collections import namedtuple

import numpy as np
from numba import uint64

from fivid.contact._layout_kernels import CNODE_V_PREDICTED, CNODE_V_STEP
from fivid.solver._contact_kernels import contact_reactions, contact_step, contact_work, finish_contact_record
from fivid.solver._kernels import (
    D_ALPHA,
    NAN,
    OK,
    R_DA,
    R_EPEN,
    R_FN,
    R_FT,
    R_KE,
    R_U,
    R_WCN,
    R_WCT,
    R_WDRIVE,
    R_WEXT,
    R_WINT,
    R_WLOAD,
    RUNAWAY,
    W_CN,
    W_CT,
    W_DRIVE,
    W_EXT,
    W_INT,
    W_LOAD,
    constrained_velocity,
    kernel,
    ramp,
    reassociating_kernel,
)
from fivid.solver._stencil_kernels import block_forces, spring_forces

__all__ = ["Structure", "Motions", "Loads", "ContactSet", "MuSeries", "ContactState", "State", "Records",
           "run_steps", "start_record", "group_velocities", "add_step_work", "finish_record", "guard_status"]

# ---- the argument groups of run_steps (built by fivid.solver.integrate; float64 / int64, C-contiguous)
#: lumped mass ``mass`` [kg] and its inverse ``minv`` (0 on massless dofs) per dof; ``active`` (n_ranges, 2): the
#: ranges ``[start, end)`` of dofs with mass, the only ones the predictor integrates (tied nodes and the padding are
#: massless: :func:`_predictor`); springs ``spr_dof[s] = (dof_a, dof_b or -1)``, ``spr_kc[s] = (k [N m-1], c [N s
#: m-1])``; Rayleigh ``alpha`` [s-1], ``beta`` [s] and the velocity filter's gain ``a_filt`` per step (1: classic
#: Rayleigh)
Structure = namedtuple("Structure", ["mass", "minv", "active", "spr_dof", "spr_kc", "alpha", "beta", "a_filt"])
#: constrained dofs ``con_dof`` in motion groups ``con_grp`` with ``grp_par[g] = (kind, amplitude, t_start,
#: ramp_time)``; ``con_react[c] = (tangential, normal)`` transducer weights; ``grp_v`` (n_groups, 2) scratch;
#: ``con_cnode[slot] = (c of the x dof, c of the y dof)`` of the contact nodes (-1 free; empty: none constrained)
Motions = namedtuple("Motions", ["con_dof", "con_grp", "grp_par", "con_react", "grp_v", "con_cnode"])
#: pressure loads: dofs ``ld_dof``, full nodal forces ``ld_force`` [N], load ``ld_grp``, ``ld_par[g] = (t_start,
#: ramp_time)``; ``ld_scale`` (n_loads,) and ``ld_vold`` (n_loaded_dofs,) scratch
Loads = namedtuple("Loads", ["ld_dof", "ld_force", "ld_grp", "ld_par", "ld_scale", "ld_vold"])
#: contact geometry and laws (see :func:`fivid.solver._contact_kernels.contact_solve`): reference coordinates
#: ``X``, slaves, master segments, pair rows, tributary areas, the contact dofs' inverse mass ``minv_c``, the
#: contact nodes ``cnodes`` and their slots ``cnode_slot``; Gauss-Seidel limits ``gs_max_iter``, ``gs_tol`` [m]
ContactSet = namedtuple("ContactSet", ["X", "slave_node", "slave_pair", "master_ptr", "master_nodes", "pair_sign",
                                       "pair_par", "law_tab", "s_area", "minv_c", "cnodes", "cnode_slot",
                                       "gs_max_iter", "gs_tol"])
#: kinetic friction coefficient of every slave, rows at ``mu_rate`` [Hz] (one row: constant): the kernels' view of a
#: :class:`fivid.friction.FrictionTable`
MuSeries = namedtuple("MuSeries", ["mu_tab", "mu_rate"])
#: the contact's state between steps: current master segment ``seg``, geometry ``geo``, multipliers ``lam``,
#: ``cstate`` (0 open, 1 stick, 2 slip), and scratch ``mu_now``, ``vold_c`` (contact-node velocities)
ContactState = namedtuple("ContactState", ["seg", "geo", "lam", "cstate", "mu_now", "vold_c"])
#: the dof state ``u``, ``v`` (half step), ``w = u + beta v`` (or ``+ beta vf``), filtered velocity ``vf``, forces
#: ``f`` and ``scratch``; the accumulated works ``acc`` (``W_*`` slots) and the transducer sums ``react_acc``
State = namedtuple("State", ["u", "v", "w", "vf", "f", "scratch", "acc", "react_acc"])
#: outputs of a call (one row per output interval, see :func:`run_steps`), the sensors recorded and ``diag``
Records = namedtuple("Records", ["rec", "rec_sens", "rec_contact", "diag", "sens_node", "sens_dir"])


@kernel
def guard_status(ke, ue, acc, runaway_factor):
    """``OK``, ``NAN`` (non-finite energy or work) or ``RUNAWAY``: the stiffness-damping loss inferred as
    ``W_int - U`` is >= 0 for a stable step up to the shadow-energy difference of central differences,
    O(omega dt / 2) times the energy, so below ``-runaway_factor (KE + U)`` the run is unstable."""
    energy = ke + ue
    if not (math.isfinite(energy) and math.isfinite(acc[W_INT]) and math.isfinite(acc[W_EXT])):
        return NAN
    if acc[W_INT] - ue < -runaway_factor * energy - 1e-300:
        return RUNAWAY
    return OK


@kernel
def start_record(react_acc, rec_contact_r):
    """Zero the interval sums of the transducer and of the contact pairs."""
    react_acc[0] = 0.0
    react_acc[1] = 0.0
    for p in range(rec_contact_r.shape[0]):
        for c in range(5):
            rec_contact_r[p, c] = 0.0


@kernel
def group_velocities(grp_par, grp_v, t, dt):
    """Velocity of every motion group over the previous step and over ``[t, t + dt]`` into ``grp_v[:, 0:2]``."""
    for g in range(grp_par.shape[0]):
        kind = int(grp_par[g, 0])
        grp_v[g, 0] = constrained_velocity(kind, grp_par[g, 1], grp_par[g, 2], grp_par[g, 3], t - dt, dt)
        grp_v[g, 1] = constrained_velocity(kind, grp_par[g, 1], grp_par[g, 2], grp_par[g, 3], t, dt)


@kernel
def add_step_work(acc, dt, wint, dal, wext, wld, wcn, wct, wdr):
    """Accumulate one step's works (rates [W] times ``dt``) in ``acc``."""
    acc[W_LOAD] += dt * wld
    acc[W_INT] += dt * wint
    acc[D_ALPHA] += dt * dal
    acc[W_EXT] += dt * wext
    acc[W_CN] += dt * wcn
    acc[W_CT] += dt * wct
    acc[W_DRIVE] += dt * wdr


@kernel
def finish_record(rec_r, rec_sens_r, rec_contact_r, acc, react_acc, ke, ue, u, v, npd, sens_node, sens_dir,
                  slave_pair, pair_par, law_tab, s_area, geo, cstate, n_sub, runaway_factor, diag, step_end, wrap):
    """Write the interval-mean transducer forces, the energies ``ke``, ``ue`` [J] and the accumulated works, the
    contact averages and the sensors' velocity and displacement of an output row; check the guards. Returns the
    status; on failure ``diag = (step_end, index of the largest speed modulo wrap)``."""
    rec_r[R_FT] = react_acc[0] / n_sub
    rec_r[R_FN] = react_acc[1] / n_sub
    rec_r[R_KE] = ke
    rec_r[R_U] = ue
    rec_r[R_WINT] = acc[W_INT]
    rec_r[R_DA] = acc[D_ALPHA]
    rec_r[R_WEXT] = acc[W_EXT]
    rec_r[R_WCN] = acc[W_CN]
    rec_r[R_WCT] = acc[W_CT]
    rec_r[R_WLOAD] = acc[W_LOAD]
    rec_r[R_WDRIVE] = acc[W_DRIVE]
    rec_r[R_EPEN] = finish_contact_record(slave_pair, pair_par, law_tab, s_area, geo, cstate, n_sub, rec_contact_r)
    for s in range(sens_node.shape[0]):
        nd = sens_node[s]
        rec_sens_r[s, 0] = v[nd] * sens_dir[s, 0] + v[nd + npd] * sens_dir[s, 1]
        rec_sens_r[s, 1] = u[nd] * sens_dir[s, 0] + u[nd + npd] * sens_dir[s, 1]
    status = guard_status(ke, ue, acc, runaway_factor)
    if status != OK:
        worst = 0
        vmax = -1.0
        for d in range(v.shape[0]):
            av = abs(v[d])
            if not math.isfinite(av):
                worst = d
                break
            if av > vmax:
                vmax = av
                worst = d
        diag[0] = step_end
        diag[1] = worst % wrap
    return status


@reassociating_kernel
def _predictor(u, v, w, vf, f, mass, minv, active, dt, alpha, beta, a_filt):
    """Central-difference predictor over all dofs; returns the work increments / dt of the internal forces and
    of the alpha damping (mid-step velocities). Reassociation lets the two sums vectorise (no NaN/inf
    assumptions: the guards still see them).

    Classic Rayleigh (``a_filt >= 1``): ``w = u + beta v``. Band-limited (``a_filt < 1``): the filtered velocity
    ``vf += a_filt (v - vf)`` (exact update of ``dvf/dt = omega_c (v - vf)`` for a velocity constant over the
    step, ``a_filt = 1 - exp(-omega_c dt)``) and ``w = u + beta vf``; the classic scheme is bit for bit what it
    always was.

    Without mass-proportional damping (``alpha == 0``, the rough pair's band-limited damping) the alpha work is 0
    and ``mass`` is not read: one array less streamed per step (the same results bit for bit).

    Only the dofs in the ranges ``active`` (those with mass) are integrated: a massless dof (a tied node of a mesh
    transition, whose ``w`` the stencil sets from its masters; the padding) keeps its ``u, v, w, vf`` -- zero force
    and zero inverse mass would change nothing but a velocity it started with, which is no physics. The 120 mm
    rough pair's tied nodes and padding are 42 % of the dof vector's entries. The dofs' updates are the full
    sweep's bit for bit; the work sums are vectorised reductions, equal to their summation order's round-off."""
    wint = 0.0
    dal = 0.0
    filtered = a_filt < 1.0  # loop-invariant: LLVM unswitches the loop (measured: no cost in the classic case)
    damped = alpha != 0.0  # loop-invariant too
    for r in range(active.shape[0]):
        d0 = uint64(active[r, 0])
        for i in range(active[r, 1] - active[r, 0]):
            d = d0 + uint64(i)  # unsigned: no negative-index wraparound, so the loop vectorises (signed: 2.2x slower)
            vo = v[d]
            vn = vo + dt * (-minv[d] * f[d] - alpha * vo)
            vm = 0.5 * (vo + vn)
            wint += f[d] * vm
            if damped:
                dal += alpha * mass[d] * vo * vm
            v[d] = vn
            ud = u[d] + dt * vn
            u[d] = ud
            if filtered:
                fv = vf[d] + a_filt * (vn - vf[d])
                vf[d] = fv
                w[d] = ud + beta * fv
            else:
                w[d] = ud + beta * vn
    return wint, dal


@kernel
def _apply_loads(t, loads, v, f):
    """``f -= r(t) F`` for the pressure loads at the step start; keeps the loaded dofs' velocities before it."""
    ld_par = loads.ld_par
    ld_scale = loads.ld_scale
    for g in range(ld_par.shape[0]):
        ld_scale[g] = ramp((t - ld_par[g, 0]) / ld_par[g, 1]) if ld_par[g, 1] > 0.0 else (
            1.0 if t >= ld_par[g, 0] else 0.0)
    for q in range(loads.ld_dof.shape[0]):
        d = loads.ld_dof[q]
        f[d] -= ld_scale[loads.ld_grp[q]] * loads.ld_force[q]
        loads.ld_vold[q] = v[d]


@kernel
def _load_work(loads, v):
    """Power of the pressure loads over the step [W] with the final mid-step velocities."""
    wld = 0.0
    for q in range(loads.ld_dof.shape[0]):
        wld += loads.ld_scale[loads.ld_grp[q]] * loads.ld_force[q] * 0.5 * (loads.ld_vold[q] + v[loads.ld_dof[q]])
    return wld


@kernel
def _keep_contact_velocities(v, npd, cnodes, vold_c, col):
    """``vold_c[:, col:col + 2]`` = the x and y velocities of the contact nodes."""
    for q in range(cnodes.shape[0]):
        nd = cnodes[q]
        vold_c[q, col] = v[nd]
        vold_c[q, col + 1] = v[nd + npd]


@kernel
def _impose_motions(t, dt, motions, structure, state, wint, dal):
    """Constrained dofs: undo the predictor's free update, impose the motion and replace the dof's share of the
    work sums ``wint``, ``dal``; the reaction ``m a + f + alpha m v`` is summed for the force transducer. Returns
    ``(wint, dal, wext, rt, rn)``: the corrected sums, the reactions' power [W] and transducer sums [N]."""
    u, v, w, vf, f = state.u, state.v, state.w, state.vf, state.f
    mass, alpha, beta, a_filt = structure.mass, structure.alpha, structure.beta, structure.a_filt
    grp_v = motions.grp_v
    wext = 0.0
    rt = 0.0
    rn = 0.0
    group_velocities(motions.grp_par, grp_v, t, dt)
    for c in range(motions.con_dof.shape[0]):
        d = motions.con_dof[c]
        vwrong = v[d]
        vo = grp_v[motions.con_grp[c], 0]
        vn = grp_v[motions.con_grp[c], 1]
        u[d] += dt * (vn - vwrong)
        v[d] = vn
        if a_filt >= 1.0:
            w[d] = u[d] + beta * vn
        else:
            vf[d] += a_filt * (vn - vwrong)
            w[d] = u[d] + beta * vf[d]
        # replace this dof's share of the energy sums
        wint -= 0.5 * f[d] * (vwrong - vn)
        dal -= 0.5 * alpha * mass[d] * vo * (vwrong - vn)
        rf = mass[d] * (vn - vo) / dt + f[d] + alpha * mass[d] * vo
        wext += rf * 0.5 * (vo + vn)
        rt += motions.con_react[c, 0] * rf
        rn += motions.con_react[c, 1] * rf
    return wint, dal, wext, rt, rn


@kernel
def _contact_correction(t, dt, npd, structure, contact, friction, cs, state, rec_contact_r, no_wmat, wint, dal):
    """The contact correction of a step (constraints at ``t + dt``), then the internal-force and alpha-damping
    work completed with the velocity change it made at the contact nodes, the contact's work and
    ``w = u + beta v`` (or ``u + beta vf``) where it moved nodes. Returns ``(wint, dal, wcn, wct, wdr)``."""
    u, v, w, vf, f = state.u, state.v, state.w, state.vf, state.f
    mass, alpha, beta, a_filt = structure.mass, structure.alpha, structure.beta, structure.a_filt
    cnodes = contact.cnodes
    vold_c = cs.vold_c
    _keep_contact_velocities(v, npd, cnodes, vold_c, CNODE_V_PREDICTED)
    contact_step(contact.X, u, v, npd, dt, t + dt, contact.minv_c, no_wmat, contact.slave_node, contact.slave_pair,
                 contact.master_ptr, contact.master_nodes, contact.pair_sign, contact.pair_par, contact.law_tab,
                 contact.s_area, cs.seg, cs.geo, cs.lam, cs.cstate, friction.mu_tab, friction.mu_rate, cs.mu_now,
                 contact.gs_max_iter, contact.gs_tol, state.acc, contact.cnode_slot, vold_c)
    # the contact correction changed the mid-step velocity of the contact nodes: complete the
    # internal-force and alpha-damping work with it (f and alpha m v_old times the velocity change)
    for q in range(cnodes.shape[0]):
        nd = cnodes[q]
        dvx = v[nd] - vold_c[q, CNODE_V_PREDICTED]
        dvy = v[nd + npd] - vold_c[q, CNODE_V_PREDICTED + 1]
        wint += 0.5 * (f[nd] * dvx + f[nd + npd] * dvy)
        dal += 0.5 * alpha * (mass[nd] * vold_c[q, CNODE_V_STEP] * dvx + mass[nd + npd] * vold_c[q, CNODE_V_STEP + 1] * dvy)
    wcn, wct, wdr = contact_work(v, npd, contact.slave_node, contact.slave_pair, contact.master_ptr,
                                 contact.master_nodes, cs.seg, contact.pair_par, cs.geo, cs.lam, cs.cstate,
                                 contact.cnode_slot, vold_c, rec_contact_r)
    # w = u + beta v (or u + beta vf) where the contact correction moved nodes
    for q in range(cnodes.shape[0]):
        d = cnodes[q]
        if a_filt >= 1.0:
            w[d] = u[d] + beta * v[d]
            w[d + npd] = u[d + npd] + beta * v[d + npd]
        else:
            vf[d] += a_filt * (v[d] - vold_c[q, CNODE_V_PREDICTED])
            vf[d + npd] += a_filt * (v[d + npd] - vold_c[q, CNODE_V_PREDICTED + 1])
            w[d] = u[d] + beta * vf[d]
            w[d + npd] = u[d + npd] + beta * vf[d + npd]
    return wint, dal, wcn, wct, wdr


@kernel
def _step(t, dt, stencil, structure, motions, loads, contact, friction, cs, state, rec_contact_r, no_wmat):
    """One central-difference step from ``t`` [s] (see :func:`run_steps`); the works go to ``state.acc``."""
    npd = stencil.npd
    u = state.u
    v = state.v
    f = state.f
    # ---- internal forces, minus the applied loads at the step start (f is the net force K w - F)
    block_forces(state.w, f, stencil)
    spring_forces(u, v, f, structure.spr_dof, structure.spr_kc, True)
    _apply_loads(t, loads, v, f)
    # ---- old velocities of contact nodes (exact contact work)
    _keep_contact_velocities(v, npd, contact.cnodes, cs.vold_c, CNODE_V_STEP)
    # ---- predictor over all dofs, fused with the energy increments and w = u + beta v
    wint, dal = _predictor(u, v, state.w, state.vf, f, structure.mass, structure.minv, structure.active, dt,
                           structure.alpha, structure.beta, structure.a_filt)
    # ---- constrained dofs: undo the free update, impose the motion, reaction = m a + f + alpha m v
    wint, dal, wext, rt, rn = _impose_motions(t, dt, motions, structure, state, wint, dal)
    state.react_acc[0] += rt
    state.react_acc[1] += rn
    # ---- contact
    wcn = 0.0
    wct = 0.0
    wdr = 0.0
    if contact.slave_node.shape[0] > 0:
        wint, dal, wcn, wct, wdr = _contact_correction(t, dt, npd, structure, contact, friction, cs, state,
                                                       rec_contact_r, no_wmat, wint, dal)
        if motions.con_cnode.shape[0] > 0:  # contact nodes on constrained dofs: their reactions take the contact force
            dwext, drt, drn = contact_reactions(v, npd, contact.slave_node, contact.slave_pair, contact.master_ptr,
                                                contact.master_nodes, cs.seg, contact.pair_par, cs.geo, cs.lam,
                                                cs.cstate, contact.cnode_slot, cs.vold_c, motions.con_cnode,
                                                motions.con_react)
            wext += dwext
            state.react_acc[0] += drt
            state.react_acc[1] += drn
    # ---- load work with the final mid-step velocities; wint summed (K w - F) v, so add F v back
    wld = _load_work(loads, v)
    wint += wld
    add_step_work(state.acc, dt, wint, dal, wext, wld, wcn, wct, wdr)


@kernel
def _interval_energies(stencil, structure, state):
    """Kinetic energy ``sum m v^2 / 2`` and strain energy ``u . (K u) / 2`` (blocks and springs) [J]."""
    u = state.u
    v = state.v
    mass = structure.mass
    scratch = state.scratch
    n = u.shape[0]
    ke = 0.0
    for d in range(n):
        ke += 0.5 * mass[d] * v[d] * v[d]
    block_forces(u, scratch, stencil)
    spring_forces(u, v, scratch, structure.spr_dof, structure.spr_kc, False)
    ue = 0.0
    for d in range(n):
        ue += 0.5 * u[d] * scratch[d]
    return ke, ue


@kernel
def run_steps(step0, nsteps, dt, n_sub, runaway_factor, stencil, structure, motions, loads, contact, friction, cs,
              state, records):
    """Advance the model ``nsteps`` central-difference steps from step ``step0`` (a whole number of outputs).

    Per step: ``f = K(u + beta v)`` (band-limited damping, ``a_filt < 1``: ``K(u + beta vf)``, see
    :func:`_predictor`) by stencil plus springs and dashpots; predictor
    ``v* = v + dt (-M^-1 f - alpha v)``, ``u* = u + dt v*``; imposed motions on the constrained dofs (their
    reactions ``m a + f + alpha m v`` summed for the force transducer); contact correction
    (:func:`fivid.solver._contact_kernels.contact_solve`, constraints at ``t + dt``); energy increments with
    mid-step velocities, so that ``KE - KE0 = W_ext + W_load + W_drive + W_cn + W_ct - W_int - D_alpha`` holds to
    round-off (``W_drive``: work of the moving rigid masters' surfaces; ``W_load``: work of the pressure loads,
    applied as ``f -= r(t) F`` before the predictor).

    Parameters
    ----------
    step0, nsteps : int
        First step and number of steps (a multiple of ``n_sub``); step ``k`` starts at ``t = k dt``.
    dt : float
        Time step [s].
    n_sub : int
        Steps per output interval.
    runaway_factor : float
        Guard: the inferred stiffness-damping loss may not fall below ``-runaway_factor (KE + U)``.
    stencil : StencilArrays
        Internal-force stencils (:mod:`fivid.solver._stencil_kernels`); ``stencil.npd`` the component length.
    structure, motions, loads, contact, friction, cs, state : Structure, Motions, Loads, ContactSet, MuSeries,
        ContactState, State
        The argument groups (module attributes); ``cs`` and ``state`` are updated in place.
    records : Records
        Every ``n_sub`` steps one output row ``r`` is written: ``rec[r]`` (see ``R_*``), sensor velocity and
        displacement ``rec_sens[r, s, :]`` at the interval end (the driver differences them into
        interval-averaged accelerations), per-pair interval averages ``rec_contact[r, p] = (normal force,
        tangential force, stick, slip, open fractions)``.

    Returns
    -------
    (status, rows_written); on NaN or runaway energy ``records.diag = (step, x-index)`` of the node with the
    largest speed.
    """
    n_out = nsteps // n_sub
    no_wmat = np.zeros((0, 0))  # lumped mass: diagonal contact correction
    rec = records.rec
    rec_sens = records.rec_sens
    rec_contact = records.rec_contact
    for r in range(n_out):
        start_record(state.react_acc, rec_contact[r])
        for sub in range(n_sub):
            step = step0 + r * n_sub + sub
            _step(step * dt, dt, stencil, structure, motions, loads, contact, friction, cs, state, rec_contact[r],
                  no_wmat)
        # ---- end of an output interval: record
        step_end = step0 + (r + 1) * n_sub
        ke, ue = _interval_energies(stencil, structure, state)
        status = finish_record(rec[r], rec_sens[r], rec_contact[r], state.acc, state.react_acc, ke, ue, state.u,
                               state.v, stencil.npd, records.sens_node, records.sens_dir, contact.slave_pair,
                               contact.pair_par, contact.law_tab, contact.s_area, cs.geo, cs.cstate, n_sub,
                               runaway_factor, records.diag, step_end, stencil.npd)
        if status != OK:
            return status, r + 1
    return OK, n_out
