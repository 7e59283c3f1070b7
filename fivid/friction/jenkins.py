"""Jenkins (Masing) friction element and Iwan series of them.

A Jenkins element is a spring of stiffness ``k`` in series with a Coulomb slider that slips at
``F_s = mu * F_n``. It sticks (force ``k (x - z)``, slider position ``z`` fixed) while
``|k (x - z)| < F_s`` and slips (force ``+-F_s``, ``z`` follows ``x``) otherwise. Under a
displacement cycle of amplitude ``a`` it dissipates (Masing loop, a parallelogram)::

    W = 4 F_s (a - F_s / k)   for a > F_s / k,   0 otherwise.

An Iwan model is a set of Jenkins elements in parallel with different slip forces: it slips
gradually (microslip) and its loops follow Masing's rule, branch(x) = F(a) - 2 F_backbone((a - x)/2).

References
----------
W. D. Iwan, "A distributed-element model for hysteresis and its steady-state dynamic response",
J. Appl. Mech. 33 (1966) 893-900.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import FividError

__all__ = [
    "jenkins_force",
    "jenkins_periodic_force",
    "jenkins_energy_per_cycle",
    "loop_energy",
    "iwan_force",
    "iwan_uniform_elements",
    "iwan_energy_per_cycle",
]


def _check_element(stiffness: float, slip_force: float) -> tuple[float, float]:
    k = float(stiffness)
    fs = float(slip_force)
    if not (np.isfinite(k) and k > 0):
        raise FividError(f"Jenkins stiffness must be finite and > 0 N/m, got {stiffness!r}")
    if not (np.isfinite(fs) and fs > 0):
        raise FividError(f"Jenkins slip force must be finite and > 0 N, got {slip_force!r}")
    return k, fs


def jenkins_force(displacement, stiffness: float, slip_force: float, initial_force: float = 0.0) -> np.ndarray:
    """Force history of a Jenkins element driven by a displacement history.

    Parameters
    ----------
    displacement : array_like, shape (n,)
        Displacement of the element's free end [m] (the other end is fixed).
    stiffness : float
        Spring (tangential contact) stiffness ``k`` [N/m].
    slip_force : float
        Slip force ``F_s = mu F_n`` [N].
    initial_force : float, default 0
        Force at the first sample [N], ``|initial_force| <= slip_force``.

    Returns
    -------
    ndarray, shape (n,)
        Element force [N] (positive in the direction of positive displacement).

    Examples
    --------
    One cycle of amplitude 2 F_s/k dissipates 4 F_s (a - F_s/k) = 4 F_s^2 / k:

    >>> import numpy as np
    >>> t = np.linspace(0, 2, 2001)
    >>> x = 2e-3 * np.sin(2 * np.pi * t)
    >>> f = jenkins_force(x, 1e3, 1.0)
    >>> round(loop_energy(x[500:1501], f[500:1501]), 6)
    0.004
    """
    k, fs = _check_element(stiffness, slip_force)
    x = np.ascontiguousarray(displacement, dtype=float)
    if x.ndim != 1:
        raise FividError(f"displacement must be one-dimensional, got shape {x.shape}")
    if abs(initial_force) > fs:
        raise FividError(f"initial_force {initial_force} N exceeds the slip force {fs} N")
    from fivid.friction._jenkins_kernels import jenkins_march  # lazy: pulls numba

    force = np.empty((1, x.size))
    anchor = np.empty((1, x.size), dtype=np.int64)
    jenkins_march(x[None, :], k, fs, np.array([float(initial_force)]), 1, force, anchor)
    return force[0]


def jenkins_periodic_force(displacement, stiffness: float, slip_force: float, n_passes: int = 2):
    """Steady force of a Jenkins element over one period of a periodic displacement (for AFT).

    The element starts stuck with the force ``k (x_0 - mean(x))`` (clipped to ``+-F_s``) and is
    marched ``n_passes`` times over the period; after one pass containing slip in both directions
    the loop no longer depends on the start. If it never slips it stays stuck about the mean
    displacement (zero mean force), the convention for a history-dependent stuck state.

    Parameters
    ----------
    displacement : ndarray, shape (n_paths, n_samples)
        Displacement samples over one period, one row per path [m].
    stiffness, slip_force : float
        ``k`` [N/m] and ``F_s`` [N].
    n_passes : int, default 2
        Passes over the period.

    Returns
    -------
    force : ndarray, shape (n_paths, n_samples)
        Force over the last pass [N].
    anchor : ndarray of int64, shape (n_paths, n_samples)
        Start sample of the current stick phase (``-1`` slipping, ``-2`` stuck since the start).
        While stuck, ``dF_j/dx = k (e_j - e_anchor)`` (or ``k (e_j - mean e)`` for ``-2``): the
        exact derivative used for the harmonic-balance Jacobian.
    """
    k, fs = _check_element(stiffness, slip_force)
    x = np.ascontiguousarray(displacement, dtype=float)
    from fivid.friction._jenkins_kernels import jenkins_march  # lazy: pulls numba

    f0 = np.clip(k * (x[:, 0] - x.mean(axis=1)), -fs, fs)
    force = np.empty_like(x)
    anchor = np.empty(x.shape, dtype=np.int64)
    jenkins_march(x, k, fs, f0, int(n_passes), force, anchor)
    return force, anchor


def jenkins_energy_per_cycle(amplitude, stiffness: float, slip_force: float):
    """Energy a Jenkins element dissipates per displacement cycle of amplitude ``a`` [J].

    ``W = 4 F_s (a - F_s/k)`` when ``a > F_s/k`` (the loop is a parallelogram of height ``2 F_s``
    and width ``2 (a - F_s/k)``), else 0.

    Parameters
    ----------
    amplitude : float or array_like
        Displacement amplitude ``a`` [m] (half the peak-to-peak).
    stiffness, slip_force : float
        ``k`` [N/m] and ``F_s`` [N].
    """
    k, fs = _check_element(stiffness, slip_force)
    a = np.asarray(amplitude, dtype=float)
    return np.where(a > fs / k, 4.0 * fs * (a - fs / k), 0.0)


def loop_energy(displacement, force) -> float:
    """Closed-path integral ``oint F dx`` of a sampled loop [J] (trapezoidal rule).

    Positive for a dissipative (clockwise in the x-F plane) loop. The path should start and end
    at the same displacement (one cycle).
    """
    return float(np.trapezoid(np.asarray(force, dtype=float), np.asarray(displacement, dtype=float)))


def iwan_force(displacement, stiffnesses, slip_forces) -> np.ndarray:
    """Force of an Iwan model (Jenkins elements in parallel), starting unloaded.

    Parameters
    ----------
    displacement : array_like, shape (n,)
        Displacement [m].
    stiffnesses, slip_forces : array_like, shape (m,)
        Stiffness [N/m] and slip force [N] of each element.

    Returns
    -------
    ndarray, shape (n,)
        Total force [N].
    """
    ks = np.atleast_1d(np.asarray(stiffnesses, dtype=float))
    fss = np.atleast_1d(np.asarray(slip_forces, dtype=float))
    if ks.shape != fss.shape:
        raise FividError(f"stiffnesses {ks.shape} and slip_forces {fss.shape} must have the same shape")
    x = np.asarray(displacement, dtype=float)
    total = np.zeros(x.size)
    for k, fs in zip(ks, fss):
        total += jenkins_force(x, k, fs)
    return total


def iwan_uniform_elements(stiffness: float, slip_force: float, n_elements: int):
    """Elements of an Iwan model with slip displacements uniform on ``(0, 2 F_s/k]``.

    Each of the ``n`` elements has stiffness ``k/n``; element ``i`` slips at displacement
    ``d_i = (2 F_s / k) (i - 1/2) / n``, so the initial stiffness is ``k`` and the fully slipped
    force is ``sum (k/n) d_i = F_s`` (macroslip at ``x = 2 F_s / k``).

    Returns
    -------
    stiffnesses, slip_forces : ndarray, shape (n,)
        [N/m] and [N].
    """
    k, fs = _check_element(stiffness, slip_force)
    n = int(n_elements)
    if n < 1:
        raise FividError(f"n_elements must be >= 1, got {n_elements!r}")
    d = (2.0 * fs / k) * (np.arange(n) + 0.5) / n
    ki = np.full(n, k / n)
    return ki, ki * d


def iwan_energy_per_cycle(amplitude, stiffnesses, slip_forces):
    """Energy per cycle of an Iwan model [J]: the sum of its elements' ``4 F_s,i (a - F_s,i / k_i)``.

    Parameters
    ----------
    amplitude : float or array_like
        Displacement amplitude ``a`` [m].
    stiffnesses, slip_forces : array_like, shape (m,)
        Stiffness [N/m] and slip force [N] of each element.

    Returns
    -------
    float or ndarray
        [J], a float for a scalar amplitude, else an array of the amplitude's shape.
    """
    ks = np.atleast_1d(np.asarray(stiffnesses, dtype=float))
    fss = np.atleast_1d(np.asarray(slip_forces, dtype=float))
    w = sum(jenkins_energy_per_cycle(amplitude, k, fs) for k, fs in zip(ks, fss))
    return float(w) if np.ndim(w) == 0 else w
