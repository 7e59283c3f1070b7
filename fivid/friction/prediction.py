"""Prediction of the amplitude A(V, Ra, Fn) with its prediction interval and the domain check.

The interval is for the amplitude of a new run at the condition (what a measurement there would
give), by the delta method on the fit scale η (ln A for every form but the constant and the
categorical lines):

    var(η̂ − η_new) = g(x)ᵀ Σ g(x) + σ²_new,

with ``g = ∂η/∂β`` (the design row for the forms linear in β), ``Σ`` the coefficient covariance and
``σ²_new`` the residual variance of a run as precise as the average fitted one (stored with the fit,
:class:`~fivid.friction.amplitude.AmplitudeModel`; relative, × Â², for categorical lines fitted with
estimator weights). ``η̂ ± t_{df} sqrt(var)`` (Student t on the fit's residual degrees of freedom) is
mapped through exp (multiplicative interval) or clipped at 0. Without a residual variance (law files of
version 1) the interval is the confidence interval of the law's mean only, and says so.

Outside the identified domain (:class:`~fivid.friction.domain.ConditionDomain`) the law still
evaluates, with an :class:`ExtrapolationWarning` naming the variable and the identified range, or an
error with ``strict=True``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from fivid.errors import FividError

__all__ = ["ExtrapolationWarning", "AmplitudePrediction", "predict_amplitude"]


class ExtrapolationWarning(UserWarning):
    """A law is evaluated outside the conditions it was identified at."""


@dataclass
class AmplitudePrediction:
    """Predicted amplitude [-] and its interval at each condition, and whether it lies in the domain."""

    amplitude: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    confidence: float
    kind: str  # "prediction" or "confidence (mean only: no residual variance recorded)"
    inside: np.ndarray
    messages: list = field(default_factory=list)

    def to_json(self) -> dict:
        """Plain-Python record (lists, one entry per condition)."""
        return {"amplitude": self.amplitude.tolist(), "lower": self.lower.tolist(), "upper": self.upper.tolist(),
                "confidence": self.confidence, "interval": self.kind, "inside_domain": self.inside.tolist(),
                "warnings": list(self.messages)}


def predict_amplitude(model, velocity, roughness, normal_load=None, *, domain=None, confidence: float = 0.95,
                      strict: bool = False) -> AmplitudePrediction:
    """A(V, Ra, Fn) with its ``confidence`` prediction interval (see the module docstring).

    Parameters
    ----------
    model : AmplitudeModel
    velocity, roughness, normal_load : array_like
        Sliding velocity [m s-1], roughness Ra [m], normal load [N] (None where the law does not use it).
    domain : ConditionDomain, optional
        Where the law was identified; None: not checked.
    confidence : float, default 0.95
    strict : bool, default False
        Raise :class:`~fivid.errors.FividError` outside the domain instead of warning.

    Warns
    -----
    ExtrapolationWarning
        A condition is outside the domain (the message names the variable and the identified range).
    """
    from scipy import stats

    if not 0 < confidence < 1:
        raise FividError(f"confidence = {confidence!r}; it must be in (0, 1)")
    messages = domain.outside(velocity, roughness, normal_load) if domain is not None else []
    if messages:
        text = "extrapolation: " + " | ".join(messages)
        if strict:
            raise FividError(text + " (strict: refused)")
        warnings.warn(text, ExtrapolationWarning, stacklevel=2)
    eta, g = model.predictor_and_gradient(velocity, roughness, normal_load)
    cov = np.nan_to_num(np.asarray(model.covariance, float).reshape(g.shape[1], g.shape[1]))
    var = np.maximum(np.einsum("ij,jk,ik->i", np.nan_to_num(g), cov, np.nan_to_num(g)), 0.0)
    amp = np.exp(eta) if model.is_log_form else np.maximum(eta, 0.0)
    s2 = float(model.residual_variance)
    kind = "prediction"
    if np.isfinite(s2):
        var = var + s2 * (amp**2 if model.residual_relative else 1.0)
    else:
        kind = "confidence (mean only: no residual variance recorded)"
    df = float(model.df_resid)
    q = stats.t.ppf(0.5 + confidence / 2, df) if np.isfinite(df) and df > 0 else stats.norm.ppf(0.5 + confidence / 2)
    half = q * np.sqrt(var)
    if model.is_log_form:
        lo, hi = np.exp(eta - half), np.exp(eta + half)
    else:
        lo, hi = np.maximum(eta - half, 0.0), np.maximum(eta + half, 0.0)
    n = amp.size
    inside = np.ones(n, bool)
    if messages and domain is not None:
        inside = np.array([not domain.outside(*(None if x is None else np.broadcast_to(x, (n,))[i]
                                                for x in (velocity, roughness, normal_load))) for i in range(n)])
    return AmplitudePrediction(amp, lo, hi, confidence, kind, inside, messages)
