"""The identified domain of a friction law: the test conditions (V, Ra, Fn) its amplitude law was fitted on.

A law is trusted inside the domain and extrapolates outside it. The domain is the convex hull of the
conditions in log coordinates (ln V, ln Ra, ln Fn: the power laws are linear there, and the conditions
of a test matrix are usually spaced by factors) of the variables that varied:

- one variable varied: its range [min, max];
- d >= 2 varied and the conditions span d dimensions (at least d + 1 of them, affine rank d): the convex
  hull (:class:`scipy.spatial.ConvexHull`; a point is inside when its distance beyond every facet is at
  most ln(1.01), the 1 % tolerance at which two conditions are the same level);
- d >= 2 varied but the conditions do not span d dimensions (e.g. every run on one line through the
  (V, Ra) plane): the bounding box of the conditions, a documented over-approximation.

A variable that did not vary is identified at that one value (± 1 %): any other value is outside.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.errors import FividError

__all__ = ["ConditionDomain", "DOMAIN_VARIABLES", "format_condition"]

#: the condition variables, their SI units and the units conditions are shown in
DOMAIN_VARIABLES = (("sliding_velocity", "m s-1", "mm/s", 1e-3), ("roughness_ra", "m", "um", 1e-6),
                    ("normal_load", "N", "N", 1.0))
_RTOL = 0.01


def format_condition(name: str, value: float) -> str:
    """``value`` [SI] of condition variable ``name`` in its display unit, e.g. ``7.5 mm/s``."""
    for var, _, unit, scale in DOMAIN_VARIABLES:
        if var == name:
            return f"{value / scale:.4g} {unit}"
    return f"{value:.4g}"


def _levels(x):
    x = np.sort(np.asarray(x, float))
    return x.size > 0 and (x[-1] - x[0]) > _RTOL * abs(x[0])


@dataclass(frozen=True)
class ConditionDomain:
    """The conditions a law was identified at.

    Parameters
    ----------
    points : ndarray, shape (n, 3)
        Sliding velocity [m s-1], roughness Ra [m], normal load [N] of each run the law was fitted on.
    """

    points: np.ndarray

    def __post_init__(self):
        p = np.asarray(self.points, float).reshape(-1, 3)
        if p.shape[0] == 0 or not np.all(np.isfinite(p) & (p > 0)):
            raise FividError("a law's domain needs at least one condition with V, Ra, Fn > 0")
        object.__setattr__(self, "points", p)

    @property
    def varying(self) -> tuple:
        """Names of the variables that took more than one value (1 % tolerance)."""
        return tuple(name for j, (name, *_) in enumerate(DOMAIN_VARIABLES) if _levels(self.points[:, j]))

    def ranges(self) -> dict:
        """``{name: (min, max)}`` [SI] of every variable."""
        return {name: (float(self.points[:, j].min()), float(self.points[:, j].max()))
                for j, (name, *_) in enumerate(DOMAIN_VARIABLES)}

    def _hull(self):
        """(ConvexHull or None, method) of the varying variables in log coordinates."""
        cols = [j for j, (name, *_) in enumerate(DOMAIN_VARIABLES) if name in self.varying]
        d = len(cols)
        if d <= 1:
            return None, "range"
        x = np.log(self.points[:, cols])
        if x.shape[0] >= d + 1 and np.linalg.matrix_rank(x - x.mean(axis=0), tol=1e-6) == d:
            from scipy.spatial import ConvexHull

            return ConvexHull(x), "convex hull"
        return None, "bounding box"

    @property
    def method(self) -> str:
        """``"range"``, ``"convex hull"`` (log coordinates) or ``"bounding box"`` (see the module docstring)."""
        return self._hull()[1]

    def describe(self) -> str:
        """One line: the identified range of every variable and the method, e.g. for error messages."""
        parts = []
        for name, (lo, hi) in self.ranges().items():
            if name in self.varying:
                parts.append(f"{name} {format_condition(name, lo)} to {format_condition(name, hi)}")
            else:
                parts.append(f"{name} {format_condition(name, lo)} only")
        return "; ".join(parts) + f" ({self.method} of {self.points.shape[0]} conditions)"

    def outside(self, velocity, roughness, normal_load=None) -> list:
        """Messages, one per condition outside the domain, naming the variable and the identified range.

        Variables passed as None (or NaN) are not checked (a law that does not depend on them).
        """
        v, ra, fn = np.broadcast_arrays(*(np.atleast_1d(np.asarray(np.nan if x is None else x, float))
                                          for x in (velocity, roughness, normal_load)))
        q = np.column_stack([v, ra, fn])
        ranges = self.ranges()
        hull, method = self._hull()
        cols = [j for j, (name, *_) in enumerate(DOMAIN_VARIABLES) if name in self.varying]
        out = []
        for row in q:
            problems = []
            for j, (name, *_) in enumerate(DOMAIN_VARIABLES):
                x = row[j]
                if not np.isfinite(x):
                    continue
                lo, hi = ranges[name]
                if x < lo * (1 - _RTOL) or x > hi * (1 + _RTOL):
                    where = (f"the identified range {format_condition(name, lo)} to {format_condition(name, hi)}"
                             if name in self.varying else f"the one value identified, {format_condition(name, lo)}")
                    problems.append(f"{name} = {format_condition(name, x)} is outside {where}")
            if not problems and hull is not None and np.all(np.isfinite(row[cols])):
                dist = hull.equations[:, :-1] @ np.log(row[cols]) + hull.equations[:, -1]
                if np.max(dist) > np.log1p(_RTOL):
                    names = ", ".join(f"{DOMAIN_VARIABLES[j][0]} = {format_condition(DOMAIN_VARIABLES[j][0], row[j])}"
                                      for j in cols)
                    problems.append(f"the combination {names} is outside the {method} of the identified "
                                    f"conditions ({self.describe()}), although each value is inside its range")
            if problems:
                out.append("; ".join(problems))
        return out

    def to_json(self) -> dict:
        """Plain-Python description: method, varying variables, ranges [SI] and the conditions."""
        return {"method": self.method, "varying": list(self.varying),
                "ranges": {k: list(v) for k, v in self.ranges().items()},
                "conditions": self.points.tolist(), "units": [u for _, u, *_ in DOMAIN_VARIABLES]}

    def interpolate(self, values, velocity, roughness, normal_load):
        """Values given per domain condition (rows of ``values``) interpolated at one condition.

        Linear in log coordinates of the varying variables (:class:`scipy.interpolate.LinearNDInterpolator`
        on the hull; ``numpy.interp`` for one variable); outside the hull the nearest condition's values.
        """
        values = np.asarray(values, float)
        cols = [j for j, (name, *_) in enumerate(DOMAIN_VARIABLES) if name in self.varying]
        if not cols:
            return values.mean(axis=0)
        q = np.array([velocity, roughness, normal_load], dtype=float)
        q = np.where(np.isfinite(q), q, np.exp(np.log(self.points).mean(axis=0)))
        x, xq = np.log(self.points[:, cols]), np.log(q[cols])
        if len(cols) == 1:
            order = np.argsort(x[:, 0])
            return np.array([np.interp(xq[0], x[order, 0], values[order, k]) for k in range(values.shape[1])])
        if self._hull()[0] is not None:
            from scipy.interpolate import LinearNDInterpolator

            res = LinearNDInterpolator(x, values)(xq[None, :])[0]
            if np.all(np.isfinite(res)):
                return res
        return values[int(np.argmin(np.sum((x - xq) ** 2, axis=1)))]
