"""Scores as JSON: the keys of issue 3 at the top level, with thresholds and flags beside them."""

from __future__ import annotations

import math

__all__ = ["scores_to_json", "envelope_to_json", "SCALAR_SCORES"]

SCALAR_SCORES = ("lsd_db", "level_diff_db", "band_level_rms_error_db", "shape_correlation")


def _num(x):
    v = float(x)
    return v if math.isfinite(v) else None


def scores_to_json(scores) -> dict:
    """A JSON-ready dict of a scores Dataset from :func:`fivid.score.score_runs`.

    Keys: ``lsd_db``, ``level_diff_db``, ``band_level_rms_error_db``, ``shape_correlation`` (numbers,
    null when undefined); ``significant`` and ``thresholds`` (per score); ``band_level_error_db``
    (per 1/3-octave band); ``peaks`` (matched peaks); ``measured``, ``simulated``, ``variable``,
    ``units``, ``band_hz`` and ``settings``; ``envelope`` when the scores hold a Monte-Carlo envelope's
    coverage (:func:`envelope_to_json`).
    """
    out: dict = {name: _num(scores[name]) for name in SCALAR_SCORES}
    out["significant"] = {name: bool(scores[f"{name}_significant"]) for name in SCALAR_SCORES}
    out["thresholds"] = {name: _num(scores[f"{name}_threshold"]) for name in SCALAR_SCORES}
    out["shape_correlation_expected"] = _num(scores["shape_correlation_expected"])
    out["band_level_error_db"] = [
        {"centre_hz": _num(c), "lower_hz": _num(lo), "upper_hz": _num(hi), "error_db": _num(e),
         "threshold_db": _num(t), "significant": bool(s)}
        for c, lo, hi, e, t, s in zip(scores["band_centre"].values, scores["band_lower"].values,
                                      scores["band_upper"].values, scores["band_level_error_db"].values,
                                      scores["band_level_error_db_threshold"].values,
                                      scores["band_level_error_db_significant"].values)
    ]
    out["peaks"] = [
        {"frequency_measured_hz": _num(fm), "frequency_simulated_hz": _num(fs), "frequency_relative_error": _num(fe),
         "frequency_relative_threshold": _num(ft), "frequency_significant": bool(fsig),
         "level_diff_db": _num(ld), "level_threshold_db": _num(lt),
         "level_significant": bool(lsig)}
        for fm, fs, fe, ft, fsig, ld, lt, lsig in zip(
            scores["peak_frequency_measured"].values, scores["peak_frequency_simulated"].values,
            scores["peak_frequency_error"].values, scores["peak_frequency_error_threshold"].values,
            scores["peak_frequency_error_significant"].values,
            scores["peak_level_diff_db"].values, scores["peak_level_diff_db_threshold"].values,
            scores["peak_level_diff_db_significant"].values)
    ]
    a = scores.attrs
    if "envelope_coverage" in scores:
        out["envelope"] = envelope_to_json(scores)
    out["measured"] = a.get("measured_run_id")
    out["simulated"] = a.get("simulated_run_id")
    out["variable"] = a.get("variable")
    out["units"] = a.get("variable_units")
    out["band_hz"] = [_num(a["band_lower"]), _num(a["band_upper"])]
    out["settings"] = {k: a[k] for k in ("sample_rate", "nperseg", "nperseg_rule", "noverlap", "window", "detrend", "confidence",
                                         "frequency_resolution", "measured_equivalent_degrees_of_freedom",
                                         "simulated_equivalent_degrees_of_freedom", "resampled", "peak_prominence_db",
                                         "peak_match_tolerance", "steady_only") if k in a}
    return out


def envelope_to_json(scores) -> dict:
    """The envelope part of the scores' JSON: ``coverage_percent``, ``inside_count``, ``n_samples``, the file,
    and per band ``centre_hz``, ``measured_db``, ``p05_db``, ``median_db``, ``p95_db``, ``inside``."""
    a = scores.attrs
    inside = scores["envelope_inside"].values.astype(bool)
    return {
        "file": a.get("envelope_file"),
        "n_samples": int(a.get("envelope_n_samples", 0)),
        "coverage_percent": _num(scores["envelope_coverage"]),
        "inside_count": int(inside.sum()),
        "quantiles": [0.05, 0.95],
        "resolution_note": a.get("envelope_resolution_note"),
        "bands": [{"centre_hz": _num(c), "measured_db": _num(m), "p05_db": _num(lo), "median_db": _num(md),
                   "p95_db": _num(hi), "inside": bool(i)}
                  for c, m, lo, md, hi, i in zip(scores["band_centre"].values, scores["band_level_measured_db"].values,
                                                  scores["envelope_band_level_p05"].values,
                                                  scores["envelope_band_level_median"].values,
                                                  scores["envelope_band_level_p95"].values, inside)],
    }
