"""Identify a Jenkins element (slip force, stiffness) from a measured force-displacement history.

The model is marched along the *measured* displacement (so ramps, varying amplitudes and partial
cycles are handled) and its force is fitted to the measured force by least squares on
``(log k, log F_s, force offset)``. Energy per cycle is compared cycle by cycle: measured loop
area ``oint F dx`` against the model's loop area over the same cycles.

Quality checks before fitting (each a :class:`~fivid.errors.DataQualityError`):

* too few cycles: fewer than 2 full displacement cycles above 20 % of the peak amplitude;
* drift: per-cycle mean displacement spread over more than 25 % of the peak amplitude (an open loop
  biases the area by about ``F_s * drift``, i.e. ``drift / (4 a)`` relative, > 6 % at 25 %);
* clipping: a run of identical samples at the signal's extreme lasting more than 2 % of a cycle
  (a sampled sinusoid stays within one quantum of its peak for ~0.5 % of a cycle at 16 bits; a
  measured slip plateau is noisy, a noise-free simulated one is rejected like a clipped signal).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.errors import DataQualityError
from fivid.friction.jenkins import jenkins_energy_per_cycle, jenkins_force, loop_energy

__all__ = ["JenkinsLoopFit", "displacement_cycles", "check_loop_quality", "fit_jenkins_loop"]

MIN_CYCLES = 2
MAX_DRIFT = 0.25
MAX_CLIP_FRACTION = 0.02


@dataclass(frozen=True)
class JenkinsLoopFit:
    """Result of :func:`fit_jenkins_loop` (SI units).

    Attributes
    ----------
    slip_force, stiffness, force_offset : float
        ``F_s`` [N], ``k`` [N/m], constant force offset [N].
    slip_force_stderr, stiffness_stderr : float
        Standard errors [N], [N/m] from the least-squares Jacobian, inflated for serially correlated
        residuals by the AR(1) factor ``sqrt((1 + rho) / (1 - rho))`` (``rho`` the lag-1
        autocorrelation of the residuals; 1 for white residuals).
    residual_autocorrelation : float
        ``rho`` [1].
    cycle_amplitudes : ndarray
        Displacement amplitude of each full cycle [m].
    energy_per_cycle_measured, energy_per_cycle_model : ndarray
        Loop area per cycle [J], measured and of the fitted model along the same displacement.
    energy_per_cycle_closed_form : ndarray
        ``4 F_s (a - F_s/k)`` per cycle [J].
    rms_residual : float
        RMS of measured minus model force [N].
    r_squared : float
        Coefficient of determination of the force fit.
    """

    slip_force: float
    stiffness: float
    force_offset: float
    slip_force_stderr: float
    stiffness_stderr: float
    residual_autocorrelation: float
    cycle_amplitudes: np.ndarray
    energy_per_cycle_measured: np.ndarray
    energy_per_cycle_model: np.ndarray
    energy_per_cycle_closed_form: np.ndarray
    rms_residual: float
    r_squared: float

    def summary(self) -> dict:
        """JSON-ready summary (energies are means over the full cycles)."""
        return {
            "slip_force": self.slip_force,
            "slip_force_stderr": self.slip_force_stderr,
            "stiffness": self.stiffness,
            "stiffness_stderr": self.stiffness_stderr,
            "force_offset": self.force_offset,
            "residual_autocorrelation": self.residual_autocorrelation,
            "n_cycles": int(self.cycle_amplitudes.size),
            "energy_per_cycle_measured": float(np.mean(self.energy_per_cycle_measured)),
            "energy_per_cycle_model": float(np.mean(self.energy_per_cycle_model)),
            "energy_per_cycle_closed_form": float(np.mean(self.energy_per_cycle_closed_form)),
            "energy_relative_error": float(np.mean(self.energy_per_cycle_model) / np.mean(self.energy_per_cycle_measured) - 1),
            "rms_residual": self.rms_residual,
            "r_squared": self.r_squared,
            "cycles": [{"amplitude": float(a), "energy_measured": float(wm), "energy_model": float(wf)}
                       for a, wm, wf in zip(self.cycle_amplitudes, self.energy_per_cycle_measured,
                                            self.energy_per_cycle_model)],
            "units": {"slip_force": "N", "stiffness": "N m-1", "force_offset": "N", "energy_per_cycle": "J",
                      "rms_residual": "N", "amplitude": "m", "energy": "J"},
        }


def displacement_cycles(displacement, threshold: float = 0.2) -> np.ndarray:
    """Sample indices of upward crossings that delimit full displacement cycles.

    A crossing counts when the displacement (minus its median) goes from below ``-threshold * A``
    to above ``+threshold * A`` (``A`` the peak absolute deviation), which ignores noise near zero.

    Returns
    -------
    ndarray of int
        Start indices; cycle ``i`` is ``[starts[i], starts[i + 1])``.
    """
    x = np.asarray(displacement, dtype=float)
    xc = x - np.median(x)
    amp = np.max(np.abs(xc))
    if amp == 0:
        return np.zeros(0, dtype=int)
    state = np.where(xc > threshold * amp, 1, np.where(xc < -threshold * amp, -1, 0))
    nz = np.flatnonzero(state)
    s = state[nz]
    ups = nz[1:][(s[1:] == 1) & (s[:-1] == -1)]
    return ups


def _longest_run_at(values: np.ndarray, level: float) -> int:
    at = np.concatenate([[False], values == level, [False]])
    edges = np.flatnonzero(np.diff(at.astype(int)))
    return int(np.max(edges[1::2] - edges[0::2])) if edges.size else 0


def check_loop_quality(displacement, force, *, file=None) -> np.ndarray:
    """Raise :class:`DataQualityError` on too few cycles, drift or clipping; return the cycle starts."""
    x = np.asarray(displacement, dtype=float)
    f = np.asarray(force, dtype=float)
    starts = displacement_cycles(x)
    n_cycles = max(starts.size - 1, 0)
    if n_cycles < MIN_CYCLES:
        raise DataQualityError(
            f"only {n_cycles} full displacement cycle(s) (above 20 % of the peak amplitude); at least {MIN_CYCLES} "
            "are needed to identify a loop and its energy per cycle", file=file, column="displacement")
    samples_per_cycle = float(np.median(np.diff(starts)))
    for name, arr in (("displacement", x), ("force", f)):
        for level in (arr.max(), arr.min()):
            run = _longest_run_at(arr, level)
            if run > MAX_CLIP_FRACTION * samples_per_cycle:
                raise DataQualityError(
                    f"{name} looks clipped: {run} consecutive samples at its extreme {level:.6g} (SI) "
                    f"(> {MAX_CLIP_FRACTION:.0%} of a {samples_per_cycle:.0f}-sample cycle); check the sensor range "
                    "(noise-free simulated slip plateaus look the same: add the measurement noise)",
                    file=file, column=name)
    means = np.array([x[a:b].mean() for a, b in zip(starts[:-1], starts[1:])])
    amps = np.array([np.ptp(x[a:b]) / 2 for a, b in zip(starts[:-1], starts[1:])])
    drift = np.ptp(means) / amps.max()
    if drift > MAX_DRIFT:
        raise DataQualityError(
            f"displacement drifts: the cycle means spread over {drift:.0%} of the peak amplitude "
            f"(allowed {MAX_DRIFT:.0%}); remove the trend or cut the record to its steady part",
            file=file, column="displacement")
    return starts


def fit_jenkins_loop(displacement, force, *, file=None) -> JenkinsLoopFit:
    """Fit a Jenkins element to a measured force-displacement history.

    Parameters
    ----------
    displacement : array_like
        Imposed displacement [m], starting from rest.
    force : array_like
        Measured friction force [N].
    file : str, optional
        For error messages.

    Returns
    -------
    JenkinsLoopFit
    """
    from scipy.optimize import least_squares

    x = np.asarray(displacement, dtype=float)
    f = np.asarray(force, dtype=float)
    starts = check_loop_quality(x, f, file=file)
    fs0 = 0.5 * (np.percentile(f, 95) - np.percentile(f, 5))
    # initial stiffness: slope of the force right after each displacement reversal (stick branch)
    span = np.ptp(x)
    k0 = 2 * fs0 / (0.1 * span)

    def model(p):
        k, fs, off = np.exp(p[0]), np.exp(p[1]), p[2]
        return jenkins_force(x, k, fs) + off

    def resid(p):
        return model(p) - f

    best = None
    for k_start in (k0 * 10, k0, k0 / 10):  # the residual is non-smooth in k: try a few starts
        r = least_squares(resid, [np.log(k_start), np.log(fs0), float(np.median(f))], method="trf",
                          x_scale=[1.0, 1.0, fs0], diff_step=1e-6)
        if best is None or r.cost < best.cost:
            best = r
    p = best.x
    k, fs, off = float(np.exp(p[0])), float(np.exp(p[1])), float(p[2])
    res = best.fun
    dof = max(res.size - 3, 1)
    s2 = float(res @ res) / dof
    rc = res - res.mean()
    rho = float(np.clip(np.sum(rc[1:] * rc[:-1]) / np.sum(rc * rc), 0.0, 0.999))
    # AR(1) residuals: the variance of a mean-like estimate grows by (1 + rho) / (1 - rho)
    inflation = np.sqrt((1 + rho) / (1 - rho))
    try:
        cov = s2 * np.linalg.inv(best.jac.T @ best.jac)
        # log-parameters: se(k) = k se(log k)
        se_k, se_fs = k * np.sqrt(cov[0, 0]) * inflation, fs * np.sqrt(cov[1, 1]) * inflation
    except np.linalg.LinAlgError:
        se_k = se_fs = float("nan")
    fm = model(p)
    cyc = list(zip(starts[:-1], starts[1:]))
    amps = np.array([np.ptp(x[a:b + 1]) / 2 for a, b in cyc])
    w_meas = np.array([loop_energy(x[a:b + 1], f[a:b + 1]) for a, b in cyc])
    w_model = np.array([loop_energy(x[a:b + 1], fm[a:b + 1]) for a, b in cyc])
    return JenkinsLoopFit(
        slip_force=fs, stiffness=k, force_offset=off, slip_force_stderr=float(se_fs), stiffness_stderr=float(se_k),
        residual_autocorrelation=rho,
        cycle_amplitudes=amps, energy_per_cycle_measured=w_meas, energy_per_cycle_model=w_model,
        energy_per_cycle_closed_form=jenkins_energy_per_cycle(amps, k, fs),
        rms_residual=float(np.sqrt(np.mean(res**2))),
        r_squared=float(1 - np.sum(res**2) / np.sum((f - f.mean()) ** 2)),
    )
