"""Least-squares model updating: named config parameters against target modes (``fivid update``).

Residuals ``r_i = (f_model,i - f_target,i) / tol_i``: each target's tolerance is read as one standard
deviation. :func:`scipy.optimize.least_squares` (trust-region reflective, bounds respected) works on the
parameters scaled by their starting values, ``x = p / p_0``; sensitivities are forward differences
(relative step: the predictor's ``diff_step``).

Statistics at the solution, from the Jacobian ``J`` of the scaled residuals:

* covariance ``C = (J^T J)^+``, scaled up by the reduced chi-square ``chi^2 / (m - n)`` when the
  targets scatter more than their tolerances and ``m > n`` (Birge ratio; with ``m = n`` it stays as the
  tolerances give it); 95 % intervals ``+-1.96 sqrt(C_ii)`` (linearised, normal);
* the correlation matrix ``C_ij / sqrt(C_ii C_jj)``;
* identifiability: a right singular vector of ``J`` whose singular value is below ``NULL_RATIO`` times the
  largest is a direction the targets do not see; its parameters get no interval (``ci95`` None), and every
  pair with ``|corr| >= PAIR_CORRELATION`` is named in a warning (mass and stiffness scaled together leave
  every frequency unchanged: such a pair is reported, not "fitted").
"""

from __future__ import annotations

import datetime as _dt
import logging
import re
from dataclasses import dataclass, field

import numpy as np

from fivid.builtin import find_builtin
from fivid.config_layer import parse_yaml_text, read_yaml
from fivid.errors import ConfigError, UnitError
from fivid.units import conversion, unit_registry
from fivid.updating.paths import get_path, replace_values, set_path
from fivid.updating.predict import predictor_for
from fivid.updating.targets import Targets

__all__ = ["Parameter", "UpdateResult", "resolve_parameters", "update_model", "NULL_RATIO", "PAIR_CORRELATION"]

log = logging.getLogger("fivid")

#: singular values of the scaled Jacobian below this fraction of the largest span unidentifiable directions
NULL_RATIO = 1e-4
#: parameter pairs correlated at least this much are named as not told apart by the targets
PAIR_CORRELATION = 0.99
_VALUE = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*")


@dataclass(frozen=True)
class Parameter:
    """A parameter being updated, in the unit it is written with in the model file.

    Attributes
    ----------
    path : str
        Dotted key in the model config.
    unit : str or None
        Its unit (None: a bare number, as the model file writes it).
    initial, lower, upper : float
        Value in the model file and bounds, in ``unit``.
    key : str
        Its entry in the targets file (``parameters[0]``).
    """

    path: str
    unit: str | None
    initial: float
    lower: float
    upper: float
    key: str

    def text(self, value: float) -> str:
        """The value as written back into the model file (9 significant digits, with the unit)."""
        return f"{value:.9g}" + (f" {self.unit}" if self.unit else "")


@dataclass
class UpdateResult:
    """The outcome of :func:`update_model` (see the module docstring for the statistics)."""

    parameters: list
    values: np.ndarray
    ci95: list
    correlation: np.ndarray
    residuals: list
    cost: float
    iterations: int
    evaluations: int
    converged: bool
    message: str
    warnings: list = field(default_factory=list)
    count_below: list = field(default_factory=list)
    identifiable: bool = True

    def to_json(self) -> dict:
        """The JSON summary (keys as in ``fivid update --json``)."""
        return {
            "parameters": [{"path": p.path, "value": float(v), "unit": p.unit or "1", "ci95": ci, "initial": p.initial,
                            "bounds": [p.lower, p.upper]}
                           for p, v, ci in zip(self.parameters, self.values, self.ci95)],
            "residuals": self.residuals,
            "count_below": self.count_below,
            "correlation": [[float(c) for c in row] for row in self.correlation],
            "cost": self.cost,
            "iterations": self.iterations,
            "evaluations": self.evaluations,
            "converged": self.converged,
            "identifiable": self.identifiable,
            "message": self.message,
            "warnings": self.warnings,
        }


def _split(value):
    """``(number, unit or None)`` of a config value, or None when it is not a number/quantity."""
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return float(value), None
    m = _VALUE.fullmatch(str(value))
    if m is None:
        return None
    return float(m.group(1)), (m.group(2) or None)


def resolve_parameters(data: dict, model_file: str, targets: Targets) -> list:
    """The targets' parameters with their model values, bounds converted to the model's unit.

    Raises
    ------
    ConfigError
        Unknown path, a value that is not a number, bounds without units (or of another dimension), a
        starting value outside the bounds: naming the targets file, line and key.
    """
    src = targets.source
    out = []
    for spec in targets.parameters:
        try:
            value = get_path(data, spec.path)
        except (KeyError, ConfigError) as exc:
            msg = exc.args[0] if isinstance(exc, KeyError) else exc.message
            raise src.error(f"{spec.key}.path",
                            f"unknown parameter path {spec.path!r} in {model_file}: {msg}") from None
        split = _split(value)
        if split is None:
            raise src.error(f"{spec.key}.path", f"{spec.path!r} in {model_file} is {value!r}, not a number or a "
                                                "quantity")
        initial, unit = split
        bounds = []
        for j, b in enumerate(spec.bounds):
            bkey = f"{spec.key}.bounds[{j}]"
            bs = _split(b)
            if bs is None:
                raise src.error(bkey, f"expected a quantity such as '150 GPa', found {b!r}")
            number, bunit = bs
            if unit is not None and bunit is None:
                raise src.error(bkey, f"bound {b!r} has no unit; {spec.path} is {value!r} in {model_file}: write "
                                      f"it with a unit, e.g. '{number:g} {unit}'")
            if bunit is not None:
                try:
                    scale, offset = conversion(bunit, unit) if unit is not None else _to_si(bunit)
                except UnitError as exc:
                    raise src.error(bkey, f"bound {b!r}: {exc.message}") from None
                number = number * scale + offset
            bounds.append(number)
        lo, hi = bounds
        if not lo < hi:
            raise src.error(f"{spec.key}.bounds", f"expected low < high, found {list(spec.bounds)!r}")
        if not lo <= initial <= hi:
            raise src.error(f"{spec.key}.bounds", f"the model's value {value!r} ({spec.path} in {model_file}) is "
                                                  f"outside the bounds {list(spec.bounds)!r}; the update starts from "
                                                  "it")
        if lo <= 0 <= hi and initial == 0:
            raise src.error(f"{spec.key}.path", f"{spec.path} is 0 in {model_file}; start from a non-zero value "
                                                "(parameters are scaled by their starting values)")
        out.append(Parameter(spec.path, unit, initial, lo, hi, spec.key))
    return out


def _resolve(path):
    """A model file path, or the shipped config of that name (``configs/models``, ``configs/dampers``)."""
    from pathlib import Path

    if Path(path).exists() or any(c in str(path) for c in "/\\"):
        return path
    return find_builtin("models", str(path)) or find_builtin("dampers", str(path)) or path


def _to_si(unit: str):
    q = unit_registry().Quantity(1.0, unit)
    return conversion(unit, str(q.to_base_units().units))


def update_model(model_path, targets: Targets):
    """Update the parameters named in ``targets`` of the model config at ``model_path``.

    Parameters
    ----------
    model_path : path-like
        FE model config (``configs/models``) or damper model config (``configs/dampers``).
    targets : Targets
        From :func:`fivid.updating.targets.load_targets`.

    Returns
    -------
    result : UpdateResult
    updated_text : str
        The model file's text with the new values and a provenance comment.
    """
    import copy

    from scipy.optimize import least_squares

    msrc = read_yaml(_resolve(model_path), "model config")
    params = resolve_parameters(msrc.data, str(model_path), targets)
    predict = predictor_for(msrc.data, targets)
    p0 = np.array([p.initial for p in params])
    f_t = np.array([t.frequency for t in targets.modes] + [t.value for t in targets.critical_mu])
    tol = np.array([t.tolerance for t in targets.modes] + [t.tolerance for t in targets.critical_mu])
    cache = {}

    def config(x):
        data = copy.deepcopy(msrc.data)
        for p, v in zip(params, np.asarray(x) * p0):
            set_path(data, p.path, p.text(v) if p.unit else float(v))
        return data

    def run(x):
        k = tuple(np.round(np.asarray(x, dtype=float), 15))
        if k not in cache:
            cache[k] = predict(config(x))
        return cache[k]

    def residual(x):
        pred = run(x)
        return (np.concatenate([pred.frequency, pred.critical_mu]) - f_t) / tol

    lb = np.array([p.lower for p in params]) / p0
    ub = np.array([p.upper for p in params]) / p0
    lo, hi = np.minimum(lb, ub), np.maximum(lb, ub)  # negative starting values flip the scaled bounds
    first = run(np.ones(len(params)))  # pairing problems surface before the fit, at the model as written
    log.info("update: %d parameters, %d targets; initial frequencies %s Hz", len(params), f_t.size,
             np.round(first.frequency, 4).tolist())
    fit = least_squares(residual, np.ones(len(params)), bounds=(lo, hi), method="trf",
                        diff_step=predict.diff_step, xtol=1e-10, ftol=1e-10, gtol=1e-10, max_nfev=200)
    values = fit.x * p0
    result = _statistics(fit, params, p0, targets, run(fit.x))
    result.evaluations = len(cache)  # every model solved, finite-difference steps included
    text = _updated_text(msrc, params, values, targets, result)
    return result, text


def _statistics(fit, params, p0, targets, pred) -> UpdateResult:
    J = np.asarray(fit.jac, dtype=float)
    r = np.asarray(fit.fun, dtype=float)
    m, n = J.shape
    _, s, vt = np.linalg.svd(J, full_matrices=False)
    log.debug("update: singular values of the scaled Jacobian %s", s)
    null = (s < NULL_RATIO * s[0]) if s.size and s[0] > 0 else np.ones(n, bool)
    cov = np.linalg.pinv(J.T @ J, rcond=NULL_RATIO**2, hermitian=True)
    chi2 = float(r @ r)
    if m > n:
        cov = cov * max(1.0, chi2 / (m - n))
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(sd, sd)
    corr[~np.isfinite(corr)] = 0.0
    np.fill_diagonal(corr, 1.0)
    unseen = np.zeros(n, bool)
    for k in np.flatnonzero(null):
        unseen |= np.abs(vt[k]) > 0.1
    warnings = []
    for i in range(n):
        for j in range(i + 1, n):
            if abs(corr[i, j]) >= PAIR_CORRELATION or (unseen[i] and unseen[j]):
                warnings.append(f"the targets cannot tell {params[i].path} and {params[j].path} apart (correlation "
                                f"{corr[i, j]:+.3f}): only a combination of them is identified; fix one of them "
                                "or add targets that separate them (the values written are one point of a valley)")
    for i in np.flatnonzero(unseen):
        if not any(params[i].path in w for w in warnings):
            warnings.append(f"the targets do not determine {params[i].path} (no sensitivity); it keeps no "
                            "confidence interval")
    ci = [None if unseen[i] else float(1.96 * sd[i] * abs(p0[i])) for i in range(n)]
    residuals = []
    for t, f, mode, mac in zip(targets.modes, pred.frequency, pred.model_mode, pred.mac):
        row = {"name": t.name, "target": t.frequency, "model": float(f),
               "error_pct": float(100 * (f - t.frequency) / t.frequency), "tolerance_hz": t.tolerance}
        if mode is not None:
            row["model_mode"] = mode
        if mac is not None:
            row["mac"] = mac
        if t.normal_load is not None:
            row["normal_load_n"] = t.normal_load
        residuals.append(row)
    for t, v, d in zip(targets.critical_mu, pred.critical_mu, pred.critical_detail):
        residuals.append({"name": t.name, "target": t.value, "model": float(v),
                          "error_pct": float(100 * (v - t.value) / t.value), "tolerance": t.tolerance,
                          "quantity": "critical_mu", "model_mode": d["mode"], "partner_mode": d["partner"],
                          "frequency_hz": d["frequency_hz"], "extrapolated": d["extrapolated"]})
        if d["extrapolated"]:
            warnings.append(f"{t.key}: the pair of CEA mode {d['mode']} stays stable over the sweep; its critical "
                            f"mu {v:.3g} is extrapolated: widen mu")
    counts = []
    for c in targets.count_below:
        n_below = int(np.sum((pred.all_frequencies > 0) & (pred.all_frequencies < c.frequency)))
        complete = n_below < pred.all_frequencies.size
        counts.append({"name": c.key, "frequency_hz": c.frequency, "count": c.count,
                       "model_count": n_below if complete else None, "satisfied": complete and n_below == c.count})
        if not complete:
            warnings.append(f"{c.key}: all {pred.all_frequencies.size} computed modes lie below {c.frequency:g} Hz; "
                            "raise n_modes to count them")
        elif n_below != c.count:
            warnings.append(f"{c.key}: the updated model has {n_below} modes below {c.frequency:g} Hz, the target "
                            f"says {c.count}")
    return UpdateResult(
        parameters=params, values=fit.x * p0, ci95=ci, correlation=corr, residuals=residuals,
        cost=float(fit.cost), iterations=int(fit.njev or 0), evaluations=int(fit.nfev),  # nfev: no FD steps
        converged=bool(fit.status > 0), message=str(fit.message), warnings=warnings, count_below=counts,
        identifiable=not unseen.any(),
    )


def _updated_text(msrc, params, values, targets, result) -> str:
    from pathlib import Path

    text = Path(msrc.file).read_text(encoding="utf-8")
    new = replace_values(text, {p.path: p.text(v) for p, v in zip(params, values)})
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    tsrc = targets.source
    lines = [f"# Updated by fivid update on {stamp} from {msrc.origin}",
             f"# targets: {tsrc.origin}"]
    for p, v, ci in zip(params, values, result.ci95):
        unit = f" {p.unit}" if p.unit else ""
        ci_text = f" +- {ci:.3g}{unit} (95 %)" if ci is not None else " (not identified by the targets)"
        lines.append(f"#   {p.path}: {p.initial:.6g}{unit} -> {v:.6g}{unit}{ci_text}")
    for row in result.residuals:
        unit = "" if row.get("quantity") == "critical_mu" else " Hz"
        lines.append(f"#   {row['name']}: target {row['target']:.6g}{unit}, model {row['model']:.6g}{unit} "
                     f"({row['error_pct']:+.3f} %)")
    for row in result.count_below:
        lines.append(f"#   {row['name']}: {row['model_count']} modes below {row['frequency_hz']:g} Hz (target "
                     f"{row['count']})")
    lines.append(f"# cost {result.cost:.4g}, {result.evaluations} model evaluations, converged: "
                 f"{str(result.converged).lower()}")
    for w in result.warnings:
        lines.append(f"# warning: {w}")
    check, _ = _parse(new)
    for p, v in zip(params, values):
        if _split(get_path(check, p.path)) != _split(p.text(v)):  # the rewrite must land where the value was
            raise ConfigError(f"could not write {p.path} back into {msrc.file}", key=p.path)
    return "\n".join(lines) + "\n" + new


def _parse(text):
    return parse_yaml_text(text)
