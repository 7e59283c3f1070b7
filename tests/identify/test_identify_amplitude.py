"""Amplitude-law fitting: statsmodels results, the A-scale AIC(c) of laws on ln A, the selection rule,
cross-validation, Cook's distance, diagnostics."""

import numpy as np
import pytest
import statsmodels.api as sm
from statsmodels.stats.outliers_influence import OLSInfluence

from fivid.errors import FividError
from fivid.friction.amplitude import CATEGORICAL_FORMS
from fivid.identify import choose_form, fit_amplitude_forms
from fivid.identify.amplitude_fit import akaike_weights, candidate_forms, condition_groups, cross_validation_error

V = np.array([0.002, 0.005, 0.01, 0.02] * 2)
RA = np.array([0.4e-6] * 4 + [1.6e-6] * 4)
FN = np.array([2.0, 5.0, 8.0, 3.0, 6.0, 2.0, 5.0, 8.0])


def _amplitudes(seed, form="power"):
    rng = np.random.default_rng(seed)
    if form == "power":
        a = 0.002 * (RA / 1e-6) ** 0.5 * (V / 1e-3) ** 0.6
    else:
        a = np.where(RA < 1e-6, 0.002 + 0.25 * V, 0.003 + 0.5 * V)
    return a * np.exp(0.02 * rng.standard_normal(a.size))


def test_power_law_matches_statsmodels_log_log_ols():
    """The runs differ in load, so the load enters the power law (seed 001)."""
    a = _amplitudes(1)
    fits = {f.form: f for f in fit_amplitude_forms(V, RA, FN, a, weighting="none")}
    pl = fits["power_law"]
    assert pl.model.names == ("log_prefactor", "roughness_exponent", "velocity_exponent", "load_exponent")
    X = sm.add_constant(np.column_stack([np.log(RA / 1e-6), np.log(V / 1e-3), np.log(FN)]))
    ref = sm.OLS(np.log(a), X).fit()
    np.testing.assert_allclose(pl.model.coefficients, ref.params, rtol=1e-12)
    np.testing.assert_allclose(pl.model.stderr, ref.bse, rtol=1e-10)
    np.testing.assert_allclose(pl.conf_int, ref.conf_int(), rtol=1e-10)
    # AIC on the A scale: ll_A = ll_lnA - Σ ln A (Jacobian of A = exp(lnA)), k = p + 1
    ll_a = ref.llf - np.sum(np.log(a))
    k, n = 5, a.size
    assert pl.aic == pytest.approx(-2 * ll_a + 2 * k, rel=1e-12)
    assert pl.aicc == pytest.approx(-2 * ll_a + 2 * k + 2 * k * (k + 1) / (n - k - 1), rel=1e-12)
    assert pl.bic == pytest.approx(-2 * ll_a + k * np.log(n), rel=1e-12)
    # studentized residuals and Cook's distance against statsmodels' OLSInfluence
    infl = OLSInfluence(ref)
    assert pl.diagnostics["max_abs_studentized_residual"] == pytest.approx(
        np.max(np.abs(infl.resid_studentized_internal)), rel=1e-10)
    np.testing.assert_allclose(pl.cooks_distance, infl.cooks_distance[0], rtol=1e-9)
    assert pl.model.residual_variance == pytest.approx(ref.scale, rel=1e-12)


def test_linear_velocity_power_law_is_the_weighted_least_squares_optimum():
    """(a + bV) Ra^n Fn^k on ln A: the normal equations hold, the covariance is s² (JᵀWJ)⁻¹, and the
    log-likelihood is statsmodels' WLS one at the optimum (checked through the linearised WLS)."""
    rng = np.random.default_rng(4)
    a = (0.001 + 0.3 * V) * (RA / 1e-6) ** 0.8 * FN**0.1 * np.exp(0.02 * rng.standard_normal(V.size))
    se = 0.02 * a * (1 + 0.5 * rng.random(V.size))
    fit = next(f for f in fit_amplitude_forms(V, RA, FN, a, se) if f.form == "linear_velocity_power_law")
    m = fit.model
    assert m.names == ("intercept", "velocity_slope", "roughness_exponent", "load_exponent")
    eta, J = m.predictor_and_gradient(V, RA, FN)
    w = (a / se) ** 2
    r = np.log(a) - eta
    assert np.all(np.abs(J.T @ (w * r)) <= 1e-6 * (np.abs(J).T @ (w * np.abs(r))))  # normal equations
    lin = sm.WLS(r + J @ m.coefficients, J, weights=w).fit()  # the Gauss-Newton linearisation at the optimum
    np.testing.assert_allclose(lin.params, m.coefficients, rtol=1e-6)
    np.testing.assert_allclose(m.covariance, lin.cov_params(), rtol=1e-6)
    assert fit.loglik == pytest.approx(lin.llf - np.sum(np.log(a)), rel=1e-9)
    # the truth inside two-sided 99.9 % Student-t bounds on the fit's residual degrees of freedom
    from scipy import stats

    assert np.all(np.abs(m.coefficients - [0.001, 0.3, 0.8, 0.1]) < stats.t.ppf(0.9995, m.df_resid) * m.stderr)


def test_jacobian_makes_aic_comparable_across_scales():
    """A lognormal-noise power law is preferred to the others; a line per roughness with additive noise,
    when the categorical forms are asked for, to a power law."""
    fn = np.full(V.size, 5.0)
    for seed in range(5):
        chosen, why = choose_form(fit_amplitude_forms(V, RA, fn, _amplitudes(seed, "power"), weighting="none"))
        assert chosen.form == "power_law", why
    rng = np.random.default_rng(0)
    lin = np.where(RA < 1e-6, 0.002 + 0.25 * V, 0.003 + 0.5 * V) + 2e-5 * rng.standard_normal(V.size)
    chosen, why = choose_form(fit_amplitude_forms(V, RA, fn, lin, weighting="none",
                                                  forms=candidate_forms(categorical=True)))
    assert chosen.form == "linear_velocity", why


def test_categorical_forms_only_on_request():
    a = _amplitudes(1)
    assert not {f.form for f in fit_amplitude_forms(V, RA, FN, a, 0.02 * a)} & set(CATEGORICAL_FORMS)
    assert set(CATEGORICAL_FORMS) <= set(candidate_forms(categorical=True))
    assert "power_law_interaction" in candidate_forms(interaction=True)


def test_selection_by_aicc_then_cross_validation():
    a = np.full(8, 0.003) * np.exp(0.02 * np.random.default_rng(3).standard_normal(8))
    fits = fit_amplitude_forms(V, RA, FN, a, weighting="none")
    chosen, why = choose_form(fits)
    ok = [f for f in fits if f.fitted]
    best = min(ok, key=lambda f: f.aicc)
    close = [f for f in ok if f.aicc - best.aicc < 2]
    assert chosen.aicc - best.aicc < 2
    assert chosen.cv_error == min(f.cv_error for f in close)
    assert chosen.form in why
    w = akaike_weights(fits)
    assert sum(w.values()) == pytest.approx(1.0, rel=1e-12)
    # weights are exp(-dAICc/2) normalised: their ratios give the AICc differences back
    f0, f1 = ok[:2]
    assert np.log(w[f0.form] / w[f1.form]) == pytest.approx(-(f0.aicc - f1.aicc) / 2, rel=1e-9)


def test_cross_validation_error_is_leave_one_condition_out():
    """Two runs per condition are left out together; the error is the RMS of ln(A_pred / A)."""
    v, ra, fn = np.repeat(V, 2), np.repeat(RA, 2), np.full(16, 5.0)
    a = 0.002 * (ra / 1e-6) ** 0.5 * (v / 1e-3) ** 0.6 * np.exp(0.03 * np.random.default_rng(5).standard_normal(16))
    err, reason = cross_validation_error("power_law", v, ra, fn, a, 0.03 * a, "none")
    groups = condition_groups(v, ra, fn)
    assert np.bincount(groups).tolist() == [2] * 8 and reason == ""
    X = sm.add_constant(np.column_stack([np.log(ra / 1e-6), np.log(v / 1e-3)]))
    manual = []
    for g in range(8):
        out = groups == g
        ref = sm.OLS(np.log(a[~out]), X[~out]).fit()
        manual.extend(X[out] @ ref.params - np.log(a[out]))
    assert err == pytest.approx(np.sqrt(np.mean(np.square(manual))), rel=1e-10)
    # a categorical line cannot predict a run whose roughness level keeps one velocity without it
    two = np.array([0.005, 0.01, 0.005, 0.01])
    err, reason = cross_validation_error("linear_velocity", two, np.repeat([0.4e-6, 1.6e-6], 2), np.full(4, 5.0),
                                         np.array([1.0, 2.0, 1.5, 2.5]) * 1e-3, np.full(4, 1e-5), "none")
    assert np.isnan(err) and "single velocity" in reason


def test_wls_uses_the_estimator_errors():
    a = _amplitudes(2, "linear")
    se = 0.01 * a
    fit = next(f for f in fit_amplitude_forms(V, RA, FN, a, se, forms=("linear_velocity",)) if f.form == "linear_velocity")
    X = np.zeros((8, 4))
    X[:4, 0], X[:4, 1], X[4:, 2], X[4:, 3] = 1, V[:4], 1, V[4:]
    ref = sm.WLS(a, X, weights=1 / se**2).fit()
    np.testing.assert_allclose(fit.model.coefficients, ref.params, rtol=1e-10)
    np.testing.assert_allclose(fit.model.stderr, ref.bse, rtol=1e-8)


def test_unidentifiable_forms_say_why():
    a = _amplitudes(1)
    fits = {f.form: f for f in fit_amplitude_forms(V[:2], RA[:2], FN[:2], a[:2], weighting="none")}
    assert "runs for" in fits["power_law"].reason
    fits = {f.form: f for f in fit_amplitude_forms(V, RA, np.full(8, 5.0), a, 0.01 * a,
                                                   forms=("power_law", "power_law_load"))}
    assert "one normal load" in fits["power_law_load"].reason
    assert fits["power_law"].model.terms == ("roughness_ra", "sliding_velocity")
    with pytest.raises(FividError, match="needs the per-run standard errors"):
        fit_amplitude_forms(V, RA, FN, a)
    with pytest.raises(FividError, match="unknown amplitude form"):
        fit_amplitude_forms(V, RA, FN, a, forms=("cubic",))
