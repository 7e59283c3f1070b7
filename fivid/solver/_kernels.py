"""Numba kernels of the explicit contact solver: arrays and scalars only (layer L0).

Data layout (prepared by :mod:`fivid.solver.stencil` and the driver; float64 / int64, C-contiguous):

- dof vectors ``u, v, w, f`` have ``2*npd`` entries: the x components of all nodes, then the y
  components (structure of arrays, so the stencil loops vectorise); node ``p`` sits at index
  ``pad + p`` of each half, with ``pad`` zero entries on both sides so that every 3x3 neighbour index of
  every node is in bounds. Nodes are passed to kernels by their x-index ``pad + p`` (y-index
  ``+ npd``), springs and constraints by flat dof index.
- ``w = u + beta*v`` is kept up to date by the update pass, so one stencil pass gives
  ``f = K (u + beta v)`` (stiffness-proportional damping folded in).
- Stencil coefficient ``((dj+1)*3 + (di+1))*4 + 2*a + b`` couples dof ``a`` of node ``p`` with dof ``b`` of
  node ``p + dj*stride + di``; in a uniform block the interior nodes share one set and so do the nodes of
  each edge (corners excluded): five patches; a mapped block is one patch with per-node coefficients
  (component-major, ``c_map[k, node]``); block corners and the seam columns of periodic rings are listed
  node by node with explicit neighbour indices.
- pressure loads: dofs ``ld_dof`` carry the full nodal forces ``ld_force``, ramped per load
  ``ld_grp`` with ``ld_par[g] = (t_start, ramp_time)`` by the smooth ramp, evaluated at the step start.
- Hot loops index with unsigned integers: numba then emits no negative-index wraparound, which
  otherwise blocks vectorisation (measured: 6x slower stencil).
- constrained dofs ``con_dof`` belong to motion groups ``con_grp``; ``grp_par[g] = (kind, amplitude, t_start,
  ramp_time)`` with kind 0 fixed, 1 displacement ramp, 2 velocity ramp (one velocity evaluation per group
  and step, not per dof); the smooth ramp is ``r(s) = s - sin(2 pi s)/(2 pi)``.

Nothing is allocated inside the time loop.
"""

import math

import numpy as np
from numba import njit, uint64

from fivid.contact._kernels import (
    LAW_RIGID,
    MASTER_EDGE,
    friction_coefficient,
    normal_energy,
    normal_pressure,
    rigid_geometry,
    surface_ramp,
)

__all__ = [
    "ramp",
    "constrained_velocity",
    "block_forces",
    "spring_forces",
    "contact_solve",
    "run_steps",
]

# energy accumulator slots (acc array)
W_INT = 0  # work of internal (stencil + spring/dashpot) forces: strain energy + stiffness-damping loss
D_ALPHA = 1  # mass-proportional damping dissipation
W_EXT = 2  # work of the constraint reactions (imposed motions)
W_CN = 3  # work of the normal contact forces (<= 0: impact losses)
W_CT = 4  # work of the tangential contact forces (<= 0: friction dissipation)
GS_SWEEPS = 5  # total Gauss-Seidel sweeps
GS_MAX = 6  # largest number of sweeps in one step
GS_CAPPED = 7  # steps that reached the sweep limit
W_LOAD = 8  # work of the applied (pressure) loads
W_DRIVE = 9  # work of the rigid masters' surface motion on the slaves (rotation / belt drive)
N_ACC = 10

# output record columns (rec array, one row per output interval)
R_FT = 0  # reaction, tangential sum, interval average [N]
R_FN = 1  # reaction, normal sum, interval average [N]
R_KE = 2  # kinetic energy at the interval end [J]
R_U = 3  # strain energy at the interval end [J]
R_WINT = 4
R_DA = 5
R_WEXT = 6
R_WCN = 7
R_WCT = 8
R_WLOAD = 9
R_WDRIVE = 10  # work of the moving rigid surfaces [J]
R_EPEN = 11  # energy stored in the compliant contact laws at the interval end [J]
N_REC = 12

# status codes
OK = 0
NAN = 1
RUNAWAY = 2


@njit(cache=True)
def ramp(s):
    """Smooth ramp ``r(s)`` from 0 (s <= 0) to 1 (s >= 1), ``r' = 1 - cos(2 pi s)`` vanishing at both ends."""
    if s <= 0.0:
        return 0.0
    if s >= 1.0:
        return 1.0
    return s - math.sin(2.0 * math.pi * s) / (2.0 * math.pi)


@njit(cache=True)
def constrained_velocity(kind, amp, t0, tr, t, dt):
    """Velocity of a constrained dof over the step ``[t, t + dt]`` [m s-1] (half-step value)."""
    if kind == 0:
        return 0.0
    if kind == 1:  # displacement history: exact increment over the step
        d1 = amp * (ramp((t + dt - t0) / tr) if tr > 0.0 else (1.0 if t + dt >= t0 else 0.0))
        d0 = amp * (ramp((t - t0) / tr) if tr > 0.0 else (1.0 if t >= t0 else 0.0))
        return (d1 - d0) / dt
    th = t + 0.5 * dt
    if tr > 0.0:
        return amp * ramp((th - t0) / tr)
    return amp if th >= t0 else 0.0


@njit(cache=True, fastmath={"contract"})
def _uniform_component(wx, wy, fo, c, a, first, ncols, nrows, stride):
    """Force component ``a`` on a rectangular patch of nodes sharing one stencil ``c`` (unsigned indices: no
    negative-index wraparound, so the row loop vectorises)."""
    st = uint64(stride)
    one = uint64(1)
    k = 2 * a
    c0 = c[k]
    c1 = c[k + 1]
    c4 = c[k + 4]
    c5 = c[k + 5]
    c8 = c[k + 8]
    c9 = c[k + 9]
    c12 = c[k + 12]
    c13 = c[k + 13]
    c16 = c[k + 16]
    c17 = c[k + 17]
    c20 = c[k + 20]
    c21 = c[k + 21]
    c24 = c[k + 24]
    c25 = c[k + 25]
    c28 = c[k + 28]
    c29 = c[k + 29]
    c32 = c[k + 32]
    c33 = c[k + 33]
    for j in range(nrows):
        b = uint64(first + j * stride)
        for i in range(ncols):
            m = b + uint64(i)
            s = m - st
            n = m + st
            fo[m] = (c0 * wx[s - one] + c1 * wy[s - one] + c4 * wx[s] + c5 * wy[s] + c8 * wx[s + one]
                     + c9 * wy[s + one] + c12 * wx[m - one] + c13 * wy[m - one] + c16 * wx[m] + c17 * wy[m]
                     + c20 * wx[m + one] + c21 * wy[m + one] + c24 * wx[n - one] + c25 * wy[n - one]
                     + c28 * wx[n] + c29 * wy[n] + c32 * wx[n + one] + c33 * wy[n + one])


@njit(cache=True, fastmath={"contract"})
def _rect_component(wx, wy, fo, c, a, first, ncols, nrows, stride):
    """As :func:`_uniform_component` for a patch of rectangular elements, whose cross-coupling (xy) with the
    axis neighbours and the node itself vanishes: 13 terms instead of 18."""
    st = uint64(stride)
    one = uint64(1)
    # own-component coefficient of neighbour position p (0..8, row-major from (-1, -1)): c[4p + 3a];
    # cross-component: c[4p + a + 1], non-zero only at the four corners
    s0 = c[3 * a]
    s1 = c[4 + 3 * a]
    s2 = c[8 + 3 * a]
    s3 = c[12 + 3 * a]
    s4 = c[16 + 3 * a]
    s5 = c[20 + 3 * a]
    s6 = c[24 + 3 * a]
    s7 = c[28 + 3 * a]
    s8 = c[32 + 3 * a]
    x0 = c[a + 1]
    x2 = c[8 + a + 1]
    x6 = c[24 + a + 1]
    x8 = c[32 + a + 1]
    if a == 0:
        ws = wx
        wo = wy
    else:
        ws = wy
        wo = wx
    for j in range(nrows):
        b = uint64(first + j * stride)
        for i in range(ncols):
            m = b + uint64(i)
            s = m - st
            n = m + st
            fo[m] = (s0 * ws[s - one] + x0 * wo[s - one] + s1 * ws[s] + s2 * ws[s + one] + x2 * wo[s + one]
                     + s3 * ws[m - one] + s4 * ws[m] + s5 * ws[m + one]
                     + s6 * ws[n - one] + x6 * wo[n - one] + s7 * ws[n] + s8 * ws[n + one] + x8 * wo[n + one])


@njit(cache=True, fastmath={"contract"})
def _mapped_component(wx, wy, fo, cm, col0, a, first, ncols, nrows, stride):
    """Force component ``a`` on a patch of nodes with per-node stencils ``cm[:, col0 + row*ncols + column]``.

    Component-major storage: each coefficient is contiguous over a row of nodes; taking the 18 row slices
    first (views, no copy) lets the row loop vectorise (indexing ``cm[k, q]`` inside it measured 2.8x slower:
    the coefficient loads were not recognised as unit-stride)."""
    st = uint64(stride)
    one = uint64(1)
    k = 2 * a
    for j in range(nrows):
        b = uint64(first + j * stride)
        q0 = col0 + j * ncols
        q1 = q0 + ncols
        c0 = cm[k, q0:q1]
        c1 = cm[k + 1, q0:q1]
        c4 = cm[k + 4, q0:q1]
        c5 = cm[k + 5, q0:q1]
        c8 = cm[k + 8, q0:q1]
        c9 = cm[k + 9, q0:q1]
        c12 = cm[k + 12, q0:q1]
        c13 = cm[k + 13, q0:q1]
        c16 = cm[k + 16, q0:q1]
        c17 = cm[k + 17, q0:q1]
        c20 = cm[k + 20, q0:q1]
        c21 = cm[k + 21, q0:q1]
        c24 = cm[k + 24, q0:q1]
        c25 = cm[k + 25, q0:q1]
        c28 = cm[k + 28, q0:q1]
        c29 = cm[k + 29, q0:q1]
        c32 = cm[k + 32, q0:q1]
        c33 = cm[k + 33, q0:q1]
        for i in range(ncols):
            m = b + uint64(i)
            s = m - st
            n = m + st
            fo[m] = (c0[i] * wx[s - one] + c1[i] * wy[s - one] + c4[i] * wx[s] + c5[i] * wy[s]
                     + c8[i] * wx[s + one] + c9[i] * wy[s + one] + c12[i] * wx[m - one] + c13[i] * wy[m - one]
                     + c16[i] * wx[m] + c17[i] * wy[m] + c20[i] * wx[m + one] + c21[i] * wy[m + one]
                     + c24[i] * wx[n - one] + c25[i] * wy[n - one] + c28[i] * wx[n] + c29[i] * wy[n]
                     + c32[i] * wx[n + one] + c33[i] * wy[n + one])


@njit(cache=True, fastmath={"contract"})
def block_forces(w, f, npd, blocks, c_uni, c_map, lst_idx, lst_nbr, lst_coef):
    """``f = K_blocks w`` by the per-block 3x3 stencils (every node of every block is written).

    Parameters
    ----------
    w : ndarray (2*npd,)
        Generalised displacement ``u + beta v`` [m], x part then y part, node ``p`` at ``pad + p``.
    f : ndarray (2*npd,)
        Output forces [N] (same layout).
    npd : int
        Length of one component (nodes plus padding on both sides).
    blocks : int64 ndarray (n_patch, 6)
        Patches: ``first x-index, columns, rows, row stride, kind, coefficients``; kind 0: one shared stencil
        ``c_uni[coefficients]`` (18 terms per force), 1: the same for rectangular elements (the xy couplings
        with the axis neighbours vanish and are skipped: 13 terms), 2: per-node stencils
        ``c_map[:, coefficients + row*columns + column]``. Neighbours outside a block have zero coefficients
        (the padding keeps their indices in bounds).
    c_uni : ndarray (n_uniform, 36)
        Shared stencils [N m-1].
    c_map : ndarray (36, n_mapped)
        Per-node stencils of mapped patches [N m-1].
    lst_idx : int64 ndarray (n_list,)
        Listed nodes (block corners, seam columns of periodic rings): x-index.
    lst_nbr : int64 ndarray (n_list, 9)
        x-indices of their 3x3 neighbours, row-major from ``(-1, -1)``.
    lst_coef : ndarray (n_list, 36)
        Their stencils [N m-1].
    """
    wx = w[:npd]
    wy = w[npd:]
    fx = f[:npd]
    fy = f[npd:]
    for b in range(blocks.shape[0]):
        kind = blocks[b, 4]
        if kind == 2:
            _mapped_component(wx, wy, fx, c_map, blocks[b, 5], 0, blocks[b, 0], blocks[b, 1], blocks[b, 2],
                              blocks[b, 3])
            _mapped_component(wx, wy, fy, c_map, blocks[b, 5], 1, blocks[b, 0], blocks[b, 1], blocks[b, 2],
                              blocks[b, 3])
            continue
        c = c_uni[blocks[b, 5]]
        if kind == 1:
            _rect_component(wx, wy, fx, c, 0, blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3])
            _rect_component(wx, wy, fy, c, 1, blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3])
        else:
            _uniform_component(wx, wy, fx, c, 0, blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3])
            _uniform_component(wx, wy, fy, c, 1, blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3])
    for r in range(lst_idx.shape[0]):
        p = lst_idx[r]
        sx = 0.0
        sy = 0.0
        for e in range(9):
            q = lst_nbr[r, e]
            k = 4 * e
            ax = wx[q]
            ay = wy[q]
            sx += lst_coef[r, k] * ax + lst_coef[r, k + 1] * ay
            sy += lst_coef[r, k + 2] * ax + lst_coef[r, k + 3] * ay
        fx[p] = sx
        fy[p] = sy


@njit(cache=True)
def spring_forces(u, v, f, spr_dof, spr_kc, with_damping):
    """Add discrete spring (and dashpot) forces to ``f``; ``spr_dof[s] = (dof_a, dof_b or -1)``, ``spr_kc = (k, c)``."""
    for s in range(spr_dof.shape[0]):
        a = spr_dof[s, 0]
        b = spr_dof[s, 1]
        du = u[a]
        dv = v[a]
        if b >= 0:
            du -= u[b]
            dv -= v[b]
        fs = spr_kc[s, 0] * du
        if with_damping:
            fs += spr_kc[s, 1] * dv
        f[a] += fs
        if b >= 0:
            f[b] -= fs


@njit(cache=True)
def _locate(X, u, npd, sn, mnodes, m0, nseg, seg_k, sign):
    """Find the master segment under slave node ``sn`` starting from ``seg_k`` (local monotone search).

    Returns ``(segment, xi, nx, ny, tx, ty, inside)`` with the unit outward normal ``n`` and tangent ``t``.
    """
    xs = X[sn] + u[sn]
    ys = X[sn + npd] + u[sn + npd]
    s = min(max(seg_k, 0), nseg - 1)
    xi = 0.0
    ex = 0.0
    ey = 0.0
    for _ in range(nseg + 1):
        a = mnodes[m0 + s]
        bb = mnodes[m0 + s + 1]
        xa = X[a] + u[a]
        ya = X[a + npd] + u[a + npd]
        ex = X[bb] + u[bb] - xa
        ey = X[bb + npd] + u[bb + npd] - ya
        xi = ((xs - xa) * ex + (ys - ya) * ey) / (ex * ex + ey * ey)
        if xi < 0.0 and s > 0:
            s -= 1
        elif xi > 1.0 and s < nseg - 1:
            s += 1
        else:
            break
    L = math.sqrt(ex * ex + ey * ey)
    tx = ex / L
    ty = ey / L
    # a slave node at the very end of the master edge (edges meeting corner to corner) must not flicker
    # in and out of contact through round-off: accept 1e-6 of a segment beyond the ends, then clamp
    inside = -1e-6 <= xi <= 1.0 + 1e-6
    xi = min(max(xi, 0.0), 1.0)
    return s, xi, sign * ty, -sign * tx, tx, ty, inside


@njit(cache=True)
def _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par):
    """x-indices of slave ``k`` and of the two nodes of its current master segment (a rigid master has none:
    the slave itself is returned for both, with shape values 0, so the master terms vanish)."""
    p = slave_pair[k]
    if pair_par[p, 6] != MASTER_EDGE:
        return slave_node[k], slave_node[k], slave_node[k]
    return slave_node[k], master_nodes[master_ptr[p] + seg[k]], master_nodes[master_ptr[p] + seg[k] + 1]


@njit(cache=True)
def _apply_contact_force(u, v, npd, dt, minv_c, wmat, sn, a, b, n0, n1, fx, fy):
    """Correct position and velocity of slave ``sn`` by the contact force ``(fx, fy)`` [N] over one step and of
    the master nodes ``a``, ``b`` by ``-N0`` and ``-N1`` times it (zero inverse mass: constrained, not moved).

    ``wmat`` empty: the lumped inverse mass ``minv_c`` (diagonal). Otherwise ``wmat`` is the dense inverse mass
    of the contact dofs (a reduced system, :mod:`fivid.solver.reduced`): the force moves every dof of
    ``u[:wmat.shape[0]]`` by ``dt^2 W G^T f``."""
    dt2 = dt * dt
    if wmat.shape[0] > 0:
        for i in range(wmat.shape[0]):
            s = (wmat[sn, i] * fx + wmat[sn + npd, i] * fy - n0 * (wmat[a, i] * fx + wmat[a + npd, i] * fy)
                 - n1 * (wmat[b, i] * fx + wmat[b + npd, i] * fy))
            u[i] += dt2 * s
            v[i] += dt * s
        return
    u[sn] += dt2 * minv_c[sn] * fx
    v[sn] += dt * minv_c[sn] * fx
    u[sn + npd] += dt2 * minv_c[sn + npd] * fy
    v[sn + npd] += dt * minv_c[sn + npd] * fy
    u[a] -= dt2 * minv_c[a] * n0 * fx
    v[a] -= dt * minv_c[a] * n0 * fx
    u[a + npd] -= dt2 * minv_c[a + npd] * n0 * fy
    v[a + npd] -= dt * minv_c[a + npd] * n0 * fy
    u[b] -= dt2 * minv_c[b] * n1 * fx
    v[b] -= dt * minv_c[b] * n1 * fx
    u[b + npd] -= dt2 * minv_c[b + npd] * n1 * fy
    v[b + npd] -= dt * minv_c[b + npd] * n1 * fy


@njit(cache=True)
def _pair_compliance(minv_c, wmat, npd, sn, a, b, n0, n1):
    """``(cxx, cxy, cyy)`` [kg-1]: the inverse mass of the relative motion ``slave - (N0 a + N1 b)`` (2x2,
    symmetric); the lumped mass has no xy term, a reduced system's dense ``wmat`` has."""
    if wmat.shape[0] == 0:
        return (minv_c[sn] + n0 * n0 * minv_c[a] + n1 * n1 * minv_c[b], 0.0,
                minv_c[sn + npd] + n0 * n0 * minv_c[a + npd] + n1 * n1 * minv_c[b + npd])
    cxx = 0.0
    cxy = 0.0
    cyy = 0.0
    for i in range(3):
        pi = sn if i == 0 else (a if i == 1 else b)
        ci = 1.0 if i == 0 else (-n0 if i == 1 else -n1)
        for j in range(3):
            pj = sn if j == 0 else (a if j == 1 else b)
            cj = 1.0 if j == 0 else (-n0 if j == 1 else -n1)
            cxx += ci * cj * wmat[pi, pj]
            cxy += ci * cj * wmat[pi, pj + npd]
            cyy += ci * cj * wmat[pi + npd, pj + npd]
    return cxx, cxy, cyy


@njit(cache=True)
def _normal_update(kind, c, nexp, tab, area, g, ln, wn):
    """New normal multiplier [N] of a slave at gap ``g`` [m] carrying ``ln``: rigid, the multiplier that closes
    the gap; compliant laws, one Newton step on ``ln = A p(-g)`` with the gap's response ``wn`` [m N-1] to the
    multiplier (implicit in the contact force: the penalty spring does not lower the stable step)."""
    if kind == LAW_RIGID:
        ln_new = ln - g / wn if wn > 0.0 else ln
    else:
        p, dp = normal_pressure(kind, c, nexp, -g, tab)
        ln_new = ln + (area * p - ln) / (1.0 + area * dp * wn)
    if ln_new < 0.0:
        ln_new = 0.0
    return ln_new


@njit(cache=True)
def _tangential_update(lt, st, wt, ln_new, mu_k, par_p, dt):
    """New tangential multiplier [N] and state (1 stick, 2 slip) from the relative tangential increment ``st``
    [m] over the step: stick if the multiplier that cancels it stays within ``mu_s ln``, else slip with the
    kinetic curve ``mu(v)`` at the slip rate ``v`` that force leaves at the end of the step."""
    lt_stick = lt - st / wt if wt > 0.0 else lt
    cap = (mu_k + par_p[3]) * ln_new
    if -cap <= lt_stick <= cap:
        return lt_stick, 1
    sgn = 1.0 if lt_stick > 0.0 else -1.0
    mu = mu_k
    if par_p[4] > 0.0 or par_p[5] != 0.0:
        # the slip rate the sliding force leaves at the end of the step, v = (st + wt (lt_new - lt)) / dt, and
        # mu(v): a fixed point contracting by dt lam_n |mu'| / m_node per pass (~1e-2)
        for _ in range(4):
            v_slip = (st + wt * (sgn * mu * ln_new - lt)) / dt
            mu = friction_coefficient(mu_k, par_p[3], par_p[4], par_p[5], v_slip)
    return sgn * mu * ln_new, 2


@njit(cache=True)
def contact_solve(X, u, v, npd, dt, t_new, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes,
                  pair_sign, pair_par, law_tab, s_area, seg, geo, lam, cstate, mu, max_iter, tol):
    """Forward-increment Lagrange multipliers (Carpenter, Taylor & Katona 1991) for all slave nodes.

    On entry ``u, v`` are the predicted ``u*``, ``v*``; on exit they are corrected so that every active slave
    node obeys its pair's normal law (rigid: no penetration of its master; linear/power: the multiplier equals
    ``A p(d)`` at the corrected penetration ``d``, ``A`` its tributary area ``s_area``) and the tangential
    multiplier obeys Coulomb's law with static and kinetic coefficients (stick: zero relative tangential
    increment over the step while ``|lam_t| <= mu_s lam_n``; slip: ``|lam_t| = mu(v) lam_n``). Normal and
    tangential multipliers of all slave nodes are iterated together by projected Gauss-Seidel until the
    largest correction of a sweep moves no node pair by more than ``tol`` [m]. ``mu[k]`` is the kinetic
    coefficient of slave ``k`` now (``mu0 + mu_p(t)``); ``pair_par`` the pairs' law rows and ``law_tab`` their
    tables (:mod:`fivid.contact._kernels`); a rigid master (line, circle) moves its surface at the ramped speed at
    ``t_new`` [s], the end of the step. ``wmat`` empty: lumped inverse mass ``minv_c``; else the dense inverse
    mass of the contact dofs of a reduced system (:func:`_apply_contact_force`).

    Nodes are given by their x-index (y-index = x-index + ``npd``). ``lam[k] = (lam_n, lam_t)`` [N] is the
    force on slave ``k`` along ``n`` and ``t``, on entry the previous step's values (warm start: applied first,
    then projected and iterated, so the converged result does not depend on it beyond the tolerance) (the master
    nodes get ``-N_j`` times it); ``cstate[k]`` 0 open, 1 stick, 2 slip; ``geo[k] = (N0, N1, nx, ny, tx, ty,
    inside, penetration, surface velocity along t)``. Returns the number of sweeps.
    """
    ns = slave_node.shape[0]
    dt2 = dt * dt
    for k in range(ns):
        p = slave_pair[k]
        mk = int(pair_par[p, 6])
        if mk == MASTER_EDGE:
            m0 = master_ptr[p]
            nseg = master_ptr[p + 1] - m0 - 1
            s, xi, nx, ny, tx, ty, inside = _locate(X, u, npd, slave_node[k], master_nodes, m0, nseg, seg[k],
                                                    pair_sign[p])
            seg[k] = s
            geo[k, 0] = 1.0 - xi
            geo[k, 1] = xi
            geo[k, 8] = 0.0
        else:
            sn = slave_node[k]
            g, nx, ny, tx, ty, vt = rigid_geometry(mk, pair_par[p, 7], pair_par[p, 8], pair_par[p, 9],
                                                   pair_par[p, 10], pair_par[p, 11], pair_par[p, 12], X[sn],
                                                   X[sn + npd], X[sn] + u[sn], X[sn + npd] + u[sn + npd])
            inside = math.isfinite(g)
            geo[k, 0] = 0.0
            geo[k, 1] = 0.0
            geo[k, 8] = vt * surface_ramp(t_new, pair_par[p, 13], pair_par[p, 14])
        geo[k, 2] = nx
        geo[k, 3] = ny
        geo[k, 4] = tx
        geo[k, 5] = ty
        geo[k, 6] = 1.0 if inside else 0.0
        geo[k, 7] = 0.0
    # warm start: apply the previous step's multipliers (re-projected by the first sweep); in steady sliding
    # they change little per step, so the projected Gauss-Seidel needs a few sweeps instead of tens
    for k in range(ns):
        ln = lam[k, 0]
        lt = lam[k, 1]
        if geo[k, 6] == 0.0 or ln <= 0.0:
            lam[k, 0] = 0.0
            lam[k, 1] = 0.0
            cstate[k] = 0
            continue
        sn, a, b = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
        n0 = geo[k, 0]
        n1 = geo[k, 1]
        _apply_contact_force(u, v, npd, dt, minv_c, wmat, sn, a, b, n0, n1, ln * geo[k, 2] + lt * geo[k, 4],
                             ln * geo[k, 3] + lt * geo[k, 5])
    sweeps = 0
    for it in range(max_iter):
        sweeps = it + 1
        change = 0.0
        for k in range(ns):
            if geo[k, 6] == 0.0:
                continue
            p = slave_pair[k]
            sn, a, b = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
            n0 = geo[k, 0]
            n1 = geo[k, 1]
            nx = geo[k, 2]
            ny = geo[k, 3]
            tx = geo[k, 4]
            ty = geo[k, 5]
            # effective inverse masses along x and y of the relative motion slave - (N0 a + N1 b)
            wx, wxy, wy = _pair_compliance(minv_c, wmat, npd, sn, a, b, n0, n1)
            # normal: gap in the current (predicted + corrected) configuration
            if pair_par[p, 6] == MASTER_EDGE:
                gx = X[sn] + u[sn] - n0 * (X[a] + u[a]) - n1 * (X[b] + u[b])
                gy = (X[sn + npd] + u[sn + npd] - n0 * (X[a + npd] + u[a + npd])
                      - n1 * (X[b + npd] + u[b + npd]))
                g = gx * nx + gy * ny
            else:
                g = rigid_geometry(int(pair_par[p, 6]), pair_par[p, 7], pair_par[p, 8], pair_par[p, 9],
                                   pair_par[p, 10], 0.0, 0.0, X[sn], X[sn + npd], X[sn] + u[sn],
                                   X[sn + npd] + u[sn + npd])[0]
            wn = dt2 * (nx * nx * wx + ny * ny * wy + 2.0 * nx * ny * wxy)
            ln = lam[k, 0]
            ln_new = _normal_update(int(pair_par[p, 0]), pair_par[p, 1], pair_par[p, 2], law_tab[p], s_area[k], g,
                                    ln, wn)
            dn = ln_new - ln
            # tangential: relative tangential increment over the step (the master's surface velocity removed),
            # including the normal correction
            rx = v[sn] - n0 * v[a] - n1 * v[b] + dt * dn * nx * wx + dt * dn * ny * wxy
            ry = v[sn + npd] - n0 * v[a + npd] - n1 * v[b + npd] + dt * dn * ny * wy + dt * dn * nx * wxy
            st = dt * (rx * tx + ry * ty - geo[k, 8])
            wt = dt2 * (tx * tx * wx + ty * ty * wy + 2.0 * tx * ty * wxy)
            lt = lam[k, 1]
            lt_new, state = _tangential_update(lt, st, wt, ln_new, mu[k], pair_par[p], dt)
            if ln_new == 0.0:
                state = 0
            dtn = lt_new - lt
            if dn != 0.0 or dtn != 0.0:  # an open node far from its master (most of them) moves nothing
                _apply_contact_force(u, v, npd, dt, minv_c, wmat, sn, a, b, n0, n1, dn * nx + dtn * tx,
                                     dn * ny + dtn * ty)
            lam[k, 0] = ln_new
            lam[k, 1] = lt_new
            cstate[k] = state
            geo[k, 7] = -(g + dn * wn) if pair_par[p, 0] != LAW_RIGID else 0.0
            # convergence measured as the displacement the last increments moved the node pair by: the
            # positions carry round-off eps |x| ~ 1e-17 m, i.e. multiplier noise eps |x| / (dt^2 w), so a
            # relative multiplier tolerance can be unreachable at small dt
            change = max(change, abs(dn) * wn, abs(dtn) * wt)
        if change <= tol:
            break
    return sweeps


@njit(cache=True)
def friction_now(mu_tab, mu_rate, t, mu_now):
    """Kinetic coefficient of every slave at time ``t`` [s]: the table ``mu_tab`` (rows at ``mu_rate`` [Hz], one
    row: constant) interpolated linearly, clipped at 0."""
    n_mu = mu_tab.shape[0]
    ns = mu_now.shape[0]
    if n_mu == 1:
        for k in range(ns):
            mu_now[k] = mu_tab[0, k]
    else:
        x = t * mu_rate
        i0 = min(int(x), n_mu - 2)
        fr = x - i0
        for k in range(ns):
            mu_now[k] = max(0.0, (1.0 - fr) * mu_tab[i0, k] + fr * mu_tab[i0 + 1, k])


@njit(cache=True)
def contact_step(X, u, v, npd, dt, t_new, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_sign,
                 pair_par, law_tab, s_area, seg, geo, lam, cstate, mu_tab, mu_rate, mu_now, max_iter, tol, acc):
    """The friction coefficients at ``t_new`` (:func:`friction_now`), the contact correction
    (:func:`contact_solve`) and its Gauss-Seidel statistics in ``acc``."""
    friction_now(mu_tab, mu_rate, t_new, mu_now)
    sweeps = contact_solve(X, u, v, npd, dt, t_new, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes,
                           pair_sign, pair_par, law_tab, s_area, seg, geo, lam, cstate, mu_now, max_iter, tol)
    acc[GS_SWEEPS] += sweeps
    acc[GS_MAX] = max(acc[GS_MAX], sweeps)
    if sweeps >= max_iter:
        acc[GS_CAPPED] += 1.0


@njit(cache=True)
def contact_work(v, npd, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par, geo, lam, cstate,
                 cnode_slot, vold_c, rec_contact_r):
    """Work / dt of the normal and tangential contact forces and of the rigid surfaces' drive over a step, with
    the mid-step velocities of the contact nodes (``vold_c[:, :2]`` before the step, ``v`` after); adds each
    pair's forces and state counts to ``rec_contact_r``. Returns ``(wcn, wct, wdr)`` [W]."""
    wcn = 0.0
    wct = 0.0
    wdr = 0.0
    for k in range(slave_node.shape[0]):
        p = slave_pair[k]
        if cstate[k] == 0:
            rec_contact_r[p, 4] += 1.0
            continue
        sn, a, b = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
        n0 = geo[k, 0]
        n1 = geo[k, 1]
        qs = cnode_slot[sn]
        qa = cnode_slot[a]
        qb = cnode_slot[b]
        rx = 0.5 * ((vold_c[qs, 0] + v[sn]) - n0 * (vold_c[qa, 0] + v[a]) - n1 * (vold_c[qb, 0] + v[b]))
        ry = 0.5 * ((vold_c[qs, 1] + v[sn + npd]) - n0 * (vold_c[qa, 1] + v[a + npd])
                    - n1 * (vold_c[qb, 1] + v[b + npd]))
        wcn += lam[k, 0] * (rx * geo[k, 2] + ry * geo[k, 3])
        # a rigid master's surface moves at geo[k, 8] along t: the friction dissipates on the
        # relative slip and the drive does the rest of the work on the slave
        wct += lam[k, 1] * (rx * geo[k, 4] + ry * geo[k, 5] - geo[k, 8])
        wdr += lam[k, 1] * geo[k, 8]
        rec_contact_r[p, 0] += lam[k, 0]
        rec_contact_r[p, 1] += lam[k, 1]
        rec_contact_r[p, 1 + cstate[k]] += 1.0
    return wcn, wct, wdr


@njit(cache=True)
def finish_contact_record(slave_pair, pair_par, law_tab, s_area, geo, cstate, n_sub, rec_contact_r):
    """Turn an interval's contact sums into averages and fractions; returns the energy stored in the compliant
    normal laws [J]."""
    epen = 0.0
    for k in range(slave_pair.shape[0]):
        p = slave_pair[k]
        if pair_par[p, 0] != LAW_RIGID and cstate[k] != 0:
            epen += s_area[k] * normal_energy(int(pair_par[p, 0]), pair_par[p, 1], pair_par[p, 2], geo[k, 7],
                                              law_tab[p])
    for p in range(rec_contact_r.shape[0]):
        cnt = rec_contact_r[p, 2] + rec_contact_r[p, 3] + rec_contact_r[p, 4]
        rec_contact_r[p, 0] /= n_sub
        rec_contact_r[p, 1] /= n_sub
        if cnt > 0.0:
            for c in range(2, 5):
                rec_contact_r[p, c] /= cnt
    return epen


@njit(cache=True)
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


@njit(cache=True)
def start_record(react_acc, rec_contact_r):
    """Zero the interval sums of the transducer and of the contact pairs."""
    react_acc[0] = 0.0
    react_acc[1] = 0.0
    for p in range(rec_contact_r.shape[0]):
        for c in range(5):
            rec_contact_r[p, c] = 0.0


@njit(cache=True)
def group_velocities(grp_par, grp_v, t, dt):
    """Velocity of every motion group over the previous step and over ``[t, t + dt]`` into ``grp_v[:, 0:2]``."""
    for g in range(grp_par.shape[0]):
        kind = int(grp_par[g, 0])
        grp_v[g, 0] = constrained_velocity(kind, grp_par[g, 1], grp_par[g, 2], grp_par[g, 3], t - dt, dt)
        grp_v[g, 1] = constrained_velocity(kind, grp_par[g, 1], grp_par[g, 2], grp_par[g, 3], t, dt)


@njit(cache=True)
def add_step_work(acc, dt, wint, dal, wext, wld, wcn, wct, wdr):
    """Accumulate one step's works (rates [W] times ``dt``) in ``acc``."""
    acc[W_LOAD] += dt * wld
    acc[W_INT] += dt * wint
    acc[D_ALPHA] += dt * dal
    acc[W_EXT] += dt * wext
    acc[W_CN] += dt * wcn
    acc[W_CT] += dt * wct
    acc[W_DRIVE] += dt * wdr


@njit(cache=True)
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


@njit(cache=True, fastmath={"contract", "reassoc"})
def _predictor(u, v, w, vf, f, mass, minv, dt, alpha, beta, a_filt):
    """Central-difference predictor over all dofs; returns the work increments / dt of the internal forces and
    of the alpha damping (mid-step velocities). Reassociation lets the two sums vectorise (no NaN/inf
    assumptions: the guards still see them).

    Classic Rayleigh (``a_filt >= 1``): ``w = u + beta v``. Band-limited (``a_filt < 1``): the filtered velocity
    ``vf += a_filt (v - vf)`` (exact update of ``dvf/dt = omega_c (v - vf)`` for a velocity constant over the
    step, ``a_filt = 1 - exp(-omega_c dt)``) and ``w = u + beta vf``; the classic scheme is bit for bit what it
    always was."""
    wint = 0.0
    dal = 0.0
    filtered = a_filt < 1.0  # loop-invariant: LLVM unswitches the loop (measured: no cost in the classic case)
    for d in range(u.shape[0]):
        vo = v[d]
        vn = vo + dt * (-minv[d] * f[d] - alpha * vo)
        vm = 0.5 * (vo + vn)
        wint += f[d] * vm
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


@njit(cache=True)
def run_steps(
    step0, nsteps, dt, alpha, beta, a_filt, n_sub, npd,
    blocks, c_uni, c_map, lst_idx, lst_nbr, lst_coef, mass, minv,
    spr_dof, spr_kc,
    con_dof, con_grp, grp_par, grp_v, con_react,
    ld_dof, ld_force, ld_grp, ld_par, ld_scale, ld_vold,
    X, slave_node, slave_pair, master_ptr, master_nodes, pair_sign, pair_par, law_tab, s_area, minv_c, seg, geo,
    lam, cstate, gs_max_iter, gs_tol, mu_tab, mu_rate, mu_now, vold_c, cnode_slot, cnodes,
    sens_node, sens_dir,
    u, v, w, vf, f, scratch, acc, react_acc,
    rec, rec_sens, rec_contact, runaway_factor, diag,
):
    """Advance the model ``nsteps`` central-difference steps from step ``step0`` (a whole number of outputs).

    Per step: ``f = K(u + beta v)`` (band-limited damping, ``a_filt < 1``: ``K(u + beta vf)``, see
    :func:`_predictor`) by stencil plus springs and dashpots; predictor
    ``v* = v + dt (-M^-1 f - alpha v)``, ``u* = u + dt v*``; imposed motions on the constrained dofs (their
    reactions ``m a + f + alpha m v`` summed for the force transducer); contact correction
    (:func:`contact_solve`, constraints at ``t + dt``); energy increments with mid-step velocities, so that
    ``KE - KE0 = W_ext + W_load + W_drive + W_cn + W_ct - W_int - D_alpha`` holds to round-off (``W_drive``: work
    of the moving rigid masters' surfaces; ``W_load``: work of the
    pressure loads ``ld_*``, applied as ``f -= r(t) F`` before the predictor; ``ld_scale``, ``ld_vold`` are scratch).

    Layout: dof vectors have length ``2*npd`` (x part, y part); nodes are given by x-index; springs and
    constraints by flat dof index. Every ``n_sub`` steps one output row is written: ``rec[r]`` (see
    ``R_*``), sensor velocity and displacement ``rec_sens[r, s, :]`` at the interval end (the driver differences them into
    interval-averaged accelerations), per-pair interval averages ``rec_contact[r, p] = (normal force,
    tangential force, stick, slip, open fractions)``. Returns ``(status, rows_written)``; on NaN or runaway
    energy ``diag = (step, x-index)`` of the node with the largest speed.
    """
    n = u.shape[0]
    n_out = nsteps // n_sub
    ns = slave_node.shape[0]
    no_wmat = np.zeros((0, 0))  # lumped mass: diagonal contact correction
    for r in range(n_out):
        start_record(react_acc, rec_contact[r])
        for sub in range(n_sub):
            step = step0 + r * n_sub + sub
            t = step * dt
            # ---- internal forces, minus the applied loads at the step start (f is the net force K w - F)
            block_forces(w, f, npd, blocks, c_uni, c_map, lst_idx, lst_nbr, lst_coef)
            spring_forces(u, v, f, spr_dof, spr_kc, True)
            for g in range(ld_par.shape[0]):
                ld_scale[g] = ramp((t - ld_par[g, 0]) / ld_par[g, 1]) if ld_par[g, 1] > 0.0 else (
                    1.0 if t >= ld_par[g, 0] else 0.0)
            for q in range(ld_dof.shape[0]):
                d = ld_dof[q]
                f[d] -= ld_scale[ld_grp[q]] * ld_force[q]
                ld_vold[q] = v[d]
            # ---- old velocities of contact nodes (exact contact work)
            for q in range(cnodes.shape[0]):
                nd = cnodes[q]
                vold_c[q, 0] = v[nd]
                vold_c[q, 1] = v[nd + npd]
            # ---- predictor over all dofs, fused with the energy increments and w = u + beta v
            wint, dal = _predictor(u, v, w, vf, f, mass, minv, dt, alpha, beta, a_filt)
            # ---- constrained dofs: undo the free update, impose the motion, reaction = m a + f + alpha m v
            wext = 0.0
            rt = 0.0
            rn = 0.0
            group_velocities(grp_par, grp_v, t, dt)
            for c in range(con_dof.shape[0]):
                d = con_dof[c]
                vwrong = v[d]
                vo = grp_v[con_grp[c], 0]
                vn = grp_v[con_grp[c], 1]
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
                rt += con_react[c, 0] * rf
                rn += con_react[c, 1] * rf
            react_acc[0] += rt
            react_acc[1] += rn
            # ---- contact
            wcn = 0.0
            wct = 0.0
            wdr = 0.0
            if ns > 0:
                for q in range(cnodes.shape[0]):
                    nd = cnodes[q]
                    vold_c[q, 2] = v[nd]
                    vold_c[q, 3] = v[nd + npd]
                contact_step(X, u, v, npd, dt, t + dt, minv_c, no_wmat, slave_node, slave_pair, master_ptr,
                             master_nodes, pair_sign, pair_par, law_tab, s_area, seg, geo, lam, cstate, mu_tab,
                             mu_rate, mu_now, gs_max_iter, gs_tol, acc)
                # the contact correction changed the mid-step velocity of the contact nodes: complete the
                # internal-force and alpha-damping work with it (f and alpha m v_old times the velocity change)
                for q in range(cnodes.shape[0]):
                    nd = cnodes[q]
                    dvx = v[nd] - vold_c[q, 2]
                    dvy = v[nd + npd] - vold_c[q, 3]
                    wint += 0.5 * (f[nd] * dvx + f[nd + npd] * dvy)
                    dal += 0.5 * alpha * (mass[nd] * vold_c[q, 0] * dvx + mass[nd + npd] * vold_c[q, 1] * dvy)
                wcn, wct, wdr = contact_work(v, npd, slave_node, slave_pair, master_ptr, master_nodes, seg,
                                             pair_par, geo, lam, cstate, cnode_slot, vold_c, rec_contact[r])
                # w = u + beta v (or u + beta vf) where the contact correction moved nodes
                for q in range(cnodes.shape[0]):
                    d = cnodes[q]
                    if a_filt >= 1.0:
                        w[d] = u[d] + beta * v[d]
                        w[d + npd] = u[d + npd] + beta * v[d + npd]
                    else:
                        vf[d] += a_filt * (v[d] - vold_c[q, 2])
                        vf[d + npd] += a_filt * (v[d + npd] - vold_c[q, 3])
                        w[d] = u[d] + beta * vf[d]
                        w[d + npd] = u[d + npd] + beta * vf[d + npd]
            # ---- load work with the final mid-step velocities; wint summed (K w - F) v, so add F v back
            wld = 0.0
            for q in range(ld_dof.shape[0]):
                wld += ld_scale[ld_grp[q]] * ld_force[q] * 0.5 * (ld_vold[q] + v[ld_dof[q]])
            wint += wld
            add_step_work(acc, dt, wint, dal, wext, wld, wcn, wct, wdr)
        # ---- end of an output interval: record
        step_end = step0 + (r + 1) * n_sub
        ke = 0.0
        for d in range(n):
            ke += 0.5 * mass[d] * v[d] * v[d]
        block_forces(u, scratch, npd, blocks, c_uni, c_map, lst_idx, lst_nbr, lst_coef)
        spring_forces(u, v, scratch, spr_dof, spr_kc, False)
        ue = 0.0
        for d in range(n):
            ue += 0.5 * u[d] * scratch[d]
        status = finish_record(rec[r], rec_sens[r], rec_contact[r], acc, react_acc, ke, ue, u, v, npd, sens_node,
                               sens_dir, slave_pair, pair_par, law_tab, s_area, geo, cstate, n_sub, runaway_factor,
                               diag, step_end, npd)
        if status != OK:
            return status, r + 1
    return OK, n_out
