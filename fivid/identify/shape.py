"""The normalised spectral shape s(f) of the friction perturbation, from the per-run PSDs.

Each used run's PSD in the band is divided by its band mean square A_i^2 (so that it integrates to 1),
mapped to a common frequency grid (for convected injection, to the reference velocity: a frozen
spatial field gives ``s(g) = (V_i/V_ref) S_i(g V_i/V_ref) / A_i^2``), and averaged. Two shapes come
out of the average:

- smoothed: a fractional-octave moving average (constant relative bandwidth, i.e. smoothing in
  log-frequency), renormalised to unit integral;
- roll-off: the parametric fit ``s(f) = c / (1 + (f/f_c)^(2p))`` by nonlinear least squares on
  ln s (:func:`scipy.optimize.curve_fit`), with standard errors of ``f_c`` [Hz] and ``p`` [-].

Does the shape depend on the condition? (:func:`shape_dependence`)
    Two summaries of each run's normalised spectrum s_i(f) in the band: its centroid in log frequency
    ``c_i = ∫ ln f s_i df`` and its spread ``w_i = sqrt(∫ (ln f − c_i)² s_i df)``. Each is regressed by
    OLS (statsmodels) on ln V, ln Ra, ln Fn (those that vary across the runs); the regression F-test
    asks whether any slope differs from 0. The two p-values are combined by Bonferroni
    (``p = min(1, 2 min(p_c, p_w))``). With ``p < 0.01`` the shape is taken as depending on the
    condition: the smoothed shape of each test condition (the mean of its runs' normalised spectra) is
    stored, and the law interpolates between them (linearly in log coordinates,
    :meth:`fivid.friction.domain.ConditionDomain.interpolate`); otherwise one shape for all.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from fivid.errors import FividError
from fivid.identify.amplitude_fit import condition_groups, distinct_levels

__all__ = ["SpectralShape", "identify_shape", "average_normalised_spectra", "normalised_spectra", "shape_dependence",
           "SHAPE_TEST_ALPHA", "octave_smooth", "octave_median", "fit_rolloff", "rolloff_shape"]


@dataclass
class SpectralShape:
    """The identified shape: grid [Hz], averaged, smoothed and roll-off shapes [Hz-1], roll-off parameters."""

    frequency: np.ndarray
    average: np.ndarray
    smoothed: np.ndarray
    rolloff: np.ndarray | None
    rolloff_params: dict
    smoothing_octaves: float
    n_runs: int


def _normalise(f, s):
    area = np.trapezoid(s, f)
    if not area > 0:
        raise FividError("the averaged spectral shape integrates to 0 in the band (all runs flat zero?)")
    return s / area


def normalised_spectra(runs, band, *, injection="uniform", reference_velocity=None):
    """Frequency grid [Hz] inside ``band`` and each run's normalised PSD on it [Hz-1], shape (runs, grid).

    Parameters
    ----------
    runs : sequence of RunAnalysis
        Used runs (with ``frequency``, ``psd``, ``mu_rms`` and ``sliding_velocity``).
    band : (float, float)
    injection : str
        ``"convected"`` maps each spectrum to ``reference_velocity`` (NaN where a run's spectrum does
        not reach).
    reference_velocity : float, optional
        [m s-1].
    """
    grid_run = max(runs, key=lambda r: r.frequency[1] - r.frequency[0])  # coarsest resolution
    fg = grid_run.frequency
    fg = fg[(fg >= band[0] - 1e-9) & (fg <= band[1] + 1e-9)]
    stack = []
    for r in runs:
        norm = r.psd / r.mu_rms**2
        if injection == "convected":
            ratio = r.sliding_velocity / reference_velocity
            stack.append(ratio * np.interp(fg * ratio, r.frequency, norm, left=np.nan, right=np.nan))
        else:
            stack.append(np.interp(fg, r.frequency, norm))
    return fg, np.array(stack)


def average_normalised_spectra(runs, band, *, injection="uniform", reference_velocity=None):
    """Frequency grid [Hz] inside ``band`` and the mean of the runs' normalised PSDs on it [Hz-1]
    (:func:`normalised_spectra`; grid points no run reaches are dropped)."""
    fg, stack = normalised_spectra(runs, band, injection=injection, reference_velocity=reference_velocity)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns of a convected map
        mean = np.nanmean(stack, axis=0)
    keep = np.isfinite(mean)
    return fg[keep], mean[keep]


SHAPE_TEST_ALPHA = 0.01


def shape_dependence(runs, band, *, injection="uniform", reference_velocity=None, smoothing_octaves=1.0 / 6.0,
                          frequency=None, alpha: float = SHAPE_TEST_ALPHA):
    """Whether the normalised spectrum's shape depends on V, Ra or Fn (see the module docstring).

    Returns
    -------
    result : dict
        ``depends`` (bool or None when not testable), ``p_value``, ``p_centroid``, ``p_spread``,
        ``variables``, ``statistic``, ``alpha`` and ``reason``.
    condition_shapes : (ndarray (m, 3), ndarray (m, len(frequency))) or None
        Conditions (V, Ra, Fn) and their smoothed, normalised shapes on ``frequency`` [Hz] (default: the
        common grid), when the shape depends on the condition.
    """
    import statsmodels.api as sm

    out = {"statistic": "log-frequency centroid and spread of the normalised spectrum ~ ln of the varying "
                        "conditions (OLS F-tests, Bonferroni x2)", "alpha": alpha, "depends": None,
           "p_value": None, "p_centroid": None, "p_spread": None, "variables": [], "reason": ""}
    fg, stack = normalised_spectra(runs, band, injection=injection, reference_velocity=reference_velocity)
    cols = np.all(np.isfinite(stack), axis=0) & (fg > 0)
    f, s = fg[cols], stack[:, cols]
    conds = np.array([[r.sliding_velocity, r.roughness_ra, r.normal_load] for r in runs])
    names = ("sliding_velocity", "roughness_ra", "normal_load")
    vary = [j for j in range(3) if np.all(conds[:, j] > 0) and distinct_levels(conds[:, j]).size > 1]
    out["variables"] = [names[j] for j in vary]
    if not vary:
        out["reason"] = "not tested: no condition variable varies across the runs"
        return out, None
    if len(runs) < len(vary) + 3 or f.size < 3:
        out["reason"] = f"not tested: {len(runs)} runs for {len(vary)} condition variables (need {len(vary) + 3})"
        return out, None
    area = np.trapezoid(s, f, axis=1)
    lf = np.log(f)
    centroid = np.trapezoid(s * lf, f, axis=1) / area
    spread = np.sqrt(np.trapezoid(s * (lf[None, :] - centroid[:, None]) ** 2, f, axis=1) / area)
    X = sm.add_constant(np.log(conds[:, vary]))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        p = [float(sm.OLS(y, X).fit().f_pvalue) for y in (centroid, spread)]
    p = [1.0 if not np.isfinite(x) else x for x in p]  # an exact fit (no residual) tests nothing
    out["p_centroid"], out["p_spread"] = p
    out["p_value"] = min(1.0, 2 * min(p))
    out["depends"] = bool(out["p_value"] < alpha)
    if not out["depends"]:
        return out, None
    grid = fg if frequency is None else np.asarray(frequency, float)
    groups = condition_groups(conds[:, 0], conds[:, 1], conds[:, 2])
    points, shapes = [], []
    for g in np.unique(groups):
        member = groups == g
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            mean = np.nanmean(stack[member], axis=0)
        ok = np.isfinite(mean)
        sm_g = octave_smooth(fg[ok], mean[ok], smoothing_octaves)
        shape = np.maximum(np.interp(grid, fg[ok], sm_g), 0.0)
        shapes.append(_normalise(grid, shape))
        points.append(conds[member].mean(axis=0))
    return out, (np.array(points), np.array(shapes))


def octave_smooth(frequency, values, octaves: float = 1.0 / 6.0) -> np.ndarray:
    """Moving average over ``[f 2^(-b/2), f 2^(b/2)]`` around each frequency (constant relative bandwidth).

    Parameters
    ----------
    frequency : ndarray [Hz], increasing, > 0
    values : ndarray
    octaves : float
        Width b of the averaging window [octaves]; 0 returns ``values``.
    """
    f = np.asarray(frequency, float)
    v = np.asarray(values, float)
    if octaves <= 0:
        return v.copy()
    c = np.concatenate(([0.0], np.cumsum(v)))
    lo = np.searchsorted(f, f * 2.0 ** (-octaves / 2), side="left")
    hi = np.searchsorted(f, f * 2.0 ** (octaves / 2), side="right")
    return (c[hi] - c[lo]) / (hi - lo)


def octave_median(frequency, values, octaves: float = 1.0 / 3.0, *, per_octave: int = 12) -> np.ndarray:
    """Running median over ``[f 2^(-b/2), f 2^(b/2)]`` (robust to spectral lines), at every frequency.

    The median is evaluated at ``per_octave`` log-spaced centres per octave and interpolated in
    log-frequency to ``frequency`` (enough for a floor that is smooth on the scale of b octaves).
    ``frequency`` must be > 0. The median of a χ²_ν/ν-distributed estimate is biased by
    ``chi2.ppf(0.5, ν)/ν``; callers correct for it.
    """
    f = np.asarray(frequency, float)
    v = np.asarray(values, float)
    n_centres = max(2, int(np.ceil(np.log2(f[-1] / f[0]) * per_octave)) + 1)
    centres = np.geomspace(f[0], f[-1], n_centres)
    lo = np.searchsorted(f, centres * 2.0 ** (-octaves / 2), side="left")
    hi = np.searchsorted(f, centres * 2.0 ** (octaves / 2), side="right")
    med = np.array([np.median(v[a:max(b, a + 1)]) for a, b in zip(lo, hi)])
    return np.interp(np.log(f), np.log(centres), med)


def rolloff_shape(frequency, corner_frequency, order):
    """Un-normalised roll-off ``1 / (1 + (f/f_c)^(2p))`` [-]."""
    return 1.0 / (1.0 + (np.asarray(frequency, float) / corner_frequency) ** (2 * order))


def fit_rolloff(frequency, shape):
    """Fit ``ln s = ln c − ln(1 + (f/f_c)^(2p))``; returns (normalised fitted shape, parameter dict).

    The parameter dict has ``corner_frequency`` [Hz], ``order`` [-], their standard errors and the RMS
    log residual; ``{}`` with ``reason`` when the fit fails.
    """
    from scipy.optimize import curve_fit

    f = np.asarray(frequency, float)
    y = np.log(np.maximum(shape, np.finfo(float).tiny))

    def model(x, lnc, lnfc, order):
        return lnc - np.log1p((x / np.exp(lnfc)) ** (2 * order))

    p0 = (y[:3].mean(), np.log(np.sqrt(f[0] * f[-1])), 1.0)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            popt, pcov = curve_fit(model, f, y, p0=p0, bounds=([-np.inf, np.log(f[0] / 10), 0.1],
                                                               [np.inf, np.log(f[-1] * 10), 10.0]))
    except (RuntimeError, ValueError) as exc:
        return None, {"reason": f"roll-off fit failed: {exc}"}
    resid = y - model(f, *popt)
    fc = float(np.exp(popt[1]))
    se = np.sqrt(np.diag(pcov))
    params = {
        "corner_frequency": fc,
        "corner_frequency_stderr": float(fc * se[1]),
        "order": float(popt[2]),
        "order_stderr": float(se[2]),
        "rms_log_residual": float(np.sqrt(np.mean(resid**2))),
    }
    return _normalise(f, rolloff_shape(f, fc, popt[2])), params


def identify_shape(runs, band, *, smoothing_octaves=1.0 / 6.0, injection="uniform", reference_velocity=None):
    """The :class:`SpectralShape` of the used runs (see the module docstring)."""
    f, avg = average_normalised_spectra(runs, band, injection=injection, reference_velocity=reference_velocity)
    if f.size < 3:
        raise FividError(f"the band {band[0]:g}-{band[1]:g} Hz holds {f.size} common frequency bins; widen it")
    avg = _normalise(f, avg)
    smoothed = _normalise(f, octave_smooth(f, avg, smoothing_octaves))
    rolloff, params = fit_rolloff(f, avg)
    return SpectralShape(f, avg, smoothed, rolloff, params, smoothing_octaves, len(runs))
