"""Friction kernels (layer L0): the kinetic curve ``mu(v)`` and the coefficient ``mu0 + mu_p(t)`` now.

The friction home's compiled side (:mod:`fivid.friction`): :func:`friction_coefficient` is the one definition of
the kinetic curve (static excess, Stribeck decay, viscous term) that the explicit solver's contact correction and
:meth:`fivid.friction.FrictionCurve.coefficient` evaluate; :func:`friction_now` the one evaluation of a slave's
kinetic coefficient at a time from the table :func:`fivid.friction.friction_table` sampled. The curve's parameters
sit in a contact pair's record at the named columns of :mod:`fivid.contact._layout_kernels`.
"""

import math

from numba import njit

__all__ = ["friction_coefficient", "friction_now"]


@njit(cache=True)
def friction_coefficient(mu_k, excess, v_s, c_v, v):
    """Kinetic friction coefficient at slip speed ``v`` [m s-1]: ``mu_k + excess exp(-|v|/v_s) + c_v |v|``.

    ``v_s = 0``: no Stribeck curve (the static excess applies only to stick, a step at ``v = 0``).
    """
    av = abs(v)
    mu = mu_k + c_v * av
    if v_s > 0.0:
        mu += excess * math.exp(-av / v_s)
    return mu


@njit(cache=True)
def friction_now(mu_tab, mu_rate, t, mu_now):
    """Kinetic coefficient ``mu0 + mu_p(t)`` of every slave at time ``t`` [s] into ``mu_now``: the table ``mu_tab``
    (rows at ``mu_rate`` [Hz], one row: constant; :func:`fivid.friction.friction_table`) interpolated linearly,
    clipped at 0."""
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
