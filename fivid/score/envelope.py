"""Monte-Carlo PSD envelopes and whether a measured spectrum lies inside them (issue 16 item 3).

An envelope is the set of PSDs of N simulations of one condition, each with a law drawn from the
identified law's uncertainty and its own seed (:mod:`fivid.identify.montecarlo`). Per frequency it
gives the median and the 5 % and 95 % quantiles (``numpy.quantile``, method ``"linear"``: Hyndman &
Fan type 7); per 1/3-octave band the same quantiles of the *band levels of the samples* (a quantile
of band powers, not the band power of a quantile PSD).

:func:`envelope_coverage` takes the bands a score uses and the measured band levels, and says for
each band whether the measured level lies within [p05, p95] of the samples' levels in that band
(computed on the envelope's own frequency grid with :func:`fivid.signal.levels.bin_weights`: a band
power does not depend on the resolution, only its estimation variance does — recorded when the
resolutions differ). A run drawn from the same distribution falls inside a 90 % band with
probability ≈ 0.9 (exactly (N - 1 - 2 ⌊0.05 (N - 1)⌋) / (N + 1) for the type-7 quantiles of N
exchangeable samples when 0.05 (N - 1) is an integer).
"""

from __future__ import annotations

import numpy as np

from fivid import __version__
from fivid.errors import ConfigError, SchemaError
from fivid.friction import coefficient_units
from fivid.schema import new_history
from fivid.score.runs import _BAND_HIGH_FRACTION, _BAND_LOW_BINS
from fivid.signal.levels import bin_weights, third_octave_weights
from fivid.units import power_units

__all__ = ["QUANTILES", "psd_quantiles", "envelope_dataset", "band_levels_of_samples", "envelope_coverage",
           "add_envelope_coverage", "read_envelope", "ENVELOPE_TITLE"]

#: the quantiles of an envelope: lower edge, median, upper edge
QUANTILES = (0.05, 0.5, 0.95)
QUANTILE_METHOD = "linear"
ENVELOPE_TITLE = "fivid Monte-Carlo PSD envelope"


def psd_quantiles(samples, quantiles=QUANTILES) -> np.ndarray:
    """Quantiles over the samples (axis 0) [same units as ``samples``], shape (len(quantiles), ...)."""
    x = np.asarray(samples, dtype=float)
    if x.ndim < 1 or x.shape[0] < 2:
        raise ConfigError(f"quantiles over {x.shape[0] if x.ndim else 0} sample(s); an envelope needs at least 2")
    return np.quantile(x, np.asarray(quantiles, dtype=float), axis=0, method=QUANTILE_METHOD)


def _band_weights(frequency, lower, upper) -> np.ndarray:
    f = np.asarray(frequency, dtype=float)
    lower, upper = np.atleast_1d(np.asarray(lower, float)), np.atleast_1d(np.asarray(upper, float))
    if not lower.size:
        return np.zeros((f.size, 0))
    return np.stack([bin_weights(f, lo, hi) for lo, hi in zip(lower, upper)], axis=-1)


def band_levels_of_samples(frequency, psd_samples, lower, upper) -> np.ndarray:
    """Band power levels ``10 log10(∫_band P df)`` [dB re 1 u²] of each sample (rows) in each band, (n, n_bands)."""
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(np.asarray(psd_samples, float) @ _band_weights(frequency, lower, upper))


def envelope_dataset(frequency, psd_samples, units: str, *, band=None, seeds=None, coefficients=None,
                     coefficient_names=None, amplitudes=None, attrs: dict | None = None):
    """The envelope file's Dataset from the samples' PSDs.

    Parameters
    ----------
    frequency : ndarray (n_f,)
        [Hz], uniform from 0.
    psd_samples : ndarray (n, n_f)
        One-sided PSD of each sample [u2 Hz-1].
    units : str
        CF units of the signal [u].
    band : (float, float), optional
        Band [Hz] of the stored 1/3-octave band levels; default the score's default band (4 bins to 80 % of
        the Nyquist frequency).
    seeds, coefficients, coefficient_names, amplitudes
        Per sample: synthesis seed, drawn amplitude-law coefficients (n, p) and their names, amplitude A [-].
    attrs : dict, optional
        Provenance and settings (merged into the global attributes).
    """
    import xarray as xr

    f = np.asarray(frequency, dtype=float)
    p = np.asarray(psd_samples, dtype=float)
    if p.ndim != 2 or p.shape[1] != f.size:
        raise ConfigError(f"PSD samples of shape {p.shape} do not match {f.size} frequencies")
    n = p.shape[0]
    df = f[1] - f[0]
    if band is None:
        band = (_BAND_LOW_BINS * df, _BAND_HIGH_FRACTION * f[-1])
    bands, weights = third_octave_weights(f, float(band[0]), float(band[1]), min_bins=1.0)
    with np.errstate(divide="ignore"):
        levels = 10.0 * np.log10(p @ weights)
    q_psd = psd_quantiles(p)
    q_lev = psd_quantiles(levels) if levels.shape[1] else np.zeros((3, 0))
    pu = power_units(units)
    db = {"units": "dB", "reference": f"1 {units}"}
    names = [str(x) for x in (coefficient_names or [])]
    data = {
        "psd_median": ("frequency", q_psd[1], {"units": pu, "long_name": "median over the samples of the PSD"}),
        "psd_p05": ("frequency", q_psd[0], {"units": pu, "long_name": "5 % quantile over the samples of the PSD"}),
        "psd_p95": ("frequency", q_psd[2], {"units": pu, "long_name": "95 % quantile over the samples of the PSD"}),
        "psd_sample": (("sample", "frequency"), p, {"units": pu, "long_name": "PSD of each Monte-Carlo sample"}),
        "band_level_sample": (("sample", "band_centre"), levels,
                              {**db, "long_name": "1/3-octave band power level of each sample"}),
        "band_level_median": ("band_centre", q_lev[1], {**db, "long_name": "median of the samples' band levels"}),
        "band_level_p05": ("band_centre", q_lev[0], {**db, "long_name": "5 % quantile of the samples' band levels"}),
        "band_level_p95": ("band_centre", q_lev[2], {**db, "long_name": "95 % quantile of the samples' band "
                                                     "levels"}),
    }
    if seeds is not None:
        data["sample_seed"] = ("sample", np.asarray(seeds, dtype=np.int64), {"long_name": "synthesis seed of the "
                                                                             "sample's friction perturbation"})
    if amplitudes is not None:
        data["sample_amplitude"] = ("sample", np.asarray(amplitudes, float),
                                    {"units": "1", "long_name": "RMS of mu_p of the sample's law at the condition"})
    coords = {
        "frequency": ("frequency", f, {"units": "Hz", "long_name": "frequency"}),
        "sample": ("sample", np.arange(n), {"units": "1", "long_name": "Monte-Carlo sample index"}),
        "band_centre": ("band_centre", bands["centre"], {"units": "Hz", "long_name": "IEC 61260-1 base-10 exact "
                                                         "mid-band frequency"}),
        "band_lower": ("band_centre", bands["lower"], {"units": "Hz", "long_name": "lower band-edge frequency"}),
        "band_upper": ("band_centre", bands["upper"], {"units": "Hz", "long_name": "upper band-edge frequency"}),
    }
    if coefficients is not None and names:
        data["sample_coefficient"] = (("sample", "coefficient"), np.asarray(coefficients, float).reshape(n, len(names)),
                                      {"long_name": "amplitude-law coefficients drawn for the sample"})
        data["coefficient_units"] = ("coefficient", np.array([coefficient_units(c) for c in names], dtype=object),
                                     {"long_name": "CF units of each amplitude-law coefficient"})
        coords["coefficient"] = ("coefficient", np.array(names, dtype=object),
                                 {"long_name": "amplitude-law coefficient name"})
    ds = xr.Dataset(data, coords=coords)
    ds.attrs = {
        "title": ENVELOPE_TITLE,
        "Conventions": "CF-1.8",
        "n_samples": n,
        "quantiles": np.asarray(QUANTILES, float),
        "quantile_method": f"numpy.quantile method '{QUANTILE_METHOD}' (Hyndman & Fan type 7)",
        "variable_units": units,
        "band_lower": float(band[0]),
        "band_upper": float(band[1]),
        "band_units": "Hz",
        "frequency_resolution": float(df),
        **(attrs or {}),
    }
    if "history" not in ds.attrs:
        ds.attrs["history"] = new_history(f"envelope of {n} Monte-Carlo PSDs")

    ds.attrs["fivid_version"] = __version__
    return ds


def read_envelope(path):
    """An envelope file (netCDF) as a Dataset; a file that is not one is a SchemaError naming it."""
    from pathlib import Path

    from fivid.io.netcdf import read_run  # lazy: pulls pydantic

    ds = read_run(Path(path), validate=False)
    missing = [v for v in ("psd_sample", "psd_p05", "psd_p95", "psd_median") if v not in ds]
    if ds.attrs.get("title") != ENVELOPE_TITLE or missing:
        raise SchemaError(f"not a fivid Monte-Carlo envelope (title {ds.attrs.get('title')!r}"
                          + (f", missing {', '.join(missing)}" if missing else "")
                          + "); write one with 'fivid simulate MODEL --law LAW.nc --samples N -o ENV.nc'", file=path)
    return ds


def envelope_coverage(envelope, band_lower, band_upper, measured_db) -> dict:
    """Whether each measured band level lies inside the envelope's 5-95 % band levels.

    Parameters
    ----------
    envelope : xarray.Dataset
        From :func:`envelope_dataset` (``psd_sample`` on ``frequency``).
    band_lower, band_upper : array_like (n_bands,)
        Band edges [Hz] (those of the score).
    measured_db : array_like (n_bands,)
        Measured band power levels [dB re 1 u²].

    Returns
    -------
    dict
        ``p05``, ``median``, ``p95`` [dB] of the samples' levels per band, ``inside`` (bool per band),
        ``coverage`` [%] (share of the bands inside; NaN without bands).
    """
    lev = band_levels_of_samples(envelope["frequency"].values, envelope["psd_sample"].values, band_lower, band_upper)
    m = np.asarray(measured_db, float)
    if lev.shape[1] == 0:
        empty = np.zeros(0)
        return {"p05": empty, "median": empty, "p95": empty, "inside": np.zeros(0, bool), "coverage": float("nan")}
    q = psd_quantiles(lev)
    inside = (m >= q[0]) & (m <= q[2])
    return {"p05": q[0], "median": q[1], "p95": q[2], "inside": inside, "coverage": float(100.0 * inside.mean())}


def add_envelope_coverage(scores, envelope, *, envelope_file: str = ""):
    """The scores (from :func:`fivid.score.score_runs`) with the envelope's coverage of the measured band levels.

    Adds per band (dim ``band_centre``) ``envelope_band_level_p05``/``_median``/``_p95`` [dB] and
    ``envelope_inside`` (0/1), the scalar ``envelope_coverage`` [%], and attrs naming the envelope.

    Raises
    ------
    SchemaError
        The envelope is of another variable or in other units than the scores.
    """
    var, units = scores.attrs.get("variable"), scores.attrs.get("variable_units")
    if envelope.attrs.get("variable") not in (None, var) or envelope.attrs.get("variable_units") != units:
        raise SchemaError(f"the envelope {envelope_file} is of {envelope.attrs.get('variable')!r} in "
                          f"{envelope.attrs.get('variable_units')!r}, the scores of {var!r} in {units!r}; simulate "
                          "the envelope for the scored variable (--variable)")
    cov = envelope_coverage(envelope, scores["band_lower"].values, scores["band_upper"].values,
                            scores["band_level_measured_db"].values)
    db = {"units": "dB"}
    out = scores.copy()
    for key, name in (("p05", "5 % quantile"), ("median", "median"), ("p95", "95 % quantile")):
        out[f"envelope_band_level_{key}"] = ("band_centre", cov[key],
                                             {**db, "long_name": f"{name} of the Monte-Carlo samples' band levels"})
    out["envelope_inside"] = ("band_centre", cov["inside"].astype(np.int8), {
        "long_name": "measured band level within the 5-95 % Monte-Carlo envelope",
        "flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "outside inside"})
    out["envelope_coverage"] = ((), cov["coverage"], {"units": "percent", "long_name": "share of the 1/3-octave "
                                                      "bands whose measured level is inside the envelope"})
    env_df = float(envelope.attrs.get("frequency_resolution", np.nan))
    out.attrs.update({
        "envelope_file": str(envelope_file),
        "envelope_n_samples": int(envelope.sizes["sample"]),
        "envelope_quantiles": "0.05 0.95",
        "envelope_frequency_resolution": env_df,
        "envelope_resolution_note": ("same resolution as the scores" if np.isclose(env_df, scores.attrs.get(
            "frequency_resolution", np.nan)) else "the envelope's resolution differs from the scores': band powers "
            "agree, but their estimation variance differs"),
    })
    for key in ("law_file_sha256", "law_sha256", "seed"):
        if key in envelope.attrs:
            out.attrs[f"envelope_{key}"] = envelope.attrs[key]
    return out
