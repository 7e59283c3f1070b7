"""Amplitude-law fitting: statsmodels results, the A-scale AIC of power laws, the selection rule, diagnostics."""

import numpy as np
import pytest
import statsmodels.api as sm
from statsmodels.stats.outliers_influence import OLSInfluence

from fivid.errors import FividError
from fivid.identify import choose_form, fit_amplitude_forms
from fivid.identify.amplitude_fit import akaike_weights

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
    a = _amplitudes(1)
    fits = {f.form: f for f in fit_amplitude_forms(V, RA, FN, a, weighting="none")}
    pl = fits["power_law"]
    X = sm.add_constant(np.column_stack([np.log(RA / 1e-6), np.log(V / 1e-3)]))
    ref = sm.OLS(np.log(a), X).fit()
    np.testing.assert_allclose(pl.model.coefficients, ref.params, rtol=1e-12)
    np.testing.assert_allclose(pl.model.stderr, ref.bse, rtol=1e-10)
    # AIC on the A scale: ll_A = ll_lnA - Σ ln A (Jacobian of A = exp(lnA)), k = p + 1
    ll_a = ref.llf - np.sum(np.log(a))
    assert pl.aic == pytest.approx(-2 * ll_a + 2 * 4, rel=1e-12)
    assert pl.bic == pytest.approx(-2 * ll_a + 4 * np.log(a.size), rel=1e-12)
    # studentized residuals against statsmodels' OLSInfluence
    r = OLSInfluence(ref).resid_studentized_internal
    assert pl.diagnostics["max_abs_studentized_residual"] == pytest.approx(np.max(np.abs(r)), rel=1e-10)


def test_jacobian_makes_aic_comparable_across_scales():
    """A lognormal-noise power law is preferred to a line; a line with additive noise to a power law."""
    for seed in range(5):
        chosen, why = choose_form(fit_amplitude_forms(V, RA, FN, _amplitudes(seed, "power"), weighting="none"))
        assert chosen.form == "power_law", why
    rng = np.random.default_rng(0)
    lin = np.where(RA < 1e-6, 0.002 + 0.25 * V, 0.003 + 0.5 * V) + 2e-5 * rng.standard_normal(V.size)
    chosen, why = choose_form(fit_amplitude_forms(V, RA, FN, lin, weighting="none"))
    assert chosen.form == "linear_velocity", why


def test_parsimony_within_two_aic_units():
    a = np.full(8, 0.003) * np.exp(0.02 * np.random.default_rng(3).standard_normal(8))
    fits = fit_amplitude_forms(V, RA, FN, a, weighting="none")
    chosen, why = choose_form(fits)
    best = min((f for f in fits if f.fitted), key=lambda f: f.aic)
    assert chosen.aic - best.aic < 2
    assert chosen.n_params == min(f.n_params for f in fits if f.fitted and f.aic - best.aic < 2)
    assert chosen.form in why
    w = akaike_weights(fits)
    assert sum(w.values()) == pytest.approx(1.0, rel=1e-12)
    # weights are exp(-dAIC/2) normalised: their ratios give the AIC differences back
    f0, f1 = [f for f in fits if f.fitted][:2]
    assert np.log(w[f0.form] / w[f1.form]) == pytest.approx(-(f0.aic - f1.aic) / 2, rel=1e-9)


def test_wls_uses_the_estimator_errors():
    a = _amplitudes(2, "linear")
    se = 0.01 * a
    fit = next(f for f in fit_amplitude_forms(V, RA, FN, a, se) if f.form == "linear_velocity")
    X = np.zeros((8, 4))
    X[:4, 0], X[:4, 1], X[4:, 2], X[4:, 3] = 1, V[:4], 1, V[4:]
    ref = sm.WLS(a, X, weights=1 / se**2).fit()
    np.testing.assert_allclose(fit.model.coefficients, ref.params, rtol=1e-10)
    np.testing.assert_allclose(fit.model.stderr, ref.bse, rtol=1e-8)


def test_unidentifiable_forms_say_why():
    a = _amplitudes(1)
    fits = {f.form: f for f in fit_amplitude_forms(V[:2], RA[:2], FN[:2], a[:2], weighting="none")}
    assert "runs for" in fits["power_law"].reason
    fits = {f.form: f for f in fit_amplitude_forms(V, RA, np.full(8, 5.0), a, 0.01 * a)}
    assert "one normal load" in fits["power_law_load"].reason
    with pytest.raises(FividError, match="needs the per-run standard errors"):
        fit_amplitude_forms(V, RA, FN, a)
    with pytest.raises(FividError, match="unknown amplitude form"):
        fit_amplitude_forms(V, RA, FN, a, forms=("cubic",))
