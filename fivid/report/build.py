"""The validation report: provenance, identified law, PSD overlays and scores, modes vs peaks, verdict.

:func:`render_report` takes plain data and file paths (what the pipeline produced) and writes one
self-contained ``report.html`` (figures embedded as PNG data URIs, no script, no external resource).
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
from importlib import metadata
from pathlib import Path

import numpy as np

from fivid import __version__
from fivid.friction import coefficient_units, law_from_dataset
from fivid.report.figures import (
    amplitude_figure,
    law_shape_figure,
    modal_figure,
    psd_envelope_figure,
    psd_overlay_figure,
)
from fivid.report.html import Page, fmt, table
from fivid.score.envelope import band_levels_of_samples, envelope_coverage, read_envelope
from fivid.storage import write_text

__all__ = ["render_report", "measured_peaks", "amplitude_interval", "PEAK_PAIRING_TOLERANCE"]

#: a model mode and a measured peak are paired only when they differ by at most this fraction of the peak [-]
#: (the coarse model's modes sit within a few % of the measured peaks; 29 % is another feature, not the mode)
PEAK_PAIRING_TOLERANCE = 0.10

# Two-sided 95 % normal quantile for the amplitude-law interval (coefficients ~ normal with the
# fitted covariance; the identify step reports the same level).
_Z95 = 1.959963984540054


def _versions() -> list[list[str]]:
    rows = [["fivid", __version__], ["python", platform.python_version()]]
    for pkg in ("numpy", "scipy", "xarray", "pandas", "netCDF4", "statsmodels", "numba", "dask", "distributed",
                "matplotlib", "pint"):
        try:
            rows.append([pkg, metadata.version(pkg)])
        except metadata.PackageNotFoundError:
            rows.append([pkg, "not installed"])
    return rows


def amplitude_interval(model, velocity, roughness, normal_load=None, z: float = _Z95):
    """Fitted amplitude and its pointwise interval ``(A, lower, upper)`` from the coefficient covariance.

    The predictor η has variance gᵀ Σ g, g = ∂η/∂β (the design row X for forms linear in β); the
    interval η ± z·σ is mapped through the form's link (identity, clipped at 0, for the categorical
    lines; exp for the forms on ln A). The interval of the law's mean: for a new run's amplitude see
    :func:`fivid.friction.predict_amplitude`.
    """
    eta, g = model.predictor_and_gradient(velocity, roughness, normal_load)
    cov = np.asarray(model.covariance, float).reshape(g.shape[1], g.shape[1])
    sigma = np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", np.nan_to_num(g), np.nan_to_num(cov), np.nan_to_num(g)), 0.0))
    lo, hi = eta - z * sigma, eta + z * sigma
    if model.is_log_form:
        return np.exp(eta), np.exp(lo), np.exp(hi)
    return np.maximum(eta, 0.0), np.maximum(lo, 0.0), np.maximum(hi, 0.0)


def measured_peaks(frequency, psd, band, *, prominence_db: float = 6.0, max_peaks: int = 12) -> np.ndarray:
    """Frequencies [Hz] of the clearest peaks of a PSD inside ``band``.

    A peak must stand ``prominence_db`` above its surroundings in 10·log10(PSD): 6 dB is well above
    the scatter of a Welch estimate with tens of averages (its χ² 95 % band is about ±1.5 dB at
    40 averages), so noise ripples are not taken for resonances. The ``max_peaks`` most prominent
    are returned, sorted by frequency.
    """
    from scipy.signal import find_peaks

    f = np.asarray(frequency, float)
    level = 10 * np.log10(np.maximum(np.asarray(psd, float), np.finfo(float).tiny))
    inside = (f >= band[0]) & (f <= band[1])
    idx, props = find_peaks(np.where(inside, level, -np.inf), prominence=prominence_db)
    keep = inside[idx]  # the same mask on the peaks and on their prominences (they are aligned)
    idx, prom = idx[keep], props["prominences"][keep]
    order = np.argsort(prom)[::-1][:max_peaks]
    return np.sort(f[idx[order]])


def _law_section(page: Page, inputs: dict) -> None:
    import xarray as xr

    page.heading("Identified friction law")
    path = inputs.get("law_path")
    if not path:
        page.paragraph("No law was identified in this run.")
        return
    with xr.open_dataset(path, engine="netcdf4") as ds:
        ds = ds.load()
    law = law_from_dataset(ds, source=str(path))
    page.paragraph(_mu0_sentence(ds))
    if ds.attrs.get("law") != "perturbed_coulomb":
        page.paragraph(f"Law: {law.describe()}.")
        return
    band = (float(ds.attrs["band_lower"]), float(ds.attrs["band_upper"]))
    injection = ds.attrs.get("injection", "uniform")
    how = {"uniform": "one signal for the whole contact", "per_node": "an independent signal at each contact node",
           "convected": "a spatial field frozen on the moving surface"}.get(injection, injection)
    page.paragraph(f"Friction perturbation μp: {how} ({injection} injection), with the normalised spectrum s(f) "
                   f"of the next figure over the valid band "
                   f"{band[0]:g}–{band[1]:g} Hz, and an RMS amplitude A(V, Ra, Fn) of the form "
                   f"{law.amplitude_model.form} (coefficients in the table below).")
    if ds.attrs.get("selection_why"):
        page.paragraph(f"Why this form: {ds.attrs['selection_why']}.")
    for warning in filter(None, str(ds.attrs.get("warnings", "")).split("\n")):
        page.paragraph(f"Warning: {warning}.", cls="warning")
    page.figure(law_shape_figure(ds["frequency"].values, ds["shape"].values, band),
                "Normalised spectrum s(f) of the friction perturbation μp (∫ s df = 1 over the valid band).",
                "perturbation spectrum")
    model = law.amplitude_model
    runs = inputs.get("runs", {})
    table_rows = _per_run_amplitudes(ds)
    loads = sorted({r["normal_load"] for r in runs.values()}) or [1.0]
    load = float(np.median(loads))
    rough = sorted({round(r["roughness_ra"], 12) for r in runs.values()})
    vel = [r["sliding_velocity"] for r in runs.values()]
    curves, points = [], []
    if rough and vel:
        v = np.linspace(min(vel) * 0.8, max(vel) * 1.1, 60)
        for ra in rough:
            label = f"Ra {ra * 1e6:.3g} µm"
            a, lo, hi = amplitude_interval(model, v, np.full_like(v, ra), np.full_like(v, load))
            curves.append({"label": label, "velocity": v, "amplitude": a, "lower": lo, "upper": hi})
            sel = [r for r in table_rows if abs(r["roughness_ra"] - ra) <= 0.01 * ra]
            if sel:
                points.append({"label": label, "velocity": [r["sliding_velocity"] for r in sel],
                               "amplitude": [r["amplitude"] for r in sel],
                               "error": [_Z95 * r["stderr"] for r in sel]})
        page.figure(amplitude_figure(curves, points),
                    f"Amplitude A (RMS of μp in the valid band) against sliding velocity, per roughness: "
                    f"fitted {model.form} law (lines) with its pointwise 95 % interval (bands, from the "
                    f"coefficient covariance) and the per-run estimates (circles, ±1.96 standard errors); normal load {load:g} N.",
                    "amplitude against velocity")

    lower = ds["amplitude_ci_lower"].values if "amplitude_ci_lower" in ds else np.full(len(model.names), np.nan)
    upper = ds["amplitude_ci_upper"].values if "amplitude_ci_upper" in ds else np.full(len(model.names), np.nan)
    rows = [[n, coefficient_units(n), float(c), float(s), float(lo), float(hi)]
            for n, c, s, lo, hi in zip(model.names, model.coefficients, model.stderr, lower, upper)]
    page.raw(table(["coefficient", "units", "value", "standard error", "95 % CI lower", "95 % CI upper"], rows))
    if "form" in ds.dims:
        _candidate_forms(page, ds)


def _mu0_sentence(ds) -> str:
    """μ0 with its interval, to as many decimals as the interval needs to show its width (at least 4)."""
    mu0 = ds["mu0"]
    lo, hi = mu0.attrs.get("ci_lower"), mu0.attrs.get("ci_upper")
    if lo is None or not np.isfinite(hi - lo) or hi <= lo:
        return f"μ0 = {float(mu0):.4f}, the mean friction coefficient Ft/Fn of the steady-sliding windows."
    decimals = int(min(8, max(4, np.ceil(-np.log10((hi - lo) / 2)) + 1)))
    return (f"μ0 = {float(mu0):.{decimals}f} (95 % interval {lo:.{decimals}f}–{hi:.{decimals}f}), the mean friction "
            "coefficient Ft/Fn of the steady-sliding windows.")


def _candidate_forms(page: Page, ds) -> None:
    """The candidate amplitude forms, compact: what the choice compared, and why a form was left out."""
    def col(name, i, spec):
        return fmt(_py(ds[name].values[i]), spec) if name in ds else None

    rows = []
    for i in range(ds.sizes["form"]):
        note = " ".join(str(ds[v].values[i]) for v in ("form_reason", "form_cv_reason") if v in ds and
                        str(ds[v].values[i]))
        rows.append([str(ds["form"].values[i]), "chosen" if "form_chosen" in ds and ds["form_chosen"].values[i] else "",
                     int(ds["form_n_params"].values[i]) if "form_n_params" in ds else None,
                     col("form_aicc", i, ".2f"), col("form_delta_aicc", i, ".2f"), col("form_akaike_weight", i, ".3f"),
                     col("form_cv_error", i, ".3f"), note])
    header = ["form", "", "coefficients", "AICc", "ΔAICc", "Akaike weight", "CV error", "not compared because"]
    keep = [j for j in range(len(header)) if j < 2 or any(r[j] not in (None, "") for r in rows)]
    page.paragraph("Candidate amplitude forms. AICc: the small-sample Akaike criterion (lower is better); Akaike "
                   "weight: the relative support of each form; CV error: leave-one-condition-out cross-validation, "
                   "the RMS of ln(A_pred/A) (0.1 ≈ 10 % typical prediction error). AIC, BIC and the log-likelihood "
                   f"are in the law file. Selection rule: {ds.attrs.get('selection_rule', 'not recorded')}.")
    page.raw(table([header[j] for j in keep], [[r[j] for j in keep] for r in rows]))


def _condition_order(item) -> tuple:
    """Sort key of a (condition key, condition) item: numerically by velocity, load, roughness, then the key
    (so that 5 mm/s comes before 10 mm/s, which a string sort of the keys does not give)."""
    key, c = item
    return tuple(float(c.get(k, np.nan)) for k in ("sliding_velocity", "normal_load", "roughness_ra")) + (str(key),)


def _condition_title(c: dict) -> str:
    return f"{c['sliding_velocity'] * 1e3:g} mm/s, {c['normal_load']:g} N, Ra {c['roughness_ra'] * 1e6:g} µm"


def _py(x):
    x = x.item() if hasattr(x, "item") else x
    return float(x) if isinstance(x, (float, np.floating)) else x


def _per_run_amplitudes(ds) -> list[dict]:
    """Per-run (V, Ra, A ± stderr) of the runs the law was fitted on (identify's table, dim ``run``)."""
    need = ("run_mu_rms", "run_sliding_velocity", "run_roughness_ra")
    if "run" not in ds.dims or any(v not in ds for v in need):
        return []
    used = ds["run_used"].values.astype(bool) if "run_used" in ds else np.ones(ds.sizes["run"], bool)
    err = ds["run_mu_rms_stderr"].values if "run_mu_rms_stderr" in ds else np.full(ds.sizes["run"], np.nan)
    return [{"amplitude": float(ds["run_mu_rms"].values[i]), "stderr": float(err[i]),
             "sliding_velocity": float(ds["run_sliding_velocity"].values[i]),
             "roughness_ra": float(ds["run_roughness_ra"].values[i])}
            for i in range(ds.sizes["run"]) if used[i]]


def _condition_sections(page: Page, inputs: dict) -> tuple:
    import xarray as xr

    page.heading("Measured against simulated, per test condition")
    band = inputs["band"]
    law_band = _law_band(inputs.get("law_path"))
    all_f, all_psd, units = None, [], ""
    checks = inputs.get("checks", [])
    for cond, c in sorted(inputs.get("conditions", {}).items(), key=_condition_order):
        page.heading(_condition_title(c), level=3)
        psd_file = inputs.get("psd_files", {}).get(cond)
        if psd_file and Path(psd_file).is_file():
            with xr.open_dataset(psd_file, engine="netcdf4") as ds:
                ds = ds.load()
            f = ds["frequency"].values
            meas = [{"label": f"measured {r}", "psd": ds["psd_measured"].values[i],
                     "lower": ds["psd_measured_lower"].values[i], "upper": ds["psd_measured_upper"].values[i]}
                    for i, r in enumerate(ds["measured_run"].values)]
            sims = [{"label": f"simulated, {s}", "psd": ds["psd_simulated"].values[i],
                     "lower": ds["psd_simulated_lower"].values[i], "upper": ds["psd_simulated_upper"].values[i]}
                    for i, s in enumerate(ds["simulated_seed"].values)]
            units = ds["psd_measured"].attrs.get("units", "")
            page.figure(psd_overlay_figure(f, meas, sims, band, units),
                        f"Acceleration PSD, measured (black) and simulated (colours), with χ² 95 % confidence bands "
                        f"(Welch, nperseg {ds.attrs.get('nperseg')}, {ds.attrs.get('equivalent_averages', 0):.3g} "
                        f"equivalent averages). Shaded: scoring band {band[0]:g}–{band[1]:g} Hz."
                        + _law_band_note(law_band, f, band), f"PSD overlay {cond}")
            all_f = f
            all_psd.extend(m["psd"] for m in meas)
            env_file = inputs.get("envelope_files", {}).get(cond)
            if env_file and Path(env_file).is_file():
                _envelope_figure(page, cond, env_file, f, meas, band, units)
        score_file = inputs.get("score_files", {}).get(cond)
        if score_file and Path(score_file).is_file():
            sc = json.loads(Path(score_file).read_text(encoding="utf-8"))
            rows = [[p["measured"], p["simulated"]] + [_score_cell(k, p["scores"].get(k)) for k in _SCORE_COLUMNS]
                    for p in sc.get("pairs", [])]
            rows.append(["mean", ""] + [_score_cell(k, sc["summary"].get(k)) for k in _SCORE_COLUMNS])
            page.raw(table(["measured run", "simulation"] + [SCORE_NAMES[k] for k in _SCORE_COLUMNS], rows))
        mine = [k for k in checks if k["condition"] == cond]
        if mine:
            page.raw(table(["score", "value (mean)", "threshold", "result"],
                           [[SCORE_NAMES.get(k["score"], k["score"]), _score_cell(k["score"], k["value"]),
                             k["threshold"], bool(k["pass"])] for k in mine]))
    return all_f, all_psd, units


def _law_band(path):
    """The identified law's valid band (lower, upper) [Hz], or None."""
    import xarray as xr

    if not path or not Path(path).is_file():
        return None
    with xr.open_dataset(path, engine="netcdf4") as ds:
        if "band_lower" not in ds.attrs:
            return None
        return float(ds.attrs["band_lower"]), float(ds.attrs["band_upper"])


def _law_band_note(law_band, frequency, band) -> str:
    """A caption sentence for the simulated PSD's drop outside the law's band, when the plot shows it."""
    if law_band is None or frequency is None or not len(frequency):
        return ""
    notes = []
    if law_band[1] < float(np.max(frequency)):
        notes.append(f"Above {law_band[1]:g} Hz the simulated PSD drops: the identified friction law holds no "
                     f"perturbation there (its valid band ends at {law_band[1]:g} Hz), so the simulation is not "
                     "excited above it")
    if not notes:
        return ""
    outside = band[1] <= law_band[1] and band[0] >= law_band[0]
    return " " + "; ".join(notes) + ("; outside the scoring band, not scored." if outside else ".")


def _envelope_figure(page: Page, cond: str, path, frequency, measured: list[dict], band, units: str) -> None:
    """The condition's Monte-Carlo envelope with its measured PSDs, and per 1/3-octave band whether each
    measured level is inside the samples' 5-95 % band levels (:func:`fivid.score.envelope.envelope_coverage`)."""
    env = read_envelope(path).load()
    n = int(env.sizes["sample"])
    page.figure(psd_envelope_figure(env["frequency"].values, env["psd_p05"].values, env["psd_median"].values,
                                    env["psd_p95"].values, n, frequency, measured, band, units),
                f"Monte-Carlo envelope of the simulated acceleration PSD: {n} simulations, each with amplitude-law "
                f"coefficients drawn from the law's covariance and its own seed ({env.attrs.get('not_sampled', '')} "
                f"not sampled). Shaded 5-95 % per frequency, line the median; black the measured PSDs.",
                f"PSD envelope {cond}")
    lo, hi = env["band_lower"].values, env["band_upper"].values
    keep = (lo >= band[0]) & (hi <= band[1])
    if not np.any(keep):
        return
    rows = []
    for m in measured:
        level = band_levels_of_samples(frequency, np.asarray(m["psd"])[None, :], lo[keep], hi[keep])[0]
        cov = envelope_coverage(env, lo[keep], hi[keep], level)
        outside = [f"{c:.4g}" for c, ok in zip(env["band_centre"].values[keep], cov["inside"]) if not ok]
        rows.append([m["label"], f"{int(cov['inside'].sum())} of {cov['inside'].size}", cov["coverage"],
                     ", ".join(outside) or "-"])
    page.raw(table(["measured run", "bands inside the 5-95 % envelope", "coverage [%]", "outside [Hz]"], rows))


_SCORE_COLUMNS = ("lsd_db", "level_diff_db", "band_level_rms_error_db", "shape_correlation")
#: one number format per score, in every table of the report (dB to 0.01, a correlation to 0.001)
_SCORE_FORMATS = {"lsd_db": ".2f", "level_diff_db": "+.2f", "band_level_rms_error_db": ".2f", "shape_correlation": ".3f"}


def _score_cell(score: str, value):
    """A score value in its report format (:data:`_SCORE_FORMATS`; others to 4 significant digits)."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return fmt(float(value), _SCORE_FORMATS.get(score, ".4g"))
    return value
#: the scores (DESIGN §6, fivid.score) as the report names them
SCORE_NAMES = {
    "lsd_db": "log-spectral distance [dB]",
    "level_diff_db": "band level difference, simulated - measured [dB]",
    "band_level_rms_error_db": "RMS error of the 1/3-octave band levels [dB]",
    "shape_correlation": "correlation of the log-PSD shapes [-]",
}


def _modal_section(page: Page, inputs: dict, frequency, psds, units: str) -> None:
    import xarray as xr

    page.heading("Modal frequencies against measured peaks")
    path = inputs.get("modal_path")
    if not path or frequency is None or not psds:
        page.paragraph("No modal analysis or no measured spectrum in this run.")
        return
    with xr.open_dataset(path, engine="netcdf4") as ds:
        modal_f = np.asarray(ds["frequency"].values, float)
    band = inputs["band"]
    mean_psd = np.mean(np.asarray(psds), axis=0)
    peaks = measured_peaks(frequency, mean_psd, band)
    in_band = modal_f[(modal_f >= band[0]) & (modal_f <= band[1])]
    page.figure(modal_figure(frequency, mean_psd, in_band, peaks, band, units),
                "Mean measured acceleration PSD with the model's modal frequencies (dashed) and the measured "
                "peaks (triangles, ≥ 6 dB prominence).", "modes against peaks")
    rows = []
    for i, fm in enumerate(modal_f):
        if not band[0] / 2 <= fm <= 1.5 * band[1]:
            continue  # far outside the analysis band: nothing measured to compare with
        if peaks.size:
            j = int(np.argmin(np.abs(peaks - fm)))
            diff = float((fm - peaks[j]) / peaks[j])
            paired = abs(diff) <= PEAK_PAIRING_TOLERANCE
            rows.append([i + 1, fmt(float(fm), ".0f"), fmt(float(peaks[j]), ".0f"), fmt(100 * diff, "+.1f"),
                         "yes" if paired else f"no: the nearest measured peak is {abs(diff) * 100:.0f} % away, more than "
                         f"{PEAK_PAIRING_TOLERANCE * 100:.0f} %; no measured peak for this mode"])
        else:
            rows.append([i + 1, fmt(float(fm), ".0f"), None, None, "no: no measured peak"])
    page.raw(table(["mode", "model frequency [Hz]", "nearest measured peak [Hz]", "difference [%]", "paired"], rows))
    page.paragraph(f"Modes computed: {modal_f.size} (linearised about the preloaded contact state: normal "
                   f"penalty springs at the slave nodes closed under the normal load, tangentially free, no "
                   f"friction); listed: those between half the band's lower edge and 1.5 times its upper edge. "
                   f"A mode is paired with the nearest measured peak only within {PEAK_PAIRING_TOLERANCE * 100:.0f} %: "
                   f"farther, the nearest peak is another feature of the spectrum, not this mode.")


def _provenance(page: Page, inputs: dict) -> None:
    import yaml

    prov = inputs.get("provenance", {})
    page.heading("Provenance")
    page.raw(table(["software", "version"], _versions()))
    rows = []
    for what in ("pipeline", "config", "model"):
        if what in prov:
            rows.append([what, prov[what].get("path"), prov[what].get("sha256")])
    page.raw(table(["file", "path", "sha256"], rows))
    _discretisation(page, prov.get("discretisation"))
    if prov.get("inputs"):
        page.paragraph("Input files:")
        page.raw(table(["input file", "sha256"], [[k, v] for k, v in sorted(prov["inputs"].items())]))
    if prov.get("settings"):
        page.paragraph("Effective settings: the values this run used, after defaults and command-line overrides "
                       "(SI units):")
        page.raw(table(["setting", "value"], [[k, _setting(v)] for k, v in prov["settings"].items()]))
    if "config" in prov and "content" in prov["config"]:
        page.paragraph("Run configuration as written in the file" + (" (the effective settings above take "
                       "precedence)" if prov.get("settings") else "") + ":")
        page.pre(yaml.safe_dump(prov["config"]["content"], sort_keys=False))


def _discretisation(page: Page, est) -> None:
    """The simulated model's mesh and its estimated discretisation error in the scoring band
    (:func:`fivid.pipeline.discretisation.discretisation_estimate`)."""
    if not est:
        return
    m = est["model"]
    page.paragraph(f"Simulated with model {m['name']} ({m['path']}): largest element side "
                   f"{m['element_size'] * 1e3:.3g} mm, {m['dofs']} dofs, {m['damping']} damping.")
    lo, hi = est["band"]
    _model_error(page, est, lo, hi)
    if not est.get("covered"):
        page.paragraph(f"Discretisation error in the scoring band {lo:g}–{hi:g} Hz: not estimated "
                       f"({est.get('reason', 'no convergence table')}).")
        return
    h = ", ".join(f"{x * 1e3:.3g}" for x in est["element_sizes"])

    def num(key):
        return "n/a" if est.get(key) is None else f"{est[key]:.2g}"
    peaks = "; ".join(f"{p['frequency']:.0f} Hz: {p['shift_hz']:+.1f} Hz ({p['shift_bins']:.2g} bins)"
                      for p in est["peaks"]) or "none in the band"
    level = (f"band level {est['band_level_deviation_db']:+.2f} dB, PSD log-spectral distance to the finest mesh "
             f"{num('band_lsd_db')} dB" if est.get("band_level_deviation_db") is not None else
             f"band level within {num('band_level_error_db')} dB (the largest error of the one-third octaves the "
             f"band overlaps)")
    note = f" Note: {est['note']}" if est.get("note") else ""
    page.paragraph(
        f"Estimated discretisation error in the scoring band {lo:g}–{hi:g} Hz (convergence table "
        f"{est['table']['path']}, meshes {h} mm; against the {est['reference']}): {level}; PSD peak shifts: "
        f"{peaks}; time step: PSD log-spectral distance {num('time_step_lsd_db')} dB from the study's smallest "
        f"step.{note}")
    rows = [[f"{o['band'][0]:.0f}–{o['band'][1]:.0f}", fmt(o["deviation_db"], "+.2f"),
             fmt(o["order"], ".2f") if o["order"] is not None else None, o["reference"]]
            for o in est["third_octaves"]]
    page.raw(table(["one-third octave [Hz]", "level error of this mesh [dB]", "observed order", "against"], rows))


def _model_error(page: Page, est, lo, hi) -> None:
    """The model's estimated error against the data's reference next to the direct check (the scores' level
    differences) and whether the two agree with the verdict (:func:`fivid.pipeline.stages.model_error_estimate`)."""
    if "estimate_db" not in est:
        return
    red = est["reduction"]
    paths = ", ".join(f"{n} {p}" for p, n in sorted(red["paths"].items())) or "none"
    direct = est["direct_check"]
    check = ("no level-difference score" if direct["largest_abs_level_diff_db"] is None else
             f"largest |level difference| simulated vs measured {direct['largest_abs_level_diff_db']:.2f} dB "
             f"(threshold {direct['level_threshold']})")
    total = est["estimate_db"]
    if total is None:
        verdict = "the model's own error is not estimated, so the verdict cannot tell it from the physics"
    elif est.get("consistent"):
        verdict = (f"the estimate is below the {est['level_threshold_db']:g} dB level threshold: the verdict reflects "
                   "the model's physics, not its discretisation")
    elif est.get("level_threshold_db") is not None:
        verdict = (f"the estimate reaches the {est['level_threshold_db']:g} dB level threshold: the verdict may be "
                   "the discretisation's, not the physics'")
    else:
        verdict = "no level threshold to compare it with"
    cont = ("" if est.get("mesh_against_continuum_db") is None else
            f" (the mesh against the extrapolated continuum: {est['mesh_against_continuum_db']:.2f} dB, which matters "
            "for real rig data)")
    page.paragraph(
        f"Model error in the scoring band {lo:g}–{hi:g} Hz: estimated "
        f"{'n/a' if total is None else f'{total:.2g} dB'} against {est['estimate_reference']}{cont}; solver paths: "
        f"{paths}, largest estimated reduction error {red['estimate_db']:.2g} dB (docs/solver.md). Direct check: "
        f"{check}. So {verdict}.")


def _setting(value):
    """A setting for the provenance table: numbers as they are, lists and mappings on one line."""
    if isinstance(value, (list, tuple)):
        return ", ".join(str(_setting(v)) for v in value)
    if isinstance(value, dict):
        return "; ".join(f"{k}: {_setting(v)}" for k, v in value.items())
    return f"{value:g}" if isinstance(value, float) else value


def render_report(path: str | os.PathLike, inputs: dict) -> Path:
    """Write the validation report to ``path`` (atomically); returns the path.

    Parameters
    ----------
    path : path-like
        ``report.html``.
    inputs : dict
        ``title``; ``provenance`` (pipeline/config/model path+sha256, config content, input sha256s);
        ``runs`` and ``conditions`` (as built by the pipeline's ingest stage); ``law_path``;
        ``modal_path``; ``psd_files`` and ``score_files`` per condition; optional ``envelope_files`` per
        condition (Monte-Carlo envelopes, drawn over the measured PSDs); ``band`` [Hz];
        ``checks`` (threshold checks); optional ``synthetic_note`` (the run's description, shown
        highlighted: say there when the inputs are synthetic); optional ``provenance["settings"]``
        (the effective settings, shown above the configuration as written); optional ``generated``
        (the date shown, default now in UTC).
    """
    page = Page(inputs.get("title", "fivid validation report"))
    generated = inputs.get("generated") or _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    page.paragraph(f"Generated {generated} by fivid {__version__}.", cls="generated")
    checks = inputs.get("checks", [])
    ok = bool(checks) and all(c["pass"] for c in checks)
    page.heading("Verdict")
    n_fail = sum(not c["pass"] for c in checks)
    verdict = ("PASS: every score is within its threshold" if ok else
               f"FAIL: {n_fail} of {len(checks)} threshold checks fail" if checks else "NO VERDICT: nothing was scored")
    page.raw(f'<p class="verdict {"pass" if ok else "fail"}">{verdict}</p>')
    if checks:
        conditions = inputs.get("conditions", {})
        order = {k: i for i, (k, _) in enumerate(sorted(conditions.items(), key=_condition_order))}
        rows = [[_condition_title(conditions[c["condition"]]) if c["condition"] in conditions else c["condition"],
                 SCORE_NAMES.get(c["score"], c["score"]), _score_cell(c["score"], c["value"]), c["threshold"],
                 bool(c["pass"])]
                for c in sorted(checks, key=lambda c: order.get(c["condition"], len(order)))]
        page.raw(table(["condition", "score", "value", "threshold", "result"], rows))
    if inputs.get("synthetic_note"):
        page.paragraph(str(inputs["synthetic_note"]), cls="synthetic")
    _law_section(page, inputs)
    f, psds, units = _condition_sections(page, inputs)
    _modal_section(page, inputs, f, psds, units)
    _provenance(page, inputs)
    return write_text(path, page.render())
