"""Amplitude models A(V, Ra, Fn): the RMS of the friction perturbation μp over the valid band.

Every form gives a predictor η(V, Ra, Fn; β): ``A = η`` (the categorical linear forms) or
``A = exp(η)`` (all other forms, fitted on ln A, so that their intervals are multiplicative). Most forms
are linear in β (η = X β, the design matrix built here in one place); ``linear_velocity_power_law`` is
not, and :meth:`AmplitudeModel.gradient` gives ∂η/∂β for its delta-method intervals.

Forms continuous in every condition variable (the candidates by default, DESIGN §3, seeds 000, 001, 003);
each uses a factor only when it varied in the data it was fitted on (``terms``), and the normal load
whenever the runs differ in load (seed 001):

``constant``
    ``A = a`` (one coefficient ``amplitude``).
``power_law``
    ``ln A = c + n ln(Ra/Ra_ref) + m ln(V/V_ref) [+ k ln(Fn/Fn_ref)]`` (seed 003); coefficients
    ``log_prefactor``, ``roughness_exponent``, ``velocity_exponent``, ``load_exponent``.
``linear_velocity_power_law``
    ``A = (a + b V) (Ra/Ra_ref)^n [(Fn/Fn_ref)^k]`` (seed 000: A linear in V; the roughness as a
    factor); coefficients ``intercept`` [-], ``velocity_slope`` [s m-1], ``roughness_exponent``,
    ``load_exponent``. Nonlinear in β.
``log_linear``
    ``ln A = c + r_V V + r_Ra Ra [+ r_Fn Fn]`` (exponential in the variables themselves, the contrast to
    the power law); coefficients ``log_prefactor``, ``velocity_rate`` [s mm-1], ``roughness_rate``
    [um-1], ``load_rate`` [N-1].
``power_law_interaction``
    ``power_law`` plus ``q ln(Ra/Ra_ref) ln(V/V_ref)`` (the velocity exponent changes with Ra);
    coefficient ``roughness_velocity_exponent``. A candidate only on request.

Categorical forms, candidates only on request (they refuse an Ra between the identified levels):

``linear_velocity``
    ``A = a_r + b_r V`` for each roughness level ``r``; coefficients ``intercept[r]`` [-] and
    ``velocity_slope[r]`` [s m-1].
``linear_velocity_load``
    as ``linear_velocity`` plus ``load_slope * Fn`` [N-1] shared by all roughness levels.

``power_law_load`` (``power_law`` with a load factor always present) is the name law files of
version 1 use; it evaluates as before.

Reference scales ``Ra_ref = 1 µm``, ``V_ref = 1 mm/s``, ``Fn_ref = 1 N`` keep the coefficients of order
one. Linear forms evaluated outside the data can go negative; the amplitude is clipped at 0.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fivid.errors import FividError

__all__ = [
    "AmplitudeModel",
    "AMPLITUDE_FORMS",
    "CONTINUOUS_FORMS",
    "INTERACTION_FORMS",
    "CATEGORICAL_FORMS",
    "LOG_FORMS",
    "NONLINEAR_FORMS",
    "coefficient_units",
    "REFERENCE_SCALES",
    "amplitude_design_matrix",
    "roughness_level_index",
]

#: forms continuous in every condition variable: the default candidates
CONTINUOUS_FORMS = ("constant", "power_law", "linear_velocity_power_law", "log_linear")
#: a candidate only on request (``interaction=True``)
INTERACTION_FORMS = ("power_law_interaction",)
#: one line per roughness level; candidates only on request (``categorical=True``)
CATEGORICAL_FORMS = ("linear_velocity", "linear_velocity_load")
AMPLITUDE_FORMS = CONTINUOUS_FORMS + INTERACTION_FORMS + CATEGORICAL_FORMS + ("power_law_load",)
#: forms fitted on ln A (A = exp(η))
LOG_FORMS = ("power_law", "power_law_load", "power_law_interaction", "log_linear", "linear_velocity_power_law")
#: forms not linear in their coefficients
NONLINEAR_FORMS = ("linear_velocity_power_law",)
#: reference scales of the power-law factors [m], [m s-1], [N]
REFERENCE_SCALES = {"roughness_ra": 1e-6, "sliding_velocity": 1e-3, "normal_load": 1.0}
#: relative tolerance within which two roughness values are the same level
ROUGHNESS_LEVEL_RTOL = 0.01


def roughness_level_index(roughness, levels) -> np.ndarray:
    """Index of the roughness level [m] each value [m] belongs to (relative tolerance 1 %).

    Raises :class:`~fivid.errors.FividError` naming the known levels for a value that matches none.
    """
    roughness = np.atleast_1d(np.asarray(roughness, dtype=float))
    levels = np.asarray(levels, dtype=float)
    if not np.all(np.isfinite(roughness)):
        raise FividError("this amplitude law depends on the roughness (one line per roughness level): pass "
                         "roughness_ra [m]")
    rel = np.abs(roughness[:, None] - levels[None, :]) / levels[None, :]
    idx = np.argmin(rel, axis=1)
    bad = rel[np.arange(roughness.size), idx] > ROUGHNESS_LEVEL_RTOL
    if np.any(bad):
        known = ", ".join(f"{r * 1e6:g} um" for r in levels)
        raise FividError(
            f"roughness Ra = {roughness[bad][0] * 1e6:g} um is not one of the roughness levels this "
            f"linear amplitude law was identified at ({known}); use a power-law form to interpolate in Ra"
        )
    return idx


#: units of each coefficient (CF/UDUNITS); ``[r]`` suffixes are stripped before the lookup
_COEFFICIENT_UNITS = {
    "amplitude": "1", "intercept": "1", "velocity_slope": "s m-1", "load_slope": "N-1", "log_prefactor": "1",
    "roughness_exponent": "1", "velocity_exponent": "1", "load_exponent": "1", "roughness_velocity_exponent": "1",
    "velocity_rate": "s mm-1", "roughness_rate": "um-1", "load_rate": "N-1",
}
#: the same scales in the units the log-linear rates are per (V in mm/s, Ra in um, Fn in N)
_RATE_SCALES = {"sliding_velocity": 1e-3, "roughness_ra": 1e-6, "normal_load": 1.0}
_FACTORS = (("roughness_ra", "roughness"), ("sliding_velocity", "velocity"), ("normal_load", "load"))


def coefficient_units(name: str) -> str:
    """CF units string of an amplitude-law coefficient (``"1"`` for a name not known)."""
    return _COEFFICIENT_UNITS.get(name.split("[")[0], "1")


def _conditions(velocity, roughness, normal_load):
    return np.broadcast_arrays(
        np.atleast_1d(np.asarray(np.nan if velocity is None else velocity, dtype=float)),
        np.atleast_1d(np.asarray(np.nan if roughness is None else roughness, dtype=float)),
        np.atleast_1d(np.asarray(np.nan if normal_load is None else normal_load, dtype=float)),
    )


def _positive(values, term, form):
    if np.any(~(values > 0)):
        bad = values[~(values > 0)][0]
        raise FividError(f"amplitude form {form!r} depends on {term}: pass {term} > 0 (got "
                         f"{'none' if np.isnan(bad) else repr(float(bad))})")
    return values


def _log_factor_columns(form, terms, values):
    """ln(x/x_ref) of the factors in ``terms`` (Ra, V, Fn order), with their exponent names."""
    cols, names = [], []
    for term, short in _FACTORS:
        if term in terms or (term == "normal_load" and form == "power_law_load"):
            if term == "normal_load":
                _need_load(values[term], form)
            cols.append(np.log(_positive(values[term], term, form) / REFERENCE_SCALES[term]))
            names.append(f"{short}_exponent")
    return cols, names


def amplitude_design_matrix(form, terms, velocity, roughness, normal_load, roughness_levels=()):
    """The design matrix and coefficient names of an amplitude form that is linear in its coefficients.

    Parameters
    ----------
    form : str
        One of :data:`AMPLITUDE_FORMS` except :data:`NONLINEAR_FORMS`.
    terms : sequence of str
        Factors the form uses among ``"sliding_velocity"``, ``"roughness_ra"``, ``"normal_load"``.
    velocity, roughness, normal_load : array_like
        Sliding velocity [m s-1], roughness Ra [m], normal load [N] (broadcast to one length).
    roughness_levels : sequence of float
        Roughness levels [m] of the categorical linear forms (one intercept and slope each).

    Returns
    -------
    X : ndarray, shape (n, p)
    names : list of str
    """
    if form not in AMPLITUDE_FORMS:
        raise FividError(f"amplitude form {form!r} is not one of {', '.join(AMPLITUDE_FORMS)}")
    if form in NONLINEAR_FORMS:
        raise FividError(f"amplitude form {form!r} is not linear in its coefficients: it has no design matrix")
    v, ra, fn = _conditions(velocity, roughness, normal_load)
    values = {"sliding_velocity": v, "roughness_ra": ra, "normal_load": fn}
    n = v.size
    terms = tuple(terms)
    cols: list[np.ndarray] = []
    names: list[str] = []
    if form == "constant":
        return np.ones((n, 1)), ["amplitude"]
    if form in CATEGORICAL_FORMS:
        levels = np.asarray(roughness_levels, dtype=float)
        if levels.size == 0:
            raise FividError(f"amplitude form {form!r} needs at least one roughness level")
        idx = roughness_level_index(ra, levels) if levels.size > 1 else np.zeros(n, dtype=int)
        for r in range(levels.size):
            member = (idx == r).astype(float)
            cols += [member, member * v]
            names += [f"intercept[{r}]", f"velocity_slope[{r}]"]
        if form == "linear_velocity_load":
            _need_load(fn, form)
            cols.append(fn)
            names.append("load_slope")
        return np.column_stack(cols), names
    cols.append(np.ones(n))
    names.append("log_prefactor")
    if form == "log_linear":
        for term, short in _FACTORS:
            if term in terms:
                if not np.all(np.isfinite(values[term])):
                    raise FividError(f"amplitude form {form!r} depends on {term}: pass it")
                cols.append(values[term] / _RATE_SCALES[term])
                names.append(f"{short}_rate")
        return np.column_stack(cols), names
    log_cols, log_names = _log_factor_columns(form, terms, values)
    cols += log_cols
    names += log_names
    if form == "power_law_interaction":
        cols.append(cols[names.index("roughness_exponent")] * cols[names.index("velocity_exponent")])
        names.append("roughness_velocity_exponent")
    return np.column_stack(cols), names


def _linear_power_names(terms):
    return ["intercept", "velocity_slope"] + [f"{short}_exponent" for term, short in _FACTORS
                                              if term in terms and term != "sliding_velocity"]


def _linear_power(beta, terms, velocity, roughness, normal_load, form="linear_velocity_power_law"):
    """η = ln(a + b V) + Σ e_j ln(x_j/x_ref) of ``linear_velocity_power_law`` and ∂η/∂β (−inf where a + b V <= 0)."""
    v, ra, fn = _conditions(velocity, roughness, normal_load)
    values = {"sliding_velocity": v, "roughness_ra": ra, "normal_load": fn}
    if not np.all(np.isfinite(v)):
        raise FividError(f"amplitude form {form!r} depends on sliding_velocity: pass it")
    others = tuple(t for t in terms if t != "sliding_velocity")
    cols, _ = _log_factor_columns(form, others, values)
    beta = np.asarray(beta, float)
    lin = beta[0] + beta[1] * v
    with np.errstate(divide="ignore", invalid="ignore"):
        eta = np.where(lin > 0, np.log(np.where(lin > 0, lin, 1.0)), -np.inf)
        inv = np.where(lin > 0, 1.0 / lin, np.nan)
    for c, e in zip(cols, beta[2:]):
        eta = eta + e * c
    jac = np.column_stack([inv, inv * v] + cols)
    return eta, jac


def linear_velocity_power_law_predictor(beta, terms, velocity, roughness, normal_load=None):
    """η and ∂η/∂β of ``linear_velocity_power_law`` (coefficient names: :func:`linear_velocity_power_law_names`)."""
    return _linear_power(beta, terms, velocity, roughness, normal_load)


def linear_velocity_power_law_names(terms) -> list:
    """Coefficient names of ``linear_velocity_power_law`` with factors ``terms``."""
    return _linear_power_names(terms)


def _need_load(fn, form):
    if np.any(~np.isfinite(fn)):
        raise FividError(f"amplitude form {form!r} depends on the normal load: pass normal_load [N]")


@dataclass(frozen=True)
class AmplitudeModel:
    """A fitted amplitude law A(V, Ra, Fn) [-] (RMS of μp over the valid band).

    Parameters
    ----------
    form : str
        One of :data:`AMPLITUDE_FORMS`.
    coefficients : ndarray
        Fitted coefficients, in the order of ``names``.
    names : tuple of str
        Coefficient names (see the module docstring).
    stderr : ndarray
        Standard errors of the coefficients (NaN where not estimable).
    covariance : ndarray, shape (p, p)
        Covariance of the coefficients.
    terms : tuple of str
        Factors the form uses.
    roughness_levels : tuple of float
        Roughness levels [m] of the categorical linear forms.
    residual_variance : float
        Variance of a new run about the law on the fit scale (ln A, or A for the categorical forms),
        for a run as precise as the average fitted one (NaN: not recorded, law file version 1).
    residual_relative : bool
        True when ``residual_variance`` is relative: the variance of A is ``residual_variance · A²``
        (categorical forms with estimator weights).
    df_resid : float
        Residual degrees of freedom of the fit (Student-t quantiles of the intervals; NaN: normal).
    """

    form: str
    coefficients: np.ndarray
    names: tuple
    stderr: np.ndarray
    covariance: np.ndarray
    terms: tuple = ()
    roughness_levels: tuple = field(default=())
    residual_variance: float = np.nan
    residual_relative: bool = False
    df_resid: float = np.nan

    def __post_init__(self):
        if self.form not in AMPLITUDE_FORMS:
            raise FividError(f"amplitude form {self.form!r} is not one of {', '.join(AMPLITUDE_FORMS)}")
        if len(self.coefficients) != len(self.names):
            raise FividError(
                f"amplitude model {self.form!r}: {len(self.coefficients)} coefficients for {len(self.names)} names"
            )

    @property
    def is_log_form(self) -> bool:
        """True for the forms fitted on ln A (A = exp(η))."""
        return self.form in LOG_FORMS

    def _check_names(self, names):
        if tuple(names) != tuple(self.names):
            raise FividError(
                f"amplitude model {self.form!r}: coefficient names {list(self.names)} do not match the form's "
                f"design {list(names)} (a corrupt law file?)"
            )

    def gradient(self, velocity, roughness, normal_load=None) -> np.ndarray:
        """∂η/∂β, shape (n, p) (the design matrix X for the forms linear in β)."""
        return self.predictor_and_gradient(velocity, roughness, normal_load)[1]

    def predictor_and_gradient(self, velocity, roughness, normal_load=None):
        """(η, ∂η/∂β) at the given conditions."""
        beta = np.asarray(self.coefficients, dtype=float)
        if self.form in NONLINEAR_FORMS:
            self._check_names(_linear_power_names(self.terms))
            return _linear_power(beta, self.terms, velocity, roughness, normal_load, self.form)
        X, names = amplitude_design_matrix(self.form, self.terms, velocity, roughness, normal_load,
                                           self.roughness_levels)
        self._check_names(names)
        return X @ beta, X

    def linear_predictor(self, velocity, roughness, normal_load=None) -> np.ndarray:
        """η (A itself for the categorical forms, ln A for the others)."""
        return self.predictor_and_gradient(velocity, roughness, normal_load)[0]

    def __call__(self, velocity, roughness, normal_load=None) -> np.ndarray:
        """A [-] at sliding velocity [m s-1], roughness Ra [m], normal load [N] (clipped at 0)."""
        eta = self.linear_predictor(velocity, roughness, normal_load)
        return np.exp(eta) if self.is_log_form else np.maximum(eta, 0.0)

    def scaled(self, factor: float) -> "AmplitudeModel":
        """The model with A multiplied by ``factor`` > 0 everywhere (relative errors unchanged)."""
        import dataclasses

        coeffs = np.array(self.coefficients, float)
        if "log_prefactor" in self.names:
            coeffs[list(self.names).index("log_prefactor")] += np.log(factor)
            return dataclasses.replace(self, coefficients=coeffs)
        # the coefficients A is linear in: every one of the categorical forms, a and b of (a + b V)
        lin = np.array([n.split("[")[0] in ("amplitude", "intercept", "velocity_slope", "load_slope")
                        for n in self.names], float)
        g = np.where(lin > 0, factor, 1.0)
        return dataclasses.replace(self, coefficients=coeffs * g, stderr=np.asarray(self.stderr, float) * g,
                                   covariance=np.asarray(self.covariance, float) * np.outer(g, g))

    def to_dict(self) -> dict:
        """Plain-Python content (for JSON and hashing)."""
        return {
            "form": self.form,
            "terms": list(self.terms),
            "coefficients": {n: float(c) for n, c in zip(self.names, self.coefficients)},
            "stderr": {n: float(s) for n, s in zip(self.names, self.stderr)},
            "covariance": np.asarray(self.covariance, dtype=float).tolist(),
            "roughness_levels": [float(r) for r in self.roughness_levels],
            "reference_scales": dict(REFERENCE_SCALES) if self.is_log_form else {},
        }
