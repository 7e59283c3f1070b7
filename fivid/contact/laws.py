"""Contact laws of a pair: normal (rigid, linear, power, Greenwood-Williamson) and tangential (mu_s/mu_k, Stribeck).

The force, tangent and energy of each law live once, in :mod:`fivid.contact._kernels`; these classes hold the
parameters, convert them to the kernels' row and evaluate the same functions from Python (static preload,
linearisation, reports).

Normal laws (pressure ``p`` [Pa] against penetration ``d`` [m], per unit area of the slave edge):

- ``rigid``: no penetration (Lagrange multipliers in the explicit solver and the static solve); modes/CEA
  couple the bodies with the pair's ``normal_stiffness`` [N m-3] penalty.
- ``linear``: ``p = k d`` with ``k`` [N m-3] (Pa per metre).
- ``power``: ``p = c d**n``.
- ``table``: ``p(d)`` tabulated on a uniform penetration grid (linear interpolation).
- ``greenwood-williamson``: rough surfaces (Greenwood & Williamson 1966): asperity summits with Gaussian heights
  of standard deviation ``sigma`` [m], tip radius ``R`` [m] and areal density ``eta`` [m-2], each a Hertz contact
  with the composite modulus ``E*``, give at mean-plane separation ``h``

      p(h) = (4/3) eta E* sqrt(R) sigma**1.5 F_3/2(h / sigma),   F_3/2(x) = int_x^inf (s - x)**1.5 phi(s) ds

  (``phi`` the standard normal density; ``F_3/2`` in closed form by a parabolic cylinder function). Every
  analysis uses it exactly, tabulated (:meth:`GreenwoodWilliamson.table_law`, penetration ``d = h0 - h`` from the
  separation ``h0`` where the pressure is 1 Pa); or, on request, the power law ``p = c d**n`` fitted to it over a
  pressure range (:meth:`GreenwoodWilliamson.power_fit`; a power law follows GW's near-Gaussian tail only over a
  decade or two: the fit's largest deviation is recorded in ``source``).

The tangential law (Coulomb with static/kinetic coefficients, Stribeck curve, viscous term, and the perturbation
``mu0 + mu_p(t)``) lives in the friction home, :mod:`fivid.friction` (:class:`~fivid.friction.FrictionCurve`).
A pair's parameters reach the kernels as one record row (:func:`kernel_row`, layout
:mod:`fivid.contact._layout_kernels`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from fivid.contact import _layout_kernels as layout
from fivid.errors import ConfigError
from fivid.friction.curve import FrictionCurve

__all__ = ["RIGID", "GreenwoodWilliamson", "NormalLaw", "RigidSurface", "composite_modulus", "kernel_row",
           "kernel_tables"]

_KINDS = {"rigid": 0, "linear": 1, "power": 2, "table": 3}
_NO_TABLE = np.zeros((2, 2))


@dataclass(frozen=True, eq=False)
class NormalLaw:
    """Normal contact law ``p(d)``.

    Attributes
    ----------
    kind : {"rigid", "linear", "power", "table"}
    coefficient : float
        ``k`` [Pa m-1] (linear), ``c`` [Pa m-n] (power) or the table's penetration step [m]; unused for rigid.
    exponent : float
        ``n`` [-] of the power law (1 for linear).
    source : str
        How the parameters were obtained (e.g. the Greenwood-Williamson surface and the table's accuracy).
    table : ndarray (2, m), optional
        Pressures [Pa] and stored energies [J m-2] at penetrations ``0, c, 2c, ...`` (kind "table"; linear
        interpolation, the last segment extended beyond).
    """

    kind: str = "rigid"
    coefficient: float = 0.0
    exponent: float = 1.0
    source: str = ""
    table: np.ndarray | None = None

    def __post_init__(self):
        if self.kind not in _KINDS:
            raise ConfigError(f"normal contact law {self.kind!r} is not one of {sorted(_KINDS)}")
        if self.kind != "rigid" and not (self.coefficient > 0 and np.isfinite(self.coefficient)):
            raise ConfigError(f"the {self.kind} normal law needs a positive coefficient, got {self.coefficient!r}")
        if self.kind == "table" and (self.table is None or np.shape(self.table)[0] != 2
                                     or np.shape(self.table)[1] < 2):
            raise ConfigError("a tabulated normal law needs a (2, m >= 2) table of pressures and energies")
        if self.kind == "power" and not (self.exponent >= 1.0 and np.isfinite(self.exponent)):
            raise ConfigError(f"the power law's exponent must be >= 1 (a tangent that vanishes at first touch "
                              f"or grows with load), got {self.exponent!r}")

    @property
    def code(self) -> int:
        """The law's kind as the integer the contact kernel switches on: 0 rigid, 1 linear, 2 power, 3 table."""
        return _KINDS[self.kind]

    @property
    def is_penalty(self) -> bool:
        """True for the compliant laws (penetration allowed), False for the rigid law."""
        return self.kind != "rigid"

    @property
    def kernel_table(self) -> np.ndarray:
        """The (2, m) table the kernels take (a dummy for the closed-form laws)."""
        return np.ascontiguousarray(self.table, dtype=float) if self.kind == "table" else _NO_TABLE

    def _eval(self, d):
        from fivid.contact._kernels import normal_pressure  # lazy: pulls numba

        d = np.asarray(d, dtype=float)
        tab = self.kernel_table
        out = np.array([normal_pressure(self.code, self.coefficient, self.exponent, float(x), tab)
                        for x in d.ravel()])
        out = out.reshape(d.shape + (2,)) if out.size else np.zeros(d.shape + (2,))
        return out[..., 0], out[..., 1]

    def pressure(self, d):
        """Pressure [Pa] at penetration ``d`` [m] (array)."""
        return self._eval(d)[0]

    def tangent(self, d):
        """``dp/dd`` [Pa m-1] at penetration ``d`` [m] (array)."""
        return self._eval(d)[1]

    def energy(self, d):
        """Stored energy per unit area [J m-2] at penetration ``d`` [m] (array)."""
        from fivid.contact._kernels import normal_energy  # lazy: pulls numba

        d = np.asarray(d, dtype=float)
        tab = self.kernel_table
        return np.array([normal_energy(self.code, self.coefficient, self.exponent, float(x), tab)
                         for x in d.ravel()]).reshape(d.shape)

    def penetration(self, p):
        """Penetration [m] at pressure ``p`` [Pa] (inverse of the law; 0 for p <= 0)."""
        p = np.maximum(np.asarray(p, dtype=float), 0.0)
        if self.kind == "rigid":
            return np.zeros_like(p)
        if self.kind == "table":
            d = self.coefficient * np.arange(self.table.shape[1])
            pt = self.table[0]
            slope = (pt[-1] - pt[-2]) / self.coefficient
            return np.where(p <= pt[-1], np.interp(p, pt, d), d[-1] + (p - pt[-1]) / slope)
        return (p / self.coefficient) ** (1.0 / self.exponent)

    def describe(self) -> str:
        """One line for logs and reports: the pressure law p(d) [Pa] of the penetration d [m], and its source."""
        if self.kind == "rigid":
            return "rigid (Lagrange multipliers)"
        if self.kind == "linear":
            text = f"linear p = {self.coefficient:.4g} Pa/m * d"
        elif self.kind == "table":
            text = f"tabulated p(d), {self.table.shape[1]} points every {self.coefficient:.4g} m"
        else:
            text = f"power p = {self.coefficient:.4g} * d^{self.exponent:.4g} Pa"
        return f"{text}; {self.source}" if self.source else text


RIGID = NormalLaw()


def composite_modulus(*materials) -> float:
    """Composite (contact) modulus ``E* = 1 / sum (1 - nu_i^2)/E_i`` [Pa] of the touching materials."""
    return 1.0 / sum((1.0 - m.nu ** 2) / m.E for m in materials)


@dataclass(frozen=True)
class GreenwoodWilliamson:
    """Greenwood-Williamson rough surface against a flat (see the module docstring).

    Attributes
    ----------
    sigma : float
        Standard deviation of the summit heights [m] (~ Rq of the profile for Gaussian surfaces).
    radius : float
        Asperity tip radius [m].
    density : float
        Areal density of summits [m-2].
    e_star : float
        Composite modulus [Pa].
    """

    sigma: float
    radius: float
    density: float
    e_star: float

    def __post_init__(self):
        for name in ("sigma", "radius", "density", "e_star"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ConfigError(f"Greenwood-Williamson {name} must be positive, got {v!r}")

    @staticmethod
    def f32(x) -> np.ndarray:
        """``F_3/2(x) = int_x^inf (s - x)^1.5 phi(s) ds`` with the standard normal density ``phi``, in closed form
        by the parabolic cylinder function: ``Gamma(5/2) / sqrt(2 pi) exp(-x^2/4) D_{-5/2}(x)``."""
        from scipy.special import pbdv

        x = np.atleast_1d(np.asarray(x, dtype=float))
        return math.gamma(2.5) / math.sqrt(2.0 * math.pi) * np.exp(-0.25 * x * x) * pbdv(-2.5, x)[0]

    def pressure_at_separation(self, h) -> np.ndarray:
        """Nominal pressure [Pa] at mean-plane separation ``h`` [m]."""
        s = self.sigma
        return 4.0 / 3.0 * self.density * self.e_star * math.sqrt(self.radius) * s ** 1.5 * self.f32(
            np.asarray(h, dtype=float) / s)

    def separation_at(self, p: float) -> float:
        """Mean-plane separation [m] where the nominal pressure is ``p`` [Pa]."""
        from scipy.optimize import brentq

        s = self.sigma
        lo, hi = -20.0 * s, 40.0 * s
        if not float(self.pressure_at_separation(lo)[0]) > p:
            raise ConfigError(f"the Greenwood-Williamson surface reaches only "
                              f"{float(self.pressure_at_separation(lo)[0]):.3g} Pa at 20 sigma of approach past "
                              f"the mean planes; {p:.3g} Pa is out of its reach")
        return brentq(lambda h: float(self.pressure_at_separation(h)[0]) - p, lo, hi, xtol=1e-12 * s)

    def table_law(self, max_pressure: float = 1e8, origin_pressure: float = 1.0, n_points: int = 2049) -> NormalLaw:
        """The exact GW law tabulated for the kernels: ``p(d) = p_GW(h0 - d) - p_GW(h0)`` on ``n_points``
        penetrations from 0 to the one of ``max_pressure`` [Pa], ``h0`` the separation where the GW pressure is
        ``origin_pressure`` [Pa] (1 Pa: nothing a lab contact can feel), energies by the exact integral of the
        linear interpolant. The interpolation's largest relative error (at the segment midpoints, against the
        closed form) is recorded in ``source``; beyond ``max_pressure`` the last segment is extended."""
        if not (max_pressure > origin_pressure > 0):
            raise ConfigError(f"max_pressure ({max_pressure!r} Pa) must exceed the origin pressure ({origin_pressure} Pa)")
        h0 = self.separation_at(origin_pressure)
        d_max = h0 - self.separation_at(max_pressure)
        step = d_max / (n_points - 1)
        d = step * np.arange(n_points)
        p0 = float(self.pressure_at_separation(h0)[0])
        p = self.pressure_at_separation(h0 - d) - p0
        p[0] = 0.0
        e = np.concatenate([[0.0], np.cumsum(0.5 * step * (p[1:] + p[:-1]))])
        mid = self.pressure_at_separation(h0 - d[:-1] - 0.5 * step) - p0
        sel = mid > 1e-6 * max_pressure
        err = float(np.max(np.abs(0.5 * (p[1:] + p[:-1])[sel] / mid[sel] - 1.0))) if sel.any() else 0.0
        src = (f"Greenwood-Williamson (sigma {self.sigma:.4g} m, asperity radius {self.radius:.4g} m, density "
               f"{self.density:.4g} m-2, E* {self.e_star:.4g} Pa), penetration from separation h0 = "
               f"{h0 / self.sigma:.4g} sigma (p = {origin_pressure:g} Pa), tabulated to {max_pressure:.3g} Pa, "
               f"interpolation error <= {100 * err:.2g} %")
        return NormalLaw("table", step, 1.0, src, np.stack([p, e]))

    def power_fit(self, pressure_range=(1e3, 1e6), n_points=40) -> NormalLaw:
        """Least-squares power law ``p = c d^n`` (log-log) to the GW pressure over ``pressure_range`` [Pa].

        The penetration ``d = h0 - h`` counts from the separation ``h0`` where the GW pressure is 1e-3 of the
        range's lower end: the power law's zero there costs the fit nothing it is asked to represent.
        """
        lo, hi = (float(p) for p in pressure_range)
        if not (0 < lo < hi):
            raise ConfigError(f"pressure_range must be two increasing positive pressures, got {pressure_range!r}")
        h0 = self.separation_at(1e-3 * lo)
        d = np.geomspace(h0 - self.separation_at(lo), h0 - self.separation_at(hi), n_points)
        p = self.pressure_at_separation(h0 - d)
        n, logc = np.polyfit(np.log(d), np.log(p), 1)
        c = math.exp(logc)
        dev = float(np.max(np.abs(c * d ** n / p - 1.0)))
        if n < 1.0:
            raise ConfigError(f"the Greenwood-Williamson fit over {lo:.3g}-{hi:.3g} Pa has exponent {n:.3g} < 1")
        src = (f"Greenwood-Williamson fit (sigma {self.sigma:.4g} m, asperity radius {self.radius:.4g} m, density "
               f"{self.density:.4g} m-2, E* {self.e_star:.4g} Pa; penetration from separation h0 = "
               f"{h0 / self.sigma:.4g} sigma) over {lo:.3g}-{hi:.3g} Pa, largest deviation {100 * dev:.2g} %")
        return NormalLaw("power", c, float(n), src)


@dataclass(frozen=True)
class RigidSurface:
    """A rigid contact master: a line or a circle, fixed in space, whose surface may move along itself; a circle
    may also expand radially (the preload of seed 002: the steel cylinder's radius grows until the contact
    pressure is reached, then it turns).

    The motions that leave the surface in place are the ones a rig imposes: a belt or plate sliding along its
    own line, a cylinder turning about its axis. Its surface speed ramps from 0 at ``start`` to full over
    ``ramp_time`` (the smooth ramp of the solver's motions). A circle's radius is ``radius + expansion r(t)``
    with the same smooth ramp ``r`` from ``expansion_start`` over ``expansion_ramp_time``
    (:func:`fivid.contact._kernels.circle_radius`, the one definition the explicit solver, the static preload
    and the linearisation for modes/CEA evaluate; the static analyses take the final radius).

    Attributes
    ----------
    kind : {"line", "circle"}
    point : ndarray (2,)
        Line: a point on it; circle: its centre [m].
    normal : ndarray (2,)
        Line: unit normal pointing to the slave side [-].
    radius : float
        Circle radius [m].
    side : {"outside", "inside"}
        Circle: the slave body lies outside (a shaft in a bore of the body) or inside it.
    velocity : ndarray (2,)
        Line: velocity of its surface [m s-1] (parallel to the line).
    angular_velocity : float
        Circle: counter-clockwise angular velocity [rad s-1].
    start, ramp_time : float
        Ramp of the surface motion [s].
    expansion : float
        Circle: radial displacement of its surface [m] (> 0 grows the radius; 0: fixed radius).
    expansion_start, expansion_ramp_time : float
        Ramp of the expansion [s].
    target_mean_pressure : float
        Circle: the mean contact pressure [Pa] the expansion was solved for
        (:func:`fivid.fe.static.resolve_expansions`; NaN: the expansion was given, or not yet solved while
        ``expansion`` is NaN).
    """

    kind: str
    point: np.ndarray
    normal: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0]))
    radius: float = 0.0
    side: str = "outside"
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(2))
    angular_velocity: float = 0.0
    start: float = 0.0
    ramp_time: float = 0.0
    expansion: float = 0.0
    expansion_start: float = 0.0
    expansion_ramp_time: float = 0.0
    target_mean_pressure: float = math.nan

    @property
    def code(self) -> int:
        """The surface's kind as the code the contact kernel switches on (:mod:`fivid.contact._layout_kernels`)."""
        return layout.MASTER_LINE if self.kind == "line" else layout.MASTER_CIRCLE

    def columns(self) -> list[float]:
        """Its record columns, :data:`~fivid.contact._layout_kernels.MASTER` to
        :data:`~fivid.contact._layout_kernels.EXPANSION_RAMP` in that order."""
        if not math.isfinite(self.expansion):
            raise ConfigError("the rigid circle's expansion is not solved yet (a target mean pressure): build the "
                              "model with fivid.fe.load_model, which solves it (fivid.fe.static.resolve_expansions)")
        if self.kind == "line":
            a, b = (float(x) for x in self.normal)
            sx, sy = (float(x) for x in self.velocity)
        else:
            a, b = float(self.radius), (1.0 if self.side == "outside" else -1.0)
            sx, sy = float(self.angular_velocity), 0.0
        return [float(self.code), float(self.point[0]), float(self.point[1]), a, b, sx, sy,
                float(self.start), float(self.ramp_time), float(self.expansion), float(self.expansion_start),
                float(self.expansion_ramp_time)]

    def radius_at(self, t=math.inf) -> float:
        """A circle's radius [m] at time ``t`` [s] (default: after the expansion), ``radius + expansion r(t)``."""
        from fivid.contact._kernels import circle_radius  # lazy: pulls numba

        delta = self.expansion if math.isfinite(self.expansion) else 0.0
        return float(circle_radius(self.radius, delta, self.expansion_start, self.expansion_ramp_time, float(t)))

    def geometry(self, xy, t=math.inf, *, reference=None):
        """Gap [m], normal (n, 2), tangent (n, 2) and surface velocity along the tangent [m s-1] at time ``t``
        [s] (default: full speed) of slave positions ``xy`` (n, 2) whose reference positions are ``reference``
        (default ``xy``; a circle's normal is radial through the reference position, its radius
        :meth:`radius_at` ``t``)."""
        from fivid.contact._kernels import rigid_geometry, surface_ramp  # lazy: pulls numba

        cols = self.columns()
        if self.kind == "circle":
            cols[3] = self.radius_at(t)
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        ref = xy if reference is None else np.asarray(reference, dtype=float).reshape(-1, 2)
        out = np.array([rigid_geometry(int(cols[0]), *cols[1:7], float(x0), float(y0), float(x), float(y))
                        for (x0, y0), (x, y) in zip(ref, xy)]).reshape(-1, 6)
        r = surface_ramp(float(t), self.start, self.ramp_time) if np.isfinite(t) else 1.0
        return out[:, 0], out[:, 1:3], out[:, 3:5], r * out[:, 5]

    def describe(self) -> str:
        """One line for logs and reports: the line or circle's geometry [m], surface velocity [m/s] or speed [rad/s]."""
        if self.kind == "line":
            return (f"rigid line through {np.round(self.point, 9).tolist()} m, normal {np.round(self.normal, 6).tolist()}"
                    f", surface velocity {np.round(self.velocity, 9).tolist()} m/s")
        grow = ""
        if self.expansion != 0.0:
            grow = (f", expanding by {self.expansion:.6g} m over {self.expansion_ramp_time:.6g} s from "
                    f"{self.expansion_start:.6g} s")
            if math.isfinite(self.target_mean_pressure):
                grow += f" (solved for a mean contact pressure of {self.target_mean_pressure:.6g} Pa)"
        return (f"rigid circle centre {np.round(self.point, 9).tolist()} m, radius {self.radius:.6g} m, slave "
                f"{self.side}, angular velocity {self.angular_velocity:.6g} rad/s{grow}")


def kernel_tables(laws) -> np.ndarray:
    """The pairs' normal-law tables stacked for the kernels, shape (n_pairs, 2, m) (zeros for closed-form laws)."""
    m = max([2] + [law.table.shape[1] for law in laws if law.kind == "table"])
    out = np.zeros((len(laws), 2, m))
    for i, law in enumerate(laws):
        if law.kind == "table":
            if law.table.shape[1] != m:  # one length for all: resample onto the longest grid's count
                raise ConfigError("tabulated contact laws of one model must have the same number of points")
            out[i] = law.table
    return out


def kernel_row(law: NormalLaw, friction: FrictionCurve, rigid: RigidSurface | None) -> np.ndarray:
    """The pair's parameter record for the kernels: :data:`~fivid.contact._layout_kernels.NPAR` floats at the named columns
    of :mod:`fivid.contact._layout_kernels` (a deformable master edge: the master columns stay 0, ``MASTER_EDGE``)."""
    row = np.zeros(layout.NPAR)
    row[layout.LAW] = law.code
    row[layout.LAW_COEFFICIENT] = law.coefficient
    row[layout.LAW_EXPONENT] = law.exponent
    curve = friction.columns()
    row[layout.FRICTION_FIRST:layout.FRICTION_FIRST + len(curve)] = curve
    if rigid is not None:
        surface = rigid.columns()
        row[layout.MASTER:layout.MASTER + len(surface)] = surface
    return row
