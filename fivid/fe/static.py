"""Static contact solve: the loading-clamp displacement that gives a target normal load, and the contact state.

Chosen method (DESIGN §5 "preload by the loading clamp"): a linear static solve of the model with
unilateral contact, tied tangentially where Coulomb's cone allows it (the contact sticks while the clamp
comes down: the tip of a bent beam would otherwise slide and the frictionless solve underestimates the
stiffness by a few per cent), by an active-set method on the node-to-segment gaps linearised in the
reference configuration. With the clamp displacement ``delta`` along the load motion's direction and
every other constrained dof at rest, the solution for a fixed active set is affine in ``delta``
(``u = u_a + delta u_b``), so is the transducer's normal reaction ``F(delta) = F_a + delta F_b``:
``delta`` follows in closed form, and the active set is updated (add penetrating nodes, drop nodes in
tension; a tied node whose tangential multiplier leaves the cone ``|lam_t| <= mu lam_n`` slips on it,
``lam_t = sign * mu lam_n``) until it repeats. Friction is path dependent, so this is the state of a clamp
lowered monotonically from a stress-free contact, which is what the ramp does.
The explicit run (:mod:`fivid.solver`) then ramps the clamp to ``delta`` smoothly and lets it settle;
friction (stick during the preload) changes the normal load slightly, and the simulated
``normal_force`` records what the transducer actually sees. Modal analysis and CEA
(:mod:`fivid.fe.modal`, :mod:`fivid.fe.cea`) linearise about this state: contact springs only at the
closed slave nodes (DESIGN §4, "linearise about the sliding equilibrium").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError
from fivid.fe.assembly import stiffness_matrix
from fivid.fe.contact_nodes import node_stiffness, slave_areas
from fivid.fe.loads import external_load_vector
from fivid.friction.curve import slave_coefficients

__all__ = ["ContactGeometry", "contact_geometry", "Preload", "preload_displacement", "preload_state",
           "expanding_circles", "pressed_by_itself", "resolve_expansions"]


@dataclass(frozen=True)
class ContactGeometry:
    """Slave nodes of all pairs with their master segment (or rigid surface) in the reference configuration.

    Attributes
    ----------
    slave_node, slave_pair, segment : ndarray of int, shape (n_slave,)
        Global slave node, pair index and master segment index (``-1``: no segment under the node, or a
        rigid master).
    xi : ndarray, shape (n_slave,)
        Position on the segment, 0 at its first node, 1 at its second.
    normal : ndarray, shape (n_slave, 2)
        Outward unit normal of the master (segment or rigid surface); the tangent is ``t = (-n_y, n_x)``.
    gap : ndarray, shape (n_slave,)
        Initial normal gap [m] (negative: penetration; inf: no master under the node).
    area : ndarray, shape (n_slave,)
        Tributary area of each slave node [m2] (half the distance to its edge neighbours x thickness).
    surface_velocity : ndarray, shape (n_slave,)
        Velocity of a rigid master's surface along ``t`` at full speed [m s-1] (0 for a body's edge).
    """

    slave_node: np.ndarray
    slave_pair: np.ndarray
    segment: np.ndarray
    xi: np.ndarray
    normal: np.ndarray
    gap: np.ndarray
    area: np.ndarray | None = None
    surface_velocity: np.ndarray | None = None

    @property
    def usable(self) -> np.ndarray:
        """Slave nodes with a master under them."""
        return np.isfinite(self.gap)

    def operators(self, n_dofs: int):
        """Sparse gap and slip operators ``(G_n, G_t)``, shape (n_slave, n_dofs): ``g = g0 + G_n u`` and the
        tangential relative displacement ``G_t u`` along ``t = (-n_y, n_x)`` (rows of unusable nodes are 0)."""
        import scipy.sparse as sp

        rows, cols, vn, vt = [], [], [], []
        for k in np.flatnonzero(self.usable):
            nvec = self.normal[k]
            tvec = np.array([-nvec[1], nvec[0]])
            terms = [(self.slave_node[k], 1.0)]
            if self.segment[k] >= 0:
                terms += [(self.master_nodes_of[k][0], -(1.0 - self.xi[k])), (self.master_nodes_of[k][1], -self.xi[k])]
            for node, w in terms:
                for c in range(2):
                    rows.append(k), cols.append(2 * node + c), vn.append(w * nvec[c]), vt.append(w * tvec[c])
        shape = (self.gap.size, n_dofs)
        return sp.csr_matrix((vn, (rows, cols)), shape=shape), sp.csr_matrix((vt, (rows, cols)), shape=shape)

    master_nodes_of: np.ndarray | None = None


def contact_geometry(model, u=None) -> ContactGeometry:
    """Project every slave node onto its master edge or rigid surface (in ``coords + u``; ``u`` global, optional).

    On a master edge the node's master point is the nearest of its orthogonal projections onto segments and of the
    interior vertices it lies beyond both segments of (a vertex: :func:`fivid.contact._kernels.vertex_geometry`'s
    gap and normal, recorded as the segment ending there at ``xi = 1``): the closest-point definition the explicit
    solver's contact search uses (:func:`fivid.solver._contact_kernels._locate`). A node beyond the edge's ends has
    none (gap inf)."""
    from fivid.contact._kernels import vertex_geometry  # lazy: pulls numba

    x = model.coords if u is None else model.coords + np.asarray(u).reshape(-1, 2)
    nodes, pairs, segs, xis, normals, gaps, ends, vts = [], [], [], [], [], [], [], []
    for p, pair in enumerate(model.contacts):
        if pair.rigid is not None:
            s = np.asarray(pair.slave_nodes)
            g, n, _, vt = pair.rigid.geometry(x[s], reference=model.coords[s])
            nodes += list(s)
            pairs += [p] * s.size
            segs += [-1] * s.size
            xis += [0.0] * s.size
            normals += [tuple(r) for r in n]
            gaps += list(g)
            ends += [(-1, -1)] * s.size
            vts += list(vt)
            continue
        m = np.asarray(pair.master_nodes)
        a, b = x[m[:-1]], x[m[1:]]
        e = b - a
        L2 = np.einsum("ij,ij->i", e, e)
        t_all = e / np.sqrt(L2)[:, None]
        n_all = np.stack([t_all[:, 1], -t_all[:, 0]], axis=1)  # tangent turned clockwise: outward
        for s in np.asarray(pair.slave_nodes):
            xi = np.einsum("ij,ij->i", x[s] - a, e) / L2
            inside = np.flatnonzero((xi >= -1e-12) & (xi <= 1.0 + 1e-12))
            # interior vertices the node lies beyond both segments of (its nearest master point may be one)
            corner = np.flatnonzero((xi[:-1] > 1.0 + 1e-12) & (xi[1:] < -1e-12))
            nodes.append(s)
            pairs.append(p)
            vts.append(0.0)
            cand = [(float(np.einsum("j,j->", x[s] - (a[j] + xi[j] * e[j]), n_all[j])), int(j),
                     float(np.clip(xi[j], 0.0, 1.0)), tuple(n_all[j])) for j in inside]
            for j in corner:
                g, nx, ny, _, _ = vertex_geometry(*x[s], *b[j], *n_all[j], *n_all[j + 1], 1.0)
                cand.append((float(g), int(j), 1.0, (float(nx), float(ny))))
            if not cand:
                segs.append(-1), xis.append(0.0), normals.append((0.0, 0.0)), gaps.append(np.inf)
                ends.append((-1, -1))
                continue
            g, j, xi_j, n_j = min(cand, key=lambda c: abs(c[0]))  # the nearest master point
            segs.append(j), xis.append(xi_j), normals.append(n_j), gaps.append(g)
            ends.append((int(m[j]), int(m[j + 1])))
    area = np.concatenate([slave_areas(model, c) for c in model.contacts]) if model.contacts else np.zeros(0)
    return ContactGeometry(
        slave_node=np.array(nodes, dtype=np.int64),
        slave_pair=np.array(pairs, dtype=np.int64),
        segment=np.array(segs, dtype=np.int64),
        xi=np.array(xis, dtype=float),
        normal=np.array(normals, dtype=float).reshape(-1, 2),
        gap=np.array(gaps, dtype=float),
        area=area,
        surface_velocity=np.array(vts, dtype=float),
        master_nodes_of=np.array(ends, dtype=np.int64).reshape(-1, 2),
    )


@dataclass(frozen=True)
class Preload:
    """Result of :func:`preload_displacement`.

    Attributes
    ----------
    displacement : float
        Signed clamp displacement along the load motion's component [m] (0 without a load motion).
    normal_load : float
        Transducer normal force it gives in the static solve [N] (without a transducer: the sum of the
        contact normal forces).
    active : ndarray of bool
        Slave nodes in contact.
    u : ndarray
        Static displacement [m], global dofs.
    iterations : int
        Active-set (and Newton, for the compliant laws) iterations.
    normal_force : ndarray, shape (n_slave,)
        Normal contact force of each slave node (>= 0; 0 at open nodes) [N].
    tangential_force : ndarray, shape (n_slave,)
        Tangential contact force along ``t = (-n_y, n_x)`` of each slave node [N].
    penetration : ndarray, shape (n_slave,)
        Penetration of each slave node under a compliant law [m] (0 for the rigid law and open nodes).
    geometry : ContactGeometry
        The projection the solve used (areas, normals).
    """

    displacement: float
    normal_load: float
    active: np.ndarray
    u: np.ndarray
    iterations: int
    normal_force: np.ndarray | None = None
    tangential_force: np.ndarray | None = None
    penetration: np.ndarray | None = None
    geometry: ContactGeometry | None = None

    @property
    def pressure(self) -> np.ndarray:
        """Contact pressure of each slave node [Pa]: normal force over tributary area."""
        return self.normal_force / self.geometry.area

    def summary(self, model) -> list[dict]:
        """Per pair: resultant normal force [N], contact length [m], peak and mean pressure [Pa], normal
        stiffness [N m-1] (the tangent of a compliant law summed over the closed nodes; for the rigid law the
        modal penalty ``normal_stiffness x area``), closed nodes."""
        out = []
        geo = self.geometry
        k_node = node_stiffness(model, geo, self.penetration)
        for p, pair in enumerate(model.contacts):
            sel = (geo.slave_pair == p) & self.active
            thick = model.block(pair.slave_block).thickness
            length = float(geo.area[sel].sum() / thick)
            pres = self.pressure[sel]
            out.append({
                "contact": pair.name,
                "normal_law": pair.law.describe(),
                "normal_force_n": float(self.normal_force[sel].sum()),
                "contact_length_m": length,
                "peak_pressure_pa": float(pres.max()) if pres.size else 0.0,
                "mean_pressure_pa": float(self.normal_force[sel].sum() / (length * thick)) if length else 0.0,
                "normal_stiffness_n_per_m": float(k_node[sel].sum()),
                "closed_nodes": int(sel.sum()),
            })
        return out


def _floating_dofs(model) -> np.ndarray:
    """Dofs of the bodies with no clamped or driven dof: held only by contact (and springs)."""
    fixed = np.zeros(model.n_dofs, dtype=bool)
    fixed[np.asarray(model.fixed_dofs, dtype=np.int64)] = True
    out = []
    for b in model.blocks:
        nodes = b.node_offset + np.arange(b.n_nodes)
        dofs = np.concatenate([2 * nodes, 2 * nodes + 1])
        if not fixed[dofs].any():
            out.append(dofs)
    return np.concatenate(out) if out else np.zeros(0, dtype=np.int64)


def preload_displacement(model, normal_load: float | None, *, normal_weights: np.ndarray | None,
                         load_dofs: np.ndarray, direction: float, mu: np.ndarray | None = None,
                         max_iterations: int = 100) -> Preload:
    """Clamp displacement giving the transducer normal force ``normal_load`` [N] (see the module docstring).

    The model's pressure loads (:func:`fivid.fe.loads.external_load_vector`, full value) act throughout: they
    are part of the zero-clamp-displacement solution, and the transducer reads ``K u - F`` at its dofs.
    ``normal_load`` None: the clamp stays where it is (a model pressed by its loads alone).

    Compliant normal laws (linear, power) enter as springs linearised at each node's current penetration
    (Newton: ``f = A (p(d0) + p'(d0) (d - d0))``), starting from the rigid solution's penetrations
    ``p^-1(lam / A)``; the active set and the penetrations are iterated together until both repeat (relative
    change of the penetrations <= 1e-10). A body held by nothing but contact gets a stiffness of 1e-10 x its
    mean diagonal on its dofs in the factorisation, so that its free sliding/rotation does not make the system
    singular; iterative refinement against the unregularised system then removes that stiffness's load share
    (each pass shrinks it by eps / (lambda + eps) on a mode of stiffness lambda).

    Parameters
    ----------
    model : Model
    normal_load : float or None
        Target normal force [N], > 0; None: no clamp displacement.
    normal_weights : ndarray (n_dofs,) or None
        Weights of the dof reactions summed into the transducer's normal force.
    load_dofs : ndarray of int
        Dofs moved by the loading clamp.
    direction : float
        +1 or -1: the sign of the clamp displacement that presses the contact (from the config).
    mu : ndarray (n_slave,), optional
        Friction coefficient of each slave node (all pairs, in order); None or 0: frictionless.
    """
    import scipy.sparse.linalg  # noqa: F401  (loaded before the BLAS limit below: threadpoolctl limits loaded libraries)
    from threadpoolctl import threadpool_limits

    geo = contact_geometry(model)
    usable = geo.usable
    if not usable.any():
        raise ConfigError("no slave node lies over its master edge: the preload cannot press the contact")
    n = model.n_dofs
    ns = geo.gap.size
    K = stiffness_matrix(model, include_springs=True).tocsr()
    fixed = np.asarray(model.fixed_dofs)
    free = model.free_dofs
    floating = _floating_dofs(model)
    reg = np.zeros(n)  # regularisation of floating bodies, removed again by iterative refinement
    if floating.size:
        reg[floating] = 1e-10 * float(K.diagonal()[floating].mean())
    e = np.zeros(n)
    e[load_dofs] = direction
    G, Gt = geo.operators(n)
    law_of = [model.contacts[p].law for p in geo.slave_pair]
    pen = np.array([law.is_penalty for law in law_of], dtype=bool)
    mu = np.zeros(ns) if mu is None else np.asarray(mu, dtype=float)
    g0 = np.where(usable, geo.gap, np.inf)
    scale = max(float(np.ptp(model.coords)), 1e-12)
    active = usable & (g0 <= 1e-9 * scale)
    if not active.any():
        active = usable & (g0 == g0[usable].min())
    tied = active & (mu > 0)
    f_ext = external_load_vector(model)  # pressure loads at full value, part of the zero-clamp solution ua
    Kfc_e = (K[:, fixed] @ e[fixed])[free]

    try:
        with threadpool_limits(limits=1, user_api="blas"):  # see _FreeStiffness
            return _active_set_iteration(K, G, Gt, geo, law_of, pen, mu, g0, usable, active, tied, e, f_ext, Kfc_e,
                                         reg, free, fixed, normal_load, normal_weights, direction, max_iterations)
    except (np.linalg.LinAlgError, RuntimeError) as exc:
        if isinstance(exc, RuntimeError) and "singular" not in str(exc):  # splu's "Factor is exactly singular"
            raise
        raise _singular_preload(model, geo, G, Gt, free, mu) from exc


def _singular_preload(model, geo, G, Gt, free, mu) -> ConfigError:
    """The ConfigError for a singular preload system (the stiffness, or the contact rows bordering it): names the
    model file, the slave nodes whose normal or (with friction) tangential constraint acts on prescribed dofs only
    (both sides clamped or driven: the constraint has nothing to move), else the other likely cause, a body held by
    nothing but contact that the preload does not hold."""
    path = model.source.rsplit(" sha256:", 1)[0] if model.source else None
    bad = []
    for rows, kind in ((G, "normal"), (Gt, "tangential")):
        dead = np.flatnonzero(geo.usable & (np.abs(rows[:, free]).sum(axis=1).A1 == 0.0))
        if kind == "tangential":
            dead = dead[mu[dead] > 0]
        bad += [(int(k), kind) for k in dead]
    if bad:
        k, kind = bad[0]
        c = model.contacts[geo.slave_pair[k]]
        s = int(geo.slave_node[k])
        more = f" (and {len(bad) - 1} more)" if len(bad) > 1 else ""
        return ConfigError(
            f"the static preload's contact system is singular: contact {c.name!r}, slave node {s} at "
            f"{model.coords[s].tolist()} m{more}: its {kind} constraint ties it to a master point whose dofs, like its "
            "own, are all prescribed (clamped or driven), so the constraint has nothing to move; leave that node out of the "
            f"slave range (contacts.{c.name}.slave x: [from, to], e.g. half an element inside the clamped or driven "
            "corner) or free one of the two", file=path, key=f"contacts.{c.name}.slave")
    return ConfigError(
        "the static preload's stiffness with the closed contact nodes is singular: likely a body held by nothing "
        "but the contact that the preload does not hold (no clamp, spring or driven dof against a free motion, and "
        "too few or no contact nodes closed at the preload); support that body (a clamp or spring), or give a "
        "normal load (--load) or pressure load that closes its contact", file=path)


def _active_set_iteration(K, G, Gt, geo, law_of, pen, mu, g0, usable, active, tied, e, f_ext, Kfc_e, reg, free, fixed,
                          normal_load, normal_weights, direction, max_iterations) -> Preload:
    """The active-set loop of :func:`preload_displacement` (its arguments as it prepares them)."""
    ns = g0.size
    slip = np.zeros(ns)  # sign of the tangential force of nodes slipping on the cone (0: not slipping)
    d0 = None  # penetrations of the compliant nodes (None: first pass treats them as rigid)
    factor = _FreeStiffness(K, G, Gt, reg, free)  # factorised once for every active set
    with_clamp = normal_load is not None
    for it in range(1, max_iterations + 1):
        lag = active & ~pen if d0 is not None else active  # Lagrange rows: rigid nodes (all, in the first pass)
        spring = active & pen if d0 is not None else np.zeros(ns, dtype=bool)
        idx = np.flatnonzero(lag)
        tdx = np.flatnonzero(tied)
        sdx = np.flatnonzero(spring)
        k_t, r = _linearised_compliant_laws(law_of, geo.area, sdx, d0, ns)
        Kt, ua, ub, lam_a, lam_b = _solve_load_cases(K, G, Gt, idx, tdx, sdx, slip, mu, k_t, r, g0, e, f_ext, Kfc_e,
                                                     reg, free, fixed, factor)
        delta = _clamp_displacement(normal_load, normal_weights, Kt, ua, ub, f_ext, direction) if with_clamp else 0.0
        u = ua + delta * ub
        lam = lam_a + delta * lam_b
        gap = np.where(usable, g0 + G @ u, np.inf)
        lam_n = np.zeros(ns)
        lam_t = np.zeros(ns)
        lam_n[idx] = lam[:idx.size]
        lam_t[tdx] = lam[idx.size:]
        lam_n[sdx] = k_t[sdx] * (-gap[sdx]) + r[sdx]
        lam_t[idx] += slip[idx] * mu[idx] * lam_n[idx]
        lam_t[sdx] += slip[sdx] * mu[sdx] * lam_n[sdx]
        tol = 1e-9 * max(abs(delta), float(np.abs(g0[usable]).max()), 1e-12)
        new = active.copy()
        if d0 is None and pen.any():
            # first pass done (all rigid): start the compliant nodes from the penetration their force needs
            d_new = np.zeros(ns)
            for k in np.flatnonzero(pen & active):
                d_new[k] = float(law_of[k].penetration(lam_n[k] / geo.area[k]))
            new[idx[lam_n[idx] < 0.0]] = False
            d_new[~new] = 0.0
            active, tied, slip, d0 = new, tied & new, slip * new, d_new
            continue
        new[idx[lam_n[idx] < 0.0]] = False
        new[usable & ~active & ~pen & (gap < -tol)] = True
        d_new = np.zeros(ns)
        if d0 is not None and pen.any():
            d_new[pen & usable] = np.maximum(-gap[pen & usable], 0.0)
            new[pen & usable] = d_new[pen & usable] > 0.0
        outside = tied & (np.abs(lam_t) > mu * lam_n * (1 + 1e-12))
        new_slip = np.where(outside, np.sign(lam_t), slip) * new
        new_tied = (tied & new & ~outside) | (new & ~active & (mu > 0))
        converged = np.array_equal(new, active) and np.array_equal(new_tied, tied) and np.array_equal(new_slip, slip)
        if d0 is not None and pen.any():
            dm = float(d_new.max()) if d_new.size else 0.0
            converged = converged and (float(np.abs(d_new - d0).max()) <= 1e-10 * dm if dm > 0 else True)
        if converged:
            total = normal_load if with_clamp else float(lam_n[new].sum())
            return Preload(displacement=float(delta), normal_load=float(total), active=active, u=u,
                           iterations=it, normal_force=np.where(active, lam_n, 0.0), tangential_force=lam_t,
                           penetration=np.where(active & pen, d_new, 0.0), geometry=geo)
        active, tied, slip = new, new_tied, new_slip
        if d0 is not None:
            d0 = d_new
        if not active.any():
            raise ConfigError("the preload active set emptied: the clamp pulls the bodies apart")
    raise ConfigError(f"the preload contact solve did not settle in {max_iterations} active-set iterations")


def _clamp_displacement(normal_load, normal_weights, Kt, ua, ub, f_ext, direction) -> float:
    """Clamp displacement ``delta`` [m] whose solution ``ua + delta ub`` gives the transducer ``normal_load`` [N]
    (the transducer reads ``Kt u - F`` at its dofs, weighted by ``normal_weights``); a clamp that does not press
    the contact is a ConfigError."""
    Fa = float(normal_weights @ (Kt @ ua - f_ext))
    Fb = float(normal_weights @ (Kt @ ub))
    if not Fb > 0.0:
        raise ConfigError(
            f"moving the loading clamp by {direction:+.0f} along its component does not press the contact "
            f"(dF/d(delta) = {Fb:.3g} N/m); check the load motion's sign and the reaction's normal component"
        )
    return (normal_load - Fa) / Fb


def _linearised_compliant_laws(law_of, area, sdx, d0, ns):
    """The compliant nodes ``sdx`` as springs linearised at their penetrations ``d0`` [m] (Newton): the normal
    force ``f = k_t d + r`` [N] with ``k_t = A p'(d0)`` [N m-1] and ``r = A (p(d0) - p'(d0) d0)`` [N] (zero on the
    other nodes; ``d0`` floored at 1e-3 of the largest, where a power law's tangent vanishes)."""
    k_t = np.zeros(ns)
    r = np.zeros(ns)
    if sdx.size:
        dl = np.maximum(d0[sdx], 1e-3 * max(float(d0[sdx].max()), 1e-15))
        pv = np.array([law_of[k].pressure(dl[j]) for j, k in enumerate(sdx)]).ravel()
        dp = np.array([law_of[k].tangent(dl[j]) for j, k in enumerate(sdx)]).ravel()
        k_t[sdx] = area[sdx] * dp
        r[sdx] = area[sdx] * (pv - dp * dl)
    return k_t, r


#: iterative refinement passes of the preload's Schur-complement solve without floating bodies
REFINEMENT_PASSES = 1


class _FreeStiffness:
    """One sparse factorisation of the free-free stiffness ``K_ff + diag(reg)`` for every active set of the preload's
    iteration, and the solutions ``K_ff^-1 G_k^T`` (normal rows) and ``K_ff^-1 Gt_k^T`` (tangential rows) of each
    slave that took part, kept: an active set's bordered system is then solved through its small Schur complement
    (:func:`_solve_load_cases`) instead of factorising the bordered matrix again at every iteration. Its user holds
    BLAS to one thread (:func:`preload_displacement`): SuperLU's supernodal solves and the Schur complement's dense
    algebra are too small to share (measured on the default rig, 42 right-hand sides: 0.06 s on one thread,
    0.5-1 s on two at load 4)."""

    def __init__(self, K, G, Gt, reg, free):
        import scipy.sparse as sp
        from scipy.sparse.linalg import splu

        self.free = free
        self.lu = splu((K[free][:, free] + sp.diags(reg[free])).tocsc(), permc_spec="MMD_AT_PLUS_A")
        self.rows = {"n": G[:, free].tocsr(), "t": Gt[:, free].tocsr()}
        self.kept = {"n": {}, "t": {}}

    def solve(self, b):
        """``K_ff^-1 b`` (``b``: (nf,) or (nf, k))."""
        return self.lu.solve(np.asfortranarray(b, dtype=float))

    def slave_solutions(self, kind, slaves):
        """``K_ff^-1 R[slaves]^T``, (nf, len(slaves)), ``R`` the normal (``kind`` "n") or tangential ("t") rows;
        each slave's solved once."""
        kept = self.kept[kind]
        new = [int(k) for k in slaves if int(k) not in kept]
        if new:
            z = self.solve(self.rows[kind][new].toarray().T)
            kept.update({k: z[:, j] for j, k in enumerate(new)})
        return np.column_stack([kept[int(k)] for k in slaves]) if len(slaves) else np.zeros((self.free.size, 0))


def _solve_load_cases(K, G, Gt, idx, tdx, sdx, slip, mu, k_t, r, g0, e, f_ext, Kfc_e, reg, free, fixed, factor):
    """One active set's linear solve for two load cases: ``a`` the loads and the initial gaps with the clamp at
    rest, ``b`` a unit clamp displacement ``e`` (the solution is ``a + delta b``). Rigid nodes ``idx`` close their
    gap (Lagrange rows), tied nodes ``tdx`` also their tangential motion, compliant nodes ``sdx`` are springs
    ``k_t d + r``; slipping nodes push along ``n + s mu t``. Returns the tangent stiffness ``Kt`` and the
    displacements [m] and multipliers [N] of both cases.

    The bordered system ``[[K_ff + Kc, -D^T], [C, 0]] [u; lam] = [f; h]`` is solved with the one factorisation
    ``factor`` (:class:`_FreeStiffness`) through its Schur complement: the springs' forces ``z = k_t G_s u`` join
    the multipliers as unknowns (``K_ff u + D_s^T z - D^T lam = f``, ``k_t G_s u - z = h_z``, ``C u = h``), so
    ``y = [z; lam]`` solves ``(F - E K_ff^-1 B) y = h - E K_ff^-1 f`` and ``u = K_ff^-1 (f - B y)`` with the slave
    rows' solutions ``K_ff^-1 G^T`` kept across iterations. Floating bodies' regularisation ``reg`` is in the
    factorisation only; iterative refinement against the unregularised system removes its share as before.
    """
    import scipy.sparse as sp

    n = K.shape[0]
    nf = free.size
    ns_, m_n, m_t = sdx.size, idx.size, tdx.size
    # compliant nodes: f = k_t d + r, d = -(g0 + G u); force on the dofs (G + s mu Gt)^T f
    Dsp = (G[sdx] + sp.diags(slip[sdx] * mu[sdx]) @ Gt[sdx]).tocsr()
    Kc = (Dsp.T @ sp.diags(k_t[sdx]) @ G[sdx]).tocsr()
    f_c = Dsp.T @ (r[sdx] - k_t[sdx] * g0[sdx])
    Kt = (K + Kc).tocsr() if Kc.nnz else K
    C = sp.vstack([G[idx], Gt[tdx]]).tocsr()
    Cf = C[:, free]
    # force directions: a slipping node pushes along n + s mu t (lam_t = s mu lam_n), a tied one along n and t
    s_mu_i, s_mu_s = slip[idx] * mu[idx], slip[sdx] * mu[sdx]
    # B = [D_s^T, -D^T] and K_ff^-1 B from the kept slave solutions (tangential rows only where they act: tied and
    # slipping nodes); E = [k_t G_s; C] on the free dofs
    sl_i, sl_s = idx[s_mu_i != 0.0], sdx[s_mu_s != 0.0]
    kinv_b = np.hstack([factor.slave_solutions("n", sdx), -factor.slave_solutions("n", idx),
                        -factor.slave_solutions("t", tdx)])
    kinv_b[:, np.flatnonzero(s_mu_s != 0.0)] += factor.slave_solutions("t", sl_s) * s_mu_s[s_mu_s != 0.0]
    kinv_b[:, ns_ + np.flatnonzero(s_mu_i != 0.0)] -= factor.slave_solutions("t", sl_i) * s_mu_i[s_mu_i != 0.0]
    B = sp.hstack([Dsp[:, free].T, -(G[idx] + sp.diags(s_mu_i) @ Gt[idx])[:, free].T, -Gt[tdx][:, free].T]).tocsr()
    E = sp.vstack([sp.diags(k_t[sdx]) @ G[sdx][:, free], Cf]).tocsr()
    ny = ns_ + m_n + m_t
    F = np.zeros((ny, ny))
    F[np.arange(ns_), np.arange(ns_)] = -1.0
    S = F - E @ kinv_b

    def solve(f, h):
        kf = factor.solve(f)
        y = np.linalg.solve(S, h - E @ kf) if ny else np.zeros((0, f.shape[1]))
        return kf - kinv_b @ y, y[ns_:]

    f = np.zeros((nf, 2))
    h = np.zeros((ny, 2))
    f[:, 0] = (f_ext + f_c)[free]
    f[:, 1] = -Kfc_e  # clamp's pull on the free dofs (the springs' share enters through z)
    h[ns_:ns_ + m_n, 0] = -g0[idx]
    h[:ns_, 1] = -(sp.diags(k_t[sdx]) @ G[sdx][:, fixed]) @ e[fixed]
    h[ns_:, 1] = -(C @ e)
    u_f, lam = solve(f, h)
    # iterative refinement against the unregularised system: one pass takes the Schur complement's solve to a
    # componentwise backward error of a few eps (from 1e-12 on the rig's first, nearly redundant active sets); with
    # floating bodies four, the regularisation's error shrinking by eps / (lambda + eps) per pass on every mode the
    # contact restrains
    Kff = Kt[free][:, free]
    D = sp.vstack([G[idx] + sp.diags(s_mu_i) @ Gt[idx], Gt[tdx]]).tocsr()[:, free]
    f_tot = f.copy()  # the right-hand side in u and lam alone: the springs' pull of the clamp included
    if Kc.nnz:
        f_tot[:, 1] -= Kc[free][:, fixed] @ e[fixed]
    for _ in range(4 if reg.any() else REFINEMENT_PASSES):
        ru = f_tot - (Kff @ u_f - D.T @ lam)
        rl = h[ns_:] - Cf @ u_f
        du, dlam = solve(ru, np.vstack([np.zeros((ns_, 2)), rl]))
        u_f, lam = u_f + du, lam + dlam
    ua = np.zeros(n)
    ub = e.copy()
    ua[free] = u_f[:, 0]
    ub[free] = u_f[:, 1]
    return Kt, ua, ub, lam[:, 0], lam[:, 1]


def preload_state(model, normal_load: float | None, *, mu=None) -> Preload:
    """The static contact state under the transducer normal force ``normal_load`` [N], clamp lowered monotonically.

    The model's motion with role "load" is the clamp (its amplitude's sign gives the pressing direction), its
    first reaction the transducer (the normal component's reaction, signed like the clamp, is the normal force).
    ``normal_load`` None: the state under the model's pressure loads and rigid-circle expansions alone (the clamp,
    if any, stays at 0), e.g. a ring pressed on an expanded cylinder; its ``normal_load`` is then the sum of the
    contact normal forces.

    Parameters
    ----------
    model : Model
    normal_load : float or None
        Target normal force [N], > 0.
    mu : float or ndarray (n_slave,), optional
        Friction coefficient during the preload (scalar: every pair; default: each pair's ``mu``).

    Raises
    ------
    ConfigError
        No load motion or no reaction, a non-positive load, or a contact that the clamp does not press.
    """
    mu_slave = mu if (mu is not None and np.ndim(mu) == 1) else slave_coefficients(model, mu)
    if normal_load is None:
        if not pressed_by_itself(model):
            raise ConfigError("the contact state needs a normal load (e.g. --load '5 N'), pressure loads in the "
                              "model ('loads:') or an expanding rigid circle ('rigid: {expansion: ...}') that "
                              "press the contact")
        return preload_displacement(model, None, normal_weights=None, load_dofs=np.zeros(0, dtype=np.int64),
                                    direction=1.0, mu=mu_slave)
    if not (np.isfinite(normal_load) and normal_load > 0):
        raise ConfigError(f"normal_load must be a positive force [N], got {normal_load!r}")
    load = model.motion("load")
    if load is None:
        raise ConfigError("normal_load was given but the model has no motion with role 'load' to set it"
                          + (" (this model is pressed by its pressure loads: leave the load out)" if model.loads
                             else ""))
    if not model.reactions:
        raise ConfigError("normal_load was given but the model has no reaction (force transducer) to measure it")
    direction = 1.0 if load.amplitude >= 0 else -1.0
    r = model.reactions[0]
    weights = np.zeros(model.n_dofs)
    weights[2 * np.asarray(r.nodes) + r.normal_component] = direction
    return preload_displacement(model, float(normal_load), normal_weights=weights, load_dofs=load.dofs,
                                direction=direction, mu=mu_slave)


def expanding_circles(model) -> list[int]:
    """Indices of the contact pairs whose rigid master is a circle with a radial expansion (given or to solve)."""
    return [p for p, c in enumerate(model.contacts)
            if c.rigid is not None and c.rigid.kind == "circle"
            and (c.rigid.expansion != 0.0 or np.isfinite(c.rigid.target_mean_pressure))]


def pressed_by_itself(model) -> bool:
    """True when the model's own loading presses its contacts without a normal load: pressure loads, or a rigid
    circle that expands."""
    return bool(model.loads) or bool(expanding_circles(model))


def _with_expansion(model, p: int, delta: float):
    """The model with pair ``p``'s rigid circle expanded by ``delta`` [m] (a copy; the model is immutable)."""
    from dataclasses import replace

    contacts = list(model.contacts)
    contacts[p] = replace(contacts[p], rigid=replace(contacts[p].rigid, expansion=float(delta)))
    return replace(model, contacts=tuple(contacts))


def resolve_expansions(model, *, rtol: float = 1e-9, max_iterations: int = 30):
    """The model with every rigid circle that states a target ``mean_pressure`` expanded by the radial
    displacement ``delta`` [m] that gives it (the static preload of seed 002: the steel cylinder grows until the
    mean contact pressure is reached). Models without such a circle are returned unchanged.

    The mean pressure is :meth:`Preload.summary`'s ``mean_pressure_pa`` (the pair's resultant normal force over
    its closed length x thickness) of :func:`preload_state` with the model's loads and expansions (friction tied
    during the preload, each pair's ``mu``). For a fixed active set and the rigid or a linear law it is affine
    in ``delta``; secant iteration from ``delta_0 = p a / E`` (the bore of a thin-walled ring) converges in two
    or three solves, a power law in a few more. Several such circles are solved one after another, repeated until
    all agree (they interact only through the bodies).

    Raises
    ------
    ConfigError
        The expansion does not press the contact (the pressure does not grow with ``delta``) or the iteration
        does not settle within ``max_iterations`` solves (``rtol`` relative on the pressure).
    """
    todo = [p for p in expanding_circles(model) if np.isfinite(model.contacts[p].rigid.target_mean_pressure)]
    for p in todo:  # start: the bore of a thin-walled ring, delta = p a / E
        rigid = model.contacts[p].rigid
        if not np.isfinite(rigid.expansion):
            E = model.block(model.contacts[p].slave_block).material.E
            model = _with_expansion(model, p, rigid.target_mean_pressure * rigid.radius / E)

    def pressure(m, p):
        return float(preload_state(m, None).summary(m)[p]["mean_pressure_pa"])

    for _round in range(max_iterations):
        settled = True
        for p in todo:
            name = model.contacts[p].name
            target = model.contacts[p].rigid.target_mean_pressure
            d1 = model.contacts[p].rigid.expansion
            p1 = pressure(model, p)
            if abs(p1 - target) <= rtol * target:
                continue
            settled = False
            d0, p0, d1 = d1, p1, 1.01 * d1
            for _it in range(max_iterations):
                p1 = pressure(_with_expansion(model, p, d1), p)
                if abs(p1 - target) <= rtol * target:
                    break
                if not p1 > p0 if d1 > d0 else not p1 < p0:
                    raise ConfigError(f"contact {name!r}: expanding the rigid circle does not raise the mean contact "
                                      f"pressure ({p0:.6g} Pa at {d0:.6g} m, {p1:.6g} Pa at {d1:.6g} m); check its "
                                      f"side and radius", key=f"contacts[{p}].rigid.expansion")
                d0, p0, d1 = d1, p1, d1 + (target - p1) * (d1 - d0) / (p1 - p0)
            else:
                raise ConfigError(f"contact {name!r}: the expansion for a mean contact pressure of {target:.6g} Pa "
                                  f"did not settle in {max_iterations} static solves",
                                  key=f"contacts[{p}].rigid.expansion.mean_pressure")
            model = _with_expansion(model, p, d1)
        if settled or len(todo) == 1:
            return model
    raise ConfigError(f"the expansions of the rigid circles {[model.contacts[p].name for p in todo]} did not settle "
                      f"together in {max_iterations} rounds")
