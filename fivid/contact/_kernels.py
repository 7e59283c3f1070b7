"""Contact-law and rigid-surface kernels: the one definition of each law's force, tangent and energy (layer L0).

Every analysis calls these same functions: the explicit solver's contact correction
(:func:`fivid.solver._contact_kernels.contact_solve`), the static preload solve (:mod:`fivid.fe.static`) and the
linearisation for modes/CEA (:mod:`fivid.fe.contact`) -- so the three cannot disagree. They are jitted
scalar functions, callable from Python too.

Per contact pair the parameters are one row ``par`` of :data:`NPAR` floats (built by
:func:`fivid.contact.kernel_row`) and, for a tabulated normal law, a table ``tab`` (2, m) of pressures and
energies on a uniform penetration grid (:func:`fivid.contact.kernel_tables`):

==== ===========================================================================================
col  meaning
==== ===========================================================================================
0    normal law: 0 rigid (Lagrange multipliers, no penetration), 1 linear ``p = c d``,
     2 power ``p = c d**n``, 3 table (``d`` penetration [m], ``p`` pressure [Pa])
1    ``c`` [Pa m-1] (linear), [Pa m-n] (power) or the table's penetration step [m]
2    ``n`` [-] (power)
3    ``mu_s - mu_k``: static excess of the friction coefficient [-]
4    Stribeck velocity ``v_s`` [m s-1] (0: no Stribeck curve, a step from ``mu_s`` to ``mu_k``)
5    viscous friction coefficient ``c_v`` [s m-1]: ``mu(v) = mu_k + (mu_s - mu_k) exp(-|v|/v_s) + c_v |v|``
6    master: 0 a deformable body's edge (node-to-segment), 1 rigid line, 2 rigid circle
7, 8 line: a point on it [m]; circle: centre [m]
9,10 line: unit normal pointing to the slave side; circle: radius [m] and side (+1: slave outside, -1 inside)
11,12 line: surface velocity [m s-1] (along the line); circle: angular velocity [rad s-1] (counter-clockwise
     positive) and unused
13,14 surface motion start time and ramp time [s] (smooth ramp ``r(s) = s - sin(2 pi s)/(2 pi)``)
==== ===========================================================================================
"""

import math

from numba import njit

__all__ = ["NPAR", "LAW_RIGID", "LAW_LINEAR", "LAW_POWER", "LAW_TABLE", "MASTER_EDGE", "MASTER_LINE", "MASTER_CIRCLE",
           "normal_pressure", "normal_energy", "friction_coefficient", "surface_ramp", "rigid_geometry"]

NPAR = 15
LAW_RIGID = 0
LAW_LINEAR = 1
LAW_POWER = 2
LAW_TABLE = 3
MASTER_EDGE = 0
MASTER_LINE = 1
MASTER_CIRCLE = 2


@njit(cache=True)
def normal_pressure(kind, c, n, d, tab):
    """Contact pressure [Pa] and its tangent ``dp/dd`` [Pa m-1] at penetration ``d`` [m] (0 when open).

    ``tab`` (2, m): a tabulated law's pressures ``tab[0, i]`` and energies ``tab[1, i]`` at ``d_i = i c``,
    interpolated linearly (tangent: the segment's slope; beyond the table: the last segment extended).
    """
    if d <= 0.0 or kind == LAW_RIGID:
        return 0.0, 0.0
    if kind == LAW_LINEAR:
        return c * d, c
    if kind == LAW_POWER:
        p = c * d ** n
        return p, n * p / d
    m = tab.shape[1]
    i = min(int(d / c), m - 2)
    slope = (tab[0, i + 1] - tab[0, i]) / c
    return tab[0, i] + slope * (d - i * c), slope


@njit(cache=True)
def normal_energy(kind, c, n, d, tab):
    """Stored energy per unit area ``int_0^d p`` [J m-2] at penetration ``d`` [m] (0 for the rigid law)."""
    if d <= 0.0 or kind == LAW_RIGID:
        return 0.0
    if kind == LAW_LINEAR:
        return 0.5 * c * d * d
    if kind == LAW_POWER:
        return c * d ** (n + 1.0) / (n + 1.0)
    m = tab.shape[1]
    i = min(int(d / c), m - 2)
    slope = (tab[0, i + 1] - tab[0, i]) / c
    s = d - i * c
    return tab[1, i] + tab[0, i] * s + 0.5 * slope * s * s


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
def surface_ramp(t, t0, tr):
    """Smooth ramp 0 -> 1 of a rigid surface's motion at time ``t`` [s] (start ``t0``, ramp time ``tr``)."""
    if t <= t0:
        return 0.0
    if tr <= 0.0 or t >= t0 + tr:
        return 1.0
    s = (t - t0) / tr
    return s - math.sin(2.0 * math.pi * s) / (2.0 * math.pi)


@njit(cache=True)
def rigid_geometry(kind, px, py, a, b, sx, sy, x0, y0, x, y):
    """Gap [m], outward unit normal ``n``, tangent ``t = (-n_y, n_x)`` and the full-speed surface velocity
    along ``t`` [m s-1] of a rigid master at a slave with reference position ``(x0, y0)`` and current position
    ``(x, y)`` [m].

    Line: through ``(px, py)`` with unit normal ``(a, b)``, surface velocity ``(sx, sy)``; ``g = (x - p) . n``.
    Circle: centre ``(px, py)``, radius ``a``, ``b = +1`` slave outside (a shaft) or ``-1`` inside (a bore),
    angular velocity ``sx`` (counter-clockwise positive): the normal is the radial direction ``e0`` through the
    slave's reference position and the gap ``g = b ((x - C) . e0 - a)``, the small-displacement kinematics of
    the bodies (a held ring turns by a milliradian; a normal that followed it would tilt the normal forces
    against the linear body's equilibrium by that angle, a torque of that order of the friction's). The
    material point under the slave moves at ``omega x (x_c - C)``.
    """
    if kind == MASTER_LINE:
        nx = a
        ny = b
        g = (x - px) * nx + (y - py) * ny
        tx = -ny
        ty = nx
        return g, nx, ny, tx, ty, sx * tx + sy * ty
    dx = x0 - px
    dy = y0 - py
    r = math.sqrt(dx * dx + dy * dy)
    if r == 0.0:
        return math.inf, 0.0, 1.0, -1.0, 0.0, 0.0
    ex = dx / r
    ey = dy / r
    nx = b * ex
    ny = b * ey
    g = b * ((x - px) * ex + (y - py) * ey - a)
    tx = -ny
    ty = nx
    # contact point x_c = C + a e; its velocity omega (-(a e_y), a e_x), projected on t
    vt = sx * a * (-ey * tx + ex * ty)
    return g, nx, ny, tx, ty, vt
