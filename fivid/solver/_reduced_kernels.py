"""Numba time loop of a Craig-Bampton reduced system (:mod:`fivid.solver.reduced`), stepped in the modal
coordinates of its free part: arrays and scalars only.

Coordinates ``q`` (length ``n``): the ``nf`` modal amplitudes ``eta`` of the free part (the reduced system's own
modes with the groups held: ``K_FF Phi = M_FF Phi Lambda``, ``Phi^T M_FF Phi = I``; the physical free coordinates are
``Phi eta``), then one coordinate per group of constrained dofs moving together (a driven edge, or a held edge
whose reaction the force transducer sums), prescribed. In these coordinates (``T~ = diag(Phi, I)``) the mass is
``[[I, B], [B^T, M_GG]]`` with ``B = Phi^T M_FG`` and the stiffness ``[[Lambda, K~_FG], [K~_FG^T, K_GG]]``,
``K~_FG = Phi^T K_FG``: a step costs ``O(nf)`` for the free part instead of the dense ``M_FF^-1`` product of the
physical coordinates. Central differences, the band-limited velocity filter and Rayleigh damping are linear and
act per coordinate, so the trajectory is the physical coordinates' one, to round-off.

Contact is solved on the physical boundary: ``qb = Phi_b eta``, ``qdb = Phi_b eta'`` (``Phi_b``: the boundary rows
of ``Phi``, the x then the y displacements of the ``nb`` physical boundary nodes -- contact and sensor nodes; node
``k`` at x-index ``k`` and y-index ``k + nb``, the layout of :mod:`fivid.solver._loop_kernels` with ``npd = nb``),
with the boundary block of the inverse mass ``W = Phi_b Phi_b^T``; the contact impulse ``c`` then moves the modes by
``dt Phi_b^T c``. The sensors are read from ``qb``, ``qdb``.

Nothing is allocated inside the time loop.
"""

import numpy as np

from fivid.contact._layout_kernels import CNODE_V_STEP, GEO_N0, GEO_N1, GEO_NX, GEO_NY, GEO_TX, GEO_TY
from fivid.solver._contact_kernels import _segment_nodes, contact_step, contact_work
from fivid.solver._kernels import OK, kernel, reassociating_kernel
from fivid.solver._loop_kernels import add_step_work, finish_record, group_velocities, start_record

__all__ = ["modal_product", "contact_impulse", "group_reactions", "damped_displacement", "run_modal_steps"]


@reassociating_kernel
def modal_product(d, a_fg, a_gf, a_gg, x, y, nf):
    """``y = [[diag(d), a_fg], [a_gf, a_gg]] x``: the stiffness (``d = Lambda``) or the mass (``d = 1``) in the
    modal coordinates times ``x`` (``a_gf`` is ``a_fg`` transposed, contiguous; reassociated: the sums over the modes
    vectorise)."""
    ng = a_gg.shape[0]
    for i in range(nf):
        s = d[i] * x[i]
        for g in range(ng):
            s += a_fg[i, g] * x[nf + g]
        y[i] = s
    for g in range(ng):
        y[nf + g] = _group_row(a_gf[g], a_gg[g], x, nf)


@reassociating_kernel
def _group_row(a_gf, a_gg, x, nf):
    """``a_gf . x[:nf] + a_gg . x[nf:]``: a group's row of the modal stiffness or mass times ``x``."""
    s = 0.0
    for i in range(nf):
        s += a_gf[i] * x[i]
    for h in range(a_gg.shape[0]):
        s += a_gg[h] * x[nf + h]
    return s


@reassociating_kernel
def _mid_step_work(f, p, vold, qd, alpha):
    """``(f . vm, alpha p . vm)`` with the mid-step velocities ``vm = (vold + qd) / 2``: the work rates [W] of the
    internal forces and of the alpha damping (reassociated: the sums vectorise)."""
    wint = 0.0
    dal = 0.0
    for i in range(qd.shape[0]):
        vm = 0.5 * (vold[i] + qd[i])
        wint += f[i] * vm
        dal += alpha * p[i] * vm
    return wint, dal


@reassociating_kernel
def _boundary_motion(phib, q, qd, qb, qdb):
    """``qb = Phi_b q[:nf]``, ``qdb = Phi_b qd[:nf]``: both products in one pass over ``Phi_b`` (reassociated: the
    inner loop vectorises)."""
    nf = phib.shape[1]
    for j in range(phib.shape[0]):
        s = 0.0
        sd = 0.0
        for i in range(nf):
            s += phib[j, i] * q[i]
            sd += phib[j, i] * qd[i]
        qb[j] = s
        qdb[j] = sd


@kernel
def _modal_impulse(phib, cimp, gimp):
    """``gimp = Phi_b^T cimp`` over the nonzero entries of ``cimp`` (the nodes in contact)."""
    nf = phib.shape[1]
    for i in range(nf):
        gimp[i] = 0.0
    for j in range(phib.shape[0]):
        c = cimp[j]
        if c != 0.0:
            for i in range(nf):
                gimp[i] += phib[j, i] * c


@kernel
def contact_impulse(cimp, nb, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par, geo, lam_c, cstate):
    """The contact forces of the step on the boundary dofs ``cimp`` (length ``2 nb``) [N]: each closed slave's
    ``lam_n n + lam_t t``, and ``-N0``, ``-N1`` times it on its master nodes."""
    for i in range(cimp.shape[0]):
        cimp[i] = 0.0
    for k in range(slave_node.shape[0]):
        if cstate[k] == 0:
            continue
        sn, a, b = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
        fx = lam_c[k, 0] * geo[k, GEO_NX] + lam_c[k, 1] * geo[k, GEO_TX]
        fy = lam_c[k, 0] * geo[k, GEO_NY] + lam_c[k, 1] * geo[k, GEO_TY]
        cimp[sn] += fx
        cimp[sn + nb] += fy
        cimp[a] -= geo[k, GEO_N0] * fx
        cimp[a + nb] -= geo[k, GEO_N0] * fy
        cimp[b] -= geo[k, GEO_N1] * fx
        cimp[b + nb] -= geo[k, GEO_N1] * fy


@kernel
def group_reactions(mag, f, p, nf, alpha, grp_v, g_react, react_acc):
    """Reactions of the prescribed coordinates ``R_G = (M a)_G + f_G + alpha p_G`` (``mag``: ``(M a)_G``) into the
    transducer sums ``react_acc``; returns their work rate [W] at the groups' mid-step velocities."""
    wext = 0.0
    for g in range(mag.shape[0]):
        rf = mag[g] + f[nf + g] + alpha * p[nf + g]
        wext += rf * 0.5 * (grp_v[g, 0] + grp_v[g, 1])
        react_acc[0] += g_react[g, 0] * rf
        react_acc[1] += g_react[g, 1] * rf
    return wext


@kernel
def damped_displacement(q, qd, vf, w, beta, a_filt):
    """``w = q + beta v`` (classic Rayleigh, ``a_filt >= 1``) or ``w = q + beta vf`` with the filtered velocity
    ``vf += a_filt (v - vf)`` (band-limited damping)."""
    for i in range(q.shape[0]):
        if a_filt >= 1.0:
            w[i] = q[i] + beta * qd[i]
        else:
            vf[i] += a_filt * (qd[i] - vf[i])
            w[i] = q[i] + beta * vf[i]


@kernel
def run_modal_steps(
    step0, nsteps, dt, alpha, beta, a_filt, n_sub, nb, nf,
    lam, kfg, kgf, kgg, one_f, bfg, bgf, mgg, phib, grp_par, grp_v, g_react,
    X, slave_node, slave_pair, master_ptr, master_nodes, pair_sign, pair_par, law_tab, s_area, minv_c, wmat, seg,
    geo, lam_c, cstate, gs_max_iter, gs_tol, mu_tab, mu_rate, mu_now, vold_c, cnode_slot, cnodes,
    sens_node, sens_dir,
    q, qd, w, vf, f, p, vold, scratch, qb, qdb, cimp, gimp, acc, react_acc,
    rec, rec_sens, rec_contact, runaway_factor, diag,
):
    """Advance the reduced system ``nsteps`` central-difference steps from step ``step0`` (whole outputs), in the
    modal coordinates of the module docstring.

    The step of :func:`fivid.solver._loop_kernels.run_steps`: ``f = K~ (q + beta v)`` (band-limited damping:
    ``+ beta vf``); free coordinates ``v_F' = v_F - dt f_F - alpha dt v_F - B (alpha dt v_G + v_G' - v_G)``
    (alpha M v and the prescribed motions' inertia; the free part's mass is the identity), prescribed ones follow
    their motion; the contact correction runs on the physical boundary ``qb``, ``qdb`` (``Phi_b`` times the
    predicted modal state) through ``wmat = Phi_b Phi_b^T`` and its impulse ``c`` moves the modes by
    ``dt Phi_b^T c``; group reactions ``R_G = (M~ a)_G + f_G + alpha p_G`` feed the transducer. Energy increments
    with mid-step velocities over every coordinate, ``p = M~ v`` kept by ``p' = p + dt M~ a``, so that
    ``KE - KE0 = W_ext + W_contact - W_int - D_alpha`` closes to round-off. Records as ``run_steps``, the sensors
    from ``qb``, ``qdb``. ``qdb`` holds the boundary velocities of the previous step on entry (the contact's
    mid-step velocities) and on return. Returns ``(status, rows_written)``; ``diag = (step, boundary coordinate
    with the largest speed)``.
    """
    n = q.shape[0]
    ng = n - nf
    nbd = 2 * nb
    n_out = nsteps // n_sub
    ns = slave_node.shape[0]
    mag = np.zeros(ng)
    ag = np.zeros(ng)
    for r in range(n_out):
        start_record(react_acc, rec_contact[r])
        for sub in range(n_sub):
            step = step0 + r * n_sub + sub
            t = step * dt
            modal_product(lam, kfg, kgf, kgg, w, f, nf)
            group_velocities(grp_par, grp_v, t, dt)
            for i in range(n):
                vold[i] = qd[i]
            # ---- predictor of the free coordinates (identity mass), motion of the prescribed ones
            for g in range(ng):
                ag[g] = alpha * grp_v[g, 0] + (grp_v[g, 1] - grp_v[g, 0]) / dt
            for i in range(nf):
                corr = 0.0
                for g in range(ng):
                    corr += bfg[i, g] * ag[g]
                vi = vold[i] + dt * (-f[i] - alpha * vold[i]) - dt * corr
                qd[i] = vi
                q[i] += dt * vi
            for g in range(ng):
                qd[nf + g] = grp_v[g, 1]
                q[nf + g] += dt * grp_v[g, 1]
            # ---- contact on the physical boundary, then its impulse on the modes
            wcn = 0.0
            wct = 0.0
            wdr = 0.0
            for i in range(nf):
                gimp[i] = 0.0
            if ns > 0:
                for c in range(cnodes.shape[0]):
                    nd = cnodes[c]
                    vold_c[c, CNODE_V_STEP] = qdb[nd]
                    vold_c[c, CNODE_V_STEP + 1] = qdb[nd + nb]
            _boundary_motion(phib, q, qd, qb, qdb)
            if ns > 0:
                contact_step(X, qb, qdb, nb, dt, t + dt, minv_c, wmat, slave_node, slave_pair, master_ptr,
                             master_nodes, pair_sign, pair_par, law_tab, s_area, seg, geo, lam_c, cstate, mu_tab,
                             mu_rate, mu_now, gs_max_iter, gs_tol, acc, cnode_slot, vold_c)
                contact_impulse(cimp, nb, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par, geo, lam_c,
                                cstate)
                _modal_impulse(phib, cimp, gimp)
                for i in range(nf):
                    qd[i] += dt * gimp[i]
                    q[i] += dt * dt * gimp[i]
                wcn, wct, wdr = contact_work(qdb, nb, slave_node, slave_pair, master_ptr, master_nodes, seg,
                                             pair_par, geo, lam_c, cstate, cnode_slot, vold_c, rec_contact[r])
            # ---- reactions of the prescribed coordinates: R_G = (M~ a)_G + f_G + alpha p_G
            for i in range(n):
                scratch[i] = (qd[i] - vold[i]) / dt
            for g in range(ng):
                mag[g] = _group_row(bgf[g], mgg[g], scratch, nf)
            wext = group_reactions(mag, f, p, nf, alpha, grp_v, g_react, react_acc)
            # ---- energy increments (mid-step velocities), momentum, filtered velocity and w
            wint, dal = _mid_step_work(f, p, vold, qd, alpha)
            for i in range(nf):
                p[i] += dt * (-f[i] - alpha * p[i] + gimp[i])
            for g in range(ng):
                p[nf + g] += dt * mag[g]
            damped_displacement(q, qd, vf, w, beta, a_filt)
            add_step_work(acc, dt, wint, dal, wext, 0.0, wcn, wct, wdr)
        # ---- end of an output interval: record (and refresh p = M~ v against round-off drift)
        step_end = step0 + (r + 1) * n_sub
        modal_product(one_f, bfg, bgf, mgg, qd, p, nf)
        ke = 0.0
        for i in range(n):
            ke += 0.5 * qd[i] * p[i]
        modal_product(lam, kfg, kgf, kgg, q, scratch, nf)
        ue = 0.0
        for i in range(n):
            ue += 0.5 * q[i] * scratch[i]
        status = finish_record(rec[r], rec_sens[r], rec_contact[r], acc, react_acc, ke, ue, qb, qdb, nb, sens_node,
                               sens_dir, slave_pair, pair_par, law_tab, s_area, geo, cstate, n_sub, runaway_factor,
                               diag, step_end, nbd)
        if status != OK:
            return status, r + 1
    return OK, n_out
