"""Inverse route of seed 001: scale the perturbation amplitude until simulated and measured acceleration
levels agree in a band.

For a measured run, the law (forward estimate) is injected into the FE simulation at the run's
velocity, roughness and load; the acceleration PSD level difference in the band,
``d = 10 log10(∫P_sim / ∫P_meas)`` [dB] (:func:`fivid.score.score_runs`, ``level_diff_db``), sets the
next amplitude scale. In weak contact the response is linear in μp, so the level scales as
``20 log10(g)`` and the first update ``g ← g 10^(−d/20)`` is already the answer; in general the
update is the secant on ``d(20 log10 g)`` from the last two iterations (the proportional update while
there is only one, or when the secant slope is not in (0.2, 5)). It stops when ``|d|`` is below the
tolerance or the score says the difference is not significant against the PSD estimation
uncertainty, or after ``max_iterations``; the result says which. Peaks are then checked without
re-tuning (seed 001): the matched-peak scores of the last simulation are reported.

Both runs are cropped to their steady part (:func:`fivid.signal.steady_part`: a measured run to its
steady-sliding window, a simulated run to ``t >= transient_end``).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from fivid.errors import ConfigError, FividError
from fivid.friction.inputs import FrictionInput, OperatingCondition
from fivid.score import score_runs
from fivid.signal.steady import steady_part
from fivid.solver import simulate
from fivid.solver.options import RunSchedule

__all__ = ["InverseAmplitude", "inverse_amplitude_scale"]

_log = logging.getLogger("fivid")


@dataclass
class InverseAmplitude:
    """Result of :func:`inverse_amplitude_scale` for one measured run."""

    run_id: str
    band: tuple
    forward_amplitude: float
    scale: float
    inverse_amplitude: float
    converged: bool
    reason: str
    iterations: list = field(default_factory=list)
    peaks: dict = field(default_factory=dict)
    nperseg: int = 0

    def to_json(self) -> dict:
        """A JSON-ready dict: amplitudes [-], band [Hz], PSD levels and the iterations of the search."""
        return {
            "run_id": self.run_id,
            "band": list(self.band),
            "forward_amplitude": self.forward_amplitude,
            "scale": self.scale,
            "inverse_amplitude": self.inverse_amplitude,
            "converged": self.converged,
            "reason": self.reason,
            "iterations": self.iterations,
            "peaks": self.peaks,
            "nperseg": self.nperseg,
        }


def inverse_amplitude_scale(law, measured, model=None, *, band, duration: float = 0.1, seed: int = 0,
                            nperseg: int | None = None, max_iterations: int = 4, tolerance_db: float = 0.5,
                            simulator=None) -> InverseAmplitude:
    """Amplitude scale g such that the simulated acceleration level matches ``measured`` in ``band``.

    Parameters
    ----------
    law : PerturbedCoulombLaw
        The forward estimate.
    measured : xarray.Dataset
        A measured RunDataset (with ``acceleration`` and an encoder signal for the steady window).
    model : Model or path, optional
        FE model for :func:`fivid.solver.simulate` (not needed with ``simulator``).
    band : (float, float)
        Band [Hz] where the levels are matched (the weak-contact band).
    duration : float
        Steady-sliding time simulated per iteration [s].
    seed : int
        Seed of the law's synthesis (the same in every iteration: only the scale changes).
    nperseg : int, optional
        Welch segment length of the scores [samples]; the simulated steady part must hold one. Default
        :func:`fivid.signal.welch.default_nperseg` of the shorter record (:func:`fivid.score.score_runs`);
        the result records the one used.
    max_iterations : int
    tolerance_db : float
        Stop when ``|level_diff_db|`` is below this [dB].
    simulator : callable, optional
        ``simulator(friction, condition, schedule) -> RunDataset`` (a :class:`fivid.friction.FrictionInput`, a
        :class:`fivid.friction.OperatingCondition` and a :class:`fivid.solver.RunSchedule`); default
        :func:`fivid.solver.simulate` on ``model`` (progress bar only on a terminal).
    """
    if isinstance(max_iterations, bool) or int(max_iterations) != max_iterations or max_iterations < 1:
        raise ConfigError(f"max_iterations (--inverse-iterations) must be an integer >= 1, got {max_iterations!r}",
                          key="max_iterations")
    if not (np.isfinite(duration) and duration > 0):
        raise ConfigError(f"duration (--inverse-duration) must be > 0 [s], got {duration!r}", key="duration")
    if simulator is None:
        if model is None:
            raise FividError("the inverse route needs an FE model (model=) to simulate")

        def simulator(friction, condition, schedule):
            return simulate(model, condition, friction, schedule=schedule)

    v = float(measured.attrs["sliding_velocity"])
    ra = float(measured.attrs["roughness_ra"])
    fn = float(measured.attrs["normal_load"])
    fs = float(measured.attrs["sample_rate"])
    run_id = str(measured.attrs.get("run_id", "?"))
    meas = steady_part(measured)
    a_fwd = float(law.amplitude(v, ra, fn))
    g, history = 1.0, []
    converged, reason, peaks, used_nperseg = False, f"not converged in {max_iterations} iterations", {}, 0
    condition, schedule = OperatingCondition(v, fn, ra), RunSchedule(duration=duration, sample_rate=fs)
    for it in range(int(max_iterations)):
        sim = steady_part(simulator(FrictionInput(law=law.scaled(g), seed=seed), condition, schedule))
        scores = score_runs(meas, sim, band=band, nperseg=nperseg)
        d = float(scores["level_diff_db"])
        used_nperseg = int(scores.attrs["nperseg"])
        significant = bool(scores["level_diff_db_significant"])
        history.append({"iteration": it, "scale": g, "level_diff_db": d, "significant": significant,
                         "lsd_db": float(scores["lsd_db"])})
        _log.info("inverse route, run %s, iteration %d: scale %.4g, level difference %.3f dB", run_id, it, g, d)
        peaks = _peak_summary(scores)
        if abs(d) < tolerance_db or not significant:
            converged = True
            reason = (f"|level difference| {abs(d):.3f} dB < {tolerance_db} dB" if abs(d) < tolerance_db
                      else "level difference not significant against the PSD estimation uncertainty")
            break
        if len(history) >= 2 and _slope(history) is not None and _slope(history) < 0.2:
            reason = (f"the simulated level hardly responds to the amplitude (slope {_slope(history):.3f} dB/dB): "
                      "the friction perturbation does not dominate the simulated response in this band")
            break
        g = _next_scale(history)
    return InverseAmplitude(run_id=run_id, band=tuple(band), forward_amplitude=a_fwd, scale=g,
                            inverse_amplitude=g * a_fwd, converged=converged, reason=reason, iterations=history,
                            peaks=peaks, nperseg=used_nperseg)


def _slope(history):
    """d(level difference)/d(20 log10 g) between the last two iterations, or None."""
    x = [20 * np.log10(h["scale"]) for h in history[-2:]]
    d = [h["level_diff_db"] for h in history[-2:]]
    return None if x[1] == x[0] else (d[1] - d[0]) / (x[1] - x[0])


def _next_scale(history) -> float:
    """Secant on d(x), x = 20 log10 g; the proportional update (slope 1) when the secant is unusable."""
    x = [20 * np.log10(h["scale"]) for h in history]
    d = [h["level_diff_db"] for h in history]
    slope = 1.0
    s = _slope(history) if len(history) >= 2 else None
    if s is not None and 0.2 < s < 5.0:
        slope = s
    return float(10 ** ((x[-1] - d[-1] / slope) / 20))


def _peak_summary(scores) -> dict:
    if "peak" not in scores.dims or scores.sizes["peak"] == 0:
        return {"n_measured": 0, "n_matched": 0}
    # a measured peak with no simulated one within the tolerance has peak_frequency_simulated NaN
    out = {"n_measured": int(scores.sizes["peak"]),
           "n_matched": int(np.isfinite(scores["peak_frequency_simulated"].values).sum())}
    for name in ("peak_frequency_measured", "peak_frequency_simulated", "peak_level_diff_db"):
        if name in scores:
            out[name] = [float(x) for x in np.asarray(scores[name].values).ravel()]
    return out
