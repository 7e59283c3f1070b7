"""Fit of the amplitude law A(V, Ra, Fn) across runs: every candidate form, statistics, the choice.

Each form of :mod:`fivid.friction.amplitude` is fitted by least squares with statsmodels on the
per-run band RMS values A_i: WLS with weights ``1/se(A_i)^2`` (``1/(se(A_i)/A_i)^2`` on the log scale),
``weighting="estimator"``, the default, or OLS, ``weighting="none"``. The estimator error of A_i is
proportional to A_i, and so is, plausibly, any run-to-run scatter of a multiplicative process; WLS
takes the weights as relative (the residual variance is estimated), so it stays valid when the
scatter is larger than the estimator error but has the same pattern. OLS with a pooled variance
across roughness levels gives intervals that are too narrow for the high-amplitude level (the
coverage test measured 76 % for a nominal 95 %). A form is fitted only when the design identifies it (the factor
varies: at least two distinct values at 1 % relative tolerance; for the linear forms at least two
velocities per roughness level) and leaves at least one residual degree of freedom; otherwise it is
listed with the reason.

Selection rule
--------------
All forms are compared on the same response, A (not ln A): the log-likelihood of a power law fitted
on ln A is transformed to the A scale with the Jacobian, ``ll_A = ll_lnA − Σ ln A_i``. With k = p + 1
parameters (coefficients and the residual variance), ``AIC = −2 ll + 2k`` and ``BIC = −2 ll + k ln n``.
The chosen form has the minimum AIC, except that among the forms within ΔAIC < 2 of the minimum (not
distinguishable by the data, Burnham & Anderson 2002 §2.6) the one with the fewest coefficients is
chosen. AICc and BIC are reported beside it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from fivid.errors import FividError
from fivid.friction.amplitude import (
    AMPLITUDE_FORMS,
    LOG_FORMS,
    ROUGHNESS_LEVEL_RTOL,
    AmplitudeModel,
    amplitude_design_matrix,
)

__all__ = ["FormFit", "fit_amplitude_forms", "choose_form", "akaike_weights", "distinct_levels", "SELECTION_RULE"]

SELECTION_RULE = (
    "minimum AIC on the amplitude scale (power laws: log-likelihood of ln A plus the Jacobian -sum ln A); "
    "among forms within dAIC < 2 of the minimum, the one with the fewest coefficients"
)


@dataclass
class FormFit:
    """One candidate amplitude form: its fit and statistics, or why it was not fitted."""

    form: str
    fitted: bool = False
    reason: str = ""
    model: AmplitudeModel | None = None
    n_runs: int = 0
    n_params: int = 0
    loglik: float = np.nan
    aic: float = np.nan
    aicc: float = np.nan
    bic: float = np.nan
    conf_int: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    diagnostics: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        """Plain-Python record for the JSON report."""
        out = {"form": self.form, "fitted": self.fitted, "reason": self.reason}
        if self.fitted:
            m = self.model
            out.update({
                "terms": list(m.terms),
                "coefficients": {n: float(c) for n, c in zip(m.names, m.coefficients)},
                "stderr": {n: float(s) for n, s in zip(m.names, m.stderr)},
                "ci95": {n: [float(a), float(b)] for n, (a, b) in zip(m.names, self.conf_int)},
                "roughness_levels": list(m.roughness_levels),
                "n_runs": self.n_runs,
                "n_params": self.n_params,
                "loglik": self.loglik,
                "aic": self.aic,
                "aicc": self.aicc,
                "bic": self.bic,
                "diagnostics": self.diagnostics,
            })
        return out


def distinct_levels(values, rtol: float = ROUGHNESS_LEVEL_RTOL) -> np.ndarray:
    """Representative values of the groups of ``values`` equal within relative tolerance ``rtol``."""
    v = np.sort(np.asarray(values, float))
    levels = []
    for x in v:
        if levels and abs(x - levels[-1][0]) <= rtol * abs(levels[-1][0]):
            levels[-1].append(x)
        else:
            levels.append([x])
    return np.array([np.mean(g) for g in levels])


def _design(form, velocity, roughness, load):
    """terms, roughness levels, or a reason why the design does not identify ``form``."""
    n = velocity.size
    v_levels = distinct_levels(velocity)
    r_levels = distinct_levels(roughness)
    f_levels = distinct_levels(load)
    vary = {"sliding_velocity": v_levels.size > 1, "roughness_ra": r_levels.size > 1, "normal_load": f_levels.size > 1}
    if form == "constant":
        return (), (), ""
    if form.startswith("linear_velocity"):
        if not vary["sliding_velocity"]:
            return None, None, f"all runs at one sliding velocity ({v_levels[0]:.4g} m s-1): no velocity dependence"
        from fivid.friction.amplitude import roughness_level_index

        idx = roughness_level_index(roughness, r_levels)
        for r, level in enumerate(r_levels):
            vs = distinct_levels(velocity[idx == r])
            if vs.size < 2:
                return None, None, (f"roughness level {level * 1e6:.3g} um has runs at a single velocity; "
                                    "a line in V per roughness needs two velocities at each roughness")
        terms = ("sliding_velocity",) + (("roughness_ra",) if vary["roughness_ra"] else ())
        if form == "linear_velocity_load":
            if not vary["normal_load"]:
                return None, None, f"all runs at one normal load ({f_levels[0]:.4g} N): no load dependence"
            terms += ("normal_load",)
        return terms, tuple(float(r) for r in r_levels), ""
    # power laws
    terms = tuple(t for t in ("roughness_ra", "sliding_velocity") if vary[t])
    if form == "power_law":
        if not terms:
            return None, None, "neither roughness nor sliding velocity varies across the runs"
    else:
        if not vary["normal_load"]:
            return None, None, f"all runs at one normal load ({f_levels[0]:.4g} N): no load dependence"
        terms += ("normal_load",)
    if n == 0:
        return None, None, "no runs"
    return terms, (), ""


def _diagnostics(res, y, fitted_scale) -> dict:
    """Residual diagnostics of a statsmodels regression result."""
    from scipy import stats
    from statsmodels.stats.diagnostic import het_breuschpagan

    resid = np.asarray(res.resid, float)
    n = resid.size
    out = {
        "r_squared": float(res.rsquared) if np.isfinite(res.rsquared) else None,
        "residual_std": float(np.sqrt(res.scale)),
        "scale": fitted_scale,
        "shapiro_wilk_p": None,
        "breusch_pagan_p": None,
        "max_abs_studentized_residual": None,
    }
    if n >= 3 and np.ptp(resid) > 0:
        out["shapiro_wilk_p"] = float(stats.shapiro(resid).pvalue)
    if res.df_resid >= 2 and np.ptp(res.fittedvalues) > 0:
        exog = np.column_stack([np.ones(n), np.asarray(res.fittedvalues, float)])
        out["breusch_pagan_p"] = float(het_breuschpagan(resid, exog)[1])
    # internally studentized residuals of the (weighted) fit: r_i = sqrt(w_i) e_i / (s sqrt(1 - h_ii)),
    # h the hat matrix of the whitened design (statsmodels' WLS results have no get_influence)
    w = np.asarray(getattr(res.model, "weights", np.ones(n)), float) * np.ones(n)
    xw = np.asarray(res.model.exog, float) * np.sqrt(w)[:, None]
    h = np.einsum("ij,ij->i", xw @ np.linalg.pinv(xw.T @ xw), xw)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.sqrt(w) * resid / (np.sqrt(res.scale) * np.sqrt(1.0 - h))
    r = r[np.isfinite(r) & (h < 1 - 1e-9)]
    if r.size:
        out["max_abs_studentized_residual"] = float(np.max(np.abs(r)))
    return out


def _fit_one(form, velocity, roughness, load, amplitude, stderr, weighting, confidence) -> FormFit:
    import statsmodels.api as sm

    fit = FormFit(form=form, n_runs=amplitude.size)
    terms, levels, reason = _design(form, velocity, roughness, load)
    if terms is None:
        fit.reason = reason
        return fit
    X, names = amplitude_design_matrix(form, terms, velocity, roughness, load, levels or (np.nan,))
    if form == "constant":
        levels = ()
    p = X.shape[1]
    fit.n_params = p
    if np.linalg.matrix_rank(X) < p:
        fit.reason = f"the runs do not separate the {p} coefficients ({', '.join(names)}): collinear design"
        return fit
    if amplitude.size <= p:
        fit.reason = f"{amplitude.size} runs for {p} coefficients: at least {p + 1} are needed for a standard error"
        return fit
    log_form = form in LOG_FORMS
    if log_form and np.any(amplitude <= 0):
        fit.reason = "a run has amplitude 0: a power law cannot be fitted on ln A"
        return fit
    y = np.log(amplitude) if log_form else amplitude
    if weighting == "estimator":
        se = stderr / amplitude if log_form else stderr
        if not np.all(np.isfinite(se) & (se > 0)):
            fit.reason = "weighting='estimator' needs a finite, positive standard error for every run"
            return fit
        model = sm.WLS(y, X, weights=1.0 / se**2)
    else:
        model = sm.OLS(y, X)
    with warnings.catch_warnings():
        # small-n statsmodels warnings (kurtosistest for n < 20, divide by zero on exact fits) are
        # irrelevant here: the diagnostics are reported as numbers
        warnings.simplefilter("ignore")
        res = model.fit()
        fit.diagnostics = _diagnostics(res, y, "ln A" if log_form else "A")
        ci = np.asarray(res.conf_int(alpha=1 - confidence), float)
    n = amplitude.size
    loglik = float(res.llf) - (float(np.sum(np.log(amplitude))) if log_form else 0.0)
    k = p + 1
    fit.loglik = loglik
    fit.aic = -2 * loglik + 2 * k
    fit.bic = -2 * loglik + k * np.log(n)
    fit.aicc = fit.aic + 2 * k * (k + 1) / (n - k - 1) if n - k - 1 > 0 else np.nan
    fit.conf_int = ci
    fit.model = AmplitudeModel(
        form=form,
        coefficients=np.asarray(res.params, float),
        names=tuple(names),
        stderr=np.asarray(res.bse, float),
        covariance=np.asarray(res.cov_params(), float),
        terms=tuple(terms),
        roughness_levels=tuple(levels),
    )
    fit.fitted = True
    return fit


def fit_amplitude_forms(velocity, roughness, load, amplitude, stderr=None, *, forms=AMPLITUDE_FORMS,
                        weighting: str = "estimator", confidence: float = 0.95) -> list[FormFit]:
    """Fit every candidate form to the per-run amplitudes.

    Parameters
    ----------
    velocity, roughness, load : array_like
        Per-run sliding velocity [m s-1], roughness Ra [m], normal load [N].
    amplitude : array_like
        Per-run band RMS of μp [-].
    stderr : array_like, optional
        Per-run standard error of the amplitude [-] (used by ``weighting="estimator"``).
    forms : sequence of str
        Candidate forms (default: all of :data:`fivid.friction.amplitude.AMPLITUDE_FORMS`).
    weighting : {"estimator", "none"}
        WLS with weights ``1/se^2`` (default), or OLS.
    confidence : float
        Level of the coefficient intervals.

    Returns
    -------
    list of FormFit
        One per form, fitted or with the reason it was not.
    """
    if weighting not in ("none", "estimator"):
        raise FividError(f"weighting {weighting!r} is not one of 'none', 'estimator'")
    unknown = [f for f in forms if f not in AMPLITUDE_FORMS]
    if unknown:
        raise FividError(f"unknown amplitude form(s) {', '.join(unknown)}; choose from {', '.join(AMPLITUDE_FORMS)}")
    v, r, fn, a = (np.asarray(x, float) for x in (velocity, roughness, load, amplitude))
    if stderr is None and weighting == "estimator":
        raise FividError("weighting='estimator' needs the per-run standard errors: pass stderr= or weighting='none'")
    se = np.full(a.shape, np.nan) if stderr is None else np.asarray(stderr, float)
    return [_fit_one(form, v, r, fn, a, se, weighting, confidence) for form in forms]


def choose_form(fits: list[FormFit]) -> tuple[FormFit | None, str]:
    """The form chosen by :data:`SELECTION_RULE` and a sentence saying why (None if none was fitted)."""
    ok = [f for f in fits if f.fitted and np.isfinite(f.aic)]
    if not ok:
        return None, "no amplitude form could be fitted"
    best = min(ok, key=lambda f: f.aic)
    close = [f for f in ok if f.aic - best.aic < 2.0]
    chosen = min(close, key=lambda f: (f.n_params, f.aic))
    others = ", ".join(f"{f.form} {f.aic - best.aic:+.2f}" for f in sorted(ok, key=lambda f: f.aic) if f is not chosen)
    if chosen is best:
        why = f"{chosen.form} has the lowest AIC ({chosen.aic:.2f})"
    else:
        why = (f"{chosen.form} is within dAIC = {chosen.aic - best.aic:.2f} < 2 of the lowest ({best.form}) "
               f"with fewer coefficients ({chosen.n_params} vs {best.n_params})")
    if others:
        why += f"; dAIC of the others: {others}"
    return chosen, why


def akaike_weights(fits: list[FormFit]) -> dict:
    """Akaike weights ``exp(-dAIC/2) / sum`` of the fitted forms: the relative support of each by the data."""
    ok = [f for f in fits if f.fitted and np.isfinite(f.aic)]
    if not ok:
        return {}
    best = min(f.aic for f in ok)
    raw = {f.form: np.exp(-(f.aic - best) / 2) for f in ok}
    total = sum(raw.values())
    return {k: float(v / total) for k, v in raw.items()}
