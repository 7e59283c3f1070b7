"""The stable time step of central differences with stiffness-proportional damping.

For ``M a + (alpha M + beta K) v + K u = f`` the central-difference scheme is stable for

``dt <= dt_crit = (2 / omega_max) (sqrt(1 + xi^2) - xi)``, ``xi = beta omega_max / 2``

(Belytschko & Hughes; the mass-proportional part only requires ``alpha dt < 2``, far from binding),
where ``omega_max^2`` is the largest eigenvalue of ``M^-1 K`` on the free dofs (lumped ``M`` with the
point masses, ``K`` with the discrete springs). Dashpots of discrete elements are integrated explicitly
too and add the condition ``dt < 2 m / c`` for each dof they load.

With band-limited damping (:mod:`fivid.fe.damping`: ``beta K`` acting on a low-pass filtered velocity) no
closed form is at hand, so the step is found from the scheme itself: the amplification matrix of one step of
the kernel's update for a mode of angular frequency ``omega`` (state: displacement, half-step velocity,
filtered velocity) must have spectral radius <= 1 for every ``omega`` up to ``omega_max``; the largest such
``dt`` is found by bisection (for classic Rayleigh this reproduces the closed form above, which a test checks).
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError
from fivid.fe.assembly import lumped_mass, stiffness_matrix
from fivid.fe.build import load_model
from fivid.fe.damping import scheme_name
from fivid.solver.integrate import velocity_filter_gain

__all__ = ["StableStep", "max_angular_frequency", "critical_time_step", "stable_step", "stable_step_bound",
           "stable_step_of", "amplification_matrix"]


@dataclass(frozen=True)
class StableStep:
    """The stability limit of a model.

    Attributes
    ----------
    omega_max : float
        Highest angular frequency of the free, undamped, unconstrained-contact system [rad s-1].
    xi : float
        Damping ratio of that mode from Rayleigh's beta, ``beta omega_max / 2`` [-] (classic Rayleigh).
    critical_time_step : float
        Classic Rayleigh: ``(2/omega_max)(sqrt(1+xi^2) - xi)``; band-limited: from the amplification matrix;
        further limited by explicit dashpots [s].
    undamped_time_step : float
        ``2/omega_max`` [s].
    damping_scheme : str
        ``"rayleigh"`` or ``"band_limited"`` (:mod:`fivid.fe.damping`).
    """

    omega_max: float
    xi: float
    critical_time_step: float
    undamped_time_step: float
    damping_scheme: str = "rayleigh"


def _scaled_free_stiffness(model):
    """``M^-1/2 K M^-1/2`` on the free dofs (CSR; springs in, lumped mass with the point masses)."""
    import scipy.sparse as sp

    free = model.free_dofs
    K = stiffness_matrix(model, include_springs=True)[free][:, free]
    m = lumped_mass(model)[free]
    if np.any(m <= 0.0):
        raise ConfigError(f"{int(np.sum(m <= 0))} free dof(s) have no mass; every node needs mass for the explicit solver")
    s = sp.diags(1.0 / np.sqrt(m))
    return (s @ K @ s).tocsr()


def max_angular_frequency(model, *, tol: float = 1e-10) -> float:
    """Largest ``omega`` [rad s-1] of ``K phi = omega^2 M phi`` on the free dofs (springs and point masses in).

    ARPACK Lanczos (``eigsh``, ``which="LA"``) on the symmetric ``M^-1/2 K M^-1/2`` instead of plain power
    iteration: on a uniform mesh the top of the spectrum is clustered, and power iteration converges
    like ``(lambda_2/lambda_1)^k``, i.e. it underestimates ``omega_max`` (an unsafe step) for thousands of
    iterations, while Lanczos resolves the extreme eigenvalue to ``tol`` in tens of iterations.
    """
    from scipy.sparse.linalg import eigsh

    A = _scaled_free_stiffness(model)
    v0 = np.random.default_rng(0).standard_normal(A.shape[0])  # fixed start: reproducible step
    lam = eigsh(A, k=1, which="LA", tol=tol, v0=v0, return_eigenvectors=False, maxiter=100 * A.shape[0])
    return float(np.sqrt(max(float(lam[0]), 0.0)))


def _dashpot_limit(model) -> float:
    """``min 2 m / c`` over dofs loaded by dashpots [s] (inf without dashpots)."""
    m = lumped_mass(model)
    c = np.zeros(model.n_dofs)
    for s in model.springs:
        if s.damping > 0.0:
            c[2 * s.node_a + s.component] += s.damping
            if s.node_b >= 0:
                c[2 * s.node_b + s.component] += s.damping
    c[model.fixed_dofs] = 0.0
    loaded = c > 0.0
    # a dashpot between two nodes acts on their relative motion with the reduced mass: 2 m/(2c) bound
    return float(np.min(m[loaded] / c[loaded])) if loaded.any() else float("inf")


def amplification_matrix(omega, dt: float, alpha: float, beta: float, cutoff: float) -> np.ndarray:
    """One kernel step for modes of angular frequency ``omega`` [rad s-1]: ``s_{n+1} = A s_n``, shape (..., 3, 3).

    State ``s = (u_n, v_{n-1/2}, vf_n)`` of :func:`fivid.solver._loop_kernels._predictor`:
    ``v' = (1 - alpha dt) v - dt omega^2 (u + beta vf)``, ``u' = u + dt v'``, ``vf' = vf + a (v' - vf)`` with
    ``a = 1 - exp(-2 pi cutoff dt)`` (1 for classic Rayleigh, ``cutoff`` inf: then ``vf`` is ``v``).
    """
    w2 = np.asarray(omega, dtype=float)[..., None] ** 2
    a = velocity_filter_gain(cutoff, dt)
    zero = np.zeros_like(w2)
    if a >= 1.0:  # vf is v itself
        rv = np.concatenate([-dt * w2, 1.0 - alpha * dt - dt * w2 * beta + zero, zero], axis=-1)
    else:
        rv = np.concatenate([-dt * w2, 1.0 - alpha * dt + zero, -dt * w2 * beta], axis=-1)
    ru = np.concatenate([1.0 + zero, zero, zero], axis=-1) + dt * rv
    rf = np.concatenate([zero, zero, (1.0 - a) + zero], axis=-1) + a * rv
    return np.stack([ru, rv, rf], axis=-2)


@functools.lru_cache(maxsize=64)
def _largest_stable_step(omega_max: float, alpha: float, beta: float, cutoff: float) -> float:
    """Largest ``dt`` [s] with spectral radius <= 1 (+ round-off) for every mode up to ``omega_max`` (bisection; 0.1 s,
    kept per argument set: a run asks for its reduced system's step twice, path choice and set-up)."""
    omegas = omega_max * np.concatenate([np.geomspace(1e-4, 1.0, 400), [1.0]])

    def stable(dt):
        rho = np.abs(np.linalg.eigvals(amplification_matrix(omegas, dt, alpha, beta, cutoff))).max()
        return rho <= 1.0 + 1e-12

    lo, hi = 0.0, 2.0 / omega_max * (1.0 + 1e-9)
    if stable(hi):
        return hi
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo


def stable_step(model) -> StableStep:
    """The :class:`StableStep` of ``model`` (Rayleigh ``alpha``, ``beta`` and damping cut-off from the model)."""
    omega = max_angular_frequency(model)
    step = stable_step_of(omega, float(model.rayleigh_alpha), float(model.rayleigh_beta), float(model.damping_cutoff))
    dashpots = _dashpot_limit(model)
    if dashpots < step.critical_time_step:
        step = dataclasses.replace(step, critical_time_step=dashpots)
    return step


def stable_step_bound(model) -> StableStep:
    """A :class:`StableStep` of ``model`` whose ``omega_max`` is an upper bound of the true one, hence whose
    ``critical_time_step`` is a lower bound of :func:`stable_step`'s [s], without an eigenvalue solve.

    ``omega_max^2 <= max_i sum_j |A_ij|``, ``A = M^-1/2 K M^-1/2`` (Gershgorin's theorem: every eigenvalue lies
    in a disc of a row), and the stable step falls as ``omega_max`` grows. For estimates that need a safe step
    count cheaply: the memory and work guard of ``fivid simulate`` (on the default rig 1.4 x the true
    ``omega_max^2``: 18 % more steps than the full model takes).
    """
    A = _scaled_free_stiffness(model)
    omega = float(np.sqrt(max(float(abs(A).sum(axis=1).max()), 0.0)))
    step = stable_step_of(omega, float(model.rayleigh_alpha), float(model.rayleigh_beta), float(model.damping_cutoff))
    dashpots = _dashpot_limit(model)
    if dashpots < step.critical_time_step:
        step = dataclasses.replace(step, critical_time_step=dashpots)
    return step


def stable_step_of(omega: float, alpha: float, beta: float, cutoff: float) -> StableStep:
    """The :class:`StableStep` of a system whose highest angular frequency is ``omega`` [rad s-1] under the
    damping scheme ``alpha`` [s-1], ``beta`` [s], ``cutoff`` [Hz] (no dashpots): the full model's, or a reduced
    system's (:mod:`fivid.solver.reduced`)."""
    if omega <= 0.0:
        raise ConfigError("the model has no stiffness on its free dofs (omega_max = 0): nothing to integrate")
    xi = 0.5 * beta * omega
    undamped = 2.0 / omega
    scheme = scheme_name(beta, cutoff)
    if scheme == "band_limited":
        dt = _largest_stable_step(omega, alpha, beta, cutoff)
    else:
        dt = undamped * (np.sqrt(1.0 + xi * xi) - xi)
    if alpha > 0.0:
        dt = min(dt, 2.0 / alpha)
    return StableStep(omega_max=omega, xi=float(xi), critical_time_step=float(dt), undamped_time_step=undamped,
                      damping_scheme=scheme)


def critical_time_step(model) -> float:
    """Critical time step of central differences for ``model`` [s] (see the module docstring).

    Parameters
    ----------
    model : Model or str or path-like
        A model or the path of its config.

    Examples
    --------
    A 1-DOF mass-spring has ``omega_max = sqrt(k/m)`` and ``dt_crit = 2/omega`` without damping.
    """
    if not hasattr(model, "blocks"):
        model = load_model(model)
    return stable_step(model).critical_time_step
