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

__all__ = ["ContactGeometry", "contact_geometry", "Preload", "preload_displacement", "preload_state",
           "slave_friction"]


@dataclass(frozen=True)
class ContactGeometry:
    """Slave nodes of all pairs with their master segment in the reference configuration.

    Attributes
    ----------
    slave_node, slave_pair, segment : ndarray of int, shape (n_slave,)
        Global slave node, pair index and master segment index (``-1``: no segment under the node).
    xi : ndarray, shape (n_slave,)
        Position on the segment, 0 at its first node, 1 at its second.
    normal : ndarray, shape (n_slave, 2)
        Outward unit normal of the master segment.
    gap : ndarray, shape (n_slave,)
        Initial normal gap [m] (negative: penetration).
    """

    slave_node: np.ndarray
    slave_pair: np.ndarray
    segment: np.ndarray
    xi: np.ndarray
    normal: np.ndarray
    gap: np.ndarray


def contact_geometry(model, u=None) -> ContactGeometry:
    """Project every slave node onto its master edge (in ``coords + u``; ``u`` global, optional)."""
    x = model.coords if u is None else model.coords + np.asarray(u).reshape(-1, 2)
    nodes, pairs, segs, xis, normals, gaps = [], [], [], [], [], []
    for p, pair in enumerate(model.contacts):
        m = np.asarray(pair.master_nodes)
        a, b = x[m[:-1]], x[m[1:]]
        e = b - a
        L2 = np.einsum("ij,ij->i", e, e)
        for s in np.asarray(pair.slave_nodes):
            xi = np.einsum("ij,ij->i", x[s] - a, e) / L2
            inside = np.flatnonzero((xi >= -1e-12) & (xi <= 1.0 + 1e-12))
            nodes.append(s)
            pairs.append(p)
            if inside.size == 0:
                segs.append(-1), xis.append(0.0), normals.append((0.0, 0.0)), gaps.append(np.inf)
                continue
            t = e[inside] / np.sqrt(L2[inside])[:, None]
            n = np.stack([t[:, 1], -t[:, 0]], axis=1)  # tangent turned clockwise: outward
            g = np.einsum("ij,ij->i", x[s] - (a[inside] + xi[inside, None] * e[inside]), n)
            k = int(np.argmin(np.abs(g)))
            segs.append(int(inside[k])), xis.append(float(np.clip(xi[inside[k]], 0.0, 1.0)))
            normals.append(tuple(n[k])), gaps.append(float(g[k]))
    return ContactGeometry(
        slave_node=np.array(nodes, dtype=np.int64),
        slave_pair=np.array(pairs, dtype=np.int64),
        segment=np.array(segs, dtype=np.int64),
        xi=np.array(xis, dtype=float),
        normal=np.array(normals, dtype=float).reshape(-1, 2),
        gap=np.array(gaps, dtype=float),
    )


@dataclass(frozen=True)
class Preload:
    """Result of :func:`preload_displacement`.

    Attributes
    ----------
    displacement : float
        Signed clamp displacement along the load motion's component [m].
    normal_load : float
        Transducer normal force it gives in the static solve [N].
    active : ndarray of bool
        Slave nodes in contact.
    u : ndarray
        Static displacement [m], global dofs.
    iterations : int
        Active-set iterations.
    normal_force : ndarray, shape (n_slave,)
        Normal contact force of each slave node (Lagrange multiplier, >= 0; 0 at open nodes) [N].
    tangential_force : ndarray, shape (n_slave,)
        Tangential contact force along ``t = (-n_y, n_x)`` of each slave node [N].
    """

    displacement: float
    normal_load: float
    active: np.ndarray
    u: np.ndarray
    iterations: int
    normal_force: np.ndarray | None = None
    tangential_force: np.ndarray | None = None


def preload_displacement(model, normal_load: float, *, normal_weights: np.ndarray, load_dofs: np.ndarray,
                         direction: float, mu: np.ndarray | None = None, max_iterations: int = 50) -> Preload:
    """Clamp displacement giving the transducer normal force ``normal_load`` [N] (see the module docstring).

    The model's pressure loads (:func:`fivid.fe.loads.external_load_vector`, full value) act throughout: they
    are part of the zero-clamp-displacement solution, and the transducer reads ``K u - F`` at its dofs.

    Parameters
    ----------
    model : Model
    normal_load : float
        Target normal force [N], > 0.
    normal_weights : ndarray (n_dofs,)
        Weights of the dof reactions summed into the transducer's normal force.
    load_dofs : ndarray of int
        Dofs moved by the loading clamp.
    direction : float
        +1 or -1: the sign of the clamp displacement that presses the contact (from the config).
    mu : ndarray (n_slave,), optional
        Friction coefficient of each slave node (all pairs, in order); None or 0: frictionless.
    """
    import scipy.sparse as sp
    from scipy.sparse.linalg import splu

    from fivid.fe.assembly import stiffness_matrix
    from fivid.fe.loads import external_load_vector

    geo = contact_geometry(model)
    usable = geo.segment >= 0
    if not usable.any():
        raise ConfigError("no slave node lies over its master edge: the preload cannot press the contact")
    n = model.n_dofs
    K = stiffness_matrix(model, include_springs=True).tocsr()
    fixed = np.asarray(model.fixed_dofs)
    free = model.free_dofs
    e = np.zeros(n)
    e[load_dofs] = direction
    # constraint rows: gap_k = g0_k + n . (u_s - (1-xi) u_a - xi u_b); slip_k = t . (same), t = (-n_y, n_x)
    rows, cols, vals = [], [], []
    trows, tvals = [], []
    for k in np.flatnonzero(usable):
        pair = model.contacts[geo.slave_pair[k]]
        a = pair.master_nodes[geo.segment[k]]
        b = pair.master_nodes[geo.segment[k] + 1]
        nvec = geo.normal[k]
        tvec = np.array([-nvec[1], nvec[0]])
        for node, w in ((geo.slave_node[k], 1.0), (a, -(1.0 - geo.xi[k])), (b, -geo.xi[k])):
            for c in range(2):
                rows.append(k), cols.append(2 * node + c), vals.append(w * nvec[c])
                trows.append(k), tvals.append(w * tvec[c])
    G = sp.csr_matrix((vals, (rows, cols)), shape=(geo.gap.size, n))
    Gt = sp.csr_matrix((tvals, (trows, cols)), shape=(geo.gap.size, n))
    mu = np.zeros(geo.gap.size) if mu is None else np.asarray(mu, dtype=float)
    g0 = np.where(usable, geo.gap, np.inf)
    active = usable & (g0 <= 1e-9 * np.ptp(model.coords))
    if not active.any():
        active = usable & (g0 == g0[usable].min())
    tied = active & (mu > 0)
    slip = np.zeros(geo.gap.size)  # sign of the tangential force of nodes slipping on the cone (0: not slipping)
    Kff = K[free][:, free]
    Kfc_e = (K[:, fixed] @ e[fixed])[free]
    f_ext = external_load_vector(model)  # pressure loads at full value, part of the zero-clamp solution ua
    for it in range(1, max_iterations + 1):
        idx = np.flatnonzero(active)
        tdx = np.flatnonzero(tied)
        C = sp.vstack([G[idx], Gt[tdx]]).tocsr()
        Cf = C[:, free]
        # force directions: a slipping node pushes along n + s mu t (lam_t = s mu lam_n), a tied one along n and t
        D = sp.vstack([G[idx] + sp.diags(slip[idx] * mu[idx]) @ Gt[idx], Gt[tdx]]).tocsr()[:, free]
        A = sp.bmat([[Kff, -D.T], [Cf, None]], format="csc")
        lu = splu(A)
        nf = free.size
        rhs = np.zeros((A.shape[0], 2))
        rhs[nf:nf + idx.size, 0] = -g0[idx]
        rhs[:nf, 0] = f_ext[free]
        rhs[:nf, 1] = -Kfc_e
        rhs[nf:, 1] = -(C @ e)
        sol = lu.solve(rhs)
        ua = np.zeros(n)
        ub = e.copy()
        ua[free] = sol[:nf, 0]
        ub[free] = sol[:nf, 1]
        Fa = float(normal_weights @ (K @ ua - f_ext))
        Fb = float(normal_weights @ (K @ ub))
        if not Fb > 0.0:
            raise ConfigError(
                f"moving the loading clamp by {direction:+.0f} along its component does not press the contact "
                f"(dF/d(delta) = {Fb:.3g} N/m); check the load motion's sign and the reaction's normal component"
            )
        delta = (normal_load - Fa) / Fb
        u = ua + delta * ub
        lam = sol[nf:, 0] + delta * sol[nf:, 1]
        lam_n = np.zeros(geo.gap.size)
        lam_t = np.zeros(geo.gap.size)
        lam_n[idx] = lam[:idx.size]
        lam_t[tdx] = lam[idx.size:]
        lam_t[idx] += slip[idx] * mu[idx] * lam_n[idx]
        gap = np.where(usable, g0 + G @ u, np.inf)
        tol = 1e-9 * max(abs(delta), float(np.abs(g0[usable]).max()), 1e-12)
        new = active.copy()
        new[idx[lam_n[idx] < 0.0]] = False
        new[usable & ~active & (gap < -tol)] = True
        outside = tied & (np.abs(lam_t) > mu * lam_n * (1 + 1e-12))
        new_slip = np.where(outside, np.sign(lam_t), slip) * new
        new_tied = (tied & new & ~outside) | (new & ~active & (mu > 0))
        if np.array_equal(new, active) and np.array_equal(new_tied, tied) and np.array_equal(new_slip, slip):
            return Preload(displacement=float(delta), normal_load=float(normal_load), active=active, u=u,
                           iterations=it, normal_force=lam_n, tangential_force=lam_t)
        active, tied, slip = new, new_tied, new_slip
        if not active.any():
            raise ConfigError("the preload active set emptied: the clamp pulls the bodies apart")
    raise ConfigError(f"the preload contact solve did not settle in {max_iterations} active-set iterations")


def slave_friction(model, mu=None) -> np.ndarray:
    """Friction coefficient of every slave node (all pairs, in order) [-]: ``mu`` if given, else each pair's own."""
    if not model.contacts:
        return np.zeros(0)
    mu_pairs = [float(mu) if mu is not None else c.mu for c in model.contacts]
    return np.concatenate([[mu_pairs[p]] * len(c.slave_nodes) for p, c in enumerate(model.contacts)])


def preload_state(model, normal_load: float, *, mu=None) -> Preload:
    """The static contact state under the transducer normal force ``normal_load`` [N], clamp lowered monotonically.

    The model's motion with role "load" is the clamp (its amplitude's sign gives the pressing direction), its
    first reaction the transducer (the normal component's reaction, signed like the clamp, is the normal force).

    Parameters
    ----------
    model : Model
    normal_load : float
        Target normal force [N], > 0.
    mu : float or ndarray (n_slave,), optional
        Friction coefficient during the preload (scalar: every pair; default: each pair's ``mu``).

    Raises
    ------
    ConfigError
        No load motion or no reaction, a non-positive load, or a contact that the clamp does not press.
    """
    if not (np.isfinite(normal_load) and normal_load > 0):
        raise ConfigError(f"normal_load must be a positive force [N], got {normal_load!r}")
    load = model.motion("load")
    if load is None:
        raise ConfigError("normal_load was given but the model has no motion with role 'load' to set it")
    if not model.reactions:
        raise ConfigError("normal_load was given but the model has no reaction (force transducer) to measure it")
    direction = 1.0 if load.amplitude >= 0 else -1.0
    r = model.reactions[0]
    weights = np.zeros(model.n_dofs)
    weights[2 * np.asarray(r.nodes) + r.normal_component] = direction
    mu_slave = mu if (mu is not None and np.ndim(mu) == 1) else slave_friction(model, mu)
    return preload_displacement(model, float(normal_load), normal_weights=weights, load_dofs=load.dofs,
                                direction=direction, mu=mu_slave)
