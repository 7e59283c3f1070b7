"""Time-domain reference: Newmark average acceleration with Newton-Raphson, run to steady state.

The same modal model as the harmonic balance, so the two differ only by their discretisations
(harmonic truncation and AFT sampling there; the time step here: average acceleration has no
amplitude error and a period elongation of ``(omega dt)^2 / 12``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.damper.modal import ModalModel
from fivid.errors import FividError

__all__ = ["SteadyStateResponse", "steady_state_response"]


@dataclass(frozen=True)
class SteadyStateResponse:
    """The last period of a time-domain run.

    Attributes
    ----------
    frequency : float
        Excitation frequency [Hz].
    time : ndarray
        Times of the last period [s].
    measurement, contact, force : ndarray
        Measured and contact displacements [m] and contact force [N] over the last period.
    periods : int
        Periods integrated.
    converged : bool
        Whether two consecutive periods agreed to ``rtol``.
    """

    frequency: float
    time: np.ndarray
    measurement: np.ndarray
    contact: np.ndarray
    force: np.ndarray
    periods: int
    converged: bool

    def harmonic(self, signal: str, h: int = 1) -> complex:
        """Complex amplitude of harmonic ``h`` of ``'measurement'``, ``'contact'`` or ``'force'``
        (``x(t) = Re sum X_h exp(i h Omega t)``)."""
        x = getattr(self, signal)
        n = x.size
        theta = 2 * np.pi * np.arange(1, n + 1) / n  # samples at the end of each step
        return complex(2.0 / n * np.sum(x * np.exp(-1j * h * theta)))


def steady_state_response(modal: ModalModel, contact_stiffness: float, slip_force: float,
                          excitation_amplitude: float, frequency: float, *, steps_per_period: int = 512,
                          max_periods: int = 4000, rtol: float = 1e-6) -> SteadyStateResponse:
    """Integrate from rest until the response is periodic (Newmark + Newton-Raphson).

    Parameters
    ----------
    modal : ModalModel
    contact_stiffness, slip_force : float
        Jenkins ``k`` [N/m] and ``F_s`` [N].
    excitation_amplitude : float
        ``P`` [N] of ``P cos(2 pi f t)``.
    frequency : float
        ``f`` [Hz].
    steps_per_period : int, default 512
        Time steps per excitation period.
    max_periods : int, default 4000
    rtol : float, default 1e-6
        Steady when the measured displacement over a period changes by less than ``rtol`` times
        its peak from the previous period.
    """
    from fivid.friction._jenkins_kernels import newmark_jenkins  # lazy: pulls numba

    if not (frequency > 0 and steps_per_period >= 8):
        raise FividError(f"need frequency > 0 Hz and steps_per_period >= 8, got {frequency}, {steps_per_period}")
    om = 2 * np.pi * float(frequency)
    dt = 2 * np.pi / om / steps_per_period
    w = modal.natural_frequencies
    args = (w**2, 2 * modal.damping_ratios * w, modal.contact, modal.excitation, modal.measurement)
    n = w.size
    q, v, a = np.zeros(n), np.zeros(n), np.zeros(n)
    a[:] = modal.excitation * excitation_amplitude  # equilibrium at t = 0 from rest: a = phi_e P
    state = np.zeros(2)
    xm, xc, fc = (np.empty(steps_per_period) for _ in range(3))
    prev = None
    converged = False
    p = 0
    for p in range(1, max_periods + 1):
        t0 = (p - 1) * steps_per_period * dt
        newmark_jenkins(*args, float(excitation_amplitude), om, dt, t0, float(contact_stiffness), float(slip_force),
                        q, v, a, state, xm, xc, fc)
        if not np.all(np.isfinite(xm)):
            raise FividError(f"time integration diverged at {frequency} Hz after {p} periods")
        if prev is not None and np.max(np.abs(xm - prev)) <= rtol * np.max(np.abs(xm)):
            converged = True
            break
        prev = xm.copy()
    t = (p - 1) * steps_per_period * dt + dt * np.arange(1, steps_per_period + 1)
    return SteadyStateResponse(frequency=float(frequency), time=t, measurement=xm.copy(), contact=xc.copy(),
                               force=fc.copy(), periods=p, converged=converged)
