"""The kinetic friction curve of a contact, and the kinetic coefficient of every contact node.

Coulomb friction with a kinetic coefficient ``mu_k`` (a pair's ``mu``, or the mean ``mu0`` of an identified
perturbation law ``mu0 + mu_p(t)``, :mod:`fivid.friction.laws`), a static ``mu_s >= mu_k`` that bounds stick, and
an optional Stribeck curve plus viscous term for sliding, ``mu(v) = mu_k + (mu_s - mu_k) exp(-|v|/v_s) + c_v |v|``
(:class:`FrictionCurve`, evaluated by the one kernel :func:`fivid.friction._curve_kernels.friction_coefficient`).
:func:`slave_coefficients` is the kinetic coefficient of every slave node, for the static preload and the
solver alike; :func:`fivid.friction.friction_table` adds ``mu_p(t)`` over time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FrictionCurve", "slave_coefficients"]


@dataclass(frozen=True)
class FrictionCurve:
    """The kinetic curve over a kinetic coefficient ``mu_k``: static excess, optional Stribeck decay and viscous term.

    ``mu(v) = mu_k + (mu_s - mu_k) exp(-|v|/v_s) + c_v |v|`` in slip; stick holds while ``|lam_t| <= mu_s lam_n``.

    Attributes
    ----------
    mu_static_excess : float
        ``mu_s - mu_k`` [-] (>= 0).
    stribeck_velocity : float
        ``v_s`` [m s-1]; 0: no Stribeck curve (a step from mu_s in stick to mu_k in slip).
    viscous : float
        ``c_v`` [s m-1].
    """

    mu_static_excess: float = 0.0
    stribeck_velocity: float = 0.0
    viscous: float = 0.0

    def coefficient(self, mu_k, v):
        """Sliding coefficient ``mu(v)`` [-] at slip speed ``v`` [m s-1] (array) over the kinetic ``mu_k``."""
        from fivid.friction._curve_kernels import friction_coefficient  # lazy: pulls numba

        v = np.asarray(v, dtype=float)
        return np.array([friction_coefficient(float(mu_k), self.mu_static_excess, self.stribeck_velocity,
                                              self.viscous, float(x)) for x in v.ravel()]).reshape(v.shape)

    def columns(self) -> list[float]:
        """Its record columns for the kernels, from :data:`~fivid.contact._layout_kernels.FRICTION_FIRST` on:
        ``(mu_static_excess, stribeck_velocity, viscous)``."""
        return [float(self.mu_static_excess), float(self.stribeck_velocity), float(self.viscous)]

    def describe(self, mu_k: float) -> str:
        """One line for logs and reports: ``mu_k`` [-], and ``mu_s`` [-], ``v_s`` [m/s], viscous [s/m] when set."""
        parts = [f"mu_k {mu_k:.4g}"]
        if self.mu_static_excess:
            parts.append(f"mu_s {mu_k + self.mu_static_excess:.4g}")
        if self.stribeck_velocity:
            parts.append(f"Stribeck v_s {self.stribeck_velocity:.4g} m/s")
        if self.viscous:
            parts.append(f"viscous {self.viscous:.4g} s/m")
        return ", ".join(parts)


def slave_coefficients(model, mu=None) -> np.ndarray:
    """Kinetic friction coefficient of every slave node (all pairs, in order) [-]: ``mu`` if given, else each
    pair's own ``mu``."""
    if not model.contacts:
        return np.zeros(0)
    mu_pairs = [float(mu) if mu is not None else c.mu for c in model.contacts]
    return np.concatenate([[mu_pairs[p]] * len(c.slave_nodes) for p, c in enumerate(model.contacts)])
