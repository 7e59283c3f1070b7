"""Reference for the modal stepping of the reduced path (tests/solver/test_reduced_modal.py): the reduced system
stepped in its physical Craig-Bampton coordinates with the dense inverse mass ``M_FF^-1`` -- fivid's own kernel
before the modal coordinates (``fivid/solver/_reduced_kernels.py`` at commit d5535b7; the contact solve
(``delassus_contact_solve``, which replaced the shared ``contact_step`` there), the contact forces on the boundary,
the group reactions, the energy rates and the damped displacement from the shared kernels of
:mod:`fivid.solver._reduced_kernels`), compiled without the on-disk cache. The contact solve is tested against the
shared projected Gauss-Seidel on its own (test_reduced_modal.py).

Coordinates ``q``: the x then the y displacements of the ``nb`` boundary nodes, the fixed-interface modes, then the
groups; stiffness dense ``kc`` over the constraint coordinates ``cidx`` and diagonal ``kdiag`` over the modes.
"""

import numpy as np
from numba import njit

from fivid.contact._layout_kernels import CNODE_V_STEP, N_CNODE, N_GEO
from fivid.solver._contact_kernels import contact_work
from fivid.solver._kernels import OK, constrained_velocity
from fivid.solver._loop_kernels import add_step_work, finish_record, group_velocities, start_record
from fivid.solver._reduced_kernels import (
    _mid_step_work,
    contact_impulse,
    damped_displacement,
    delassus_contact_solve,
    group_reactions,
)

kernel = njit(cache=False)
reassociating_kernel = njit(cache=False, fastmath={"contract", "reassoc"})


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
    act, closed = np.zeros(ns, dtype=np.int64), np.zeros(ns, dtype=np.int64)
    cmat, resp, rel = np.zeros((ns, ns, 4)), np.zeros((ns, 2, 2 * nb)), np.zeros((ns, 4))
    applied, dmat = np.zeros((ns, 2)), np.zeros((2 * ns, 2 * ns + 1))
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
            if ns > 0:
                for c in range(cnodes.shape[0]):
                    nd = cnodes[c]
                    vold_c[c, CNODE_V_STEP] = vold[nd]
                    vold_c[c, CNODE_V_STEP + 1] = vold[nd + nb]
                delassus_contact_solve(X, q, qd, nb, dt, t + dt, wmat, slave_node, slave_pair, master_ptr, master_nodes,
                                       pair_sign, pair_par, law_tab, s_area, seg, geo, lam, cstate, mu_tab, mu_rate,
                                       mu_now, gs_max_iter, gs_tol, acc, act, cmat, resp, rel, applied, closed, dmat)
                contact_impulse(cimp, nb, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par, geo, lam,
                                cstate)
                _matvec(minv_ff, cimp, scratch, nbd, nf, nbd)
                for i in range(nbd, nf):
                    qd[i] += dt * scratch[i]
                    q[i] += dt * dt * scratch[i]
                wcn, wct, wdr = contact_work(qd, nb, slave_node, slave_pair, master_ptr, master_nodes, seg,
                                             pair_par, geo, lam, cstate, cnode_slot, vold_c, rec_contact[r])
            # ---- reactions of the prescribed coordinates: R_G = (M a)_G + f_G + alpha p_G
            for i in range(n):
                scratch[i] = (qd[i] - vold[i]) / dt
            _matvec(m_g, scratch, mag, 0, ng, n)
            wext = group_reactions(mag, f, p, nf, alpha, grp_v, g_react, react_acc)
            # ---- energy increments (mid-step velocities), momentum, filtered velocity and w
            wint, dal = _mid_step_work(f, p, vold, qd, alpha)
            for i in range(nf):
                p[i] += dt * (-f[i] - alpha * p[i] + (cimp[i] if i < nbd else 0.0))
            for g in range(ng):
                p[nf + g] += dt * mag[g]
            damped_displacement(q, qd, vf, w, beta, a_filt)
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


def physical_arrays(rs, cholesky=False) -> dict:
    """The kernel arrays of the physical-coordinate step from the reduced system ``rs`` (as fivid built them before
    the modal coordinates); ``cholesky``: ``M_FF^-1`` from a Cholesky factorisation instead of ``numpy.linalg.inv``
    (the same matrix up to round-off: how far round-off alone moves the run)."""
    a = rs.kernel
    nb, nf, n = a["nb"], a["nf"], rs.size
    cidx = np.concatenate([np.arange(2 * nb), np.arange(nf, n)]).astype(np.int64)
    if cholesky:
        import scipy.linalg

        minv_ff = scipy.linalg.cho_solve(scipy.linalg.cho_factor(rs.M[:nf, :nf]), np.eye(nf))
    else:
        minv_ff = np.linalg.inv(rs.M[:nf, :nf])
    minv_ff = 0.5 * (minv_ff + minv_ff.T)
    c = np.ascontiguousarray
    return dict(kc=c(rs.K[np.ix_(cidx, cidx)]), cidx=cidx, kdiag=c(np.diag(rs.K)[2 * nb:nf]), minv_ff=c(minv_ff),
                b_fg=c(minv_ff @ rs.M[:nf, nf:]), m_g=c(rs.M[nf:]), m=c(rs.M), wmat=c(minv_ff[:2 * nb, :2 * nb]))


def integrate_physical(prep, cholesky=False):
    """``(rec, sens_v, contact)`` records of the prepared reduced run ``prep`` stepped in the physical coordinates
    (zero initial velocity: the rig's runs start at rest); ``cholesky``: see :func:`physical_arrays`."""
    from fivid.solver._kernels import N_ACC, N_REC
    from fivid.solver.integrate import RUNAWAY_FACTOR, shortest_master_segment, velocity_filter_gain

    model, rs, fric, settings = prep.model, prep.reduced, prep.friction, prep.settings
    a, r = rs.kernel, physical_arrays(rs, cholesky)
    dt, n_sub, n_int = settings.time_step, settings.steps_per_interval, settings.n_intervals
    n, nb, nf = rs.size, a["nb"], a["nf"]
    assert not np.any(model.initial_velocity())
    qd = np.zeros(n)
    for g in range(n - nf):
        p = a["grp_par"][g]
        qd[nf + g] = constrained_velocity(int(p[0]), p[1], p[2], p[3], -dt, dt)
    q = np.zeros(n)
    beta = float(model.rayleigh_beta)
    a_filt = velocity_filter_gain(model.damping_cutoff, dt)
    vf, w, p_mom = qd.copy(), q + beta * qd, rs.M @ qd
    ns = a["slave_node"].size
    rec = np.full((n_int, N_REC), np.nan)
    sens_v = np.full((n_int, a["sens_node"].size, 2), np.nan)
    contact = np.full((n_int, a["master_ptr"].size - 1, 5), np.nan)
    gs_tol = settings.gs_tolerance * shortest_master_segment(a["X"], nb, a["master_ptr"], a["master_nodes"],
                                                             a["slave_node"], a["slave_pair"])
    bufs = [np.zeros(n) for _ in range(4)]
    status, _ = run_reduced_steps(
        0, n_int * n_sub, dt, float(model.rayleigh_alpha), beta, a_filt, n_sub, nb, nf,
        r["kc"], r["cidx"], r["kdiag"], r["minv_ff"], r["b_fg"], r["m_g"], r["m"], a["grp_par"], np.zeros((n - nf, 2)),
        a["g_react"], a["X"], a["slave_node"], a["slave_pair"], a["master_ptr"], a["master_nodes"], a["pair_sign"],
        a["pair_par"], a["law_tab"], a["s_area"], a["minv_c"], r["wmat"], a["seg"].copy(), np.zeros((ns, N_GEO)),
        np.zeros((ns, 2)), np.zeros(ns, dtype=np.int64), settings.gs_max_iterations, gs_tol,
        np.ascontiguousarray(fric.mu), float(fric.rate), np.zeros(ns), np.zeros((a["cnodes"].size, N_CNODE)),
        a["cnode_slot"], a["cnodes"], a["sens_node"], a["sens_dir"], q, qd, w, vf, bufs[0], p_mom, bufs[1], bufs[2],
        np.zeros(r["cidx"].size), np.zeros(r["cidx"].size), np.zeros(2 * nb), np.zeros(N_ACC), np.zeros(2), rec,
        sens_v, contact, RUNAWAY_FACTOR, np.zeros(2, dtype=np.int64))
    assert status == OK
    return rec, sens_v, contact
