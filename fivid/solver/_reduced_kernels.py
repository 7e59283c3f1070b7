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
with the boundary block of the inverse mass ``W = Phi_b Phi_b^T`` (:func:`delassus_contact_solve`: the projected
Gauss-Seidel on the Delassus operator ``G W G^T`` of the slaves in or near contact, with exact steps for the
states it finds); the contact impulse ``c`` then moves the modes by ``dt Phi_b^T c``. ``qdb`` is one product per
step, ``qb`` follows from it (``qb' = qb + dt qdb'``, as ``q' = q + dt qd'``) and is recomputed as ``Phi_b q`` at
the start of every output interval. The sensors are read from ``qb``, ``qdb``.

Nothing is allocated inside the time loop.
"""

import math

import numpy as np

from fivid.contact._kernels import rigid_geometry
from fivid.contact._layout_kernels import (
    CNODE_V_STEP, GEO_IDLE, GEO_INSIDE, GEO_N0, GEO_N1, GEO_NX, GEO_NY, GEO_PENETRATION, GEO_SURFACE_VELOCITY,
    GEO_TX, GEO_TY, LAW, LAW_RIGID, MASTER, MASTER_EDGE, STRIBECK_VELOCITY, SURFACE_B,
    SURFACE_X, SURFACE_Y, VISCOUS,
)
from fivid.friction._curve_kernels import friction_now
from fivid.solver._contact_kernels import (
    CANDIDATE_MARGIN,
    _edge_gap,
    _multiplier_update,
    _rigid_a,
    _segment_nodes,
    _slave_geometry,
    contact_work,
)
from fivid.solver._kernels import GS_CAPPED, GS_MAX, GS_SWEEPS, OK, kernel, reassociating_kernel
from fivid.solver._loop_kernels import add_step_work, finish_record, group_velocities, start_record

#: exact steps (:func:`_exact_multipliers`) the Delassus solve may take per pass between its sweeps
EXACT_STEPS = 3

#: the most closed slaves an exact step solves for: its elimination costs ``(2c)^3 / 3``, a sweep ``O(c m)``, so
#: beyond this the sweeps alone are cheaper (a rough pair's hundreds of closed slaves)
EXACT_MAX_CLOSED = 48

__all__ = ["modal_product", "delassus_contact_solve", "contact_impulse", "group_reactions", "damped_displacement",
           "run_modal_steps"]


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


@reassociating_kernel
def _boundary_step(phib, qd, qb, qdb, dt):
    """``qdb = Phi_b qd[:nf]`` and ``qb += dt qdb``: the boundary motion of a central-difference step from the
    previous step's ``qb`` (``q' = q + dt qd'`` holds for the modes, so for ``Phi_b q``), one product instead of
    :func:`_boundary_motion`'s two. Four rows per pass, each modal velocity loaded once for the four
    (reassociated: the loop vectorises, each row's sum in the order of a one-row loop, so the values are the
    one-row loop's bit for bit; the fine rig's 92 x 268 block measured 0.75 times its time, same run)."""
    nr = phib.shape[0]
    j = 0
    while j + 4 <= nr:
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        s3 = 0.0
        for i in range(phib.shape[1]):
            x = qd[i]
            s0 += phib[j, i] * x
            s1 += phib[j + 1, i] * x
            s2 += phib[j + 2, i] * x
            s3 += phib[j + 3, i] * x
        qdb[j] = s0
        qdb[j + 1] = s1
        qdb[j + 2] = s2
        qdb[j + 3] = s3
        j += 4
    for r in range(j, nr):  # the last rows (fewer than four), one at a time
        s = 0.0
        for i in range(phib.shape[1]):
            s += phib[r, i] * qd[i]
        qdb[r] = s
    for r in range(nr):
        qb[r] += dt * qdb[r]


@kernel
def _modal_impulse(phib, cimp, gimp, rows):
    """``gimp = Phi_b^T cimp`` over the nonzero entries of ``cimp`` (the nodes in contact; their rows into the work
    array ``rows``, length ``2 nb``), added row by row in ascending order as a one-row loop would, four rows per
    pass over ``gimp`` (each entry loaded and stored once for the four: the same operations in the same order,
    so the same values bit for bit)."""
    nz = 0
    for j in range(phib.shape[0]):
        if cimp[j] != 0.0:
            rows[nz] = j
            nz += 1
    for i in range(phib.shape[1]):
        gimp[i] = 0.0
    k = 0
    while k + 4 <= nz:
        j0 = rows[k]
        j1 = rows[k + 1]
        j2 = rows[k + 2]
        j3 = rows[k + 3]
        c0 = cimp[j0]
        c1 = cimp[j1]
        c2 = cimp[j2]
        c3 = cimp[j3]
        for i in range(phib.shape[1]):
            g = gimp[i] + phib[j0, i] * c0
            g = g + phib[j1, i] * c1
            g = g + phib[j2, i] * c2
            gimp[i] = g + phib[j3, i] * c3
        k += 4
    for r in range(k, nz):
        j = rows[r]
        c = cimp[j]
        for i in range(phib.shape[1]):
            gimp[i] += phib[j, i] * c


@kernel
def _move_relative(rel, cmat, m, j, dt, fx, fy):
    """The active slaves' relative positions and velocities ``rel[:m]`` after a force increment ``(fx, fy)`` [N] on
    active slave ``j`` over the step: ``+ dt^2 C_ij f`` and ``+ dt C_ij f``."""
    for i in range(m):
        dx = cmat[i, j, 0] * fx + cmat[i, j, 1] * fy
        dy = cmat[i, j, 2] * fx + cmat[i, j, 3] * fy
        rel[i, 0] += dt * dt * dx
        rel[i, 1] += dt * dt * dy
        rel[i, 2] += dt * dx
        rel[i, 3] += dt * dy


@kernel
def _delassus_column(nb, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_par, seg, geo, act, m, j, cmat,
                     resp):
    """Slave ``j``'s column of the active slaves' Delassus operator. ``resp[j]`` (2, 2 nb): the boundary dofs'
    inverse-mass response ``W G_j^T`` to a unit force along x (row 0) and y (row 1) on slave ``j`` applied as the
    contact applies it (``-N0``, ``-N1`` times it on its master nodes); ``cmat[i, j]`` (xx, xy, yx, yy)
    ``= G_i W G_j^T`` [kg-1], the response of active slave ``i``'s relative motion ``s - N0 a - N1 b`` to it, for
    every active ``i``, and ``cmat[j, i]`` its transpose (``W`` symmetric). Computed when slave ``j`` is first
    updated in a pass; ``cmat[j, j, 0] > 0`` marks it done (a diagonal block of a positive definite ``W`` is)."""
    sj, aj, bj = _segment_nodes(act[j], slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
    n0 = geo[act[j], GEO_N0]
    n1 = geo[act[j], GEO_N1]
    rx = resp[j, 0]
    ry = resp[j, 1]
    for r in range(wmat.shape[0]):
        rx[r] = wmat[sj, r] - n0 * wmat[aj, r] - n1 * wmat[bj, r]
        ry[r] = wmat[sj + nb, r] - n0 * wmat[aj + nb, r] - n1 * wmat[bj + nb, r]
    for i in range(m):
        k = act[i]
        sk, ak, bk = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
        m0 = geo[k, GEO_N0]
        m1 = geo[k, GEO_N1]
        cxx = rx[sk] - m0 * rx[ak] - m1 * rx[bk]
        cxy = ry[sk] - m0 * ry[ak] - m1 * ry[bk]
        cyx = rx[sk + nb] - m0 * rx[ak + nb] - m1 * rx[bk + nb]
        cyy = ry[sk + nb] - m0 * ry[ak + nb] - m1 * ry[bk + nb]
        cmat[i, j, 0] = cxx
        cmat[i, j, 1] = cxy
        cmat[i, j, 2] = cyx
        cmat[i, j, 3] = cyy
        cmat[j, i, 0] = cxx
        cmat[j, i, 1] = cyx
        cmat[j, i, 2] = cxy
        cmat[j, i, 3] = cyy


@kernel
def _active_set(X, u, v, nb, dt, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_par, seg, geo, lam,
                applied, act, cmat, resp, rel):
    """The slaves that take part in the sweeps (facing their master, not idle) into ``act[:m]``, and their relative
    positions and velocities ``rel[i] = (x, y, vx, vy)`` of ``s - N0 a - N1 b`` in the configuration ``u``, ``v``
    moved by the multipliers not applied to it yet (``lam - applied``); the Delassus columns of those slaves
    (:func:`_delassus_column`), the others marked not computed. Returns ``m``."""
    m = 0
    for k in range(slave_node.shape[0]):
        if geo[k, GEO_INSIDE] != 0.0 and geo[k, GEO_IDLE] == 0.0:
            act[m] = k
            m += 1
    for i in range(m):
        k = act[i]
        sk, ak, bk = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
        n0 = geo[k, GEO_N0]
        n1 = geo[k, GEO_N1]
        rel[i, 0] = X[sk] + u[sk] - n0 * (X[ak] + u[ak]) - n1 * (X[bk] + u[bk])
        rel[i, 1] = X[sk + nb] + u[sk + nb] - n0 * (X[ak + nb] + u[ak + nb]) - n1 * (X[bk + nb] + u[bk + nb])
        rel[i, 2] = v[sk] - n0 * v[ak] - n1 * v[bk]
        rel[i, 3] = v[sk + nb] - n0 * v[ak + nb] - n1 * v[bk + nb]
        cmat[i, i, 0] = 0.0
    for j in range(m):
        k = act[j]
        dn = lam[k, 0] - applied[k, 0]
        dtn = lam[k, 1] - applied[k, 1]
        if dn != 0.0 or dtn != 0.0:
            _delassus_column(nb, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_par, seg, geo, act, m, j,
                             cmat, resp)
            _move_relative(rel, cmat, m, j, dt, dn * geo[k, GEO_NX] + dtn * geo[k, GEO_TX],
                           dn * geo[k, GEO_NY] + dtn * geo[k, GEO_TY])
    return m


@kernel
def _delassus_sweep(X, nb, dt, t_new, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_par, law_tab,
                    s_area, seg, geo, lam, cstate, mu, act, m, cmat, resp, rel):
    """One projected Gauss-Seidel sweep over the active slaves ``act[:m]``: the update of
    :func:`fivid.solver._contact_kernels.contact_solve` (same laws, same order, same convergence measure), with each
    slave's gap and relative velocity read from ``rel`` and each increment moving ``rel`` through the Delassus
    column (``O(m)``) instead of every boundary dof through ``W`` (``O(nb)``). An open slave (no force) whose gap is
    not closed keeps no force whatever its compliance: it is passed without its column. Returns the largest
    displacement [m] an increment moved a node pair by."""
    change = 0.0
    for i in range(m):
        k = act[i]
        p = slave_pair[k]
        nx = geo[k, GEO_NX]
        ny = geo[k, GEO_NY]
        tx = geo[k, GEO_TX]
        ty = geo[k, GEO_TY]
        if pair_par[p, MASTER] == MASTER_EDGE:
            g = rel[i, 0] * nx + rel[i, 1] * ny
        else:  # rigid master: rel holds the slave's own position
            sn = slave_node[k]
            g = rigid_geometry(int(pair_par[p, MASTER]), pair_par[p, SURFACE_X], pair_par[p, SURFACE_Y],
                               _rigid_a(pair_par[p], t_new), pair_par[p, SURFACE_B], 0.0, 0.0, X[sn], X[sn + nb],
                               rel[i, 0], rel[i, 1])[0]
        ln = lam[k, 0]
        rigid = pair_par[p, LAW] == LAW_RIGID
        if ln == 0.0 and g >= 0.0:  # both laws give no force at no penetration; lam_t is 0 with lam_n
            cstate[k] = 0
            geo[k, GEO_PENETRATION] = 0.0 if rigid else -g
            continue
        if cmat[i, i, 0] == 0.0:
            _delassus_column(nb, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_par, seg, geo, act, m,
                             i, cmat, resp)
        lt = lam[k, 1]
        ln_new, lt_new, state, wn, wt = _multiplier_update(pair_par[p], law_tab[p], s_area[k], mu[k], dt, g, ln, lt,
                                                           rel[i, 2], rel[i, 3], nx, ny, tx, ty,
                                                           geo[k, GEO_SURFACE_VELOCITY], cmat[i, i, 0], cmat[i, i, 1],
                                                           cmat[i, i, 3])
        dn = ln_new - ln
        dtn = lt_new - lt
        if dn != 0.0 or dtn != 0.0:
            _move_relative(rel, cmat, m, i, dt, dn * nx + dtn * tx, dn * ny + dtn * ty)
        lam[k, 0] = ln_new
        lam[k, 1] = lt_new
        cstate[k] = state
        geo[k, GEO_PENETRATION] = 0.0 if rigid else -(g + dn * wn)
        change = max(change, abs(dn) * wn, abs(dtn) * wt)
    return change


@kernel
def _exact_multipliers(dt, slave_pair, pair_par, geo, lam, cstate, mu, act, m, cmat, rel, closed, dmat):
    """One exact step of the sweeps: the multipliers that close every closed slave's gap with the states the last
    sweep left (stick: no relative tangential increment either; slip: ``lam_t = sign(lam_t) mu lam_n``) -- the
    equations the Gauss-Seidel update satisfies at its fixed point -- by Gaussian elimination (partial pivoting)
    on the ``2c x 2c`` system the Delassus blocks ``cmat`` give for the ``c`` closed slaves; ``rel`` and ``lam``
    moved to it. Only for rigid normal laws on master edges with a constant kinetic coefficient (the equations are
    then linear); skipped, returning False, otherwise, when no slave or more than :data:`EXACT_MAX_CLOSED` are
    closed, when the system is singular or when
    it would pull a slave (``lam_n < 0``): the sweeps go on from where they were and decide (they verify the states
    in every case). ``closed`` (ns,) int and ``dmat`` (2 c_max, 2 c_max + 1), ``c_max = min(ns,
    EXACT_MAX_CLOSED)``, are work arrays."""
    c = 0
    for i in range(m):
        k = act[i]
        if cstate[k] == 0:
            continue
        p = slave_pair[k]
        if (pair_par[p, LAW] != LAW_RIGID or pair_par[p, MASTER] != MASTER_EDGE or pair_par[p, STRIBECK_VELOCITY] > 0.0
                or pair_par[p, VISCOUS] != 0.0):
            return False
        closed[c] = i
        c += 1
    if c == 0 or c > EXACT_MAX_CLOSED:
        return False
    nn = 2 * c
    dt2 = dt * dt
    for a in range(c):
        i = closed[a]
        k = act[i]
        nx = geo[k, GEO_NX]
        ny = geo[k, GEO_NY]
        tx = geo[k, GEO_TX]
        ty = geo[k, GEO_TY]
        stick = cstate[k] == 1
        for b in range(c):
            j = closed[b]
            kj = act[j]
            cnx = cmat[i, j, 0] * geo[kj, GEO_NX] + cmat[i, j, 1] * geo[kj, GEO_NY]
            cny = cmat[i, j, 2] * geo[kj, GEO_NX] + cmat[i, j, 3] * geo[kj, GEO_NY]
            ctx = cmat[i, j, 0] * geo[kj, GEO_TX] + cmat[i, j, 1] * geo[kj, GEO_TY]
            cty = cmat[i, j, 2] * geo[kj, GEO_TX] + cmat[i, j, 3] * geo[kj, GEO_TY]
            dmat[2 * a, 2 * b] = dt2 * (nx * cnx + ny * cny)
            dmat[2 * a, 2 * b + 1] = dt2 * (nx * ctx + ny * cty)
            dmat[2 * a + 1, 2 * b] = dt2 * (tx * cnx + ty * cny) if stick else 0.0
            dmat[2 * a + 1, 2 * b + 1] = dt2 * (tx * ctx + ty * cty) if stick else 0.0
        dmat[2 * a, nn] = -(rel[i, 0] * nx + rel[i, 1] * ny)
        if stick:
            dmat[2 * a + 1, nn] = -dt * (rel[i, 2] * tx + rel[i, 3] * ty - geo[k, GEO_SURFACE_VELOCITY])
        else:
            sgn = 1.0 if lam[k, 1] > 0.0 else -1.0
            dmat[2 * a + 1, 2 * a] = -sgn * mu[k]
            dmat[2 * a + 1, 2 * a + 1] = 1.0
            dmat[2 * a + 1, nn] = sgn * mu[k] * lam[k, 0] - lam[k, 1]
    for col in range(nn):  # forward elimination, partial pivoting
        piv = col
        for r in range(col + 1, nn):
            if abs(dmat[r, col]) > abs(dmat[piv, col]):
                piv = r
        if not abs(dmat[piv, col]) > 0.0:
            return False
        if piv != col:
            for q in range(col, nn + 1):
                dmat[col, q], dmat[piv, q] = dmat[piv, q], dmat[col, q]
        for r in range(col + 1, nn):
            f = dmat[r, col] / dmat[col, col]
            if f != 0.0:
                for q in range(col, nn + 1):
                    dmat[r, q] -= f * dmat[col, q]
    for r in range(nn - 1, -1, -1):  # back substitution: the increments into the right-hand side
        s = dmat[r, nn]
        for q in range(r + 1, nn):
            s -= dmat[r, q] * dmat[q, nn]
        dmat[r, nn] = s / dmat[r, r]
    for a in range(c):
        if lam[act[closed[a]], 0] + dmat[2 * a, nn] < 0.0:
            return False
    for a in range(c):
        i = closed[a]
        k = act[i]
        dn = dmat[2 * a, nn]
        dtn = dmat[2 * a + 1, nn]
        lam[k, 0] += dn
        lam[k, 1] += dtn
        _move_relative(rel, cmat, m, i, dt, dn * geo[k, GEO_NX] + dtn * geo[k, GEO_TX],
                       dn * geo[k, GEO_NY] + dtn * geo[k, GEO_TY])
    return True


@reassociating_kernel
def _add_response(u, v, dt, rx, ry, fx, fy):
    """``u += dt^2 (rx fx + ry fy)``, ``v += dt (rx fx + ry fy)``: a force ``(fx, fy)`` [N] over one step through
    the inverse-mass responses ``rx``, ``ry`` [kg-1]."""
    for r in range(rx.shape[0]):
        s = rx[r] * fx + ry[r] * fy
        u[r] += dt * dt * s
        v[r] += dt * s


@kernel
def delassus_contact_solve(X, u, v, nb, dt, t_new, wmat, slave_node, slave_pair, master_ptr, master_nodes,
                           pair_sign, pair_par, law_tab, s_area, seg, geo, lam, cstate, mu_tab, mu_rate, mu_now,
                           max_iter, tol, acc, act, cmat, resp, rel, applied, closed, dmat):
    """The contact correction of a reduced system (dense boundary inverse mass ``wmat``): the projected
    Gauss-Seidel of :func:`fivid.solver._contact_kernels.contact_step` (friction now, geometry, warm start, sweeps
    to ``tol`` [m], statistics in ``acc``) on the Delassus operator of the slaves that take part.

    A contact increment on one slave moves every boundary dof through ``W``: the shared solve pays ``O(nb)`` per
    update (the dense rows of ``W``) and sweeps every slave facing its master. Here the sweeps run over the active
    slaves only -- those with a force from the previous step or a predicted gap within
    :data:`fivid.solver._contact_kernels.CANDIDATE_MARGIN` of their segment's length (the others idle, as on the
    lumped path) -- and on their relative motion alone: the 2x2 blocks ``C_ij = G_i W G_j^T`` of the slaves that
    get a force (:func:`_delassus_column`, ``O(nb + m)`` each, once per pass) carry an increment on slave ``j`` to
    every active slave's gap and relative velocity in ``O(m)``; an open slave whose gap stays open costs ``O(1)``
    per sweep. The converged multipliers then move ``u``, ``v`` once (``dt^2 W G^T lam``, ``dt W G^T lam``). An idle
    slave whose gap the corrections closed (measured after the pass) joins the active set and the sweeps resume
    from the multipliers reached (another pass). The update and the convergence measure are the shared solve's;
    between sweeps that have not converged, up to :data:`EXACT_STEPS` exact steps (:func:`_exact_multipliers`)
    jump to the multipliers of the states the last sweep found, which the next sweep then verifies (on the
    default rig 1.8 sweeps per step instead of 5.9). Both solves converge to the same multipliers; the shared
    one stops within its tolerance of them, this one usually at them (the records of a run differ by the
    Gauss-Seidel residual, ~6e-7 of their largest values on the coarse rig).

    Work arrays (``ns`` slaves, ``nb`` boundary nodes): ``act`` (ns,) int, ``cmat`` (ns, ns, 4), ``resp``
    (ns, 2, 2 nb), ``rel`` (ns, 4), ``applied`` (ns, 2), ``closed`` (ns,) int, ``dmat`` (2 c_max, 2 c_max + 1)
    (:func:`_exact_multipliers`).
    """
    ns = slave_node.shape[0]
    friction_now(mu_tab, mu_rate, t_new, mu_now)
    _slave_geometry(X, u, nb, t_new, slave_node, slave_pair, master_ptr, master_nodes, pair_sign, pair_par, seg, geo,
                    lam, CANDIDATE_MARGIN, math.inf)
    # warm start: the previous step's multipliers of the slaves still facing their master, the others released
    for k in range(ns):
        applied[k, 0] = 0.0
        applied[k, 1] = 0.0
        if geo[k, GEO_INSIDE] == 0.0 or lam[k, 0] <= 0.0:
            lam[k, 0] = 0.0
            lam[k, 1] = 0.0
            cstate[k] = 0
    sweeps = 0
    capped = False
    again = True
    while again:
        m = _active_set(X, u, v, nb, dt, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_par, seg, geo,
                        lam, applied, act, cmat, resp, rel)
        exact = 0
        for it in range(max_iter):
            sweeps += 1
            change = _delassus_sweep(X, nb, dt, t_new, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_par,
                                     law_tab, s_area, seg, geo, lam, cstate, mu_now, act, m, cmat, resp, rel)
            if change <= tol:
                break
            capped = capped or it == max_iter - 1
            if exact < EXACT_STEPS and _exact_multipliers(dt, slave_pair, pair_par, geo, lam, cstate, mu_now, act, m,
                                                          cmat, rel, closed, dmat):
                exact += 1
        # the pass's increments on the boundary dofs: dt^2 W G^T dlam, dt W G^T dlam (W G^T in resp)
        for i in range(m):
            k = act[i]
            dn = lam[k, 0] - applied[k, 0]
            dtn = lam[k, 1] - applied[k, 1]
            if dn != 0.0 or dtn != 0.0:
                fx = dn * geo[k, GEO_NX] + dtn * geo[k, GEO_TX]
                fy = dn * geo[k, GEO_NY] + dtn * geo[k, GEO_TY]
                _add_response(u, v, dt, resp[i, 0], resp[i, 1], fx, fy)
            applied[k, 0] = lam[k, 0]
            applied[k, 1] = lam[k, 1]
        # the idle slaves (deformable masters only) in the corrected configuration: a closed gap joins the sweeps
        again = False
        for k in range(ns):
            if geo[k, GEO_INSIDE] != 0.0 and geo[k, GEO_IDLE] != 0.0:
                sn, a, b = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
                if _edge_gap(X, u, nb, sn, a, b, geo[k, GEO_N0], geo[k, GEO_N1], geo[k, GEO_NX], geo[k, GEO_NY]) <= 0.0:
                    geo[k, GEO_IDLE] = 0.0
                    again = True
    acc[GS_SWEEPS] += sweeps
    acc[GS_MAX] = max(acc[GS_MAX], sweeps)
    if capped:
        acc[GS_CAPPED] += 1.0


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
    act = np.zeros(ns, dtype=np.int64)  # the Delassus contact solve's work arrays
    cmat = np.zeros((ns, ns, 4))
    resp = np.zeros((ns, 2, 2 * nb))
    rel = np.zeros((ns, 4))
    applied = np.zeros((ns, 2))
    closed = np.zeros(ns, dtype=np.int64)
    dmat = np.zeros((2 * min(ns, EXACT_MAX_CLOSED), 2 * min(ns, EXACT_MAX_CLOSED) + 1))
    nz_rows = np.zeros(2 * nb, dtype=np.int64)  # the contact impulse's nonzero boundary rows (_modal_impulse)
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
            if sub == 0:  # Phi_b q afresh once per output interval: no round-off drift between records
                _boundary_motion(phib, q, qd, qb, qdb)
            else:
                _boundary_step(phib, qd, qb, qdb, dt)
            if ns > 0:
                delassus_contact_solve(X, qb, qdb, nb, dt, t + dt, wmat, slave_node, slave_pair, master_ptr,
                                       master_nodes, pair_sign, pair_par, law_tab, s_area, seg, geo, lam_c, cstate,
                                       mu_tab, mu_rate, mu_now, gs_max_iter, gs_tol, acc, act, cmat, resp, rel, applied,
                                       closed, dmat)
                contact_impulse(cimp, nb, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par, geo, lam_c,
                                cstate)
                _modal_impulse(phib, cimp, gimp, nz_rows)
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
