"""Per-node contact quantities of a model's contact pairs: tributary areas [m2] and linearised normal stiffness
[N m-1]. Shared by the static preload (:mod:`fivid.fe.static`), the linearised contact (:mod:`fivid.fe.contact`)
and the explicit solver's set-up."""

from __future__ import annotations

import numpy as np

__all__ = ["slave_areas", "node_stiffness"]


def _tributary_lengths(xy: np.ndarray) -> np.ndarray:
    """Half the distance to each neighbour along an ordered chain of points [m]."""
    seg = np.hypot(*np.diff(xy, axis=0).T)
    w = np.zeros(len(xy))
    w[:-1] += seg / 2.0
    w[1:] += seg / 2.0
    return w


def slave_areas(model, pair) -> np.ndarray:
    """Tributary area of each slave node of ``pair`` [m2]: half the distance to its edge neighbours x thickness.

    A slave range that is a whole closed ring edge (first and last node adjacent through the seam) closes
    the chain.
    """
    xy = model.coords[np.asarray(pair.slave_nodes)]
    w = _tributary_lengths(xy)
    if len(xy) > 2:
        closing = float(np.hypot(*(xy[0] - xy[-1])))
        step = float(np.median(np.hypot(*np.diff(xy, axis=0).T)))
        if closing < 1.5 * step:  # closed chain (ring seam)
            w[0] += closing / 2.0
            w[-1] += closing / 2.0
    return w * model.block(pair.slave_block).thickness


def node_stiffness(model, geo, penetration=None) -> np.ndarray:
    """Normal stiffness of each slave node [N m-1] for the linearised contact: the compliant law's tangent
    ``A p'(d)`` at the node's penetration ``d`` [m] (``penetration``, e.g. of the static preload), or for the rigid
    law the pair's modal penalty ``normal_stiffness x A``."""
    k = np.zeros(geo.slave_node.size)
    d = np.zeros_like(k) if penetration is None else np.asarray(penetration, dtype=float)
    for p, pair in enumerate(model.contacts):
        sel = geo.slave_pair == p
        if pair.law.is_penalty:
            k[sel] = geo.area[sel] * pair.law.tangent(d[sel])
        else:
            k[sel] = geo.area[sel] * pair.normal_stiffness
    return k
