"""Model updating: friction coefficient and contact stiffness from measured FRFs at several normal loads.

Least squares (:func:`scipy.optimize.least_squares`) on the log of the first-harmonic displacement
amplitudes at the sensor, ``r = log(A_model / A_measured)``, over every frequency of every FRF, in
the parameters ``(mu, log k_d)``. Log residuals weigh the damped plateau and the peaks alike and are
the natural scale of multiplicative measurement error. Uncertainty: ``cov = s^2 (J^T J)^-1`` with
``s^2`` the residual variance (independent residuals assumed), mapped to ``k_d`` by ``se(k) = k se(log k)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.damper.hbm import HarmonicBalance
from fivid.damper.model import DamperModel
from fivid.errors import FividError

__all__ = ["ContactUpdate", "update_contact_parameters", "model_amplitudes"]


@dataclass(frozen=True)
class ContactUpdate:
    """Result of :func:`update_contact_parameters`.

    Attributes
    ----------
    friction_coefficient, contact_stiffness : float
        Estimates ``mu`` [1] and ``k_d`` [N/m].
    friction_coefficient_stderr, contact_stiffness_stderr : float
        Standard errors [1], [N/m].
    covariance : ndarray, shape (2, 2)
        Covariance of ``(mu, log k_d)``.
    rms_log_residual : float
        RMS of ``log(A_model / A_measured)`` [1] (0.01 is ~1 % amplitude error).
    n_points : int
    """

    friction_coefficient: float
    contact_stiffness: float
    friction_coefficient_stderr: float
    contact_stiffness_stderr: float
    covariance: np.ndarray
    rms_log_residual: float
    n_points: int


def model_amplitudes(model: DamperModel, normal_load: float, frequencies) -> np.ndarray:
    """First-harmonic displacement amplitude at the sensor [m] at the given frequencies [Hz]."""
    sols = HarmonicBalance.from_model(model, normal_load).sweep(np.sort(np.asarray(frequencies, dtype=float)))
    amp = np.array([abs(s.measurement[0]) for s in sols])
    order = np.argsort(np.argsort(np.asarray(frequencies, dtype=float)))
    return amp[order]


def update_contact_parameters(model: DamperModel, measurements, *, initial=None) -> ContactUpdate:
    """Fit ``mu`` and ``k_d`` of ``model`` to measured FRFs.

    Parameters
    ----------
    model : DamperModel
        The structure (its contact parameters are the starting point unless ``initial`` is given).
    measurements : sequence of MeasuredFRF
        Each with its ``normal_load`` [N]; displacement amplitudes or receptances (times the
        model's excitation amplitude).
    initial : (float, float), optional
        Starting ``(mu, k_d)``.

    Returns
    -------
    ContactUpdate
    """
    from scipy.optimize import least_squares

    data = []
    for i, m in enumerate(measurements):
        if m.normal_load is None or not m.normal_load > 0:
            raise FividError(f"measurement {i} has no normal load (a '# normal_load: 2 N' line)")
        amp = m.displacement_amplitude(model.excitation_amplitude)
        if np.any(amp <= 0):
            raise FividError(f"measurement {i} has zero amplitudes; log residuals need positive amplitudes")
        data.append((m.normal_load, m.frequency, np.log(amp)))
    if not data:
        raise FividError("no measurements to update the model on")
    mu0, k0 = initial if initial is not None else (model.friction_coefficient, model.contact_stiffness)

    def resid(p):
        trial = model.with_parameters(friction_coefficient=p[0], contact_stiffness=np.exp(p[1]))
        return np.concatenate([np.log(model_amplitudes(trial, fn, f)) - la for fn, f, la in data])

    fit = least_squares(resid, [mu0, np.log(k0)], bounds=([1e-6, np.log(1e2)], [10.0, np.log(1e12)]),
                        x_scale=[0.1, 1.0], diff_step=[1e-4, 1e-4], method="trf")
    res = fit.fun
    dof = max(res.size - 2, 1)
    s2 = float(res @ res) / dof
    cov = s2 * np.linalg.pinv(fit.jac.T @ fit.jac)
    mu, logk = fit.x
    return ContactUpdate(
        friction_coefficient=float(mu), contact_stiffness=float(np.exp(logk)),
        friction_coefficient_stderr=float(np.sqrt(cov[0, 0])),
        contact_stiffness_stderr=float(np.exp(logk) * np.sqrt(cov[1, 1])),
        covariance=cov, rms_log_residual=float(np.sqrt(np.mean(res**2))), n_points=int(res.size),
    )
