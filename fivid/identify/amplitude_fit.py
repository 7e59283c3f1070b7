"""Fit of the amplitude law A(V, Ra, Fn) across runs: every candidate form, statistics, the choice.

Candidates (:mod:`fivid.friction.amplitude`): by default the forms continuous in every condition
variable (``constant``, ``power_law``, ``linear_velocity_power_law``, ``log_linear``), each using every
factor that varied across the runs — the normal load wherever the runs differ in load; on request the
interaction form and the categorical per-roughness-level lines (:func:`candidate_forms`).

Every form but the constant and the categorical lines is fitted on ln A: WLS with weights
``1/(se(A_i)/A_i)^2`` (``weighting="estimator"``, the default; on the A scale ``1/se(A_i)^2``) or OLS
(``weighting="none"``). The estimator error of A_i is proportional to A_i, and so is, plausibly, any
run-to-run scatter of a multiplicative process; WLS takes the weights as relative (the residual variance
is estimated), so it stays valid when the scatter is larger than the estimator error but has the same
pattern. Linear forms use statsmodels; ``linear_velocity_power_law``, nonlinear in its coefficients,
scipy's ``least_squares`` with the same weights, Gauss–Newton covariance ``s² (J_wᵀJ_w)⁻¹`` and the same
Gaussian log-likelihood. A form is fitted only when the design identifies it and leaves a residual
degree of freedom; otherwise it is listed with the reason.

Selection rule
--------------
All forms are compared on the same response, A: the log-likelihood of a fit on ln A is transformed to
the A scale with the Jacobian, ``ll_A = ll_lnA − Σ ln A_i``. With k = p + 1 parameters (coefficients and
the residual variance), ``AIC = −2 ll + 2k``, ``AICc = AIC + 2k(k + 1)/(n − k − 1)`` (Hurvich & Tsai
1989; the small-sample correction, large at lab data sizes: +13 for k = 4 at n = 8) and
``BIC = −2 ll + k ln n``. Akaike weights ``exp(−ΔAICc/2)/Σ`` give each form's relative support. The
chosen form has the minimum AICc; among the forms within ΔAICc < 2 of it (not distinguishable by the
data, Burnham & Anderson 2002 §2.6) the one with the smallest leave-one-condition-out cross-validation
error (:func:`cross_validation_error`) is chosen, the prediction error being what the law is for.
Where no form has an AICc (n <= k + 1), AIC takes its place.

Influence
---------
Cook's distance of every run in the chosen fit (statsmodels ``OLSInfluence``); a run with
``D_i > 4/n`` (the usual rule of thumb, Bollen & Jackman 1990) is reported as influential, never
dropped.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from fivid.errors import FividError
from fivid.friction.amplitude import (
    AMPLITUDE_FORMS, CATEGORICAL_FORMS, CONTINUOUS_FORMS, INTERACTION_FORMS, LOG_FORMS, NONLINEAR_FORMS,
    ROUGHNESS_LEVEL_RTOL, AmplitudeModel, amplitude_design_matrix, coefficient_units, linear_velocity_power_law_names,
    linear_velocity_power_law_predictor, roughness_level_index,
)

__all__ = ["FormFit", "fit_amplitude_forms", "choose_form", "not_compared_reason", "constant_law_warning",
           "CONSTANT_SPREAD_WARN", "CV_ERROR_WARN", "akaike_weights", "distinct_levels", "SELECTION_RULE",
           "candidate_forms", "cross_validation_error", "condition_groups", "influential_runs", "COOKS_RULE"]

SELECTION_RULE = (
    "minimum AICc on the amplitude scale (fits on ln A: log-likelihood plus the Jacobian -sum ln A); "
    "among forms within dAICc < 2 of the minimum, the one with the smallest leave-one-condition-out "
    "cross-validation error (RMS of ln(A_pred/A)); cross-validation overrules when that choice predicts the "
    "left-out conditions more than 2x worse than the best-predicting form"
)
COOKS_RULE = "Cook's distance D_i > 4/n (statsmodels OLSInfluence on the whitened fit): influential, kept"


def candidate_forms(*, interaction: bool = False, categorical: bool = False) -> tuple:
    """The candidate amplitude forms: the continuous ones, plus the interaction and categorical forms on request."""
    return CONTINUOUS_FORMS + (INTERACTION_FORMS if interaction else ()) + (CATEGORICAL_FORMS if categorical else ())


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
    cv_error: float = np.nan
    cv_reason: str = ""
    conf_int: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    cooks_distance: np.ndarray = field(default_factory=lambda: np.zeros(0))
    diagnostics: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        """Plain-Python record for the JSON report."""
        out = {"form": self.form, "fitted": self.fitted, "reason": self.reason}
        if self.fitted:
            m = self.model
            out.update({
                "terms": list(m.terms),
                "coefficients": {n: float(c) for n, c in zip(m.names, m.coefficients)},
                "units": {n: coefficient_units(n) for n in m.names},
                "stderr": {n: float(s) for n, s in zip(m.names, m.stderr)},
                "ci95": {n: [float(a), float(b)] for n, (a, b) in zip(m.names, self.conf_int)},
                "roughness_levels": list(m.roughness_levels),
                "n_runs": self.n_runs,
                "n_params": self.n_params,
                "loglik": self.loglik,
                "aic": self.aic,
                "aicc": _finite_or_none(self.aicc),
                "bic": self.bic,
                "cv_error": _finite_or_none(self.cv_error),
                "cv_reason": self.cv_reason,
                "residual_variance": m.residual_variance,
                "cooks_distance": [float(d) for d in self.cooks_distance],
                "diagnostics": self.diagnostics,
            })
        return out


def _finite_or_none(x):
    return float(x) if np.isfinite(x) else None


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
    if n == 0:
        return None, None, "no runs"
    v_levels = distinct_levels(velocity)
    r_levels = distinct_levels(roughness)
    f_levels = distinct_levels(load)
    vary = {"sliding_velocity": v_levels.size > 1, "roughness_ra": r_levels.size > 1, "normal_load": f_levels.size > 1}
    varying = tuple(t for t in ("roughness_ra", "sliding_velocity", "normal_load") if vary[t])
    one_load = f"all runs at one normal load ({f_levels[0]:.4g} N): no load dependence"
    if form == "constant":
        return (), (), ""
    if form in CATEGORICAL_FORMS:
        if not vary["sliding_velocity"]:
            return None, None, f"all runs at one sliding velocity ({v_levels[0]:.4g} m s-1): no velocity dependence"

        idx = roughness_level_index(roughness, r_levels)
        for r, level in enumerate(r_levels):
            vs = distinct_levels(velocity[idx == r])
            if vs.size < 2:
                return None, None, (f"roughness level {level * 1e6:.3g} um has runs at a single velocity; "
                                    "a line in V per roughness needs two velocities at each roughness")
        terms = ("sliding_velocity",) + (("roughness_ra",) if vary["roughness_ra"] else ())
        if form == "linear_velocity_load":
            if not vary["normal_load"]:
                return None, None, one_load
            terms += ("normal_load",)
        return terms, tuple(float(r) for r in r_levels), ""
    if not varying:
        return None, None, "neither roughness, sliding velocity nor normal load varies across the runs"
    if form == "power_law_load":
        if not vary["normal_load"]:
            return None, None, one_load
        return varying, (), ""
    if form == "power_law_interaction" and not (vary["roughness_ra"] and vary["sliding_velocity"]):
        return None, None, "an Ra x V interaction needs runs at several roughnesses and several velocities"
    if form == "linear_velocity_power_law" and not vary["sliding_velocity"]:
        return None, None, (f"all runs at one sliding velocity ({v_levels[0]:.4g} m s-1): (a + b V) is not "
                            "identified (the form is then the power law)")
    return varying, (), ""


def _diagnostics(reg, fitted_scale) -> dict:
    """Residual diagnostics of a (whitened) regression."""
    from scipy import stats
    from statsmodels.stats.diagnostic import het_breuschpagan

    resid = reg.resid_w / np.sqrt(reg.weights)
    y = reg.fitted + resid
    n = resid.size
    ss_tot = float(np.sum(reg.weights * (y - np.average(y, weights=reg.weights)) ** 2))
    out = {
        "r_squared": float(1 - reg.resid_w @ reg.resid_w / ss_tot) if ss_tot > 0 else None,
        "residual_std": float(np.sqrt(reg.scale)),
        "scale": fitted_scale,
        "shapiro_wilk_p": None,
        "breusch_pagan_p": None,
        "max_abs_studentized_residual": None,
    }
    if n >= 3 and np.ptp(resid) > 0:
        out["shapiro_wilk_p"] = float(stats.shapiro(resid).pvalue)
    if reg.df_resid >= 2 and np.ptp(reg.fitted) > 0:
        exog = np.column_stack([np.ones(n), reg.fitted])
        out["breusch_pagan_p"] = float(het_breuschpagan(resid, exog)[1])
    # internally studentized residuals r_i = e_w,i / (s sqrt(1 - h_ii)), h the hat matrix of the whitened design
    xw = reg.jac_w
    h = np.einsum("ij,ij->i", xw @ np.linalg.pinv(xw.T @ xw), xw)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = reg.resid_w / (np.sqrt(reg.scale) * np.sqrt(1.0 - h))
    r = r[np.isfinite(r) & (h < 1 - 1e-9)]
    if r.size:
        out["max_abs_studentized_residual"] = float(np.max(np.abs(r)))
    return out


@dataclass
class _Regression:
    """One least-squares fit on the fit scale y (ln A or A): what the statistics need."""

    params: np.ndarray
    cov: np.ndarray
    llf: float
    scale: float
    df_resid: int
    weights: np.ndarray
    jac_w: np.ndarray  # whitened ∂η/∂β at the optimum (the design for a linear form)
    resid_w: np.ndarray  # whitened residuals sqrt(w) (y - η)
    fitted: np.ndarray
    result: object = None  # the statsmodels result of a linear form


def _gaussian_llf(ssr_w, weights):
    """statsmodels' WLS log-likelihood at the ML variance: −n/2 (1 + ln(2π SSR_w / n)) + ½ Σ ln w."""
    n = weights.size
    with np.errstate(divide="ignore"):  # an exact fit (no residual dof) has ssr 0: +inf, refused by _fit_one
        return float(-n / 2 * (1 + np.log(2 * np.pi * ssr_w / n)) + 0.5 * np.sum(np.log(weights)))


def _regress_linear(X, y, weights):
    import statsmodels.api as sm

    model = sm.WLS(y, X, weights=weights) if weights is not None else sm.OLS(y, X)
    res = model.fit()
    w = np.ones(y.size) if weights is None else np.asarray(weights, float)
    sw = np.sqrt(w)
    return _Regression(np.asarray(res.params, float), np.asarray(res.cov_params(), float), float(res.llf),
                       float(res.scale), int(round(res.df_resid)), w, X * sw[:, None], sw * np.asarray(res.resid, float),
                       np.asarray(res.fittedvalues, float), res)


def _regress_linear_power(terms, v, r, fn, y, weights, start):
    """Nonlinear least squares of ``linear_velocity_power_law`` on ln A (scipy ``least_squares``, weighted).

    ``start``: (a, b, exponents...) from a linear fit; the covariance is ``s² (J_wᵀ J_w)⁻¹`` with
    ``s² = SSR_w/(n − p)`` (Gauss–Newton, as statsmodels does for a linear WLS).
    """
    from scipy.optimize import least_squares

    w = np.ones(y.size) if weights is None else np.asarray(weights, float)
    sw = np.sqrt(w)

    def resid(beta):
        eta, _ = linear_velocity_power_law_predictor(beta, terms, v, r, fn)
        out = sw * (y - eta)
        return np.where(np.isfinite(out), out, 1e6)

    def jac(beta):
        return -sw[:, None] * np.nan_to_num(linear_velocity_power_law_predictor(beta, terms, v, r, fn)[1])

    sol = least_squares(resid, np.asarray(start, float), jac=jac, x_scale="jac", method="lm", xtol=1e-12,
                        ftol=1e-12, gtol=1e-12)
    eta, J = linear_velocity_power_law_predictor(sol.x, terms, v, r, fn)
    if not np.all(np.isfinite(eta)):
        raise FividError("a + b V <= 0 at a fitted run")
    rw = sw * (y - eta)
    n, p = J.shape
    ssr = float(rw @ rw)
    jw = J * sw[:, None]
    scale = ssr / (n - p)
    cov = scale * np.linalg.pinv(jw.T @ jw)
    return _Regression(np.asarray(sol.x, float), cov, _gaussian_llf(ssr, w), scale, n - p, w, jw, rw, eta)


def _linear_power_start(terms, v, r, fn, a, weights):
    """Starting values of ``linear_velocity_power_law``: exponents of a log-log fit, then (a, b) by WLS of
    A / Π x_j^e_j on V."""
    others = tuple(t for t in terms if t != "sliding_velocity")
    if others:
        X, _ = amplitude_design_matrix("power_law", others + ("sliding_velocity",), v, r, fn)
        beta = np.linalg.lstsq(X, np.log(a), rcond=None)[0]
        exps = beta[1:-1]
        factor = np.exp(X[:, 1:-1] @ exps)
    else:
        exps, factor = np.zeros(0), np.ones(a.size)
    sw = np.sqrt(np.ones(a.size) if weights is None else weights) / a  # ln-scale weight -> A-scale weight
    Xl = np.column_stack([np.ones(a.size), v]) * sw[:, None]
    ab = np.linalg.lstsq(Xl, a / factor * sw, rcond=None)[0]
    if not np.all(ab[0] + ab[1] * v > 0):
        ab = np.array([np.mean(a / factor), 0.0])
    return np.r_[ab, exps]


def _regress(form, terms, levels, v, r, fn, a, se, weighting):
    """The regression of ``form`` on the runs; (None, reason) when it cannot be done."""
    log_form = form in LOG_FORMS
    if log_form and np.any(a <= 0):
        return None, "a run has amplitude 0: a law on ln A cannot be fitted"
    y = np.log(a) if log_form else a
    weights = None
    if weighting == "estimator":
        s = se / a if log_form else se
        if not np.all(np.isfinite(s) & (s > 0)):
            return None, "weighting='estimator' needs a finite, positive standard error for every run"
        weights = 1.0 / s**2
    if form in NONLINEAR_FORMS:
        names = linear_velocity_power_law_names(terms)
        if a.size <= len(names):
            return None, (f"{a.size} runs for {len(names)} coefficients: at least {len(names) + 1} are needed "
                          "for a standard error")
        try:
            reg = _regress_linear_power(terms, v, r, fn, y, weights, _linear_power_start(terms, v, r, fn, a, weights))
        except (FividError, np.linalg.LinAlgError, ValueError) as exc:
            return None, f"the nonlinear fit failed: {exc}"
        if np.linalg.matrix_rank(reg.jac_w) < len(names):
            return None, f"the runs do not separate the {len(names)} coefficients ({', '.join(names)})"
        return (reg, names), ""
    X, names = amplitude_design_matrix(form, terms, v, r, fn, levels or (np.nan,))
    p = X.shape[1]
    if a.size <= p:
        return None, f"{a.size} runs for {p} coefficients: at least {p + 1} are needed for a standard error"
    if np.linalg.matrix_rank(X) < p:
        return None, f"the runs do not separate the {p} coefficients ({', '.join(names)}): collinear design"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # exact fits of few runs: divide-by-zero warnings, reported as numbers
        return (_regress_linear(X, y, weights), names), ""


def _fit_one(form, velocity, roughness, load, amplitude, stderr, weighting, confidence) -> FormFit:
    from scipy import stats

    fit = FormFit(form=form, n_runs=amplitude.size)
    terms, levels, reason = _design(form, velocity, roughness, load)
    if terms is None:
        fit.reason = reason
        return fit
    if form not in CATEGORICAL_FORMS:
        levels = ()
    done, reason = _regress(form, terms, levels, velocity, roughness, load, amplitude, stderr, weighting)
    if done is None:
        fit.reason = reason
        return fit
    reg, names = done
    log_form = form in LOG_FORMS
    n, p = amplitude.size, len(names)
    fit.n_params = p
    if n <= p:  # an exact fit: no residual to estimate a likelihood or a standard error from
        fit.reason = f"{n} runs for {p} coefficients: at least {p + 1} are needed for a standard error"
        return fit
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit.diagnostics = _diagnostics(reg, "ln A" if log_form else "A")
    loglik = reg.llf - (float(np.sum(np.log(amplitude))) if log_form else 0.0)
    k = p + 1
    fit.loglik = loglik
    fit.aic = -2 * loglik + 2 * k
    fit.bic = -2 * loglik + k * np.log(n)
    fit.aicc = fit.aic + 2 * k * (k + 1) / (n - k - 1) if n - k - 1 > 0 else np.nan
    bse = np.sqrt(np.maximum(np.diag(reg.cov), 0.0))
    half = stats.t.ppf(0.5 + confidence / 2, reg.df_resid) * bse
    fit.conf_int = np.column_stack([reg.params - half, reg.params + half])
    # variance of a new run about the law, for a run as precise as the average fitted one (module docstring)
    relative = not log_form and weighting == "estimator"
    inv_w = 1.0 / reg.weights / (amplitude**2 if relative else 1.0)
    fit.cooks_distance = _cooks_distance(reg)
    fit.model = AmplitudeModel(
        form=form, coefficients=reg.params, names=tuple(names), stderr=bse, covariance=reg.cov, terms=tuple(terms),
        roughness_levels=tuple(levels), residual_variance=float(reg.scale * np.mean(inv_w)),
        residual_relative=relative, df_resid=float(reg.df_resid),
    )
    fit.fitted = True
    return fit


def _cooks_distance(reg) -> np.ndarray:
    """Cook's distance of each run (statsmodels ``OLSInfluence`` on the whitened, linearised regression).

    For a weighted fit, OLS of ``sqrt(w) y`` on ``sqrt(w) X`` has the same estimates, so its influence
    measures are the weighted fit's; for the nonlinear form the whitened Jacobian at the optimum is the
    design and ``J_w β̂ + r_w`` the response (the Gauss–Newton linearisation: same estimate and residuals).
    """
    import statsmodels.api as sm
    from statsmodels.stats.outliers_influence import OLSInfluence

    z = reg.jac_w @ reg.params + reg.resid_w
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        infl = OLSInfluence(sm.OLS(z, reg.jac_w).fit())
        return np.asarray(infl.cooks_distance[0], float)


def fit_amplitude_forms(velocity, roughness, load, amplitude, stderr=None, *, forms=CONTINUOUS_FORMS,
                        weighting: str = "estimator", confidence: float = 0.95,
                        cross_validate: bool = True) -> list[FormFit]:
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
        Candidate forms (default: :data:`~fivid.friction.amplitude.CONTINUOUS_FORMS`; see
        :func:`candidate_forms` for the interaction and categorical forms).
    weighting : {"estimator", "none"}
        WLS with weights ``1/se^2`` (default), or OLS.
    confidence : float
        Level of the coefficient intervals.
    cross_validate : bool, default True
        Leave-one-condition-out cross-validation error of each form (:func:`cross_validation_error`).

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
    fits = [_fit_one(form, v, r, fn, a, se, weighting, confidence) for form in forms]
    if cross_validate:
        for f in fits:
            if f.fitted:
                f.cv_error, f.cv_reason = cross_validation_error(f.form, v, r, fn, a, se, weighting)
    return fits


def condition_groups(velocity, roughness, load, rtol: float = ROUGHNESS_LEVEL_RTOL) -> np.ndarray:
    """Index of the test condition (V, Ra, Fn equal within relative tolerance ``rtol``) of each run."""
    keys = []
    for x in (velocity, roughness, load):
        x = np.asarray(x, float)
        levels = distinct_levels(x, rtol)
        keys.append(np.argmin(np.abs(x[:, None] - levels[None, :]), axis=1))
    _, idx = np.unique(np.column_stack(keys), axis=0, return_inverse=True)
    return idx.reshape(-1)


def cross_validation_error(form, velocity, roughness, load, amplitude, stderr, weighting="estimator"):
    """Leave-one-condition-out cross-validation error of ``form``: RMS of ln(Â_(−c)/A) over the runs.

    The runs of each test condition are left out together (runs repeated at one condition are not
    independent evidence about the law between conditions), the form is refitted on the others and
    predicts them. The error is on the log scale, so forms fitted on A and on ln A are compared alike
    (0.1 ≈ 10 % typical prediction error). Returns (error, reason); the error is NaN, with the reason,
    when a left-out condition cannot be predicted (the rest does not identify the form, or it predicts
    A <= 0 there).
    """
    v, r, fn, a, se = (np.asarray(x, float) for x in (velocity, roughness, load, amplitude, stderr))
    groups = condition_groups(v, r, fn)
    if groups.max(initial=0) < 1:
        return np.nan, "all runs at one condition: nothing to cross-validate"
    err = np.empty(a.size)
    for g in np.unique(groups):
        out = groups == g
        keep = ~out
        fit = _fit_one(form, v[keep], r[keep], fn[keep], a[keep], se[keep], weighting, 0.95)
        if not fit.fitted:
            return np.nan, f"without the runs at condition {g + 1}: {fit.reason}"
        try:
            pred = fit.model(v[out], r[out], fn[out])
        except FividError as exc:
            return np.nan, f"condition {g + 1} cannot be predicted without its runs: {exc}"
        if np.any(pred <= 0):
            return np.nan, f"without its runs, condition {g + 1} is predicted at A <= 0"
        err[out] = np.log(pred / a[out])
    return float(np.sqrt(np.mean(err**2))), ""


#: cross-validation overrules the information criterion when its choice predicts left-out conditions this many
#: times worse (RMS log error) than the best-predicting form
CV_OVERRULE = 2.0


def _criterion(fits):
    """The fitted forms and the criterion compared: AICc, or AIC where no form has an AICc."""
    ok = [f for f in fits if f.fitted and np.isfinite(f.aic)]
    if any(np.isfinite(f.aicc) for f in ok):
        return [f for f in ok if np.isfinite(f.aicc)], "aicc"
    return ok, "aic"


def choose_form(fits: list[FormFit]) -> tuple[FormFit | None, str]:
    """The form chosen by :data:`SELECTION_RULE` and a sentence saying why (None if none was fitted)."""
    ok, crit = _criterion(fits)
    if not ok:
        return None, "no amplitude form could be fitted"
    name = crit.upper().replace("AICC", "AICc")
    score = {f.form: getattr(f, crit) for f in ok}
    best = min(ok, key=lambda f: score[f.form])
    close = [f for f in ok if score[f.form] - score[best.form] < 2.0]
    chosen = min(close, key=lambda f: (np.nan_to_num(f.cv_error, nan=np.inf), f.n_params, score[f.form]))
    others = ", ".join(f"{f.form} {score[f.form] - score[best.form]:+.2f}"
                       for f in sorted(ok, key=lambda f: score[f.form]) if f is not chosen)
    with_cv = [f for f in ok if np.isfinite(f.cv_error)]
    cv_best = min(with_cv, key=lambda f: (f.cv_error, f.n_params)) if with_cv else None
    if cv_best is not None and not chosen.cv_error <= CV_OVERRULE * cv_best.cv_error:
        # a handful of runs: AICc's small-sample penalty can favour a form that predicts the left-out conditions
        # far worse (the 6-run sample: constant, CV 0.51, vs the power law's 0.045); prediction is the law's job
        why = (f"{cv_best.form} predicts left-out conditions best (cross-validation error {cv_best.cv_error:.3g}); "
               f"the lowest-{name} form {chosen.form} does {chosen.cv_error:.3g}, more than {CV_OVERRULE:g}x worse, "
               f"so cross-validation overrules {name} (few runs: its small-sample penalty dominates)")
        others = ", ".join(f"{f.form} {score[f.form] - score[best.form]:+.2f}"
                           for f in sorted(ok, key=lambda f: score[f.form]) if f is not cv_best)
        return cv_best, why + (f"; d{name}: {others}" if others else "")
    if chosen is best:
        why = f"{chosen.form} has the lowest {name} ({score[chosen.form]:.2f})"
        if len(ok) == 1 and sum(f.fitted for f in fits) > 1:
            why = f"{chosen.form} is the only form with an {name} ({score[chosen.form]:.2f}): the others need more runs"
        if len(close) > 1:
            why += f" and the smallest cross-validation error ({chosen.cv_error:.3g}) of the forms within d{name} < 2"
    else:
        why = (f"{chosen.form} is within d{name} = {score[chosen.form] - score[best.form]:.2f} < 2 of the lowest "
               f"({best.form}) with a smaller cross-validation error ({chosen.cv_error:.3g} vs {best.cv_error:.3g})")
    if others:
        why += f"; d{name} of the others: {others}"
    return chosen, why


#: a constant amplitude law is flagged when the used runs' amplitudes spread more than this (max / min)
CONSTANT_SPREAD_WARN = 2.0
#: ... or when its cross-validation error (RMS of ln(A_pred / A)) exceeds this: ln 1.5, a left-out condition
#: mispredicted by a factor of about 1.5 or more, on average
CV_ERROR_WARN = float(np.log(1.5))


def not_compared_reason(fit: FormFit, fits: list[FormFit]) -> str:
    """Why ``fit`` takes no part in the choice, in runs needed vs given ("" when it does).

    A form not fitted says why (its design, or ``n <= p``); a fitted form without an AICc
    (``n <= k + 1``, k = p + 1) is left out when another form has one (:func:`choose_form` compares like with like).
    """
    if not fit.fitted:
        return fit.reason
    ok, crit = _criterion(fits)
    if fit in ok:
        return ""
    k = fit.n_params + 1
    return f"its AICc needs at least {k + 2} runs for {fit.n_params} coefficients, {fit.n_runs} given"


def constant_law_warning(chosen: FormFit | None, amplitude) -> str:
    """A warning when the chosen amplitude law is the constant although the data say otherwise ("" when not).

    Flagged: the used runs' amplitudes ``amplitude`` spread more than :data:`CONSTANT_SPREAD_WARN` times
    (max / min), or the constant's cross-validation error exceeds :data:`CV_ERROR_WARN`.
    """
    if chosen is None or chosen.form != "constant":
        return ""
    a = np.asarray(amplitude, float)
    a = a[np.isfinite(a) & (a > 0)]
    spread = float(a.max() / a.min()) if a.size else 1.0
    why = []
    if spread > CONSTANT_SPREAD_WARN:
        why.append(f"the runs' amplitudes spread {spread:.2g}x (more than {CONSTANT_SPREAD_WARN:g}x)")
    if np.isfinite(chosen.cv_error) and chosen.cv_error > CV_ERROR_WARN:
        why.append(f"its cross-validation error {chosen.cv_error:.2g} exceeds {CV_ERROR_WARN:.2f} (= ln 1.5: "
                   f"left-out conditions mispredicted by a factor of about {np.exp(chosen.cv_error):.2g})")
    if not why:
        return ""
    return ("a constant amplitude law was chosen although " + " and ".join(why) + ": it holds only because the "
            "other forms could not be compared with these runs (see the table); record runs at more conditions, "
            "or treat the amplitude as condition-dependent with care")


def akaike_weights(fits: list[FormFit]) -> dict:
    """Akaike weights ``exp(-dAICc/2) / sum`` of the fitted forms (AIC where no form has an AICc)."""
    ok, crit = _criterion(fits)
    if not ok:
        return {}
    best = min(getattr(f, crit) for f in ok)
    raw = {f.form: np.exp(-(getattr(f, crit) - best) / 2) for f in ok}
    total = sum(raw.values())
    return {k: float(v / total) for k, v in raw.items()}


def influential_runs(fit: FormFit) -> np.ndarray:
    """True for the runs whose Cook's distance in ``fit`` exceeds 4/n (:data:`COOKS_RULE`)."""
    d = np.asarray(fit.cooks_distance, float)
    return np.isfinite(d) & (d > 4.0 / max(d.size, 1))
