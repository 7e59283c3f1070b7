"""The minimal 2-DOF mode-coupling model (Hoffmann, Fischer, Gaul & Hahn 2002) as a study system.

A mass ``m`` on a belt moving at ``V`` along +x is held by springs ``k1`` at +45° and ``k2`` at 135° and pressed on
the belt by a contact spring ``k3`` preloaded to the normal force ``N0``. Springs at angle ``a`` contribute
``k [[c², cs], [cs, s²]]``, so ``k11 = k22 = (k1 + k2)/2`` and ``k12 = (k1 − k2)/2``; mass-proportional damping
``c``. Linearised about steady sliding, friction ``mu N = mu k3 (d0 − y)`` couples the normal displacement into
the tangential equation (the non-symmetric ``mu K_f``): for ``k12 < 0`` two modes coalesce and one turns
unstable above (DESIGN §9, tests/fe/test_fe_cea.py)

``mu_c = −[(k11 − k22')² + 4 k12² + 2 c² (k11 + k22')/m] / (4 k3 k12)``,  ``k22' = k22 + k3``.

The CEA runs through :mod:`fivid.fe.cea` (the same code as the FE models'); the transient is the nonlinear
model (unilateral contact, Coulomb stick/slip with ``mu_s``/``mu_k``) marched by central differences
(:func:`fivid.study._kernels.hoffmann_steps`), so that growth, saturation into a limit cycle, loss of contact or
stick-slip appear as they would in the FE solver.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError
from fivid.fe.cea import complex_eigenvalue_sweep, project_on_modes

__all__ = ["HoffmannSystem"]


@dataclass(frozen=True)
class HoffmannSystem:
    """Parameters of the 2-DOF model (SI units).

    Attributes
    ----------
    mass : float
        [kg]
    k1, k2 : float
        Holding springs at +45° and 135° [N m-1].
    k3 : float
        Contact spring [N m-1].
    damping : float
        Mass-proportional dashpot on both directions [N s m-1].
    preload : float
        Normal force of the contact spring at y = 0 [N].
    belt_velocity : float
        [m s-1], along +x.
    """

    mass: float = 1.0
    k1: float = 1.0e6
    k2: float = 1.6e6
    k3: float = 0.8e6
    damping: float = 20.0
    preload: float = 100.0
    belt_velocity: float = 1.0

    def __post_init__(self):
        for name in ("mass", "k1", "k2", "k3", "preload", "belt_velocity"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ConfigError(f"{name} must be finite and > 0, got {getattr(self, name)!r}", key=f"system.{name}")
        if not (math.isfinite(self.damping) and self.damping >= 0):
            raise ConfigError(f"damping must be finite and >= 0, got {self.damping!r}", key="system.damping")

    @property
    def _k(self):
        k11 = 0.5 * (self.k1 + self.k2)
        k12 = 0.5 * (self.k1 - self.k2)
        return k11, k12, k11

    def matrices(self):
        """``(K, M, C, K_f)`` of the linearised model, ``M u'' + C u' + (K + mu K_f) u = 0`` (2 x 2 arrays)."""
        k11, k12, k22 = self._k
        K = np.array([[k11, k12], [k12, k22 + self.k3]])
        M = self.mass * np.eye(2)
        C = self.damping * np.eye(2)
        Kf = np.array([[0.0, self.k3], [0.0, 0.0]])
        return K, M, C, Kf

    def critical_mu(self) -> float:
        """Closed-form flutter threshold [-] (inf when ``k12 >= 0``: no coalescence on a +x belt)."""
        k11, k12, k22 = self._k
        k22 = k22 + self.k3
        if k12 >= 0:
            return math.inf
        return -((k11 - k22) ** 2 + 4 * k12**2 + 2 * self.damping**2 * (k11 + k22) / self.mass) / (4 * self.k3 * k12)

    def frequencies(self) -> np.ndarray:
        """Undamped natural frequencies at mu = 0 [Hz]."""
        K, M, _, _ = self.matrices()
        return np.sqrt(np.linalg.eigvalsh(K / self.mass)) / (2 * np.pi)

    def cea(self, mu) -> dict:
        """Complex eigenvalue analysis over ``mu`` (increasing), by :func:`fivid.fe.cea.complex_eigenvalue_sweep`."""
        K, M, C, Kf = self.matrices()
        return complex_eigenvalue_sweep(project_on_modes(K, M, C, Kf), np.asarray(mu, dtype=float))

    def equilibrium(self, mu: float) -> np.ndarray:
        """Steady sliding position (x, y) [m] under friction ``mu``."""
        K, _, _, Kf = self.matrices()
        d0 = self.preload / self.k3
        return np.linalg.solve(K + mu * Kf, np.array([mu * self.k3 * d0, self.k3 * d0]))

    def transient(self, mu: float, *, duration: float, sample_rate: float, perturbation: float = 1e-6,
                  mu_static: float | None = None, steps_per_period: int = 200):
        """Nonlinear transient from steady sliding with the mass displaced by ``perturbation`` [m] in y.

        Returns an xarray Dataset on ``time`` [s]: ``x``, ``y`` [m] (from the sliding equilibrium),
        ``velocity_x``, ``velocity_y`` [m s-1], ``normal_force``, ``friction_force`` [N] and ``contact_state``
        (1 stick, 2 slip, 0 open), like the FE solver's contact diagnostics.
        """
        import xarray as xr

        from fivid.study._kernels import hoffmann_steps  # lazy: pulls numba

        mu_s = mu if mu_static is None else float(mu_static)
        if not (mu >= 0 and mu_s >= mu):
            raise ConfigError(f"need 0 <= mu_kinetic <= mu_static, got {mu} and {mu_s}", key="mu")
        f_max = float(self.frequencies().max())
        n_sub = max(1, math.ceil(steps_per_period * f_max / sample_rate))
        dt = 1.0 / (sample_rate * n_sub)
        n_out = int(round(duration * sample_rate))
        k11, k12, k22 = self._k
        u = self.equilibrium(mu).astype(float)
        u[1] += perturbation
        v = np.zeros(2)  # steady sliding: the mass stands still, the belt slides under it
        out = np.full((n_out, 6), np.nan)
        hoffmann_steps(n_out, n_sub, dt, self.mass, self.damping, k11, k12, k22, self.k3, self.preload / self.k3,
                       mu_s, mu, self.belt_velocity, u, v, out)
        eq = self.equilibrium(mu)
        time = np.arange(1, n_out + 1) / sample_rate
        slipping = np.abs(out[:, 2] - self.belt_velocity) > 1e-9 * self.belt_velocity
        state = np.where(out[:, 4] <= 0.0, 0, np.where(slipping, 2, 1)).astype(np.int8)
        return xr.Dataset(
            {"x": ("time", out[:, 0] - eq[0], {"units": "m", "long_name": "tangential displacement from equilibrium"}),
             "y": ("time", out[:, 1] - eq[1], {"units": "m", "long_name": "normal displacement from equilibrium"}),
             "velocity_x": ("time", out[:, 2], {"units": "m s-1"}),
             "velocity_y": ("time", out[:, 3], {"units": "m s-1"}),
             "normal_force": ("time", out[:, 4], {"units": "N"}),
             "friction_force": ("time", out[:, 5], {"units": "N"}),
             "contact_state": ("time", state, {"long_name": "contact state", "flag_values": [0, 1, 2],
                                                "flag_meanings": "open stick slip"})},
            coords={"time": ("time", time, {"units": "s"})},
            attrs={"time_step": dt, "sample_rate": float(sample_rate), "mu": float(mu), "mu_static": mu_s},
        )
