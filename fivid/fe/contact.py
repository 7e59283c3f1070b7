"""Linearised frictional contact about the sliding state: penalty normal springs and friction coupling.

For every closed slave node (the closed set comes from the static preload solve, :mod:`fivid.fe.static`) ``s`` of a contact pair, projected on its master segment ``(m1, m2)`` at the
parameter ``xi`` (shape values ``N1 = 1 - xi``, ``N2 = xi``), the gap increment and the tangential
relative displacement are

    g = n . (u_s - N1 u_m1 - N2 u_m2),     w = t . (u_s - N1 u_m1 - N2 u_m2),

i.e. ``g = G_n u`` and ``w = G_t u`` with sparse rows ``G_n``, ``G_t``. ``n`` is the master's outward
normal, ``t`` the master segment tangent. With a penalty ``k`` per node the contact pressure
increment is ``p = -k g``; on a sliding interface the friction force is ``mu p`` along ``d t``, where
``d = sign((v_master - v_slave) . t)`` is the sliding direction (friction drags the slave along with
the master). The force vector is therefore

    f = p (G_n^T + mu d G_t^T) = -(G_n^T + mu G_t^T D) diag(k) G_n u,

so the contact adds ``K_n = G_n^T diag(k) G_n`` (symmetric) plus ``mu K_f`` with
``K_f = G_t^T diag(k d) G_n`` (non-symmetric: normal displacement drives tangential force). This
is the mode-coupling mechanism of seed 002 (Massi et al.), also Hoffmann et al. (2002).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError
from fivid.fe.contact_nodes import node_stiffness
from fivid.fe.static import contact_geometry, preload_state, pressed_by_itself

__all__ = ["ContactLinearisation", "linearise_contact", "linearise_preloaded_contact", "sliding_directions"]


@dataclass(frozen=True)
class ContactLinearisation:
    """Rows of the linearised contact: one per slave node of every pair.

    Attributes
    ----------
    G_n, G_t : scipy.sparse.csr_matrix, shape (n_contact, n_dofs)
        Gap and tangential-slip operators [-].
    stiffness : ndarray, shape (n_contact,)
        Penalty stiffness per slave node [N m-1] (pressure stiffness x tributary area).
    direction : ndarray, shape (n_contact,)
        Sliding direction ``d`` in {-1, 0, +1} of each node along the master tangent.
    pair : ndarray of int, shape (n_contact,)
        Index of the contact pair of each row.
    slave : ndarray of int, shape (n_contact,), optional
        Index of each row's node among all slave nodes (all pairs, in order).
    """

    G_n: object
    G_t: object
    stiffness: np.ndarray
    direction: np.ndarray
    pair: np.ndarray
    slave: np.ndarray | None = None

    def normal_stiffness_matrix(self):
        """``K_n = G_n^T diag(k) G_n`` [N m-1] (sparse, symmetric)."""
        import scipy.sparse as sp

        return (self.G_n.T @ sp.diags(self.stiffness) @ self.G_n).tocsr()

    def friction_stiffness_matrix(self):
        """``K_f = G_t^T diag(k d) G_n`` [N m-1] (sparse, non-symmetric); the contact stiffness is ``K_n + mu K_f``."""
        import scipy.sparse as sp

        return (self.G_t.T @ sp.diags(self.stiffness * self.direction) @ self.G_n).tocsr()


def sliding_directions(model, velocities: dict[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
    """Rigid sliding velocity of each body [m s-1] from the base motion (or ``velocities`` to override).

    A body carrying a velocity motion with role "base" moves at its amplitude along its component;
    the others are at rest.
    """
    v = {b.name: np.zeros(2) for b in model.blocks}
    for m in model.motions:
        if m.role == "base" and m.kind == "velocity":
            v[model.block_of_node(int(m.nodes[0])).name][m.component] = m.amplitude
    if velocities:
        v.update({k: np.asarray(val, dtype=float) for k, val in velocities.items()})
    return v


def linearise_contact(model, *, velocities: dict[str, np.ndarray] | None = None,
                      closed: np.ndarray | None = None, penetration: np.ndarray | None = None
                      ) -> ContactLinearisation:
    """Linearise the contact pairs of ``model`` about a sliding state, one row per closed slave node.

    The geometry (projection, normals) is that of the reference configuration, like the static contact solve
    of :mod:`fivid.fe.static` whose closed set it takes (the preload displacements are microns); the operators
    are :meth:`fivid.fe.static.ContactGeometry.operators`, the node stiffnesses :func:`fivid.fe.contact_nodes.node_stiffness`. A rigid
    master's moving surface sets the sliding direction of its slaves.

    Parameters
    ----------
    model : Model
    velocities : dict, optional
        Body name -> rigid velocity [m s-1] setting the sliding direction; default from the base motion.
    closed : ndarray of bool, shape (n_slave,), optional
        Which slave nodes (all pairs, in order) are in contact, e.g. ``preload_state(model, load).active``
        (:func:`fivid.fe.static.preload_state`); open nodes get no row. Default: every slave node (a bonded
        interface: the operators of the whole slave range, not a physical state of a preloaded rig).
    penetration : ndarray, shape (n_slave,), optional
        Penetration of each slave node [m] where the compliant laws' tangent is taken (the preload's).

    Raises
    ------
    ConfigError
        A slave node does not project onto its master edge, or the bodies do not slide relative to each other.
    """
    geo = contact_geometry(model)
    n_slave = geo.slave_node.size
    closed = np.ones(n_slave, dtype=bool) if closed is None else np.asarray(closed, dtype=bool)
    if closed.shape != (n_slave,):
        raise ValueError(f"closed must have one flag per slave node ({n_slave}), got shape {closed.shape}")
    off = closed & ~geo.usable
    if off.any():
        k = int(np.flatnonzero(off)[0])
        c = model.contacts[geo.slave_pair[k]]
        s = int(geo.slave_node[k])
        raise ConfigError(f"contact {c.name!r}: slave node {s} at {model.coords[s].tolist()} m does not project onto "
                          f"master edge of body {c.master_block!r}; shorten the slave range",
                          key=f"contacts.{c.name}.slave")
    vel = sliding_directions(model, velocities)
    tangent = np.stack([-geo.normal[:, 1], geo.normal[:, 0]], axis=1)
    direction = np.zeros(n_slave)
    for p, c in enumerate(model.contacts):
        sel = geo.slave_pair == p
        v_master = vel[c.master_block] if c.rigid is None else 0.0
        v_rel = v_master - vel[c.slave_block]
        direction[sel] = np.sign(tangent[sel] @ v_rel + geo.surface_velocity[sel])
    G_n, G_t = geo.operators(model.n_dofs)
    rows = np.flatnonzero(closed)
    stiffness = node_stiffness(model, geo, penetration)
    return ContactLinearisation(G_n[rows], G_t[rows], stiffness[rows], direction[rows], geo.slave_pair[rows],
                                rows.astype(int))


def linearise_preloaded_contact(model, normal_load: float | None, *, velocities: dict[str, np.ndarray] | None = None,
                                mu=None, state=None):
    """Linearise the contact about the preloaded sliding equilibrium: springs only at the closed slave nodes.

    The closed set comes from the static contact solve under the transducer normal force ``normal_load``
    (:func:`fivid.fe.static.preload_state`, clamp lowered monotonically with friction ``mu``, default each pair's).
    On the default rig the bent upper beam touches with its tip corner only, not along its whole slave range.

    Parameters
    ----------
    model : Model
    normal_load : float
        Normal force [N] read by the transducer (the model's first reaction).
    velocities : dict, optional
        Body name -> rigid velocity [m s-1] setting the sliding direction (default from the base motion).
    mu : float, optional
        Friction coefficient during the preload.
    state : Preload, optional
        That static state already solved (``preload_state(model, normal_load, mu=mu)``, e.g. from a cache);
        default: solved here.

    Returns
    -------
    ContactLinearisation
        Rows of the closed nodes only.
    Preload
        The static state (closed set, normal forces [N], clamp displacement [m]).

    Raises
    ------
    ConfigError
        ``normal_load`` is None, or the model cannot be preloaded (no load motion or reaction).
    """
    if normal_load is None and not pressed_by_itself(model):
        raise ConfigError("linearising the contact needs the normal load: only the slave nodes closed under it "
                          "carry contact springs (give normal_load [N], e.g. --load '5 N')", key="normal_load")
    if state is None:
        state = preload_state(model, normal_load, mu=mu)
    return linearise_contact(model, velocities=velocities, closed=state.active,
                             penetration=state.penetration), state
