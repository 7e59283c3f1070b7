"""Rayleigh damping, classic or band-limited: the modal damping ratio it gives at each frequency.

Two schemes share the damping matrix ``C = alpha M + beta K``; they differ in the velocity the stiffness part
acts on:

``rayleigh``
    ``f_damp = alpha M v + beta K v``: modal ratio ``zeta(omega) = alpha/(2 omega) + beta omega / 2``. In an
    explicit solver the ``beta K v`` term shrinks the stable step to ``(2/omega_max)(sqrt(1+xi^2) - xi)``,
    ``xi = beta omega_max / 2``: on the default rig 6-7x below the Courant step, spent on damping modes at tens of
    MHz that no sensor sees.
``band_limited``
    ``f_damp = alpha M v + beta K v_f`` with ``v_f`` the velocity through a first-order low-pass filter of
    cut-off ``f_c`` (``dv_f/dt = omega_c (v - v_f)``, ``omega_c = 2 pi f_c``). For a mode of angular
    frequency ``omega`` the filter's response ``omega_c / (omega_c + i omega)`` splits the stiffness term into a
    damping part and a small stiffening part:

    ``zeta(omega) = alpha/(2 omega) + (beta omega / 2) / (1 + (omega/omega_c)^2)``,
    ``omega_eff^2 = omega^2 (1 + beta omega_c (omega/omega_c)^2 / (1 + (omega/omega_c)^2))``.

    Below ``f_c`` the damping is the classic one (reduced by ``1/(1 + (f/f_c)^2)``, which the fit to the user's
    ratios takes into account, so the configured ratios hold exactly at the configured frequencies); far above
    ``f_c`` the term is a stiffness ``beta omega_c K`` and no longer limits the step: the stable step is within
    ``1/sqrt(1 + beta omega_c)`` of the undamped Courant step (see :mod:`fivid.solver.timestep`). The cut-off
    is chosen a few times above the analysis band (the default rig: 60 kHz for a band up to 20 kHz, where
    the stiffening is 0.6 % in frequency at 20 kHz and 0.16 % at 10 kHz).

The filter is the scheme's own: modal analysis (real modes) is unaffected; the transient solver integrates
``v_f`` with the exact exponential update of a piecewise-constant input (one extra vector, no extra stencil
pass).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError, FividError

__all__ = ["modal_root", "damping_ratio", "frequency_factor", "rayleigh_through_two_ratios", "RayleighFit",
           "fit_rayleigh_least_squares", "scheme_name"]


def scheme_name(beta: float, cutoff: float) -> str:
    """``"band_limited"`` when a finite cut-off [Hz] filters a nonzero ``beta`` [s], else ``"rayleigh"``."""
    return "band_limited" if math.isfinite(cutoff) and beta > 0.0 else "rayleigh"


def _cutoff_factor(omega, cutoff):
    """``1 / (1 + (omega/omega_c)^2)`` (1 for ``cutoff`` inf or None)."""
    if cutoff is None or not math.isfinite(cutoff):
        return np.ones_like(omega)
    wc = 2.0 * np.pi * float(cutoff)
    return 1.0 / (1.0 + (omega / wc) ** 2)


def modal_root(frequency, alpha: float, beta: float, cutoff: float | None = None) -> np.ndarray:
    """Exact complex eigenvalue ``s`` [rad s-1] (upper half-plane) of a mode of undamped ``frequency`` [Hz].

    Classic Rayleigh: ``s^2 + (alpha + beta omega^2) s + omega^2 = 0``. Band-limited: the mode's equation
    ``s^2 + alpha s + omega^2 (1 + beta omega_c s / (s + omega_c)) = 0`` times ``(s + omega_c)``, a cubic whose
    complex pair is the vibration (the real root is the filter's own decaying state).
    """
    f = np.atleast_1d(np.asarray(frequency, dtype=float))
    out = np.empty(f.shape, dtype=complex)
    for i, fi in enumerate(f.flat):
        w = 2.0 * np.pi * fi
        if cutoff is None or not math.isfinite(cutoff):
            r = np.roots([1.0, alpha + beta * w * w, w * w])
        else:
            wc = 2.0 * np.pi * float(cutoff)
            r = np.roots([1.0, alpha + wc, w * w + alpha * wc + beta * w * w * wc, w * w * wc])
        out.flat[i] = r[np.argmax(r.imag)]
    return out.reshape(np.shape(frequency)) if np.ndim(frequency) else out[0]


def damping_ratio(frequency, alpha: float, beta: float, cutoff: float | None = None) -> np.ndarray:
    """Modal damping ratio ``-Re(s)/|s|`` of a mode at ``frequency`` [Hz] under the scheme [-].

    Exact (:func:`modal_root`); to first order in the damping it is
    ``alpha/(2 omega) + (beta omega / 2) / (1 + (omega/omega_c)^2)``.

    Parameters
    ----------
    frequency : array_like
        Undamped mode frequencies [Hz], positive.
    alpha : float
        Mass-proportional coefficient [s-1].
    beta : float
        Stiffness-proportional coefficient [s].
    cutoff : float or None
        Cut-off of the velocity filter of the stiffness part [Hz]; None or inf: classic Rayleigh.

    Examples
    --------
    >>> round(float(damping_ratio(1e4, 0.0, 2e-7)), 6)   # beta omega / 2 = 2e-7 * 2 pi 1e4 / 2
    0.006283
    >>> round(float(damping_ratio(1e4, 0.0, 2e-7, cutoff=1e4)), 4)  # about half of it at the cut-off
    0.0031
    """
    s = modal_root(frequency, alpha, beta, cutoff)
    return -np.real(s) / np.abs(s)


def frequency_factor(frequency, beta: float, cutoff: float | None = None) -> np.ndarray:
    """Ratio of a mode's frequency with the scheme to its undamped real-mode frequency [-].

    ``sqrt(1 + beta omega_c x^2 / (1 + x^2))``, ``x = omega/omega_c``: the in-phase part of ``beta K v_f``
    stiffens the mode slightly (1 for classic Rayleigh, which has none). Damping's own shift of the damped
    frequency, ``sqrt(1 - zeta^2)``, is not included.
    """
    omega = 2.0 * np.pi * np.asarray(frequency, dtype=float)
    if cutoff is None or not math.isfinite(cutoff):
        return np.ones_like(omega)
    wc = 2.0 * np.pi * float(cutoff)
    x2 = (omega / wc) ** 2
    return np.sqrt(1.0 + beta * wc * x2 / (1.0 + x2))


def rayleigh_through_two_ratios(f1: float, zeta1: float, f2: float, zeta2: float,
                                cutoff: float | None = None) -> tuple[float, float]:
    """``(alpha [s-1], beta [s])`` giving exactly the ratio ``zeta1`` at ``f1`` and ``zeta2`` at ``f2`` [Hz]
    under the scheme: a solve through two points (a model file's ``damping: ratios``), not a fit (for that, see
    :func:`fit_rayleigh_least_squares`).

    Classic Rayleigh: the linear system ``zeta_i = alpha/(2 omega_i) + beta omega_i / 2`` (exact). Band-limited:
    that system with ``beta`` scaled by ``1/(1 + (omega_i/omega_c)^2)`` as the start, then Newton on the exact
    ratios of :func:`damping_ratio` to float resolution.

    Raises
    ------
    fivid.errors.ConfigError
        The frequencies are not two distinct positive numbers.

    Examples
    --------
    >>> a, b = rayleigh_through_two_ratios(1e3, 0.005, 1e4, 0.01)
    >>> round(a, 1), round(b * 1e7, 2)
    (50.8, 3.05)
    >>> a, b = rayleigh_through_two_ratios(1e3, 0.005, 1e4, 0.01, cutoff=6e4)
    >>> [round(float(z), 9) for z in damping_ratio([1e3, 1e4], a, b, cutoff=6e4)]
    [0.005, 0.01]
    """
    if not (float(f1) > 0 and float(f2) > 0) or float(f1) == float(f2):
        raise ConfigError(f"need two distinct positive frequencies, got {f1} and {f2} Hz", key="damping.ratios")
    w = 2.0 * np.pi * np.array([f1, f2], dtype=float)
    target = np.array([zeta1, zeta2], dtype=float)
    g = _cutoff_factor(w, cutoff)
    A = np.column_stack([1.0 / (2.0 * w), 0.5 * w * g])
    x = np.linalg.solve(A, target)
    if cutoff is None or not math.isfinite(cutoff):
        return float(x[0]), float(x[1])
    freqs = np.array([f1, f2], dtype=float)
    for _ in range(20):
        r = damping_ratio(freqs, x[0], x[1], cutoff) - target
        if np.all(np.abs(r) <= 1e-13 * np.maximum(np.abs(target), 1e-300)):
            break
        h = np.abs(x) * 1e-7 + 1e-300
        J = np.column_stack([(damping_ratio(freqs, x[0] + h[0], x[1], cutoff) - target - r) / h[0],
                             (damping_ratio(freqs, x[0], x[1] + h[1], cutoff) - target - r) / h[1]])
        x = x - np.linalg.solve(J, r)
    return float(x[0]), float(x[1])


@dataclass
class RayleighFit:
    """Rayleigh coefficients α [s-1], β [s] with standard errors and covariance."""

    alpha: float
    beta: float
    alpha_stderr: float
    beta_stderr: float
    covariance: np.ndarray
    n_modes: int
    chi2_p_value: float = np.nan

    def zeta(self, frequency) -> np.ndarray:
        """ζ(f) = α/(2ω) + βω/2 at ``frequency`` [Hz]."""
        w = 2 * np.pi * np.asarray(frequency, float)
        return self.alpha / (2 * w) + self.beta * w / 2

    def to_json(self) -> dict:
        """A JSON-ready dict: ``alpha`` [s-1], ``beta`` [s], their standard errors and covariance, fit statistics."""
        return {
            "alpha": self.alpha, "alpha_stderr": self.alpha_stderr, "alpha_units": "s-1",
            "beta": self.beta, "beta_stderr": self.beta_stderr, "beta_units": "s",
            "covariance": np.asarray(self.covariance).tolist(), "n_modes": self.n_modes,
            "chi2_p_value": self.chi2_p_value,
        }


def fit_rayleigh_least_squares(frequency, zeta, zeta_stderr=None) -> RayleighFit:
    """Least-squares fit of ``ζ = α/(2ω) + βω/2`` to two or more measured modal damping ratios.

    Weighted least squares (statsmodels WLS, weights ``1/se(ζ_i)^2``). The covariance takes the ratios'
    standard errors as known, ``(X' W X)^-1``; with more modes than two a χ² goodness-of-fit p-value says
    whether Rayleigh damping describes the measured ratios within their errors, and the covariance is scaled by
    the reduced χ² when it exceeds 1 (Birge ratio). Without standard errors the residual variance is estimated
    (at least three modes are needed for an error). Classic Rayleigh only; to place exactly two ratios under
    either scheme use :func:`rayleigh_through_two_ratios`.

    Parameters
    ----------
    frequency : array_like
        Modal frequencies [Hz].
    zeta : array_like
        Damping ratios [-].
    zeta_stderr : array_like, optional
        Their standard errors [-]; without them, unweighted least squares.
    """
    import statsmodels.api as sm
    from scipy import stats

    f = np.asarray(frequency, float)
    z = np.asarray(zeta, float)
    if f.size < 2:
        raise FividError(f"a Rayleigh fit needs at least two modes; got {f.size}")
    if np.unique(np.round(f, 9)).size < 2:
        raise FividError("a Rayleigh fit needs two distinct modal frequencies")
    w = 2 * np.pi * f
    X = np.column_stack([1 / (2 * w), w / 2])
    se = None if zeta_stderr is None else np.asarray(zeta_stderr, float)
    if se is not None and not np.all(np.isfinite(se) & (se > 0)):
        se = None
    weights = np.ones_like(z) if se is None else 1 / se**2
    res = sm.WLS(z, X, weights=weights).fit()
    params = np.asarray(res.params, float)
    p_value = np.nan
    dof = f.size - 2
    if se is not None:
        # the ratios' standard errors are taken as known (absolute sigma); with dof >= 1 the covariance is
        # scaled up by the reduced χ² when the modes scatter more than their errors (Birge ratio)
        cov = np.linalg.inv(X.T @ (weights[:, None] * X))
        if dof >= 1:
            chi2 = float(np.sum(weights * np.asarray(res.resid) ** 2))
            p_value = float(stats.chi2.sf(chi2, dof))
            cov = cov * max(1.0, chi2 / dof)
    elif dof >= 1:
        cov = np.asarray(res.cov_params(), float)
    else:
        cov = np.full((2, 2), np.nan)
    return RayleighFit(alpha=float(params[0]), beta=float(params[1]), alpha_stderr=float(np.sqrt(cov[0, 0])),
                       beta_stderr=float(np.sqrt(cov[1, 1])), covariance=cov, n_modes=int(f.size),
                       chi2_p_value=p_value)
