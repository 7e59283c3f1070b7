"""Numba time loop of a Craig-Bampton reduced system (:mod:`fivid.solver.reduced`): arrays and scalars only.

Coordinates ``q`` (length ``n``), in this order: the x then the y displacements of the ``nb`` physical boundary
nodes (contact and sensor nodes; node ``k`` has x-index ``k`` and y-index ``k + nb``, the layout of
:mod:`fivid.solver._loop_kernels` with ``npd = nb`` and no padding), the amplitudes of the fixed-interface modes,
then one coordinate per group of constrained dofs moving together (a driven edge, or a held edge whose reaction
the force transducer sums). The first ``nF = 2 nb + n_modes`` coordinates are free, the last ``ng`` prescribed.

Stiffness: dense ``kc`` over the constraint coordinates ``cidx`` (boundary nodes and groups: the condensed
stiffness), diagonal ``kdiag`` (``omega_i^2``) over the modes (constraint and fixed-interface modes are
K-orthogonal). Mass: dense; the kernel needs ``minv_ff = M_FF^-1``, ``b_fg = M_FF^-1 M_FG`` (the inertial
load of the prescribed motions), the group rows ``m_g = M_G:`` (reactions) and the whole ``m`` (kinetic
energy, refreshed momentum ``p = M v`` at every record).

Nothing is allocated inside the time loop.
"""

import numpy as np

from fivid.contact._layout_kernels import CNODE_V_STEP, GEO_N0, GEO_N1, GEO_NX, GEO_NY, GEO_TX, GEO_TY
from fivid.solver._contact_kernels import _segment_nodes, contact_step, contact_work
from fivid.solver._kernels import OK, kernel, reassociating_kernel
from fivid.solver._loop_kernels import add_step_work, finish_record, group_velocities, start_record

__all__ = ["reduced_forces", "run_reduced_steps"]


@reassociating_kernel
def _matvec(a, x, y, i0, i1, ncols):
    """``y[i] = a[i, :ncols] @ x[:ncols]`` for ``i0 <= i < i1`` (the whole double loop in one function, reassociated:
    the inner loop vectorises; a per-row dot helper measured 3x slower)."""
    for i in range(i0, i1):
        s = 0.0
        for j in range(ncols):
            s += a[i, j] * x[j]
        y[i] = s


@kernel
def reduced_forces(w, f, kc, cidx, kdiag, m0, wc, fc):
    """``f = K_r w``: dense ``kc`` over the constraint coordinates ``cidx``, ``kdiag`` over the modes from ``m0``;
    ``wc``, ``fc`` (len(cidx)) are scratch for the gathered constraint coordinates and their forces."""
    nc = cidx.shape[0]
    for j in range(nc):
        wc[j] = w[cidx[j]]
    _matvec(kc, wc, fc, 0, nc, nc)
    for i in range(nc):
        f[cidx[i]] = fc[i]
    for m in range(kdiag.shape[0]):
        f[m0 + m] = kdiag[m] * w[m0 + m]


@kernel
def run_reduced_steps(
    step0, nsteps, dt, alpha, beta, a_filt, n_sub, nb, nf,
    kc, cidx, kdiag, minv_ff, b_fg, m_g, m, grp_par, grp_v, g_react,
    X, slave_node, slave_pair, master_ptr, master_nodes, pair_sign, pair_par, law_tab, s_area, minv_c, wmat, seg,
    geo, lam, cstate, gs_max_iter, gs_tol, mu_tab, mu_rate, mu_now, vold_c, cnode_slot, cnodes,
    sens_node, sens_dir,
    q, qd, w, vf, f, p, vold, scratch, wc, fc, cimp, acc, react_acc,
    rec, rec_sens, rec_contact, runaway_factor, diag,
):
    """Advance the reduced system ``nsteps`` central-difference steps from step ``step0`` (whole outputs).

    The step of :func:`fivid.solver._loop_kernels.run_steps` with a dense mass: ``f = K_r (q + beta v)`` (band-limited
    damping: ``+ beta vf``); free coordinates
    ``v_F' = v_F - dt M_FF^-1 f_F - alpha dt v_F - B (alpha dt v_G + v_G' - v_G)``, ``B = M_FF^-1 M_FG``
    (alpha M v and the prescribed motions' inertia), prescribed ones follow their motion; the contact correction
    runs on the boundary nodes through the dense inverse mass ``wmat`` (the boundary block of ``M_FF^-1``) and
    its impulse ``c`` then moves the modes by ``dt M_FF^-1[modes, b] c``; group reactions
    ``R_G = (M a)_G + f_G + alpha p_G`` feed the transducer. Energy increments with mid-step velocities over
    every coordinate, ``p = M v`` kept by ``p' = p + dt M a``, so that
    ``KE - KE0 = W_ext + W_contact - W_int - D_alpha`` closes to round-off. Records as ``run_steps``.
    Returns ``(status, rows_written)``; ``diag = (step, coordinate with the largest speed)``.
    """
    n = q.shape[0]
    ng = n - nf
    nbd = 2 * nb
    n_out = nsteps // n_sub
    ns = slave_node.shape[0]
    mag = np.zeros(ng)
    for r in range(n_out):
        start_record(react_acc, rec_contact[r])
        for sub in range(n_sub):
            step = step0 + r * n_sub + sub
            t = step * dt
            reduced_forces(w, f, kc, cidx, kdiag, nbd, wc, fc)
            group_velocities(grp_par, grp_v, t, dt)
            for i in range(n):
                vold[i] = qd[i]
            # ---- predictor of the free coordinates (dense inverse mass), motion of the prescribed ones
            _matvec(minv_ff, f, scratch, 0, nf, nf)
            for i in range(nf):
                corr = 0.0
                for g in range(ng):
                    corr += b_fg[i, g] * (alpha * grp_v[g, 0] + (grp_v[g, 1] - grp_v[g, 0]) / dt)
                vi = vold[i] + dt * (-scratch[i] - alpha * vold[i]) - dt * corr
                qd[i] = vi
                q[i] += dt * vi
            for g in range(ng):
                qd[nf + g] = grp_v[g, 1]
                q[nf + g] += dt * grp_v[g, 1]
            # ---- contact on the boundary nodes, then its impulse on the modes
            wcn = 0.0
            wct = 0.0
            wdr = 0.0
            for i in range(nbd):
                cimp[i] = 0.0
            if ns > 0:
                for c in range(cnodes.shape[0]):
                    nd = cnodes[c]
                    vold_c[c, CNODE_V_STEP] = vold[nd]
                    vold_c[c, CNODE_V_STEP + 1] = vold[nd + nb]
                contact_step(X, q, qd, nb, dt, t + dt, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes,
                             pair_sign, pair_par, law_tab, s_area, seg, geo, lam, cstate, mu_tab, mu_rate, mu_now,
                             gs_max_iter, gs_tol, acc, cnode_slot, vold_c)
                for k in range(ns):
                    if cstate[k] == 0:
                        continue
                    sn, a, b = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
                    fx = lam[k, 0] * geo[k, GEO_NX] + lam[k, 1] * geo[k, GEO_TX]
                    fy = lam[k, 0] * geo[k, GEO_NY] + lam[k, 1] * geo[k, GEO_TY]
                    cimp[sn] += fx
                    cimp[sn + nb] += fy
                    cimp[a] -= geo[k, GEO_N0] * fx
                    cimp[a + nb] -= geo[k, GEO_N0] * fy
                    cimp[b] -= geo[k, GEO_N1] * fx
                    cimp[b + nb] -= geo[k, GEO_N1] * fy
                _matvec(minv_ff, cimp, scratch, nbd, nf, nbd)
                for i in range(nbd, nf):
                    qd[i] += dt * scratch[i]
                    q[i] += dt * dt * scratch[i]
                wcn, wct, wdr = contact_work(qd, nb, slave_node, slave_pair, master_ptr, master_nodes, seg,
                                             pair_par, geo, lam, cstate, cnode_slot, vold_c, rec_contact[r])
            # ---- reactions of the prescribed coordinates: R_G = (M a)_G + f_G + alpha p_G
            for i in range(n):
                scratch[i] = (qd[i] - vold[i]) / dt
            wext = 0.0
            rt = 0.0
            rn = 0.0
            _matvec(m_g, scratch, mag, 0, ng, n)
            for g in range(ng):
                rf = mag[g] + f[nf + g] + alpha * p[nf + g]
                wext += rf * 0.5 * (grp_v[g, 0] + grp_v[g, 1])
                rt += g_react[g, 0] * rf
                rn += g_react[g, 1] * rf
            react_acc[0] += rt
            react_acc[1] += rn
            # ---- energy increments (mid-step velocities), momentum, filtered velocity and w
            wint = 0.0
            dal = 0.0
            for i in range(n):
                vm = 0.5 * (vold[i] + qd[i])
                wint += f[i] * vm
                dal += alpha * p[i] * vm
            for i in range(nf):
                p[i] += dt * (-f[i] - alpha * p[i] + (cimp[i] if i < nbd else 0.0))
            for g in range(ng):
                p[nf + g] += dt * mag[g]
            for i in range(n):
                if a_filt >= 1.0:
                    w[i] = q[i] + beta * qd[i]
                else:
                    vf[i] += a_filt * (qd[i] - vf[i])
                    w[i] = q[i] + beta * vf[i]
            add_step_work(acc, dt, wint, dal, wext, 0.0, wcn, wct, wdr)
        # ---- end of an output interval: record (and refresh p = M v against round-off drift)
        step_end = step0 + (r + 1) * n_sub
        ke = 0.0
        _matvec(m, qd, p, 0, n, n)
        for i in range(n):
            ke += 0.5 * qd[i] * p[i]
        reduced_forces(q, scratch, kc, cidx, kdiag, nbd, wc, fc)
        ue = 0.0
        for i in range(n):
            ue += 0.5 * q[i] * scratch[i]
        status = finish_record(rec[r], rec_sens[r], rec_contact[r], acc, react_acc, ke, ue, q, qd, nb, sens_node,
                               sens_dir, slave_pair, pair_par, law_tab, s_area, geo, cstate, n_sub, runaway_factor,
                               diag, step_end, n)
        if status != OK:
            return status, r + 1
    return OK, n_out
