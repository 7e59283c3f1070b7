"""Forward identification of the friction law from measured runs (DESIGN §3, seeds 000 and 001).

:func:`identify_friction_law` takes RunDatasets at several sliding velocities, roughnesses and loads
and returns μ0 with its confidence interval, the normalised perturbation spectrum s(f), the per-run
RMS amplitudes and the amplitude law A(V, Ra, Fn) fitted in every candidate form, with the chosen
form and why. The result is a law file (:meth:`FrictionIdentification.to_dataset`, read back by
:func:`fivid.friction.load_law`) and a JSON report (:meth:`FrictionIdentification.to_json`).

μ0 across runs is the mean of the per-run means, with a Student-t interval on n − 1 degrees of
freedom from their scatter (it covers both the estimation error and any real run-to-run spread);
with a single run it is that run's batch-means interval.
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field, replace

import numpy as np

from fivid.errors import ConfigError, DataQualityError, FividError
from fivid.friction import (
    AmplitudeModel, ConditionDomain, PerturbedCoulombLaw, coefficient_units, law_dataset, write_law,
)
from fivid.friction.laws import INJECTION_MODES
from fivid.identify.amplitude_fit import (COOKS_RULE, SELECTION_RULE, FormFit, akaike_weights, candidate_forms,
                                          choose_form, constant_law_warning, fit_amplitude_forms, influential_runs,
                                          not_compared_reason)
from fivid.identify.runs import (DEFAULT_BAND_HIGH, DEFAULT_BAND_LOW, NPERSEG_RULE, RunAnalysis,
                                  RunAnalysisSettings, analyse_run)
from fivid.identify.shape import SpectralShape, identify_shape, shape_dependence
from fivid.io import read_run
from fivid.schema import new_history, validate_run

__all__ = ["FrictionIdentification", "identify_friction_law", "ShapeSettings", "AmplitudeSettings",
           "identification_arguments", "load_runs", "SHAPE_METHODS"]

SHAPE_METHODS = ("smoothed", "rolloff")
_log = logging.getLogger("fivid")


@dataclass
class FrictionIdentification:
    """Everything :func:`identify_friction_law` found; ``law`` is the identified law object."""

    law: PerturbedCoulombLaw
    mu0: float
    mu0_ci: tuple
    band: tuple
    runs: list
    shape: SpectralShape
    shape_method: str
    form_fits: list
    chosen: FormFit | None
    why: str
    law_across_runs: bool
    messages: list = field(default_factory=list)
    settings: dict = field(default_factory=dict)
    domain: ConditionDomain | None = None
    shape_test: dict = field(default_factory=dict)
    warnings: list = field(default_factory=list)

    @property
    def used_runs(self) -> list:
        """The runs kept for the law (not excluded), in input order."""
        return [r for r in self.runs if r.used]

    def selection_table(self) -> list:
        """One row per candidate form: AICc, dAICc, Akaike weight (from AICc), CV error, AIC, BIC, or why not fitted."""
        weights = akaike_weights(self.form_fits)
        fitted = [f.aicc for f in self.form_fits if f.fitted and np.isfinite(f.aicc)]
        best = min(fitted) if fitted else np.nan
        rows = []
        for f in self.form_fits:
            rows.append({
                "form": f.form, "fitted": f.fitted, "chosen": self.chosen is f, "n_params": f.n_params,
                "aicc": _num(f.aicc), "delta_aicc": _num(f.aicc - best), "akaike_weight": weights.get(f.form),
                "cv_error": _num(f.cv_error), "aic": _num(f.aic), "bic": _num(f.bic),
                "reason": not_compared_reason(f, self.form_fits) or f.cv_reason,
            })
        return rows

    def influence(self) -> dict:
        """Cook's distance per used run in the chosen fit and whether it exceeds 4/n (run_id -> (D, flag))."""
        if self.chosen is None or self.chosen.cooks_distance.size != len(self.used_runs):
            return {}
        flags = influential_runs(self.chosen)
        return {r.run_id: (float(d), bool(k)) for r, d, k in zip(self.used_runs, self.chosen.cooks_distance, flags)}

    def to_json(self) -> dict:
        """The JSON report: ``mu0``, ``mu0_ci``, ``amplitude_model``, ``candidate_forms``, ``runs``, ..."""
        m = self.law.amplitude_model
        ci = self.chosen.conf_int if self.chosen is not None else None
        amp = m.to_dict()
        amp["units"] = {n: coefficient_units(n) for n in m.names}
        amp["residual_variance"] = _num(m.residual_variance)
        amp["df_resid"] = _num(m.df_resid)
        if ci is not None:
            amp["ci95"] = {n: [float(a), float(b)] for n, (a, b) in zip(m.names, ci)}
        influence = self.influence()
        runs = []
        for r in self.runs:
            row = r.table_row()
            if r.run_id in influence:
                row["cooks_distance"], row["influential"] = influence[r.run_id]
            runs.append(row)
        return {
            "mu0": self.mu0,
            "mu0_ci": list(self.mu0_ci),
            "confidence": self.settings.get("confidence", 0.95),
            "band": list(self.band),
            "law_across_runs": self.law_across_runs,
            "amplitude_model": amp,
            "selection": {"rule": SELECTION_RULE, "chosen": m.form, "why": self.why,
                          "table": self.selection_table()},
            "candidate_forms": [dict(f.to_json(), akaike_weight=akaike_weights(self.form_fits).get(f.form))
                                for f in self.form_fits],
            "domain": None if self.domain is None else self.domain.to_json(),
            "outliers": {"rule": COOKS_RULE, "influential": [k for k, (_, flag) in influence.items() if flag]},
            "shape_dependence": dict(self.shape_test),
            "shape": {
                "method": self.shape_method,
                "smoothing_octaves": self.shape.smoothing_octaves,
                "n_frequencies": int(self.shape.frequency.size),
                "rolloff": self.shape.rolloff_params,
            },
            "injection": self.law.injection,
            "runs": runs,
            "messages": list(self.messages),
            "warnings": list(self.warnings),
            "settings": dict(self.settings),
            "law_sha256": self.law.sha256,
        }

    def summary(self) -> str:
        """A few human-readable lines (what the CLI prints without --json)."""
        used = self.used_runs
        lines = [
            f"mu0 = {self.mu0:.5f}  ({self.settings.get('confidence', 0.95):.0%} CI {self.mu0_ci[0]:.5f} .. "
            f"{self.mu0_ci[1]:.5f}) from {len(used)} of {len(self.runs)} runs",
            f"band {self.band[0]:g}-{self.band[1]:g} Hz; amplitude form {self.law.amplitude_model.form}: {self.why}",
        ]
        for row in self.selection_table():
            if row["fitted"] and row["aicc"] is None and row["reason"]:
                lines.append(f"  {row['form']:26s} not compared: {row['reason']}")
            elif row["fitted"]:
                w = row["akaike_weight"]
                lines.append(f"  {row['form']:26s} AICc {_fmt(row['aicc'], '9.2f')}  dAICc {_fmt(row['delta_aicc'], '7.2f')}  "
                             f"weight {_fmt(w, '.3f')}  CV error {_fmt(row['cv_error'], '.3g')}"
                             + ("  <- chosen" if row["chosen"] else ""))
            else:
                lines.append(f"  {row['form']:26s} not fitted: {row['reason']}")
        influence = self.influence()
        for r in self.runs:
            state = "used" if r.used else f"excluded: {r.reason}"
            if r.run_id in influence:
                d, flag = influence[r.run_id]
                state += f", Cook's D {d:.2g}" + (" > 4/n: influential (kept)" if flag else "")
            lines.append(f"  run {r.run_id}: mu {r.mu_mean:.4f}, A {r.mu_rms:.3g} ± {r.mu_rms_stderr:.2g} ({state})")
        lines += [f"warning: {m}" for m in self.warnings]
        lines += [f"note: {m}" for m in self.messages]
        return "\n".join(lines)

    def to_dataset(self):
        """The law-file content (:func:`fivid.friction.law_dataset`) plus the per-run and candidate-form tables."""
        import xarray as xr

        conf = self.settings.get("confidence", 0.95)
        attrs = {}
        for k, v in self.settings.items():
            if isinstance(v, dict):
                attrs.update({f"setting_{k}_{kk}": _attr(vv) for kk, vv in v.items()})
            else:
                attrs[f"setting_{k}"] = _attr(v)
        attrs.update({
            "selection_rule": SELECTION_RULE,
            "outlier_rule": COOKS_RULE,
            "selection_why": self.why,
            "law_across_runs": int(self.law_across_runs),
            "shape_method": self.shape_method,
            "messages": "\n".join(self.messages),
            "warnings": "\n".join(self.warnings),
            "source": "; ".join(f"{r.run_id}: {r.source}" for r in self.runs),
            "history": new_history(f"identify: friction law from {len(self.used_runs)} of {len(self.runs)} runs",
                                   timestamp=False),  # same runs, same law file bytes (issue 18)
        })
        for k, v in self.shape_test.items():
            attrs[f"shape_test_{k}"] = _attr(v)
        ds = law_dataset(self.law, mu0_ci=self.mu0_ci, confidence=conf, attrs=attrs, domain=self.domain)
        if self.chosen is not None:
            ds["amplitude_ci_lower"] = ("coefficient", self.chosen.conf_int[:, 0], {"confidence": conf})
            ds["amplitude_ci_upper"] = ("coefficient", self.chosen.conf_int[:, 1], {"confidence": conf})
        for name, values, long in (
            ("shape_average", self.shape.average, "average of the runs' normalised PSDs"),
            ("shape_smoothed", self.shape.smoothed, "fractional-octave smoothed shape"),
            ("shape_rolloff", self.shape.rolloff, "parametric roll-off fit of the shape"),
        ):
            if values is not None:
                ds[name] = ("frequency", values, {"units": "Hz-1", "long_name": long})
        run = np.array([r.run_id for r in self.runs], dtype=object)
        table = {
            "run_sliding_velocity": ([r.sliding_velocity for r in self.runs], "m s-1"),
            "run_roughness_ra": ([r.roughness_ra for r in self.runs], "m"),
            "run_normal_load": ([r.normal_load for r in self.runs], "N"),
            "run_mu_mean": ([r.mu_mean for r in self.runs], "1"),
            "run_mu_mean_ci_lower": ([r.mu_mean_ci[0] for r in self.runs], "1"),
            "run_mu_mean_ci_upper": ([r.mu_mean_ci[1] for r in self.runs], "1"),
            "run_mu_rms": ([r.mu_rms for r in self.runs], "1"),
            "run_mu_rms_stderr": ([r.mu_rms_stderr for r in self.runs], "1"),
            "run_window_start": ([r.t_start for r in self.runs], "s"),
            "run_window_stop": ([r.t_stop for r in self.runs], "s"),
        }
        for name, (values, units) in table.items():
            ds[name] = ("run", np.asarray(values, float), {"units": units})
        ds["run_used"] = ("run", np.array([r.used for r in self.runs], dtype=np.int8))
        ds["run_nperseg"] = ("run", np.array([r.psd_attrs.get("nperseg", 0) for r in self.runs], dtype=np.int32),
                             {"units": "1", "long_name": "Welch segment length [samples] (0: run not analysed)"})
        ds["run_mains_bins_removed"] = ("run", np.array([r.mains_bins_removed for r in self.runs], dtype=np.int32),
                                        {"units": "1"})
        ds["run_mains_removal"] = ("run", np.array([r.mains_removal for r in self.runs], dtype=object))
        ds["run_reason"] = ("run", np.array([r.reason for r in self.runs], dtype=object))
        ds["run_glitches_replaced"] = ("run", np.array([r.glitches_replaced for r in self.runs], dtype=np.int32),
                                       {"units": "1", "long_name": "force samples replaced as DAQ glitches"})
        influence = self.influence()
        ds["run_cooks_distance"] = ("run", np.array([influence.get(r.run_id, (np.nan, False))[0] for r in self.runs]),
                                    {"units": "1", "long_name": "Cook's distance in the chosen amplitude fit"})
        ds["run_influential"] = ("run", np.array([influence.get(r.run_id, (np.nan, False))[1] for r in self.runs],
                                                 np.int8), {"long_name": COOKS_RULE})
        ds = ds.assign_coords(run=("run", run))
        forms = np.array([f.form for f in self.form_fits], dtype=object)
        if forms.size:
            ds = ds.assign_coords(form=("form", forms))
            for name in ("aic", "aicc", "bic", "loglik", "cv_error"):
                ds[f"form_{name}"] = ("form", np.array([getattr(f, name) for f in self.form_fits], float))
            table = self.selection_table()
            ds["form_delta_aicc"] = ("form", np.array([_nan(r["delta_aicc"]) for r in table]))
            ds["form_akaike_weight"] = ("form", np.array([_nan(r["akaike_weight"]) for r in table]),
                                        {"long_name": "Akaike weight from AICc"})
            ds["form_chosen"] = ("form", np.array([r["chosen"] for r in table], np.int8))
            ds["form_n_params"] = ("form", np.array([f.n_params for f in self.form_fits], np.int32))
            ds["form_fitted"] = ("form", np.array([f.fitted for f in self.form_fits], np.int8))
            ds["form_reason"] = ("form", np.array([not_compared_reason(f, self.form_fits) for f in self.form_fits],
                                                  dtype=object))
            ds["form_cv_reason"] = ("form", np.array([f.cv_reason for f in self.form_fits], dtype=object))
        for name, long in _LONG_NAMES.items():  # CF: every variable says what it is
            if name in ds and "long_name" not in ds[name].attrs:
                ds[name].attrs["long_name"] = long
        return ds

    def write(self, path, *, overwrite: bool = False):
        """Write the law file atomically (:func:`fivid.friction.write_law`); returns the path."""
        return write_law(self.to_dataset(), path, overwrite=overwrite)


_LONG_NAMES = {
    "coefficient": "amplitude-law coefficient name",
    "coefficient_b": "amplitude-law coefficient name (second index of the covariance)",
    "amplitude_coefficient_units": "units of each amplitude-law coefficient",
    "run": "run identifier",
    "form": "candidate amplitude-law form",
    "amplitude_ci_lower": "lower bound of the amplitude-law coefficient's confidence interval",
    "amplitude_ci_upper": "upper bound of the amplitude-law coefficient's confidence interval",
    "run_sliding_velocity": "sliding velocity of the run",
    "run_roughness_ra": "roughness Ra of the run",
    "run_normal_load": "normal load of the run",
    "run_mu_mean": "mean friction coefficient of the run's steady window",
    "run_mu_mean_ci_lower": "lower bound of the 95 % interval of the run's mean friction coefficient",
    "run_mu_mean_ci_upper": "upper bound of the 95 % interval of the run's mean friction coefficient",
    "run_mu_rms": "RMS of the friction perturbation in the valid band (amplitude A)",
    "run_mu_rms_stderr": "standard error of the run's amplitude A",
    "run_window_start": "start of the run's steady-sliding window",
    "run_window_stop": "end of the run's steady-sliding window",
    "run_used": "run used in the identification (1) or left out (0)",
    "run_mains_bins_removed": "PSD bins removed around mains harmonics",
    "run_mains_removal": "how mains harmonics were removed from the run's spectrum",
    "run_reason": "why the run was left out (empty if used)",
    "form_aic": "Akaike information criterion of the amplitude form",
    "form_aicc": "small-sample corrected Akaike information criterion of the amplitude form",
    "form_bic": "Bayesian information criterion of the amplitude form",
    "form_loglik": "log-likelihood of the amplitude form on the amplitude scale",
    "form_cv_error": "leave-one-condition-out cross-validation error, RMS of ln(A_pred/A)",
    "form_delta_aicc": "AICc minus the lowest AICc of the candidate forms",
    "form_chosen": "the chosen amplitude form (1) or not (0)",
    "form_n_params": "number of coefficients of the amplitude form",
    "form_fitted": "the amplitude form could be fitted (1) or not (0)",
    "form_reason": "why the amplitude form could not be fitted or compared (empty if it was compared)",
    "form_cv_reason": "why the form has no cross-validation error (empty if it has one)",
}


def _num(x):
    return float(x) if x is not None and np.isfinite(x) else None


def _nan(x):
    return np.nan if x is None else float(x)


def _fmt(x, spec):
    return "-" if x is None else format(x, spec)


def _attr(v):
    if v is None:
        return "none"
    if isinstance(v, (tuple, list)):
        return " ".join(f"{x:g}" if isinstance(x, float) else str(x) for x in v)
    if isinstance(v, bool):
        return int(v)
    return v


def load_runs(runs) -> list:
    """RunDatasets from a sequence of Datasets or netCDF paths (paths are read with :func:`fivid.io.read_run`).

    Raises
    ------
    ConfigError
        Two items are the same run (same ``run_id``), naming both.
    """
    out, where = [], {}
    for item in runs:
        if isinstance(item, (str, os.PathLike)):
            ds, name = read_run(item), str(item)
        else:
            ds = validate_run(item)
            name = f"the dataset from {ds.attrs['source']}" if ds.attrs.get("source") else "a dataset"
        run_id = str(ds.attrs.get("run_id"))
        if run_id in where:
            first = where[run_id]
            given = f"twice ({name})" if first == name else f"twice: {first} and {name}"
            raise ConfigError(f"run_id {run_id!r} is given {given}; give each run once (a run counted twice would "
                              "weigh double in mu0 and in the amplitude-law fit)", key="runs")
        where[run_id] = name
        out.append(ds)
    return out


def _check_band(band, datasets):
    rates = [float(ds.attrs["sample_rate"]) for ds in datasets]
    nyquist = min(rates) / 2
    if band is None:
        return (DEFAULT_BAND_LOW, min(DEFAULT_BAND_HIGH, 0.4 * min(rates)))
    lo, hi = (float(b) for b in band)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
        raise ConfigError(f"band = ({lo:g}, {hi:g}) Hz; need 0 <= F_LO < F_HI", key="band")
    if hi > nyquist:
        slow = [ds.attrs.get("run_id") for ds, r in zip(datasets, rates) if r / 2 < hi]
        raise ConfigError(
            f"band upper edge {hi:g} Hz is beyond the Nyquist frequency {nyquist:g} Hz of run(s) "
            f"{', '.join(map(str, slow))}; choose F_HI < {nyquist:g} Hz", key="band"
        )
    return lo, hi


def _unloaded_start(ds, fraction: float = 0.05):
    """Length [s] of the record's unloaded start (|Fn| < ``fraction`` of the nominal load) and the mean
    friction force (sign as in μ > 0) and normal force [N] there (the sensor offsets), or None when the
    record starts loaded."""
    fn = np.asarray(ds["normal_force"].values, float)
    load = float(ds.attrs.get("normal_load", np.nan))
    if not load > 0 or fn.size < 2:
        return None
    above = np.abs(fn) >= fraction * load
    k = int(np.argmax(above))
    if k < 10 or not above.any():
        return None
    t = np.asarray(ds["time"].values, float)
    ft = np.asarray(ds["friction_force"].values, float)
    sign = 1.0 if np.mean(ft) >= 0 else -1.0  # the sign convention analyse_run makes positive
    return float(t[k] - t[0]), sign * float(np.mean(ft[:k])), float(np.mean(fn[:k]))


def _tare_hint(datasets, analyses):
    """A message when no tare was given but every used run starts unloaded: the offsets there bias μ0."""
    pairs = [(ds, r) for ds, r in zip(datasets, analyses) if r.used]
    starts = [_unloaded_start(ds) for ds, _ in pairs]
    if not pairs or any(s is None for s in starts):
        return None
    bias = [(ft0 - r.mu_mean * fn0) / r.normal_load for (_, r), (_, ft0, fn0) in zip(pairs, starts)]
    span = min(s[0] for s in starts)
    return (f"no tare given, but every run starts unloaded for >= {span * 1e3:.3g} ms (|Fn| < 5 % of the nominal "
            f"load), where the force sensors read offsets that bias mu by (offset_t - mu offset_n)/Fn, up to "
            f"{max(np.abs(bias)):.2g} here; pass tare=(0, {0.75 * span:.3g}) s "
            f"(--tare 0 {0.75 * span:.3g}) to remove them")


def _mu0_interval(used, confidence):
    from scipy import stats

    means = np.array([r.mu_mean for r in used])
    if means.size == 1:
        return float(means[0]), tuple(used[0].mu_mean_ci)
    half = stats.t.ppf(0.5 + confidence / 2, means.size - 1) * means.std(ddof=1) / np.sqrt(means.size)
    return float(means.mean()), (float(means.mean() - half), float(means.mean() + half))


@dataclass(frozen=True)
class ShapeSettings:
    """How the perturbation's spectral shape s(f) is estimated.

    Attributes
    ----------
    method : {"smoothed", "rolloff"}
        Which shape goes into the law (both are in the law file; default smoothed).
    smoothing_octaves : float
        Width of the log-frequency smoothing [octaves] (default 1/6).
    """

    method: str = "smoothed"
    smoothing_octaves: float = 1.0 / 6.0


@dataclass(frozen=True)
class AmplitudeSettings:
    """Which amplitude laws A(V, Ra, Fn) are fitted across the runs, and how.

    Attributes
    ----------
    forms : sequence of str or None
        Candidate amplitude forms; None: :func:`fivid.identify.amplitude_fit.candidate_forms`: the forms continuous
        in V, Ra and Fn, plus the following two on request.
    interaction : bool
        Also the power law with an Ra × V interaction (default False).
    categorical : bool
        Also the categorical forms (one line in V per roughness level; they refuse an Ra between levels).
    weighting : {"estimator", "none"}
        WLS with the per-run estimator variances as relative weights (default), or OLS.
    """

    forms: tuple[str, ...] | None = None
    interaction: bool = False
    categorical: bool = False
    weighting: str = "estimator"


#: where each flat setting of the ``identify:`` section of a run configuration (and of ``fivid identify``'s options)
#: goes among the arguments of :func:`identify_friction_law`
_SETTING_GROUPS = {
    **{k: ("analysis", k) for k in ("nperseg", "tolerance", "min_normal_force", "tare", "window", "mains_frequency",
                                    "noise_correction", "glitch_repair", "confidence", "allow_implausible")},
    "shape_method": ("shape", "method"), "smoothing_octaves": ("shape", "smoothing_octaves"),
    **{k: ("amplitude", k) for k in ("forms", "interaction", "categorical", "weighting")},
    **{k: (None, k) for k in ("band", "transfer_function", "injection")},
}


def identification_arguments(settings: dict) -> dict:
    """The keyword arguments of :func:`identify_friction_law` from flat ``settings`` (the keys of a run
    configuration's ``identify:`` section: ``band``, ``tare``, ``nperseg``, ``shape_method``, ``forms``,
    ``injection`` ...; see :data:`_SETTING_GROUPS`); an unknown key is a ConfigError naming it."""
    unknown = sorted(set(settings) - set(_SETTING_GROUPS))
    if unknown:
        raise ConfigError(f"unknown identification setting(s) {', '.join(unknown)}; allowed: "
                          f"{', '.join(sorted(_SETTING_GROUPS))}", key=unknown[0])
    groups: dict = {"analysis": {}, "shape": {}, "amplitude": {}}
    out = {}
    for key, value in settings.items():
        group, name = _SETTING_GROUPS[key]
        (out if group is None else groups[group])[name] = value
    kinds = {"analysis": RunAnalysisSettings, "shape": ShapeSettings, "amplitude": AmplitudeSettings}
    out.update({g: kinds[g](**kw) for g, kw in groups.items() if kw})
    return out


def identify_friction_law(runs, *, band=None, analysis: RunAnalysisSettings = RunAnalysisSettings(),
                          transfer_function=None, shape: ShapeSettings = ShapeSettings(),
                          amplitude: AmplitudeSettings = AmplitudeSettings(),
                          injection: str = "uniform") -> FrictionIdentification:
    """Identify μ0, the perturbation spectrum and the amplitude law from measured runs.

    Parameters
    ----------
    runs : sequence of xarray.Dataset or path
        RunDatasets (SI units) or netCDF files written by ``fivid ingest``.
    band : (float, float), optional
        Valid band [Hz]; default 20 Hz to min(2 kHz, 0.4 fs) — set it to where the force chain
        is dynamic-free (or give ``transfer_function``).
    analysis : RunAnalysisSettings
        The per-run analysis, recorded in the law file (:class:`fivid.identify.runs.RunAnalysisSettings`):

        - ``nperseg``: Welch segment length [samples]; None: per run :func:`fivid.identify.runs.default_nperseg`,
          bins of at most mains/4 (12.5 Hz at 50 Hz) so that mains-line removal takes only the lines, within ≥ 7
          segments, else the coarser rule of ≥ 31 segments (lines then left in, with a message); every run's is
          in the law file (``run_nperseg``);
        - ``tolerance``: relative velocity tolerance of the steady-sliding window [-] (0.05);
        - ``min_normal_force``: runs with a mean normal force below this on the window are excluded [N] (0.1);
        - ``tare``: unloaded interval [s] whose mean forces are subtracted (force-sensor offsets);
        - ``window``: steady-sliding window [s] for every run; None: from each run's encoder signal
          (``velocity`` or ``position``), or from its forces when it has neither
          (:func:`fivid.signal.steady_force_window`);
        - ``mains_frequency``: mains harmonics standing out of the PSD are interpolated over [Hz] (50), in runs
          whose Welch bins are <= mains/4 (else left in, with a message); None disables;
        - ``noise_correction``: with ``tare``, subtract the sensor-noise PSD measured on the unloaded interval;
        - ``glitch_repair``: replace force-channel DAQ glitches first; None: on for measured runs, off for
          simulated ones;
        - ``confidence``: level of every interval (0.95);
        - ``allow_implausible``: identify from runs whose mean Ft/Fn is beyond +-2 (an error otherwise: a swapped
          column or unit, and a sign that would be lost).
    transfer_function : xarray.DataArray, optional
        Force-chain transfer function on dim ``frequency`` [Hz]; the μp PSD is divided by ``|H|^2``.
    shape : ShapeSettings
        Which shape goes into the law (``method``: smoothed or roll-off) and the width of the log-frequency
        smoothing [octaves].
    amplitude : AmplitudeSettings
        The candidate amplitude forms (default: those continuous in V, Ra and Fn; the interaction and categorical
        forms on request) and the weighting of the fit (estimator variances or none).
    injection : {"uniform", "per_node", "convected"}
        Injection mode written into the law.

    Returns
    -------
    FrictionIdentification

    Raises
    ------
    FividError
        Bad band (beyond Nyquist, empty), bad settings.
    SchemaError
        A run is not a valid RunDataset (missing forces, wrong units).
    DataQualityError
        No run is usable (each run's reason is listed).
    """
    shape_method, smoothing_octaves = shape.method, shape.smoothing_octaves
    forms, interaction, categorical = amplitude.forms, amplitude.interaction, amplitude.categorical
    weighting, confidence, tare = amplitude.weighting, analysis.confidence, analysis.tare
    if shape_method not in SHAPE_METHODS:
        raise FividError(f"shape_method {shape_method!r} is not one of {', '.join(SHAPE_METHODS)}")
    if injection not in INJECTION_MODES:
        raise FividError(f"injection {injection!r} is not one of {', '.join(INJECTION_MODES)}")
    if not 0 < confidence < 1:
        raise FividError(f"confidence = {confidence!r}; it must be in (0, 1)")
    datasets = load_runs(runs)
    if not datasets:
        raise FividError("no runs given")
    band = _check_band(band, datasets)
    window = analysis.window
    settings = replace(analysis, tare=None if tare is None else tuple(float(x) for x in tare),
                       window=None if window is None else tuple(float(x) for x in window),
                       allow_implausible=bool(analysis.allow_implausible))
    analyses: list[RunAnalysis] = [analyse_run(ds, settings, band=band, transfer_function=transfer_function)
                                   for ds in datasets]
    used = [r for r in analyses if r.used]
    if not used:
        reasons = "; ".join(f"{r.run_id}: {r.reason}" for r in analyses)
        raise DataQualityError(f"no usable run among {len(analyses)}: {reasons}")
    messages = [f"run {r.run_id} excluded: {r.reason}" for r in analyses if not r.used]
    messages += [f"run {r.run_id}: steady window {r.t_start:.4g}-{r.t_stop:.4g} s from the forces (no velocity or "
                 "position recorded; check it, or give it with --window T0 T1)" for r in used
                 if r.window_source.startswith("forces")]
    messages += [f"run {r.run_id}: mains-line removal {r.mains_removal}" for r in used
                 if r.mains_removal.startswith("not done")]
    messages += [f"run {r.run_id}: {r.glitches_replaced} force sample(s) replaced as DAQ glitches (spikes or "
                 "dropouts, fivid.identify.glitches; see docs/identification.md)" for r in analyses
                 if r.glitches_replaced]
    mu0, mu0_ci = _mu0_interval(used, confidence)
    hint = _tare_hint(datasets, analyses) if tare is None else None
    if hint:
        messages.append(hint)
        _log.info(hint)
    v_ref = float(np.exp(np.mean(np.log([r.sliding_velocity for r in used])))) if injection == "convected" else None
    shape = identify_shape(used, band, smoothing_octaves=smoothing_octaves, injection=injection,
                           reference_velocity=v_ref)
    if forms is None:
        forms = candidate_forms(interaction=interaction, categorical=categorical)
    amplitude = np.array([r.mu_rms for r in used])
    stderr = np.array([r.mu_rms_stderr for r in used])
    if len(used) >= 2:
        fits = fit_amplitude_forms([r.sliding_velocity for r in used], [r.roughness_ra for r in used],
                                   [r.normal_load for r in used], amplitude, stderr, forms=forms,
                                   weighting=weighting, confidence=confidence)
        chosen, why = choose_form(fits)
    else:
        fits, chosen, why = [], None, ""
    law_across_runs = chosen is not None
    warnings = []
    if chosen is not None:
        model = chosen.model
        for f in fits:
            if not f.fitted and f.form != "constant":
                messages.append(f"amplitude form {f.form} not fitted: {f.reason}")
        warning = constant_law_warning(chosen, amplitude)
        if warning:
            warnings.append(warning)
        for r, d, flag in zip(used, chosen.cooks_distance, influential_runs(chosen)):
            if flag:
                messages.append(f"run {r.run_id} is influential in the {chosen.form} fit: Cook's distance {d:.3g} > "
                                f"4/n = {4 / len(used):.3g} (kept; check the run)")
    else:
        run = used[0]
        why = (f"a single usable run ({run.run_id}): no amplitude law across runs can be fitted; the law "
               "holds this run's band RMS as a constant, valid only at its velocity, roughness and load")
        messages.append(why)
        model = AmplitudeModel("constant", np.array([run.mu_rms]), ("amplitude",), np.array([run.mu_rms_stderr]),
                               np.array([[run.mu_rms_stderr**2]]))
    law_shape = shape.smoothed
    if shape_method == "rolloff":
        if shape.rolloff is None:
            raise FividError(f"shape_method 'rolloff': {shape.rolloff_params.get('reason', 'the fit failed')}")
        law_shape = shape.rolloff
    shape_test, condition_shapes = shape_dependence(used, band, injection=injection, reference_velocity=v_ref,
                                                    smoothing_octaves=smoothing_octaves, frequency=shape.frequency)
    if shape_test["depends"]:
        messages.append(f"the spectral shape depends on {', '.join(shape_test['variables'])} (p = "
                        f"{shape_test['p_value']:.3g} < {shape_test['alpha']:g}): the law holds one shape per "
                        f"condition ({condition_shapes[0].shape[0]}) and interpolates between them")
    law = PerturbedCoulombLaw(mu0, shape.frequency, law_shape, model, band, injection=injection,
                              reference_velocity=v_ref, condition_shapes=condition_shapes)
    points = np.array([[r.sliding_velocity, r.roughness_ra, r.normal_load] for r in used])
    domain = ConditionDomain(points) if np.all(np.isfinite(points) & (points > 0)) else None
    if domain is None:
        messages.append("a used run lacks a sliding velocity, roughness or load > 0: the law file records no domain")
    recorded = {
        "band": band, **settings.to_dict(),
        "transfer_function": "none" if transfer_function is None else "given",
        "shape_method": shape_method, "smoothing_octaves": smoothing_octaves, "forms": ",".join(forms),
        "weighting": weighting, "injection": injection, "confidence": confidence,
        "nperseg_rule": "given" if analysis.nperseg else NPERSEG_RULE,
        "welch": dict(used[0].psd_attrs),
    }
    return FrictionIdentification(
        law=law, mu0=mu0, mu0_ci=mu0_ci, band=band, runs=analyses, shape=shape, shape_method=shape_method,
        form_fits=fits, chosen=chosen, why=why, law_across_runs=law_across_runs, messages=messages, warnings=warnings,
        settings=recorded, domain=domain, shape_test=shape_test,
    )
