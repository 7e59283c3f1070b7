"""Amplitude models A(V, Ra, Fn): the RMS of the friction perturbation μp over the valid band.

Every form is a linear predictor ``η = X(V, Ra, Fn) β`` with either ``A = η`` (linear forms) or
``A = exp(η)`` (power-law forms fitted by log-log least squares). The design matrix is built here, in
one place, for fitting (:mod:`fivid.identify`) and for evaluation (the law objects).

Forms (DESIGN §3; seeds 000, 001 and 003):

``constant``
    ``A = a`` (one coefficient ``amplitude``).
``linear_velocity``
    ``A = a_r + b_r V`` for each roughness level ``r`` (seed 000: A linear in V, set by the roughness);
    coefficients ``intercept[r]`` [-] and ``velocity_slope[r]`` [s m-1].
``linear_velocity_load``
    as ``linear_velocity`` plus ``load_slope * Fn`` [N-1] shared by all roughness levels.
``power_law``
    ``A = exp(c) (Ra/Ra_ref)^n (V/V_ref)^m`` (seed 003); coefficients ``log_prefactor``,
    ``roughness_exponent``, ``velocity_exponent`` (a term is present only if its factor varied in the
    data it was fitted on).
``power_law_load``
    as ``power_law`` times ``(Fn/Fn_ref)^k``; coefficient ``load_exponent``.

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
    "LOG_FORMS",
    "REFERENCE_SCALES",
    "amplitude_design_matrix",
    "roughness_level_index",
]

AMPLITUDE_FORMS = ("constant", "linear_velocity", "linear_velocity_load", "power_law", "power_law_load")
LOG_FORMS = ("power_law", "power_law_load")
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


def amplitude_design_matrix(form, terms, velocity, roughness, normal_load, roughness_levels=()):
    """The design matrix and coefficient names of an amplitude form.

    Parameters
    ----------
    form : str
        One of :data:`AMPLITUDE_FORMS`.
    terms : sequence of str
        Factors the form uses among ``"sliding_velocity"``, ``"roughness_ra"``, ``"normal_load"``.
    velocity, roughness, normal_load : array_like
        Sliding velocity [m s-1], roughness Ra [m], normal load [N] (broadcast to one length).
    roughness_levels : sequence of float
        Roughness levels [m] of the linear forms (one intercept and slope each).

    Returns
    -------
    X : ndarray, shape (n, p)
    names : list of str
    """
    if form not in AMPLITUDE_FORMS:
        raise FividError(f"amplitude form {form!r} is not one of {', '.join(AMPLITUDE_FORMS)}")
    v, ra, fn = np.broadcast_arrays(
        np.atleast_1d(np.asarray(np.nan if velocity is None else velocity, dtype=float)),
        np.atleast_1d(np.asarray(np.nan if roughness is None else roughness, dtype=float)),
        np.atleast_1d(np.asarray(np.nan if normal_load is None else normal_load, dtype=float)),
    )
    n = v.size
    terms = tuple(terms)
    cols: list[np.ndarray] = []
    names: list[str] = []
    if form == "constant":
        return np.ones((n, 1)), ["amplitude"]
    if form in ("linear_velocity", "linear_velocity_load"):
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
    # power laws
    cols.append(np.ones(n))
    names.append("log_prefactor")
    for term, name, values in (
        ("roughness_ra", "roughness_exponent", ra),
        ("sliding_velocity", "velocity_exponent", v),
        ("normal_load", "load_exponent", fn),
    ):
        if term == "normal_load" and form != "power_law_load":
            continue
        if term in terms or term == "normal_load":  # power_law_load always has its load term
            if term == "normal_load":
                _need_load(values, form)
            if np.any(~(values > 0)):
                bad = values[~(values > 0)][0]
                raise FividError(f"amplitude form {form!r} depends on {term}: pass {term} > 0 (got "
                                 f"{'none' if np.isnan(bad) else repr(float(bad))})")
            cols.append(np.log(values / REFERENCE_SCALES[term]))
            names.append(name)
    return np.column_stack(cols), names


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
        Roughness levels [m] of the linear forms.
    """

    form: str
    coefficients: np.ndarray
    names: tuple
    stderr: np.ndarray
    covariance: np.ndarray
    terms: tuple = ()
    roughness_levels: tuple = field(default=())

    def __post_init__(self):
        if self.form not in AMPLITUDE_FORMS:
            raise FividError(f"amplitude form {self.form!r} is not one of {', '.join(AMPLITUDE_FORMS)}")
        if len(self.coefficients) != len(self.names):
            raise FividError(
                f"amplitude model {self.form!r}: {len(self.coefficients)} coefficients for {len(self.names)} names"
            )

    @property
    def is_log_form(self) -> bool:
        """True for the power laws (fitted on log A)."""
        return self.form in LOG_FORMS

    def linear_predictor(self, velocity, roughness, normal_load=None) -> np.ndarray:
        """η = X β (A itself for linear forms, ln A for power laws)."""
        X, names = amplitude_design_matrix(
            self.form, self.terms, velocity, roughness, normal_load, self.roughness_levels
        )
        if tuple(names) != tuple(self.names):
            raise FividError(
                f"amplitude model {self.form!r}: coefficient names {list(self.names)} do not match the form's "
                f"design {names} (a corrupt law file?)"
            )
        return X @ np.asarray(self.coefficients, dtype=float)

    def __call__(self, velocity, roughness, normal_load=None) -> np.ndarray:
        """A [-] at sliding velocity [m s-1], roughness Ra [m], normal load [N] (clipped at 0)."""
        eta = self.linear_predictor(velocity, roughness, normal_load)
        return np.exp(eta) if self.is_log_form else np.maximum(eta, 0.0)

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
