"""FRF peak of a damper model: the frequency of the largest first-harmonic displacement at the sensor.

A measured FRF's peak frequency per normal load is what model updating compares a damper model with
(seed 004 reads 86 Hz off its stuck FRF at 40 N). The peak is bracketed on a uniform grid by the
harmonic-balance sweep, then refined by Brent's bounded method on ``-|X_1|`` between the neighbours of
the grid maximum (each solve warm-started from the nearest grid solution). The refinement makes the
peak frequency a smooth function of the model parameters, as finite-difference sensitivities need;
its tolerance, ``xatol`` [Hz], is far below any measured peak's uncertainty.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.damper.hbm import HarmonicBalance
from fivid.damper.model import DamperModel
from fivid.errors import FividError

__all__ = ["FRFPeak", "frf_peak"]


@dataclass(frozen=True)
class FRFPeak:
    """The peak of a damper model's FRF at one normal load.

    Attributes
    ----------
    frequency : float
        Peak frequency [Hz].
    amplitude : float
        First-harmonic displacement amplitude at the sensor there [m].
    normal_load : float
        [N].
    on_edge : bool
        The grid maximum is at an end of the band (the peak may lie outside it).
    """

    frequency: float
    amplitude: float
    normal_load: float
    on_edge: bool


def frf_peak(model: DamperModel, normal_load: float, *, band=None, points: int = 116,
             xatol: float = 1e-6) -> FRFPeak:
    """Frequency [Hz] and amplitude [m] of the largest first-harmonic response at the sensor.

    Parameters
    ----------
    model : DamperModel
    normal_load : float
        Normal load [N].
    band : (float, float), optional
        Frequency band searched [Hz] (default: the model's ``frequency_range``).
    points : int
        Grid points of the bracketing sweep (default 116: 1 Hz over the seed's 15-130 Hz).
    xatol : float
        Absolute tolerance of the refined peak frequency [Hz].

    Returns
    -------
    FRFPeak
    """
    from scipy.optimize import minimize_scalar

    lo, hi = model.frequency_range if band is None else band
    if not (0 < lo < hi) or points < 3:
        raise FividError(f"a peak search needs 0 < low < high and >= 3 points, got band {[lo, hi]!r} Hz, "
                         f"{points} points")
    hb = HarmonicBalance.from_model(model, normal_load)
    grid = np.linspace(lo, hi, int(points))
    sols = hb.sweep(grid)
    amp = np.array([abs(s.measurement[0]) for s in sols])
    i = int(np.argmax(amp))
    on_edge = i in (0, grid.size - 1)
    if on_edge:
        return FRFPeak(float(grid[i]), float(amp[i]), float(normal_load), True)
    guesses = {k: np.r_[sols[k].contact.real, sols[k].contact.imag][_interleave(hb.harmonics.size)]
               for k in (i - 1, i, i + 1)}

    def negative_amplitude(f):
        k = min(guesses, key=lambda j: abs(grid[j] - f))
        u, it = hb.solve(2 * np.pi * f, guesses[k])
        return -abs(hb.solution(u, 2 * np.pi * f, it).measurement[0])

    res = minimize_scalar(negative_amplitude, bounds=(grid[i - 1], grid[i + 1]), method="bounded",
                          options={"xatol": xatol})
    return FRFPeak(float(res.x), float(-res.fun), float(normal_load), False)


def _interleave(n: int) -> np.ndarray:
    """Index that turns ``[Re X_1..Re X_n, Im X_1..Im X_n]`` into ``[Re X_1, Im X_1, ...]``."""
    return np.ravel(np.column_stack([np.arange(n), n + np.arange(n)]))
