"""The contact search of the explicit solver (issue 26 items 1 and 5) against a brute-force nearest point.

The oracle is the definition itself, computed by brute force in plain Python: the distance from the slave to every
segment of the master polyline (clamped foot points), its minimum, and the side the slave is on (above or below the
polyline's height at its x, by the pair's orientation). The kernel's walk (:func:`fivid.solver._contact_kernels._locate`,
started from any segment) must return a master point at that distance for every penetrating slave (under concave
vertices too, where the projection falls beyond both segments) and for every slave over a convex vertex, and never a
point nearer than the nearest for an open one; the slave must lie on the returned normal through the returned point
(``x_s = x_p + g n``).
"""

import math

import numpy as np
import pytest

from fivid.solver._contact_kernels import _edge_gap, _locate


def _nearest_reference(xs, ys, px, py, sign):
    """``(distance [m], outside, at_vertex)``: the brute-force distance from ``(xs, ys)`` to the polyline ``(px, py)``
    (x increasing), whether the slave is on the outward side (``sign`` -1: above the polyline, +1: below) and whether
    the nearest point is an interior vertex with the slave beyond both segments meeting there."""
    best, vertex = math.inf, False
    for j in range(px.size - 1):
        ex, ey = px[j + 1] - px[j], py[j + 1] - py[j]
        t = ((xs - px[j]) * ex + (ys - py[j]) * ey) / (ex * ex + ey * ey)
        tc = min(max(t, 0.0), 1.0)
        d = math.hypot(xs - px[j] - tc * ex, ys - py[j] - tc * ey)
        if d < best:
            best, vertex = d, (t > 1.0 and j < px.size - 2) or (t < 0.0 and j > 0)
    above = ys > np.interp(xs, px, py)
    return best, above == (sign < 0), vertex


def _rough_edge(rng, nseg, spacing, rq, n_slaves, lift):
    """Synthetic rough master (``nseg`` segments of ``spacing`` [m] along x, heights N(0, rq)) and slaves at random
    x above it (``lift`` [m] plus their own random heights), in the kernel layout: ``(X, u, npd, slave indices,
    master indices)``; u is a random small displacement field."""
    nm = nseg + 1
    npd = nm + n_slaves + 4
    X = np.zeros(2 * npd)
    u = np.zeros(2 * npd)
    mnodes = np.arange(2, 2 + nm)
    X[mnodes] = np.arange(nm) * spacing
    X[mnodes + npd] = rng.normal(0.0, rq, nm)
    snodes = np.arange(2 + nm, 2 + nm + n_slaves)
    X[snodes] = rng.uniform(-2 * spacing, (nseg + 2) * spacing, n_slaves)  # some beyond the edge's ends
    X[snodes + npd] = lift + rng.normal(0.0, rq, n_slaves)
    u[:] = rng.normal(0.0, 1e-3 * spacing, 2 * npd)
    u[:2] = u[-2:] = 0.0
    return X, u, npd, snodes, mnodes


@pytest.mark.parametrize("nseg", [2, 3, 50, 401])
@pytest.mark.parametrize("lift_in_rq", [-0.5, 0.0, 0.5, 3.0])
def test_walk_finds_the_nearest_master_point(nseg, lift_in_rq):
    rng = np.random.default_rng(nseg * 100 + int(10 * lift_in_rq) + 7)
    spacing, rq = 11.5e-6, 2e-6
    X, u, npd, snodes, mnodes = _rough_edge(rng, nseg, spacing, rq, 300, 0.0)
    px, py = X[mnodes] + u[mnodes], X[mnodes + npd] + u[mnodes + npd]
    # slaves near the surface: its height at their x, plus the lift and a scatter of Rq / 4
    X[snodes + npd] = (np.interp(X[snodes] + u[snodes], px, py) - u[snodes + npd] + lift_in_rq * rq
                       + rng.normal(0.0, rq / 4, snodes.size))
    seen = {"penetrating": 0, "under a concave vertex": 0, "over a convex vertex": 0, "beyond the ends": 0}
    for sn in snodes:
        xs, ys = X[sn] + u[sn], X[sn + npd] + u[sn + npd]
        for start in (0, nseg - 1, int(rng.integers(0, nseg)), int(rng.integers(-3, nseg + 3))):
            for sign in (1.0, -1.0):
                s, xi, nx, ny, tx, ty, inside = _locate(X, u, npd, sn, mnodes, 0, nseg, start, sign)
                if not px[0] + spacing <= xs <= px[-1] - spacing:  # a slave near an end may face the end node
                    if not px[0] - spacing <= xs <= px[-1] + spacing:
                        seen["beyond the ends"] += 1
                        assert not inside
                    continue
                d, outside, at_vertex = _nearest_reference(xs, ys, px, py, sign)
                assert inside
                a, b = mnodes[s], mnodes[s + 1]
                g = _edge_gap(X, u, npd, sn, a, b, 1.0 - xi, xi, nx, ny)
                assert math.hypot(nx, ny) == pytest.approx(1.0, abs=1e-14)
                assert (tx, ty) == pytest.approx((-sign * ny, sign * nx), abs=1e-14)
                # the slave sits on the normal through its master point, at the gap (float resolution of x ~ 1e-3 m)
                xp = (1 - xi) * (X[a] + u[a]) + xi * (X[b] + u[b])
                yp = (1 - xi) * (X[a + npd] + u[a + npd]) + xi * (X[b + npd] + u[b + npd])
                assert (xs - xp, ys - yp) == pytest.approx((g * nx, g * ny), abs=1e-15)
                if not outside:
                    assert g == pytest.approx(-d, rel=1e-9, abs=1e-16), (sn, start, sign)
                    seen["penetrating"] += 1
                    seen["under a concave vertex"] += at_vertex
                else:
                    assert g >= d * (1 - 1e-9) - 1e-16
                    if at_vertex:
                        assert g == pytest.approx(d, rel=1e-9, abs=1e-16)
                        seen["over a convex vertex"] += 1
    if nseg > 3 and lift_in_rq <= 0:
        assert seen["under a concave vertex"] > 0 and seen["penetrating"] > 0, seen
    if nseg > 3 and lift_in_rq >= 0:
        assert seen["over a convex vertex"] > 0, seen


def _solve_state(rng, nseg, law, law_coefficient):
    """A rough lower body's edge (master, ``nseg`` segments of 11.5 um, Rq 2 um, unit-ish masses) under a rough
    slave edge of twice as many nodes lowered so that about a tenth of the slaves penetrate: the arguments of
    :func:`contact_solve` as a dict (lumped inverse mass, one pair, Coulomb mu 0.2 with a static excess)."""
    from fivid.contact._layout_kernels import LAW, LAW_COEFFICIENT, MU_STATIC_EXCESS, N_CNODE, N_GEO, NPAR

    spacing, rq = 11.5e-6, 2e-6
    ns = 2 * nseg
    X, u, npd, snodes, mnodes = _rough_edge(rng, nseg, spacing, rq, ns, 0.0)
    X[snodes] = np.sort(X[snodes])
    zm = np.interp(X[snodes], X[mnodes], X[mnodes + npd])
    X[snodes + npd] = zm + rng.normal(1.3 * rq, rq, ns)
    cnodes = np.concatenate([mnodes, snodes])
    cnode_slot = np.full(npd, -1, dtype=np.int64)
    cnode_slot[cnodes] = np.arange(cnodes.size)
    minv = np.zeros(2 * npd)
    minv[np.concatenate([cnodes, cnodes + npd])] = rng.uniform(0.5, 2.0, 2 * cnodes.size) * 1e4  # 1/kg
    par = np.zeros((1, NPAR))
    par[0, LAW] = law
    par[0, LAW_COEFFICIENT] = law_coefficient
    par[0, MU_STATIC_EXCESS] = 0.05
    seg = np.array([int(np.argmin(np.abs(0.5 * (X[mnodes[:-1]] + X[mnodes[1:]]) - x))) for x in X[snodes]])
    return dict(X=X, u=u, v=rng.normal(0.0, 1e-3, 2 * npd), npd=npd, dt=1e-9, t_new=0.0, minv_c=minv,
                wmat=np.zeros((0, 0)), slave_node=snodes.astype(np.int64), slave_pair=np.zeros(ns, dtype=np.int64),
                master_ptr=np.array([0, nseg + 1], dtype=np.int64), master_nodes=mnodes.astype(np.int64),
                pair_sign=np.array([-1.0]), pair_par=par, law_tab=np.zeros((1, 2, 2)), s_area=np.full(ns, 1e-7),
                seg=seg.astype(np.int64), geo=np.zeros((ns, N_GEO)), lam=np.zeros((ns, 2)),
                cstate=np.zeros(ns, dtype=np.int64), mu=np.full(ns, 0.2), max_iter=200, tol=1e-12 * spacing,
                cnode_slot=cnode_slot, vold_c=np.zeros((cnodes.size, N_CNODE)))


@pytest.mark.parametrize("law, coefficient", [(0, 0.0), (1, 1e17)])  # rigid; linear, 1e17 Pa/m
def test_candidate_sweeps_match_sweeping_all_slaves(law, coefficient):
    """The contact solve with idle slaves left out (the default margin) against the plain algorithm (infinite
    margin: every slave swept), over steps in which the slave edge slides past many master segments (the search
    starts from the previous segment each time) with the multipliers warm-started: bit-for-bit the same
    positions, velocities, multipliers, states, segments and geometry, with most slaves idle."""
    from fivid.contact._layout_kernels import CNODE_MOVED, GEO_IDLE, GEO_PENETRATION
    from fivid.solver._contact_kernels import CANDIDATE_MARGIN, contact_solve

    rng = np.random.default_rng(law)
    nseg = 300
    base = _solve_state(rng, nseg, law, coefficient)
    runs = {m: {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in base.items()}
            for m in (CANDIDATE_MARGIN, np.inf)}
    calm = closed = 0
    for step in range(12):
        # every fourth step the slave edge slides past ~7 segments onto fresh asperities (large corrections: idle
        # slaves next to them are measured and some close); in between, small motions
        slide = step % 4 == 1
        shift = rng.normal(0.0, 3e-8 if slide else 1e-11, 2 * base["npd"])
        if slide:
            shift[base["slave_node"]] += 7.3 * 11.5e-6
        out = {}
        for m, st in runs.items():
            st["u"] += shift
            out[m] = contact_solve(*st.values(), m, False)
        a, b = runs[CANDIDATE_MARGIN], runs[np.inf]
        assert out[CANDIDATE_MARGIN] == out[np.inf]
        for key in ("u", "v", "lam", "cstate", "seg"):
            np.testing.assert_array_equal(a[key], b[key], err_msg=f"step {step}: {key}")
        shut = a["cstate"] != 0
        cols = [c for c in range(a["geo"].shape[1]) if c not in (GEO_IDLE, GEO_PENETRATION)]
        np.testing.assert_array_equal(a["geo"][:, cols], b["geo"][:, cols])
        np.testing.assert_array_equal(a["geo"][shut, GEO_PENETRATION], b["geo"][shut, GEO_PENETRATION])
        assert not a["vold_c"][:, CNODE_MOVED].any()  # the bounds are cleared after each solve
        assert not b["geo"][:, GEO_IDLE].any()
        calm += a["geo"][:, GEO_IDLE].sum() > 0.5 * shut.size
        closed += int(shut.sum())
    assert closed > 0 and calm >= 10, (closed, calm)


@pytest.mark.parametrize("law, coefficient", [(0, 0.0), (1, 1e17)])  # rigid; linear, 1e17 Pa/m
def test_sleeping_slaves_change_no_force(law, coefficient):
    """Sleeping slaves (the time loop's contact solve) against the plain algorithm (infinite margin: every slave
    located and swept) over steps that move the nodes as the time loop does (``u += dt v``, then the solve): the
    slave edge slides along the master at a steady speed (past 2.4 segments in all) and sinks onto it, with small
    random velocities. Bit-for-bit the same positions, velocities, multipliers and states at every step, while
    most slaves sleep; slaves wake and close (the closed set changes)."""
    from fivid.contact._layout_kernels import GEO_SLEEP
    from fivid.solver._contact_kernels import CANDIDATE_MARGIN, contact_solve

    rng = np.random.default_rng(10 + law)
    nseg = 300
    base = _solve_state(rng, nseg, law, coefficient)
    base["u"][:] = 0.0
    npd, dt, sn = base["npd"], base["dt"], base["slave_node"]
    runs = {m: {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in base.items()}
            for m in (CANDIDATE_MARGIN, np.inf)}
    asleep, closed_sets = [], set()
    for step in range(60):
        jitter = rng.normal(0.0, 0.3, 2 * npd)  # m/s: 0.3 nm per step
        for m, st in runs.items():
            v = st["v"]
            v += jitter
            v[sn] += 0.04 * 11.5e-6 / dt  # 0.04 segment per step along x
            v[sn + npd] -= 0.05e-6 / dt  # sinking 0.05 um per step (3 um = 1.5 Rq in all)
            st["u"] += dt * v
            contact_solve(*st.values(), m, m != np.inf)
            v[sn] -= 0.04 * 11.5e-6 / dt
            v[sn + npd] += 0.05e-6 / dt
        a, b = runs[CANDIDATE_MARGIN], runs[np.inf]
        for key in ("u", "v", "lam", "cstate"):
            np.testing.assert_array_equal(a[key], b[key], err_msg=f"step {step}: {key}")
        asleep.append(float(np.mean(a["geo"][:, GEO_SLEEP] > 0.0)))
        closed_sets.add(tuple(np.flatnonzero(a["cstate"])))
        assert not b["geo"][:, GEO_SLEEP].any()
    assert max(asleep) > 0.5 and len(closed_sets) > 10, (asleep, len(closed_sets))
