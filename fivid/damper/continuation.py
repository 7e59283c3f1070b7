"""Pseudo-arclength continuation of harmonic-balance solutions in excitation frequency.

The branch ``R(u, Omega) = 0`` is followed in the scaled variables ``y = (u / x_s, Omega / Omega_s)``
(``x_s`` the largest linear response over the range, free or stuck contact; ``Omega_s`` the width of
the range), so turning points (folds) are passed. Predictor: the unit tangent ``t`` (null vector of
``[dR/du, dR/dOmega]``, oriented along the previous one). Corrector: Newton on
``[R(y); t . (y - y_pred)] = 0``. The step grows after easy corrections and shrinks after hard or
failed ones. Stability of each point by Floquet multipliers (:mod:`fivid.damper.stability`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.damper.hbm import HarmonicBalance
from fivid.damper.stability import floquet_multipliers
from fivid.errors import FividError

__all__ = ["FrequencyResponseCurve", "continue_frequency_response"]


@dataclass(frozen=True)
class FrequencyResponseCurve:
    """A branch of periodic solutions.

    Attributes
    ----------
    frequency : ndarray, shape (n_points,)
        [Hz], in branch order (not necessarily monotonic at folds).
    contact, measurement : ndarray of complex, shape (n_points, n_harmonics)
        Complex harmonic amplitudes of the contact and measured displacements [m].
    force : ndarray of complex, shape (n_points, n_harmonics)
        Contact-force harmonics [N].
    harmonics : ndarray of int
    max_multiplier : ndarray, shape (n_points,)
        Largest Floquet-multiplier modulus (NaN when stability was not computed).
    stable : ndarray of bool
        ``max_multiplier <= 1 + 1e-9``.
    """

    frequency: np.ndarray
    contact: np.ndarray
    measurement: np.ndarray
    force: np.ndarray
    harmonics: np.ndarray
    max_multiplier: np.ndarray
    stable: np.ndarray

    @property
    def amplitude(self) -> np.ndarray:
        """First-harmonic displacement amplitude at the sensor [m]."""
        return np.abs(self.measurement[:, 0])


def continue_frequency_response(hb: HarmonicBalance, f_start: float, f_end: float, *, step: float = 0.01,
                                min_step: float = 1e-6, max_step: float = 0.02, max_points: int = 5000,
                                stability: bool = True, stability_modes: int = 8) -> FrequencyResponseCurve:
    """Follow the periodic response from ``f_start`` to ``f_end`` [Hz] by pseudo-arclength continuation.

    Parameters
    ----------
    hb : HarmonicBalance
    f_start, f_end : float
        Frequency range [Hz]; either order.
    step, min_step, max_step : float
        Initial, smallest and largest arclength step in scaled variables (the range has length >= 1).
    max_points : int
    stability : bool
        Compute Floquet multipliers of each point.
    stability_modes : int
        Modes kept in the Floquet analysis.
    """
    om0, om1 = 2 * np.pi * f_start, 2 * np.pi * f_end
    direction = 1.0 if om1 > om0 else -1.0
    om_s = abs(om1 - om0)
    grid = np.linspace(om0, om1, 50)
    x_s = max(max(np.linalg.norm(hb.linear_start(w, stuck)) for stuck in (False, True)) for w in grid)
    n = hb.n_unknowns
    u, _ = hb.solve(om0)
    y = np.concatenate([u / x_s, [om0 / om_s]])
    t_prev = np.zeros(n + 1)
    t_prev[-1] = direction
    points = [(u.copy(), om0)]
    ds = step
    while len(points) < max_points:
        u, om = y[:n] * x_s, y[n] * om_s
        _, ju, jw = hb.residual(u, om, frequency_derivative=True)
        a = np.vstack([np.hstack([ju, (jw * om_s / x_s)[:, None]]), t_prev])
        try:
            t = np.linalg.solve(a, np.concatenate([np.zeros(n), [1.0]]))
        except np.linalg.LinAlgError:
            raise FividError(f"continuation: singular tangent system at {om / (2 * np.pi):.5g} Hz") from None
        t /= np.linalg.norm(t)
        if t @ t_prev < 0:
            t = -t
        while True:
            y_pred = y + ds * t
            y_new, iters = _correct(hb, y_pred, t, x_s, om_s)
            if y_new is not None:
                break
            ds *= 0.5
            if ds < min_step:
                raise FividError(f"continuation stalled near {om / (2 * np.pi):.5g} Hz (step below {min_step})")
        y, t_prev = y_new, t
        om = y[n] * om_s
        if direction * (om - om1) >= 0:  # passed the end: land on it
            u_end, _ = hb.solve(om1, y[:n] * x_s)
            points.append((u_end, om1))
            break
        points.append((y[:n] * x_s, om))
        ds = min(max_step, ds * 1.5) if iters <= 3 else max(min_step, ds * 0.7) if iters > 6 else ds
    else:
        raise FividError(f"continuation used {max_points} points without reaching {f_end} Hz; raise max_step")
    sols = [hb.solution(u, om) for u, om in points]
    mult = np.full(len(sols), np.nan)
    if stability:
        for i, (s, (_, om)) in enumerate(zip(sols, points)):
            mult[i] = np.abs(floquet_multipliers(hb.modal, hb.k, s.slipping, om, stability_modes)[0])
    return FrequencyResponseCurve(
        frequency=np.array([om for _, om in points]) / (2 * np.pi),
        contact=np.array([s.contact for s in sols]),
        measurement=np.array([s.measurement for s in sols]),
        force=np.array([s.force for s in sols]),
        harmonics=hb.harmonics.copy(),
        max_multiplier=mult,
        stable=mult <= 1 + 1e-9,
    )


def _correct(hb, y_pred, t, x_s, om_s, *, max_iterations=10, rtol=1e-10):
    n = hb.n_unknowns
    y = y_pred.copy()
    for it in range(1, max_iterations + 1):
        u, om = y[:n] * x_s, y[n] * om_s
        if om <= 0:
            return None, it
        r, ju, jw = hb.residual(u, om, frequency_derivative=True)
        g = np.concatenate([r / x_s, [t @ (y - y_pred)]])
        a = np.vstack([np.hstack([ju, (jw * om_s / x_s)[:, None]]), t])
        try:
            dy = np.linalg.solve(a, -g)
        except np.linalg.LinAlgError:
            return None, it
        y = y + dy
        # scaled residual and update at float resolution x condition (see HarmonicBalance.solve)
        if np.linalg.norm(dy) <= rtol * max(1.0, np.linalg.norm(y)) * 1e2 and np.linalg.norm(r) / x_s <= rtol * 1e2:
            return y, it
    return None, max_iterations
