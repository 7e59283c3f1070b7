"""Contact-law and rigid-surface kernels: the one definition of each law's force, tangent and energy (layer L0).

Every analysis calls these same functions: the explicit solver's contact correction
(:func:`fivid.solver._contact_kernels.contact_solve`), the static preload solve (:mod:`fivid.fe.static`) and the
linearisation for modes/CEA (:mod:`fivid.fe.contact`) -- so the three cannot disagree. They are jitted
scalar functions, callable from Python too.

A deformable master (a body's edge, node-to-segment) is a polyline; the gap of a slave is its signed distance to
the polyline's closest point, along the outward normal there: the foot of its orthogonal projection on a segment
(that segment's normal), or a vertex when it lies beyond both segments meeting there
(:func:`vertex_geometry`). The searches differ (the explicit solver walks locally, the static preload compares every
segment) but the segment and vertex definitions are these.

Per contact pair the parameters are one row ``par`` of the record :mod:`fivid.contact._layout_kernels` (built by
:func:`fivid.contact.kernel_row`) and, for a tabulated normal law, a table ``tab`` (2, m) of pressures and
energies on a uniform penetration grid (:func:`fivid.contact.kernel_tables`). The friction curve's kernel is
:func:`fivid.friction._curve_kernels.friction_coefficient` (the friction home).
"""

import math

from numba import njit

import fivid._cache_kernels  # noqa: F401  (cache keyed on every kernel source: these read _layout_kernels' constants)
from fivid.contact._layout_kernels import LAW_LINEAR, LAW_POWER, LAW_RIGID, MASTER_LINE

__all__ = ["normal_pressure", "normal_energy", "surface_ramp", "circle_radius", "rigid_geometry", "vertex_geometry"]


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
def surface_ramp(t, t0, tr):
    """Smooth ramp 0 -> 1 of a rigid surface's motion at time ``t`` [s] (start ``t0``, ramp time ``tr``)."""
    if t <= t0:
        return 0.0
    if tr <= 0.0 or t >= t0 + tr:
        return 1.0
    s = (t - t0) / tr
    return s - math.sin(2.0 * math.pi * s) / (2.0 * math.pi)


@njit(cache=True)
def circle_radius(a, delta, t0, tr, t):
    """Radius [m] at time ``t`` [s] of a rigid circle of initial radius ``a`` [m] expanding radially by ``delta``
    [m] over the smooth ramp (start ``t0``, ramp time ``tr``) of :func:`surface_ramp`: ``a + delta r(t)``. The one
    definition of an expanding master's radius history (explicit solver, static preload, linearisation); ``t``
    inf: the final radius ``a + delta``."""
    if delta == 0.0:
        return a
    return a + delta * surface_ramp(t, t0, tr)


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


@njit(cache=True)
def vertex_geometry(xs, ys, xv, yv, n1x, n1y, n2x, n2y, sign):
    """Gap [m], outward unit normal ``n`` and unit tangent ``t`` of a slave at ``(xs, ys)`` [m] whose closest point
    on a master polyline is the vertex ``(xv, yv)`` [m]: the slave projects beyond both segments meeting there
    (``xi > 1`` on the one ending at the vertex, ``xi < 0`` on the one starting there), the wedge between the
    segments' outward unit normals ``n1``, ``n2`` (open, over a convex vertex) or between their opposites
    (penetrating, under a concave vertex: a slave there projects onto neither segment and would otherwise carry
    no force however deep it goes).

    The closest-point (signed-distance) definition of node-to-segment contact on a non-smooth master: the slave's
    gap is its distance to the nearest point of the master, signed by the side it is on. Where no orthogonal
    projection onto a master segment exists the nearest point is the master node, and the normal the unit vector
    joining it to the slave (the node-to-node treatment of that region in Wriggers, *Computational Contact
    Mechanics*, 2nd ed. 2006, ch. 9, node-to-segment discretisation; an averaged vertex normal instead would make
    the gap jump by ``|x_s - x_v| (1 - cos(theta / 2))`` where the slave enters the wedge of angle ``theta``): ``g = s |x_s - x_v|`` and ``n = s (x_s - x_v) / |x_s - x_v|``, with
    ``s = sign((x_s - x_v) . (n1 + n2))`` (+1 outside, -1 inside). On the wedge's boundary ``x_s - x_v`` is parallel
    to the neighbouring segment's normal, so gap and normal continue those of the segment (no jump as a slave slides
    across the vertex). At the vertex itself (zero distance) the normal is the bisector ``(n1 + n2) / |n1 + n2|``,
    the gap 0. The tangent is ``t = sign (-n_y, n_x)``, oriented like the segments' (``n = sign (t_y, -t_x)``,
    ``sign`` the pair's orientation, :func:`fivid.solver._contact_kernels._locate`).
    """
    dx = xs - xv
    dy = ys - yv
    mx = n1x + n2x
    my = n1y + n2y
    d = math.sqrt(dx * dx + dy * dy)
    m = math.sqrt(mx * mx + my * my)
    if d == 0.0 or m == 0.0:
        nx = mx / m if m > 0.0 else n1x
        ny = my / m if m > 0.0 else n1y
        g = 0.0
    else:
        s = 1.0 if dx * mx + dy * my >= 0.0 else -1.0
        nx = s * dx / d
        ny = s * dy / d
        g = s * d
    return g, nx, ny, -sign * ny, sign * nx
