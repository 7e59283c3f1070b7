"""The contact correction of the explicit solver (layer L0): forward-increment Lagrange multipliers with
Coulomb friction by projected Gauss-Seidel, the friction coefficients now, and the contact's work and record.

Used by the full model's loop (:mod:`fivid.solver._loop_kernels`, lumped inverse mass) and by the reduced
system's (:mod:`fivid.solver._reduced_kernels`, dense inverse mass ``wmat`` of the contact dofs). The normal
laws and rigid surfaces are those of :mod:`fivid.contact._kernels`, the friction curve and ``mu(t)`` those of
:mod:`fivid.friction._curve_kernels`; a pair's parameters are read by the named columns of
:mod:`fivid.contact._layout_kernels`. Record layout: :mod:`fivid.solver._kernels`.
"""

import math

from fivid.contact._kernels import (
    circle_radius,
    normal_energy,
    normal_pressure,
    rigid_geometry,
    surface_ramp,
    vertex_geometry,
)
from fivid.contact._layout_kernels import (
    CNODE_MOVED,
    CNODE_V_STEP,
    EXPANSION,
    EXPANSION_RAMP,
    EXPANSION_START,
    GEO_GAP,
    GEO_IDLE,
    GEO_INSIDE,
    GEO_N0,
    GEO_N1,
    GEO_NX,
    GEO_NY,
    GEO_PENETRATION,
    GEO_SLEEP,
    GEO_SURFACE_VELOCITY,
    GEO_TX,
    GEO_TY,
    LAW,
    LAW_COEFFICIENT,
    LAW_EXPONENT,
    LAW_RIGID,
    MASTER,
    MASTER_CIRCLE,
    MASTER_EDGE,
    MU_STATIC_EXCESS,
    REC_NORMAL,
    REC_OPEN,
    REC_SLIP,
    REC_STICK,
    REC_TANGENTIAL,
    STRIBECK_VELOCITY,
    SURFACE_A,
    SURFACE_B,
    SURFACE_RAMP,
    SURFACE_START,
    SURFACE_SX,
    SURFACE_SY,
    SURFACE_X,
    SURFACE_Y,
    VISCOUS,
)
from fivid.friction._curve_kernels import friction_coefficient, friction_now
from fivid.solver._kernels import GS_CAPPED, GS_MAX, GS_SWEEPS, kernel

__all__ = ["contact_solve", "contact_step", "contact_work", "contact_reactions", "slave_force", "finish_contact_record",
           "CANDIDATE_MARGIN", "SLEEP_MARGINS"]

#: an open slave whose predicted gap exceeds this fraction of its master segment's length sits out the Gauss-Seidel
#: sweeps of the step until the corrections have moved its nodes by half that gap (see :func:`contact_solve`)
CANDIDATE_MARGIN = 1e-3

#: an open slave farther than this many candidate margins (:data:`CANDIDATE_MARGIN` times its segment's length) from
#: the whole master edge sleeps: it is not located until the contact nodes may have moved by half that distance
#: (see :func:`contact_solve`)
SLEEP_MARGINS = 4.0


@kernel
def _segment_xi(X, u, npd, xs, ys, a, b):
    """``(xi, ex, ey)``: the parameter of the projection of ``(xs, ys)`` on the segment from node ``a`` to node
    ``b`` and the segment's vector [m] in the configuration ``X + u``."""
    xa = X[a] + u[a]
    ya = X[a + npd] + u[a + npd]
    ex = X[b] + u[b] - xa
    ey = X[b + npd] + u[b + npd] - ya
    return ((xs - xa) * ex + (ys - ya) * ey) / (ex * ex + ey * ey), ex, ey


@kernel
def _locate(X, u, npd, sn, mnodes, m0, nseg, seg_k, sign):
    """Find the master point nearest to slave node ``sn`` starting from segment ``seg_k`` (local monotone search).

    Returns ``(segment, xi, nx, ny, tx, ty, inside)``: the master point is ``N0 a + N1 b`` (``N0 = 1 - xi``,
    ``N1 = xi``) of the segment from node ``a`` to ``b``, with the unit outward normal ``n`` and tangent ``t`` there;
    ``inside`` false: beyond the edge's ends (no master).

    The walk steps to the neighbour segment while the projection falls before (``xi < 0``) or beyond (``xi > 1``)
    the current one. It starts from the previous step's segment, which the slave has left by a small fraction of
    a segment at most, so it costs one or two projections: no spatial search structure is needed. A walk that turns
    back has found a slave beyond both segments meeting at an interior vertex: over a convex vertex (a rough
    master's asperity tops, open) or under a concave one (its valleys, penetrating): its nearest master point is
    that vertex, and its gap and normal are :func:`fivid.contact._kernels.vertex_geometry`'s (returned as the
    segment ending at the vertex, ``xi = 1``). A penetrating slave that projects onto its segment may project onto a
    neighbour too (under a convex vertex, where both overlap): the one with the smaller penetration (the nearer
    surface point) is taken, so the gap is the signed distance to the edge and continuous as the slave slides
    across the vertex (the normal turns there, as it must).
    """
    xs = X[sn] + u[sn]
    ys = X[sn + npd] + u[sn + npd]
    s = min(max(seg_k, 0), nseg - 1)
    xi = 0.0
    ex = 0.0
    ey = 0.0
    last = 0  # the previous move: -1 down, +1 up, 0 none yet
    for it in range(nseg + 1):
        xi, ex, ey = _segment_xi(X, u, npd, xs, ys, mnodes[m0 + s], mnodes[m0 + s + 1])
        if xi < 0.0 and s > 0:
            step = -1
        elif xi > 1.0 and s < nseg - 1:
            step = 1
        else:
            break
        if step == -last:
            # turned back: beyond both segments meeting at the vertex between s and s + step
            return _vertex_point(X, u, npd, xs, ys, mnodes, m0, min(s, s + step), sign)
        s += step
        last = step
    L = math.sqrt(ex * ex + ey * ey)
    tx = ex / L
    ty = ey / L
    # a slave node at the very end of the master edge (edges meeting corner to corner) must not flicker
    # in and out of contact through round-off: accept 1e-6 of a segment beyond the ends, then clamp
    inside = -1e-6 <= xi <= 1.0 + 1e-6
    xi = min(max(xi, 0.0), 1.0)
    nx = sign * ty
    ny = -sign * tx
    if inside:
        a = mnodes[m0 + s]
        g = _edge_gap(X, u, npd, sn, a, mnodes[m0 + s + 1], 1.0 - xi, xi, nx, ny)
        if g < 0.0:
            # penetrating: a neighbour segment it also projects onto with a smaller penetration is nearer
            for j in (s - 1, s + 1):
                if j < 0 or j >= nseg:
                    continue
                xj, fx, fy = _segment_xi(X, u, npd, xs, ys, mnodes[m0 + j], mnodes[m0 + j + 1])
                if not 0.0 <= xj <= 1.0:
                    continue
                Lj = math.sqrt(fx * fx + fy * fy)
                gj = _edge_gap(X, u, npd, sn, mnodes[m0 + j], mnodes[m0 + j + 1], 1.0 - xj, xj, sign * fy / Lj,
                               -sign * fx / Lj)
                if gj > g:
                    g = gj
                    s = j
                    xi = xj
                    tx = fx / Lj
                    ty = fy / Lj
            nx = sign * ty
            ny = -sign * tx
    return s, xi, nx, ny, tx, ty, inside


@kernel
def _vertex_point(X, u, npd, xs, ys, mnodes, m0, s, sign):
    """:func:`_locate`'s result for a slave at ``(xs, ys)`` [m] beyond both segments ``s`` and ``s + 1`` of a master
    edge: the vertex between them (node ``mnodes[m0 + s + 1]``, ``xi = 1`` on segment ``s``) with the gap's normal
    and tangent of :func:`fivid.contact._kernels.vertex_geometry`."""
    a = mnodes[m0 + s]
    v = mnodes[m0 + s + 1]
    b = mnodes[m0 + s + 2]
    xv = X[v] + u[v]
    yv = X[v + npd] + u[v + npd]
    e1x = xv - X[a] - u[a]
    e1y = yv - X[a + npd] - u[a + npd]
    e2x = X[b] + u[b] - xv
    e2y = X[b + npd] + u[b + npd] - yv
    l1 = math.sqrt(e1x * e1x + e1y * e1y)
    l2 = math.sqrt(e2x * e2x + e2y * e2y)
    _, nx, ny, tx, ty = vertex_geometry(xs, ys, xv, yv, sign * e1y / l1, -sign * e1x / l1, sign * e2y / l2,
                                        -sign * e2x / l2, sign)
    return s, 1.0, nx, ny, tx, ty, True


@kernel
def _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par):
    """x-indices of slave ``k`` and of the two nodes of its current master segment (a rigid master has none:
    the slave itself is returned for both, with shape values 0, so the master terms vanish). One return: numba's
    reference-count pruning then drops the array arguments' increments and decrements, which two returns left in
    every call (eight atomic NRT calls, tens of calls per step: 20 -> 16 % of the reduced loop's profile on the
    default rig)."""
    p = slave_pair[k]
    sn = slave_node[k]
    a = sn
    b = sn
    if pair_par[p, MASTER] == MASTER_EDGE:
        a = master_nodes[master_ptr[p] + seg[k]]
        b = master_nodes[master_ptr[p] + seg[k] + 1]
    return sn, a, b


@kernel
def _apply_contact_force(u, v, npd, dt, minv_c, wmat, cnode_slot, vold_c, sn, a, b, n0, n1, fx, fy):
    """Correct position and velocity of slave ``sn`` by the contact force ``(fx, fy)`` [N] over one step and of
    the master nodes ``a``, ``b`` by ``-N0`` and ``-N1`` times it (zero inverse mass: constrained, not moved);
    add the displacements' ``|dx| + |dy|`` [m] to the nodes' ``vold_c[slot, CNODE_MOVED]`` (lumped mass only).

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
    vold_c[cnode_slot[sn], CNODE_MOVED] += dt2 * (minv_c[sn] * abs(fx) + minv_c[sn + npd] * abs(fy))
    vold_c[cnode_slot[a], CNODE_MOVED] += dt2 * n0 * (minv_c[a] * abs(fx) + minv_c[a + npd] * abs(fy))
    vold_c[cnode_slot[b], CNODE_MOVED] += dt2 * n1 * (minv_c[b] * abs(fx) + minv_c[b + npd] * abs(fy))


@kernel
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


@kernel
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


@kernel
def _tangential_update(lt, st, wt, ln_new, mu_k, par_p, dt):
    """New tangential multiplier [N] and state (1 stick, 2 slip) from the relative tangential increment ``st``
    [m] over the step: stick if the multiplier that cancels it stays within ``mu_s ln``, else slip with the
    kinetic curve ``mu(v)`` at the slip rate ``v`` that force leaves at the end of the step."""
    lt_stick = lt - st / wt if wt > 0.0 else lt
    cap = (mu_k + par_p[MU_STATIC_EXCESS]) * ln_new
    if -cap <= lt_stick <= cap:
        return lt_stick, 1
    sgn = 1.0 if lt_stick > 0.0 else -1.0
    mu = mu_k
    if par_p[STRIBECK_VELOCITY] > 0.0 or par_p[VISCOUS] != 0.0:
        # the slip rate the sliding force leaves at the end of the step, v = (st + wt (lt_new - lt)) / dt, and
        # mu(v): a fixed point contracting by dt lam_n |mu'| / m_node per pass (~1e-2)
        for _ in range(4):
            v_slip = (st + wt * (sgn * mu * ln_new - lt)) / dt
            mu = friction_coefficient(mu_k, par_p[MU_STATIC_EXCESS], par_p[STRIBECK_VELOCITY], par_p[VISCOUS],
                                      v_slip)
    return sgn * mu * ln_new, 2


@kernel
def _edge_gap(X, u, npd, sn, a, b, n0, n1, nx, ny):
    """Gap [m] of slave ``sn`` along the normal ``(nx, ny)`` from the point ``N0 a + N1 b`` of its master segment
    (configuration ``X + u``)."""
    gx = X[sn] + u[sn] - n0 * (X[a] + u[a]) - n1 * (X[b] + u[b])
    gy = (X[sn + npd] + u[sn + npd] - n0 * (X[a + npd] + u[a + npd])
          - n1 * (X[b + npd] + u[b + npd]))
    return gx * nx + gy * ny


@kernel
def _rigid_a(par_p, t):
    """A rigid master's ``SURFACE_A`` column at time ``t`` [s]: a line's normal x-component, a circle's radius
    after its expansion ramp (:func:`fivid.contact._kernels.circle_radius`)."""
    if int(par_p[MASTER]) == MASTER_CIRCLE:
        return circle_radius(par_p[SURFACE_A], par_p[EXPANSION], par_p[EXPANSION_START], par_p[EXPANSION_RAMP], t)
    return par_p[SURFACE_A]


@kernel
def _step_travel(v, npd, dt, slave_node, master_nodes):
    """Bound [m] on how far any slave node and any master node moved relative to each other over the step: ``dt``
    times the largest ``|vx| + |vy|`` over the slave nodes plus the same over the master nodes."""
    vs = 0.0
    for k in range(slave_node.shape[0]):
        q = slave_node[k]
        vs = max(vs, abs(v[q]) + abs(v[q + npd]))
    vm = 0.0
    for k in range(master_nodes.shape[0]):
        q = master_nodes[k]
        vm = max(vm, abs(v[q]) + abs(v[q + npd]))
    return dt * (vs + vm)


@kernel
def _monotone_direction(X, u, npd, mnodes, m0, nseg):
    """``(ex, ey, monotone)``: the unit vector from the first to the last node of a master edge and whether every
    segment advances along it (the edge is then sorted along ``e``: its segments are binned by their extent
    along ``e``, and those outside a window are farther than the window's half-width)."""
    a = mnodes[m0]
    b = mnodes[m0 + nseg]
    ex = X[b] + u[b] - X[a] - u[a]
    ey = X[b + npd] + u[b + npd] - X[a + npd] - u[a + npd]
    L = math.sqrt(ex * ex + ey * ey)
    if not L > 0.0:
        return 0.0, 0.0, False
    ex /= L
    ey /= L
    ok = True
    for j in range(nseg):
        a = mnodes[m0 + j]
        b = mnodes[m0 + j + 1]
        ok &= (X[b] + u[b] - X[a] - u[a]) * ex + (X[b + npd] + u[b + npd] - X[a + npd] - u[a + npd]) * ey > 0.0
    return ex, ey, ok


@kernel
def _point_segment_distance(X, u, npd, xs, ys, a, b):
    """Euclidean distance [m] from ``(xs, ys)`` to the segment from node ``a`` to node ``b`` (configuration ``X + u``)."""
    xa = X[a] + u[a]
    ya = X[a + npd] + u[a + npd]
    ex = X[b] + u[b] - xa
    ey = X[b + npd] + u[b + npd] - ya
    xi = min(max(((xs - xa) * ex + (ys - ya) * ey) / (ex * ex + ey * ey), 0.0), 1.0)
    dx = xs - xa - xi * ex
    dy = ys - ya - xi * ey
    return math.sqrt(dx * dx + dy * dy)


@kernel
def _clearance(X, u, npd, xs, ys, mnodes, m0, nseg, s, r, ex, ey):
    """``min(r, distance [m] from (xs, ys) to the master edge)`` for an edge sorted along ``(ex, ey)``
    (:func:`_monotone_direction`): only the segments reaching into the window ``xs . e +- r`` are measured, found
    by walking both ways from segment ``s`` (the others are farther than ``r``)."""
    pe = xs * ex + ys * ey
    best = r
    j = min(max(s, 0), nseg - 1)
    while j >= 0:
        a = mnodes[m0 + j]
        b = mnodes[m0 + j + 1]
        if (X[b] + u[b]) * ex + (X[b + npd] + u[b + npd]) * ey < pe - r:
            break
        best = min(best, _point_segment_distance(X, u, npd, xs, ys, a, b))
        j -= 1
    j = min(max(s, 0), nseg - 1) + 1
    while j < nseg:
        a = mnodes[m0 + j]
        b = mnodes[m0 + j + 1]
        if (X[a] + u[a]) * ex + (X[a + npd] + u[a + npd]) * ey > pe + r:
            break
        best = min(best, _point_segment_distance(X, u, npd, xs, ys, a, b))
        j += 1
    return best


@kernel
def _slave_geometry(X, u, npd, t_new, slave_node, slave_pair, master_ptr, master_nodes, pair_sign, pair_par, seg, geo,
                    lam, margin, travel):
    """Master segment ``seg[k]`` and geometry ``geo[k]`` of every slave in the predicted configuration ``u`` (see
    :func:`contact_solve`); a rigid master's surface velocity at ``t_new`` [s]. A slave on a deformable master
    with no force from the previous step and a predicted gap beyond ``margin`` times its segment's length is
    marked idle (``GEO_IDLE``); ``margin`` infinite: none is. ``travel`` [m] (:func:`_step_travel`; infinite: no
    slave sleeps) is taken off the sleeping slaves' budgets; a slave whose budget lasts is not located (it faces no
    master this step: ``GEO_INSIDE`` 0), one without force farther than :data:`SLEEP_MARGINS` margins from its whole
    master edge (:func:`_clearance`, edges sorted along a direction only) falls asleep with half that distance as
    its budget."""
    ns = slave_node.shape[0]
    sleepy = math.isfinite(travel) and math.isfinite(margin)
    mono_pair = -1  # the pair whose edge direction was last checked this step (slaves come grouped by pair)
    mono = False
    mex = 0.0
    mey = 0.0
    for k in range(ns):
        budget = geo[k, GEO_SLEEP]
        if budget > 0.0:
            budget -= travel
            if budget > 0.0:
                geo[k, GEO_SLEEP] = budget
                geo[k, GEO_INSIDE] = 0.0
                geo[k, GEO_IDLE] = 0.0
                continue
            geo[k, GEO_SLEEP] = 0.0
        p = slave_pair[k]
        mk = int(pair_par[p, MASTER])
        idle = 0.0
        if mk == MASTER_EDGE:
            m0 = master_ptr[p]
            nseg = master_ptr[p + 1] - m0 - 1
            sn = slave_node[k]
            s, xi, nx, ny, tx, ty, inside = _locate(X, u, npd, sn, master_nodes, m0, nseg, seg[k], pair_sign[p])
            seg[k] = s
            a = master_nodes[m0 + s]
            b = master_nodes[m0 + s + 1]
            g = _edge_gap(X, u, npd, sn, a, b, 1.0 - xi, xi, nx, ny)
            if lam[k, 0] <= 0.0:
                ex = X[b] + u[b] - X[a] - u[a]
                ey = X[b + npd] + u[b + npd] - X[a + npd] - u[a + npd]
                seg_len = math.sqrt(ex * ex + ey * ey)
                if inside and g > margin * seg_len:
                    idle = 1.0
                reach = SLEEP_MARGINS * margin * seg_len
                # outside the master: a positive gap to the point it faces (a segment's foot point, or a vertex it
                # is beyond both segments of), or to the edge's end point (beyond the edge's ends); a facing slave's
                # distance to the edge is at most its gap: a cheap pre-check
                if sleepy and g > reach:
                    if p != mono_pair:
                        mex, mey, mono = _monotone_direction(X, u, npd, master_nodes, m0, nseg)
                        mono_pair = p
                    if mono:
                        d = _clearance(X, u, npd, X[sn] + u[sn], X[sn + npd] + u[sn + npd], master_nodes, m0, nseg, s,
                                       seg_len, mex, mey)
                        if d > reach:
                            geo[k, GEO_SLEEP] = 0.5 * d
                            geo[k, GEO_INSIDE] = 0.0
                            geo[k, GEO_IDLE] = 0.0
                            continue
            geo[k, GEO_N0] = 1.0 - xi
            geo[k, GEO_N1] = xi
            geo[k, GEO_SURFACE_VELOCITY] = 0.0
            geo[k, GEO_GAP] = g
        else:
            sn = slave_node[k]
            g, nx, ny, tx, ty, vt = rigid_geometry(mk, pair_par[p, SURFACE_X], pair_par[p, SURFACE_Y],
                                                   _rigid_a(pair_par[p], t_new), pair_par[p, SURFACE_B],
                                                   pair_par[p, SURFACE_SX], pair_par[p, SURFACE_SY], X[sn],
                                                   X[sn + npd], X[sn] + u[sn], X[sn + npd] + u[sn + npd])
            inside = math.isfinite(g)
            geo[k, GEO_N0] = 0.0
            geo[k, GEO_N1] = 0.0
            geo[k, GEO_SURFACE_VELOCITY] = vt * surface_ramp(t_new, pair_par[p, SURFACE_START],
                                                             pair_par[p, SURFACE_RAMP])
            geo[k, GEO_GAP] = g
        geo[k, GEO_NX] = nx
        geo[k, GEO_NY] = ny
        geo[k, GEO_TX] = tx
        geo[k, GEO_TY] = ty
        geo[k, GEO_INSIDE] = 1.0 if inside else 0.0
        geo[k, GEO_PENETRATION] = 0.0
        geo[k, GEO_IDLE] = idle


@kernel
def _warm_start(u, v, npd, dt, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_par, seg, geo, lam,
                cstate, cnode_slot, vold_c):
    """Apply the previous step's multipliers ``lam`` (re-projected by the first sweep) to the slaves still facing
    their master; release the others (state open)."""
    ns = slave_node.shape[0]
    for k in range(ns):
        ln = lam[k, 0]
        lt = lam[k, 1]
        if geo[k, GEO_INSIDE] == 0.0 or ln <= 0.0:
            lam[k, 0] = 0.0
            lam[k, 1] = 0.0
            cstate[k] = 0
            continue
        sn, a, b = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
        _apply_contact_force(u, v, npd, dt, minv_c, wmat, cnode_slot, vold_c, sn, a, b, geo[k, GEO_N0],
                             geo[k, GEO_N1], ln * geo[k, GEO_NX] + lt * geo[k, GEO_TX],
                             ln * geo[k, GEO_NY] + lt * geo[k, GEO_TY])


@kernel
def _clear_moved(slave_node, slave_pair, master_ptr, master_nodes, pair_par, seg, geo, cnode_slot, vold_c):
    """Zero the displacement bounds ``vold_c[:, CNODE_MOVED]`` the step's corrections set: those of the nodes of
    the slaves that took part (facing their master, not idle; only they apply forces); take twice the largest of
    them (a slave's and a master node's) off the sleeping slaves' budgets (``GEO_SLEEP``)."""
    moved = 0.0
    for k in range(slave_node.shape[0]):
        if geo[k, GEO_IDLE] == 0.0 and geo[k, GEO_INSIDE] != 0.0:
            sn, a, b = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
            moved = max(moved, vold_c[cnode_slot[sn], CNODE_MOVED], vold_c[cnode_slot[a], CNODE_MOVED],
                        vold_c[cnode_slot[b], CNODE_MOVED])
            vold_c[cnode_slot[sn], CNODE_MOVED] = 0.0
            vold_c[cnode_slot[a], CNODE_MOVED] = 0.0
            vold_c[cnode_slot[b], CNODE_MOVED] = 0.0
    if moved > 0.0:
        for k in range(slave_node.shape[0]):
            if geo[k, GEO_SLEEP] > 0.0:
                geo[k, GEO_SLEEP] = max(geo[k, GEO_SLEEP] - 2.0 * moved, 0.0)


@kernel
def _multiplier_update(par_p, tab, area, mu_k, dt, g, ln, lt, vx, vy, nx, ny, tx, ty, vs, wx, wxy, wy):
    """The projected Gauss-Seidel update of one slave's multipliers ``(ln, lt)`` [N] (:func:`contact_solve`): at
    gap ``g`` [m], relative velocity ``(vx, vy)`` [m s-1] of ``slave - (N0 a + N1 b)``, unit normal and tangent,
    the master's surface velocity ``vs`` along ``t`` and the inverse mass ``(wx, wxy, wy)`` [kg-1] of that relative
    motion (:func:`_pair_compliance`). Returns ``(ln_new, lt_new, state, wn, wt)``: state 0 open, 1 stick, 2 slip,
    and the gap's and the tangential increment's responses [m N-1] to their multipliers."""
    dt2 = dt * dt
    wn = dt2 * (nx * nx * wx + ny * ny * wy + 2.0 * nx * ny * wxy)
    ln_new = _normal_update(int(par_p[LAW]), par_p[LAW_COEFFICIENT], par_p[LAW_EXPONENT], tab, area, g, ln, wn)
    dn = ln_new - ln
    # tangential: relative tangential increment over the step (the master's surface velocity removed),
    # including the normal correction
    rx = vx + dt * dn * nx * wx + dt * dn * ny * wxy
    ry = vy + dt * dn * ny * wy + dt * dn * nx * wxy
    st = dt * (rx * tx + ry * ty - vs)
    wt = dt2 * (tx * tx * wx + ty * ty * wy + 2.0 * tx * ty * wxy)
    lt_new, state = _tangential_update(lt, st, wt, ln_new, mu_k, par_p, dt)
    if ln_new == 0.0:
        state = 0
    return ln_new, lt_new, state, wn, wt


@kernel
def _gauss_seidel_sweep(X, u, v, npd, dt, t_new, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes,
                        pair_par, law_tab, s_area, seg, geo, lam, cstate, mu, cnode_slot, vold_c):
    """One projected Gauss-Seidel sweep over the slaves facing their master and not idle (see
    :func:`contact_solve`; a rigid circle at its radius at ``t_new`` [s]): update each multiplier pair and apply its
    increment at once. Returns the largest displacement [m] an increment moved a node pair by."""
    ns = slave_node.shape[0]
    change = 0.0
    for k in range(ns):
        if geo[k, GEO_INSIDE] == 0.0:
            continue
        p = slave_pair[k]
        sn, a, b = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
        n0 = geo[k, GEO_N0]
        n1 = geo[k, GEO_N1]
        nx = geo[k, GEO_NX]
        ny = geo[k, GEO_NY]
        if geo[k, GEO_IDLE] != 0.0:
            # idle (open, no force, predicted gap beyond the margin): its update changes nothing while its gap is
            # positive, which holds while the corrections moved its nodes by less than the gap (a bound of three
            # loads); else the gap is measured, and a closed one makes it a candidate from here on
            moved = (vold_c[cnode_slot[sn], CNODE_MOVED] + n0 * vold_c[cnode_slot[a], CNODE_MOVED]
                     + n1 * vold_c[cnode_slot[b], CNODE_MOVED])
            if 2.0 * moved < geo[k, GEO_GAP] or _edge_gap(X, u, npd, sn, a, b, n0, n1, nx, ny) > 0.0:
                continue
            geo[k, GEO_IDLE] = 0.0
        tx = geo[k, GEO_TX]
        ty = geo[k, GEO_TY]
        # effective inverse masses along x and y of the relative motion slave - (N0 a + N1 b)
        wx, wxy, wy = _pair_compliance(minv_c, wmat, npd, sn, a, b, n0, n1)
        # normal: gap in the current (predicted + corrected) configuration
        if pair_par[p, MASTER] == MASTER_EDGE:
            g = _edge_gap(X, u, npd, sn, a, b, n0, n1, nx, ny)
        else:
            g = rigid_geometry(int(pair_par[p, MASTER]), pair_par[p, SURFACE_X], pair_par[p, SURFACE_Y],
                               _rigid_a(pair_par[p], t_new), pair_par[p, SURFACE_B], 0.0, 0.0, X[sn], X[sn + npd],
                               X[sn] + u[sn], X[sn + npd] + u[sn + npd])[0]
        ln = lam[k, 0]
        lt = lam[k, 1]
        ln_new, lt_new, state, wn, wt = _multiplier_update(
            pair_par[p], law_tab[p], s_area[k], mu[k], dt, g, ln, lt, v[sn] - n0 * v[a] - n1 * v[b],
            v[sn + npd] - n0 * v[a + npd] - n1 * v[b + npd], nx, ny, tx, ty, geo[k, GEO_SURFACE_VELOCITY], wx, wxy, wy)
        dn = ln_new - ln
        dtn = lt_new - lt
        if dn != 0.0 or dtn != 0.0:  # an open node far from its master (most of them) moves nothing
            _apply_contact_force(u, v, npd, dt, minv_c, wmat, cnode_slot, vold_c, sn, a, b, n0, n1,
                                 dn * nx + dtn * tx, dn * ny + dtn * ty)
        lam[k, 0] = ln_new
        lam[k, 1] = lt_new
        cstate[k] = state
        geo[k, GEO_PENETRATION] = -(g + dn * wn) if pair_par[p, LAW] != LAW_RIGID else 0.0
        # convergence measured as the displacement the last increments moved the node pair by: the
        # positions carry round-off eps |x| ~ 1e-17 m, i.e. multiplier noise eps |x| / (dt^2 w), so a
        # relative multiplier tolerance can be unreachable at small dt
        change = max(change, abs(dn) * wn, abs(dtn) * wt)
    return change


@kernel
def contact_solve(X, u, v, npd, dt, t_new, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes,
                  pair_sign, pair_par, law_tab, s_area, seg, geo, lam, cstate, mu, max_iter, tol, cnode_slot, vold_c,
                  margin, sleep=False):
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
    ``t_new`` [s], the end of the step, and a rigid circle has its radius at ``t_new`` (a radial expansion: the
    gap closes by the radius' growth over the step, which the normal multiplier enforces like any predicted
    penetration; during the expansion the normal work ``W_CN`` contains the expanding master's work). ``wmat`` empty: lumped inverse mass ``minv_c``; else the dense inverse
    mass of the contact dofs of a reduced system (:func:`_apply_contact_force`).

    Nodes are given by their x-index (y-index = x-index + ``npd``). ``lam[k] = (lam_n, lam_t)`` [N] is the
    force on slave ``k`` along ``n`` and ``t``, on entry the previous step's values (warm start: applied first,
    then projected and iterated, so the converged result does not depend on it beyond the tolerance) (the master
    nodes get ``-N_j`` times it); ``cstate[k]`` 0 open, 1 stick, 2 slip; ``geo[k]`` the slave's geometry (columns
    ``GEO_*`` of :mod:`fivid.contact._layout_kernels`). Returns the number of sweeps.

    Candidate slaves (lumped mass, deformable masters): a slave with no force from the previous step whose
    predicted gap exceeds ``margin`` times its segment's length is idle. An open slave's update changes nothing
    (it stays open, no force) as long as its gap is positive, which holds while the corrections have moved its
    nodes by less than that gap: each correction adds its displacement bound ``|dx| + |dy|`` to the nodes it moves
    (``vold_c[:, CNODE_MOVED]``, the contact nodes' slots ``cnode_slot``), so a sweep passes an idle slave after
    three loads, measures its gap only once the bound reaches half the predicted one, and updates it only if that
    gap has closed (it is a candidate from then on). The result is bit-for-bit the one of updating every slave
    (up to the sign of a zero tangential multiplier); ``margin`` infinite: no slave is idle. A reduced system's
    correction moves every dof, so none is there either.

    Sleeping slaves (``sleep`` true, finite ``margin``, lumped mass): most slaves of a rough pair are far from
    their master (a seated 1 um surface touches at a few asperities), and locating each one every step was the
    contact's cost (65 ns per slave and step on the 120 mm pair). A slave with no force whose Euclidean distance
    ``d`` to its whole master edge exceeds :data:`SLEEP_MARGINS` candidate margins, outside the master (its gap
    to the nearest point of the segment it faces or is nearest to exceeds as much; ``d`` measured over the segments
    within one segment length along the edge's direction, :func:`_clearance`; edges that are not sorted along a
    direction are not used) is not located while the contact nodes may have moved relative to each other by less
    than ``d / 2``: each step takes ``dt`` times the largest speed ``|vx| + |vy|`` of the slave nodes plus that of
    the master nodes (:func:`_step_travel`), and after the solve twice the largest correction bound, off its
    budget ``d / 2`` (the distance to a set moves by no more than the point and the set do). While asleep its
    distance stays above ``d / 2 > 2`` margins, so it would be idle and open: it faces no master (``GEO_INSIDE``
    0, its force 0). This rests on ``u`` changing between calls by ``dt v`` plus the corrections (the time
    loop's central difference), and on one step's corrections moving no contact node by ``d / 2`` (a velocity
    jump of ``d / (2 dt)``, 10 m/s for 11.5 um segments at 1 ns); it changes which of several local projections a
    woken slave's walk finds first (its walk starts from its last segment), not a closed slave's force.
    """
    if wmat.shape[0] > 0:
        margin = math.inf
    travel = _step_travel(v, npd, dt, slave_node, master_nodes) if sleep and math.isfinite(margin) else math.inf
    _slave_geometry(X, u, npd, t_new, slave_node, slave_pair, master_ptr, master_nodes, pair_sign, pair_par, seg, geo,
                    lam, margin, travel)
    sweeps = _sweeps(X, u, v, npd, dt, t_new, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes,
                     pair_par, law_tab, s_area, seg, geo, lam, cstate, mu, max_iter, tol, cnode_slot, vold_c)
    if wmat.shape[0] == 0:
        _clear_moved(slave_node, slave_pair, master_ptr, master_nodes, pair_par, seg, geo, cnode_slot, vold_c)
    return sweeps


@kernel
def _sweeps(X, u, v, npd, dt, t_new, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_par, law_tab,
            s_area, seg, geo, lam, cstate, mu, max_iter, tol, cnode_slot, vold_c):
    """The warm start and the projected Gauss-Seidel sweeps of :func:`contact_solve`; returns their number."""
    # warm start: in steady sliding the multipliers change little per step, so the projected Gauss-Seidel needs a
    # few sweeps instead of tens
    _warm_start(u, v, npd, dt, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_par, seg, geo, lam,
                cstate, cnode_slot, vold_c)
    sweeps = 0
    for it in range(max_iter):
        sweeps = it + 1
        change = _gauss_seidel_sweep(X, u, v, npd, dt, t_new, minv_c, wmat, slave_node, slave_pair, master_ptr,
                                     master_nodes, pair_par, law_tab, s_area, seg, geo, lam, cstate, mu, cnode_slot,
                                     vold_c)
        if change <= tol:
            break
    return sweeps


@kernel
def contact_step(X, u, v, npd, dt, t_new, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes, pair_sign,
                 pair_par, law_tab, s_area, seg, geo, lam, cstate, mu_tab, mu_rate, mu_now, max_iter, tol, acc,
                 cnode_slot, vold_c):
    """The friction coefficients at ``t_new`` (:func:`friction_now`), the contact correction
    (:func:`contact_solve`, candidate margin :data:`CANDIDATE_MARGIN`, sleeping slaves) and its Gauss-Seidel statistics in ``acc``."""
    friction_now(mu_tab, mu_rate, t_new, mu_now)
    sweeps = contact_solve(X, u, v, npd, dt, t_new, minv_c, wmat, slave_node, slave_pair, master_ptr, master_nodes,
                           pair_sign, pair_par, law_tab, s_area, seg, geo, lam, cstate, mu_now, max_iter, tol, cnode_slot,
                           vold_c, CANDIDATE_MARGIN, True)
    acc[GS_SWEEPS] += sweeps
    acc[GS_MAX] = max(acc[GS_MAX], sweeps)
    if sweeps >= max_iter:
        acc[GS_CAPPED] += 1.0


@kernel
def contact_work(v, npd, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par, geo, lam, cstate,
                 cnode_slot, vold_c, rec_contact_r):
    """Work / dt of the normal and tangential contact forces and of the rigid surfaces' drive over a step, with
    the mid-step velocities of the contact nodes (``vold_c[:, CNODE_V_STEP:CNODE_V_STEP + 2]`` before the step, ``v`` after); adds each
    pair's forces and state counts to ``rec_contact_r``. Returns ``(wcn, wct, wdr)`` [W]."""
    wcn = 0.0
    wct = 0.0
    wdr = 0.0
    for k in range(slave_node.shape[0]):
        p = slave_pair[k]
        if cstate[k] == 0:
            rec_contact_r[p, REC_OPEN] += 1.0
            continue
        sn, a, b = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
        n0 = geo[k, GEO_N0]
        n1 = geo[k, GEO_N1]
        qs = cnode_slot[sn]
        qa = cnode_slot[a]
        qb = cnode_slot[b]
        c = CNODE_V_STEP
        rx = 0.5 * ((vold_c[qs, c] + v[sn]) - n0 * (vold_c[qa, c] + v[a]) - n1 * (vold_c[qb, c] + v[b]))
        ry = 0.5 * ((vold_c[qs, c + 1] + v[sn + npd]) - n0 * (vold_c[qa, c + 1] + v[a + npd])
                    - n1 * (vold_c[qb, c + 1] + v[b + npd]))
        wcn += lam[k, 0] * (rx * geo[k, GEO_NX] + ry * geo[k, GEO_NY])
        # a rigid master's surface moves at geo[k, GEO_SURFACE_VELOCITY] along t: the friction dissipates on the
        # relative slip and the drive does the rest of the work on the slave
        vs = geo[k, GEO_SURFACE_VELOCITY]
        wct += lam[k, 1] * (rx * geo[k, GEO_TX] + ry * geo[k, GEO_TY] - vs)
        wdr += lam[k, 1] * vs
        rec_contact_r[p, REC_NORMAL] += lam[k, 0]
        rec_contact_r[p, REC_TANGENTIAL] += lam[k, 1]
        rec_contact_r[p, REC_STICK - 1 + cstate[k]] += 1.0
    return wcn, wct, wdr


@kernel
def slave_force(lam, geo, k):
    """The contact force ``(fx, fy)`` [N] on slave ``k``: ``lam_n n + lam_t t`` (its master nodes get ``-N_j`` times
    it)."""
    return (lam[k, 0] * geo[k, GEO_NX] + lam[k, 1] * geo[k, GEO_TX],
            lam[k, 0] * geo[k, GEO_NY] + lam[k, 1] * geo[k, GEO_TY])


@kernel
def contact_reactions(v, npd, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par, geo, lam, cstate,
                      cnode_slot, vold_c, con_cnode, con_react):
    """The part of the constraint reactions that holds contact nodes on constrained dofs against their contact
    forces: their power over the step [W] (mid-step velocities, as :func:`contact_work`) and the transducer sums
    [N]. Returns ``(wext, rt, rn)``.

    A constrained dof has zero inverse mass, so the contact force on it (the slave's ``lam`` along ``n``, ``t``;
    a master node's ``-N_j`` times it) moves nothing: the constraint takes it, ``R = m a + f + alpha m v - F_c``.
    :func:`contact_work` counts that force's work (a driven slave's friction is dissipated), so the imposed
    motion's work must include ``-F_c . v``. ``con_cnode[slot] = (c_x, c_y)``: the constraint index (rows of
    ``con_react``) of a contact node's x and y dof, -1 if free."""
    wext = 0.0
    rt = 0.0
    rn = 0.0
    for k in range(slave_node.shape[0]):
        if cstate[k] == 0:
            continue
        sn, a, b = _segment_nodes(k, slave_node, slave_pair, master_ptr, master_nodes, seg, pair_par)
        fx, fy = slave_force(lam, geo, k)
        n_nodes = 3 if pair_par[slave_pair[k], MASTER] == MASTER_EDGE else 1  # a rigid master has no nodes
        for i in range(n_nodes):
            nd = sn if i == 0 else (a if i == 1 else b)
            weight = 1.0 if i == 0 else -geo[k, GEO_N0] if i == 1 else -geo[k, GEO_N1]
            q = cnode_slot[nd]
            for comp in range(2):
                c = con_cnode[q, comp]
                if c < 0:
                    continue
                force = weight * (fx if comp == 0 else fy)
                vm = 0.5 * (vold_c[q, CNODE_V_STEP + comp] + v[nd + comp * npd])
                wext -= force * vm
                rt -= con_react[c, 0] * force
                rn -= con_react[c, 1] * force
    return wext, rt, rn


@kernel
def finish_contact_record(slave_pair, pair_par, law_tab, s_area, geo, cstate, n_sub, rec_contact_r):
    """Turn an interval's contact sums into averages and fractions; returns the energy stored in the compliant
    normal laws [J]."""
    epen = 0.0
    for k in range(slave_pair.shape[0]):
        p = slave_pair[k]
        if pair_par[p, LAW] != LAW_RIGID and cstate[k] != 0:
            epen += s_area[k] * normal_energy(int(pair_par[p, LAW]), pair_par[p, LAW_COEFFICIENT],
                                              pair_par[p, LAW_EXPONENT], geo[k, GEO_PENETRATION], law_tab[p])
    for p in range(rec_contact_r.shape[0]):
        cnt = rec_contact_r[p, REC_STICK] + rec_contact_r[p, REC_SLIP] + rec_contact_r[p, REC_OPEN]
        rec_contact_r[p, REC_NORMAL] /= n_sub
        rec_contact_r[p, REC_TANGENTIAL] /= n_sub
        if cnt > 0.0:
            for c in range(REC_STICK, REC_OPEN + 1):
                rec_contact_r[p, c] /= cnt
    return epen
