"""The contact search of the explicit solver (issue 26 item 5) against a reference implementation.

The reference is the master-segment walk as it was before its alternation short-cut (fivid 978d7a7,
:func:`fivid.solver._contact_kernels._locate`), written here in plain Python: from the slave's previous segment,
step to the neighbour while the projection falls before or beyond the segment, for at most ``nseg + 1``
projections. The kernel must give bit-for-bit the same segment, shape values, normal and inside flag on synthetic
rough masters (Gaussian-random heights; many convex vertices, where the walk alternates) with slaves started from
segments anywhere along the edge (a slave that slid past many segments since its last search).
"""

import math

import numpy as np
import pytest

from fivid.solver._contact_kernels import _locate


def _locate_reference(X, u, npd, sn, mnodes, m0, nseg, seg_k, sign):
    """The pre-short-cut walk (plain Python, same arithmetic in the same order); returns its result and the number
    of projections it made."""
    xs = X[sn] + u[sn]
    ys = X[sn + npd] + u[sn + npd]
    s = min(max(seg_k, 0), nseg - 1)
    xi = ex = ey = 0.0
    n = 0
    for _ in range(nseg + 1):
        n += 1
        a = mnodes[m0 + s]
        b = mnodes[m0 + s + 1]
        xa = X[a] + u[a]
        ya = X[a + npd] + u[a + npd]
        ex = X[b] + u[b] - xa
        ey = X[b + npd] + u[b + npd] - ya
        xi = ((xs - xa) * ex + (ys - ya) * ey) / (ex * ex + ey * ey)
        if xi < 0.0 and s > 0:
            s -= 1
        elif xi > 1.0 and s < nseg - 1:
            s += 1
        else:
            break
    L = math.sqrt(ex * ex + ey * ey)
    tx, ty = ex / L, ey / L
    inside = -1e-6 <= xi <= 1.0 + 1e-6
    xi = min(max(xi, 0.0), 1.0)
    return (s, xi, sign * ty, -sign * tx, tx, ty, inside), n


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


@pytest.mark.parametrize("nseg", [1, 2, 3, 50, 401])
@pytest.mark.parametrize("lift_in_rq", [-1.0, 0.0, 3.0, 30.0])
def test_walk_matches_reference_on_rough_masters(nseg, lift_in_rq):
    rng = np.random.default_rng(nseg * 100 + int(10 * lift_in_rq) + 7)
    spacing, rq = 11.5e-6, 2e-6
    X, u, npd, snodes, mnodes = _rough_edge(rng, nseg, spacing, rq, 300, lift_in_rq * rq)
    alternated = 0  # walks that used their whole budget (alternation at a convex vertex)
    for sn in snodes:
        for start in (0, nseg - 1, int(rng.integers(0, nseg)), int(rng.integers(-3, nseg + 3))):
            for sign in (1.0, -1.0):
                got = _locate(X, u, npd, sn, mnodes, 0, nseg, start, sign)
                ref, n = _locate_reference(X, u, npd, sn, mnodes, 0, nseg, start, sign)
                assert got == ref, (sn, start, got, ref)
                alternated += n == nseg + 1
    if nseg > 3 and lift_in_rq > 0:
        assert alternated > 0  # slaves facing convex vertices: the short-cut was exercised


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
