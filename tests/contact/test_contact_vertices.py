"""Node-to-segment contact at the vertices of a piecewise-linear master (issue 26 item 1).

A slave under a concave master vertex (a valley of a rough master) projects beyond both segments meeting there;
it used to carry no force however deep it went (19 % of the lifted Ra 1 pair's slaves). The definition now is the
closest point (:func:`fivid.contact._kernels.vertex_geometry`): the gap is the signed distance to the nearest
master point, so such a slave's penetration is its distance to the vertex. Oracles: the one-slave closed forms of
the explicit solver's contact correction (:func:`fivid.solver._contact_kernels.contact_solve`): rigid law
``lam = d / (dt^2 w)`` with ``w`` the relative inverse mass along the normal, linear law ``lam = A c d / (1 + A c
dt^2 w)``; the signed distance's Lipschitz bound (``|dg| <= |dx|``) along a slide across a vertex; a brute-force
signed distance on Table 1's Ra 1 surfaces; the static solve's projection (:func:`fivid.fe.static.contact_geometry`)
on conformal triangular profiles, where every slave's penetration is known in closed form.
"""

import math

import numpy as np
import pytest

from fivid.contact._layout_kernels import LAW, LAW_COEFFICIENT, N_CNODE, N_GEO, NPAR
from fivid.solver._contact_kernels import _edge_gap, _locate, contact_solve

DT = 1e-9  # s
M_SLAVE = 2e-6  # kg


def _system(master_xy, slave_xy, *, sign, m_master=math.inf, law=0, coefficient=0.0, area=1e-7):
    """One slave over a master polyline in the kernel layout (nodes 1.. with one pad node each side; the master
    listed in ``master_xy``'s order, ``sign`` its orientation): the arguments of :func:`contact_solve` as a dict.
    Master nodes of inverse mass ``1 / m_master`` (inf: held), slave ``1 / M_SLAVE``; Coulomb mu 0.2; at rest."""
    master_xy = np.asarray(master_xy, float)
    nm = master_xy.shape[0]
    npd = nm + 3
    X = np.zeros(2 * npd)
    mnodes = np.arange(1, 1 + nm)
    sn = 1 + nm
    X[mnodes], X[mnodes + npd] = master_xy[:, 0], master_xy[:, 1]
    X[sn], X[sn + npd] = slave_xy
    cnodes = np.append(mnodes, sn)
    cnode_slot = np.full(npd, -1, dtype=np.int64)
    cnode_slot[cnodes] = np.arange(cnodes.size)
    minv = np.zeros(2 * npd)
    minv[[sn, sn + npd]] = 1.0 / M_SLAVE
    minv[np.concatenate([mnodes, mnodes + npd])] = 0.0 if math.isinf(m_master) else 1.0 / m_master
    par = np.zeros((1, NPAR))
    par[0, LAW] = law
    par[0, LAW_COEFFICIENT] = coefficient
    return dict(X=X, u=np.zeros(2 * npd), v=np.zeros(2 * npd), npd=npd, dt=DT, t_new=0.0, minv_c=minv,
                wmat=np.zeros((0, 0)), slave_node=np.array([sn]), slave_pair=np.zeros(1, dtype=np.int64),
                master_ptr=np.array([0, nm]), master_nodes=mnodes.astype(np.int64), pair_sign=np.array([sign]),
                pair_par=par, law_tab=np.zeros((1, 2, 2)), s_area=np.full(1, area), seg=np.zeros(1, dtype=np.int64),
                geo=np.zeros((1, N_GEO)), lam=np.zeros((1, 2)), cstate=np.zeros(1, dtype=np.int64),
                mu=np.full(1, 0.2), max_iter=200, tol=1e-22, cnode_slot=cnode_slot,
                vold_c=np.zeros((cnodes.size, N_CNODE)))


def _oriented(nodes):
    """The master's node order and orientation sign for an outward normal pointing up (+y): left to right with
    sign -1, or right to left with sign +1 (the body edges' counter-clockwise order)."""
    return [(list(nodes), -1.0), (list(nodes)[::-1], 1.0)]


L, H = 10e-6, 3e-6  # flank run and rise [m]: slope 0.3
VALLEY = [(-L, H), (0.0, 0.0), (L, H)]  # concave vertex at the origin (seen from the slave above)
PEAK = [(-L, -H), (0.0, 0.0), (L, -H)]  # convex vertex at the origin


@pytest.mark.parametrize("order", [0, 1])
@pytest.mark.parametrize("x0", [0.0, 0.2e-6, -0.25e-6])  # inside the wedge |x0| < delta H / L = 0.3 um
@pytest.mark.parametrize("law, coefficient", [(0, 0.0), (1, 1e17)])  # rigid; linear 1e17 Pa/m
def test_slave_under_a_concave_vertex_gets_the_closed_form_force(order, x0, law, coefficient):
    delta = 1e-6
    nodes, sign = _oriented(VALLEY)[order]
    st = _system(nodes, (x0, -delta), sign=sign, law=law, coefficient=coefficient)
    contact_solve(*st.values(), np.inf, False)
    d = math.hypot(x0, delta)  # penetration: the distance to the vertex
    w = DT**2 / M_SLAVE
    lam = d / w if law == 0 else 1e-7 * coefficient * d / (1.0 + 1e-7 * coefficient * w)
    assert st["lam"][0, 0] == pytest.approx(lam, rel=1e-9)
    assert st["lam"][0, 1] == pytest.approx(0.0, abs=1e-9 * lam)  # at rest: stuck, no tangential force
    # the force acts along the line from the vertex to the slave: it moves the slave straight toward the vertex
    sn, npd = st["slave_node"][0], st["npd"]
    moved = np.array([st["u"][sn], st["u"][sn + npd]])
    assert moved == pytest.approx(lam * w * np.array([-x0, delta]) / d, rel=1e-9, abs=1e-9 * d)


@pytest.mark.parametrize("order", [0, 1])
def test_elastic_master_vertex_node_takes_the_reaction(order):
    """A deformable master: only the vertex node carries the reaction (the slave's master point is the vertex), the
    multiplier closes the relative gap ``d = lam dt^2 (1/m_s + 1/m_m)``, momentum is conserved."""
    delta, m_master = 1e-6, 5e-6
    nodes, sign = _oriented(VALLEY)[order]
    st = _system(nodes, (0.0, -delta), sign=sign, m_master=m_master)
    contact_solve(*st.values(), np.inf, False)
    lam = delta / (DT**2 * (1.0 / M_SLAVE + 1.0 / m_master))
    assert st["lam"][0, 0] == pytest.approx(lam, rel=1e-9)
    npd, sn, mn = st["npd"], st["slave_node"][0], st["master_nodes"]
    vy = st["v"][npd:]
    assert vy[sn] == pytest.approx(lam * DT / M_SLAVE, rel=1e-9)
    vertex = mn[1]
    assert vy[vertex] == pytest.approx(-lam * DT / m_master, rel=1e-9)
    assert not st["v"][mn[[0, 2]]].any() and not vy[mn[[0, 2]]].any()  # the flanks' far nodes: no force
    assert M_SLAVE * vy[sn] + m_master * vy[vertex] == pytest.approx(0.0, abs=1e-12 * M_SLAVE * vy[sn])


@pytest.mark.parametrize("order", [0, 1])
@pytest.mark.parametrize("x0", [0.3e-6, -0.1e-6])
def test_slave_under_a_convex_vertex_gets_one_force_from_the_nearer_flank(order, x0):
    """Under a convex vertex the slave projects onto both flanks: it takes one multiplier, the closed form of the
    flank with the smaller penetration (the signed distance), along that flank's normal -- not two."""
    delta = 1e-6
    nodes, sign = _oriented(PEAK)[order]
    st = _system(nodes, (x0, -delta), sign=sign)
    contact_solve(*st.values(), np.inf, False)
    s = math.hypot(L, H)
    n_near = np.array([H * np.sign(x0), L]) / s  # outward normal of the flank on the slave's side
    d = -(x0 * n_near[0] - delta * n_near[1])  # its penetration, the smaller of the two
    assert d == pytest.approx(min(delta * L / s - abs(x0) * H / s, delta * L / s + abs(x0) * H / s))
    lam = d * M_SLAVE / DT**2
    assert st["lam"][0, 0] == pytest.approx(lam, rel=1e-9)
    sn, npd = st["slave_node"][0], st["npd"]
    # the slave's whole velocity change is that one force along the near flank's normal
    assert np.array([st["v"][sn], st["v"][sn + npd]]) == pytest.approx(lam * DT / M_SLAVE * n_near, rel=1e-9)


@pytest.mark.parametrize("master", ["valley", "peak"])
@pytest.mark.parametrize("order", [0, 1])
def test_gap_is_continuous_as_a_slave_slides_across_a_vertex(master, order):
    """A slave at a fixed depth below the vertex slid across it under both flanks: it faces its master
    all the way, its gap is the (negative) signed distance -- 1-Lipschitz in its position, no jump, never 0 --
    and equals the closed form at the vertex (the depth under a valley; under a peak the flank distance)."""
    delta = 0.5e-6
    nodes, sign = _oriented(VALLEY if master == "valley" else PEAK)[order]
    reach = 0.5 * L if master == "valley" else 0.9 * delta * L / H  # under the peak's flanks all the way
    xs = np.linspace(-reach, reach, 2001)
    st = _system(nodes, (0.0, -delta), sign=sign)
    X, u, npd, sn, mn = st["X"], st["u"], st["npd"], st["slave_node"][0], st["master_nodes"]
    gaps, seg = [], 0
    for x in xs:
        X[sn] = x
        seg, xi, nx, ny, _, _, inside = _locate(X, u, npd, sn, mn, 0, 2, seg, sign)
        assert inside
        gaps.append(_edge_gap(X, u, npd, sn, mn[seg], mn[seg + 1], 1.0 - xi, xi, nx, ny))
    gaps = np.array(gaps)
    assert (gaps < 0).all()
    assert np.abs(np.diff(gaps)).max() <= (xs[1] - xs[0]) * (1 + 1e-9)
    mid = gaps[xs.size // 2]
    assert mid == pytest.approx(-delta if master == "valley" else -delta * L / math.hypot(L, H), rel=1e-9)


def _table1_pair(lower, upper, interference):
    """Table 1's surfaces as a master (the lower profile's samples, listed right to left: sign +1, outward normal
    up; held) and a slave edge (the upper profile at the same x, its end samples dropped, lowered onto the lower one
    until it touches and then by ``interference`` [m]): ``(arguments of contact_solve, slave x, slave y, master x,
    master y)``, the master's coordinates left to right."""
    x = lower["x"].values
    zl, zu = lower.values, np.interp(x, upper["x"].values, upper.values)
    xs, ys = x[1:-1], (zu + np.max(zl - zu) - interference)[1:-1]
    st = _system(np.column_stack([x, zl])[::-1], (0.0, 0.0), sign=1.0)
    nm, n = x.size, xs.size
    npd = nm + n + 2
    X = np.zeros(2 * npd)
    mnodes = np.arange(1, 1 + nm)
    snodes = np.arange(1 + nm, 1 + nm + n)
    X[mnodes], X[mnodes + npd] = x[::-1], zl[::-1]
    X[snodes], X[snodes + npd] = xs, ys
    cnodes = np.concatenate([mnodes, snodes])
    slot = np.full(npd, -1, dtype=np.int64)
    slot[cnodes] = np.arange(cnodes.size)
    minv = np.zeros(2 * npd)
    minv[np.concatenate([snodes, snodes + npd])] = 1.0 / M_SLAVE
    st.update(X=X, u=np.zeros(2 * npd), v=np.zeros(2 * npd), npd=npd, minv_c=minv, slave_node=snodes,
              slave_pair=np.zeros(n, dtype=np.int64), master_ptr=np.array([0, nm]), master_nodes=mnodes,
              s_area=np.full(n, 1e-7), seg=(nm - 2 - np.arange(1, n + 1)).astype(np.int64),
              geo=np.zeros((n, N_GEO)), lam=np.zeros((n, 2)), cstate=np.zeros(n, dtype=np.int64),
              mu=np.full(n, 0.2), cnode_slot=slot, vold_c=np.zeros((cnodes.size, N_CNODE)))
    return st, xs, ys, x, zl


def test_every_penetrating_slave_of_the_table1_pair_carries_force():
    """Table 1's Ra 1 surfaces (seed 003's Rsm 92 um; profile seeds 3 and 4, sampled and meshed at Rsm/8 as the
    study's pair, both surfaces at the same x) pressed 6 um past first touch: every slave whose brute-force signed
    distance to the master is negative carries a normal multiplier. Before the vertex definition 10.7 % of them
    (9 of 84) carried none: the slaves under concave master vertices."""
    from fivid.surface.rough_pair import table1_profiles

    lower, upper = table1_profiles(1e-6, 4e-3, seeds=(3, 4), step=92e-6 / 8)
    st, xs, ys, ax, ay = _table1_pair(lower, upper, 6e-6)
    contact_solve(*st.values(), np.inf, False)
    pen, under_vertex = [], []
    for k in range(xs.size):
        segs = np.column_stack([ax[:-1], ay[:-1], ax[1:], ay[1:]])
        ex, ey = segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]
        t = ((xs[k] - segs[:, 0]) * ex + (ys[k] - segs[:, 1]) * ey) / (ex**2 + ey**2)
        below = ys[k] < np.interp(xs[k], ax, ay)
        if below:
            pen.append(k)
            under_vertex.append(not ((t >= 0) & (t <= 1)).any())
    pen = np.array(pen)
    assert pen.size > 50 and np.sum(under_vertex) > 5  # the case arises, often
    forceless = np.mean(st["lam"][pen, 0] <= 0.0)
    assert forceless == 0.0, f"{forceless:.1%} of the penetrating slaves carry no force"


def test_static_projection_uses_the_same_vertex_definition():
    """The static preload's projection (:func:`fivid.fe.static.contact_geometry`, also the modal/CEA
    linearisation's) on ``rough_pair_short.yaml`` with conformal triangular profiles (1 mm period, 10 um amplitude,
    mesh nodes at peaks, flanks' middles and valleys, both bodies at the same x), the upper body moved down by
    ``delta``: under a valley (concave vertex) the gap is ``-delta`` with the normal straight up (it had no master:
    gap inf), under a peak or a flank ``-delta cos(theta)`` along the flank's normal."""
    from pathlib import Path

    from fivid.fe import load_model
    from fivid.fe.rough_pair import rough_pair_config
    from fivid.fe.static import contact_geometry
    from fivid.surface import make_profile

    base = Path(__file__).resolve().parents[2] / "configs" / "models" / "rough_pair_short.yaml"
    period, amp, delta = 1e-3, 10e-6, 1e-6
    x = np.linspace(0.0, 20e-3, 321)
    z = amp * (4.0 * np.abs((x / period) % 1.0 - 0.5) - 1.0)  # peaks at whole periods, valleys half way
    prof = make_profile(x, z, attrs={"synthetic": "yes", "generator": "triangle wave (this test)"})
    cfg, info = rough_pair_config(base, prof, prof)
    model = load_model(cfg)
    pair = model.contacts[0]
    u = np.zeros(model.n_dofs)
    upper = model.block(info["upper_body"])
    nodes = upper.node_offset + np.arange(upper.n_nodes)
    u[2 * nodes + 1] = -delta
    geo = contact_geometry(model, u)
    xs = model.coords[geo.slave_node, 0]
    phase = (xs / period) % 1.0
    valley = np.isclose(phase, 0.5, atol=1e-6)
    assert np.array_equal(geo.slave_node, np.asarray(pair.slave_nodes)) and valley.sum() >= 10
    cos_t = (period / 4) / math.hypot(period / 4, amp)  # flank: drops amp per quarter period
    np.testing.assert_allclose(geo.gap[valley], -delta, rtol=1e-9)
    np.testing.assert_allclose(geo.normal[valley], np.tile([0.0, 1.0], (valley.sum(), 1)), atol=1e-9)
    np.testing.assert_allclose(geo.gap[~valley], -delta * cos_t, rtol=1e-6)
    np.testing.assert_allclose(np.abs(geo.normal[~valley, 1]), cos_t, rtol=1e-6)
