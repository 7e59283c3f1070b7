"""Scores of a simulated run against a measured one (DESIGN §6), each with its uncertainty judgement.

Both runs are brought to one frequency grid (the lower of the two sampling rates, polyphase
resampling of the other; the same ``nperseg``), their Welch PSDs compared over ``[f_lo, f_hi]``, and
every score compared with the threshold two estimates of one spectrum would stay under with
probability ``confidence`` (:mod:`fivid.score.uncertainty`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError, SchemaError, UnitError
from fivid.schema import apply_cf_attrs, new_history
from fivid.score.metrics import shape_correlation
from fivid.score.uncertainty import (
    correlation_ceiling,
    log_psd_bias_db,
    log_psd_std_db,
    relative_power_std,
    rms_threshold_db,
)
from fivid.signal.compare import band_levels_db, level_difference_db, log_psd_db, log_spectral_distance
from fivid.signal.levels import bin_weights, third_octave_weights
from fivid.signal.peaks import match_peaks, refine_peak, spectral_peaks
from fivid.signal.resample import resample_to
from fivid.signal.sampling import run_label, sample_rate_of
from fivid.signal.spectral import bin_correlation, bin_degrees_of_freedom, check_nperseg, segment_window
from fivid.signal.steady import steady_part
from fivid.signal.welch import NPERSEG_RULE, default_nperseg, welch_psd
from fivid.units import power_units

__all__ = ["score_runs", "WelchOptions", "PeakMatching"]

_DB = 10.0 / np.log(10.0)
# Default band: from 4 bins (below, the Hann leakage of the removed mean and of drifts dominates) to
# 80 % of the lower Nyquist frequency (anti-aliasing filters of DAQs and of resample_poly roll off above).
_BAND_LOW_BINS = 4
_BAND_HIGH_FRACTION = 0.8


def _label(ds, role: str) -> str:
    return f"{role} {run_label(ds, default='run')}"


def _signal(ds, variable: str, sensor, label: str):
    if variable not in ds.data_vars:
        raise SchemaError(f"{label} has no variable {variable!r}; it has: {', '.join(sorted(map(str, ds.data_vars)))}")
    da = ds[variable]
    if "sensor" in da.dims:
        names = [str(s) for s in da["sensor"].values] if "sensor" in da.coords else list(range(da.sizes["sensor"]))
        if sensor is None and len(names) == 1:
            da = da.isel(sensor=0)
        elif sensor is None or str(sensor) not in map(str, names):
            raise ConfigError(f"{label}: {variable!r} has sensors {names}; choose one with sensor= (--sensor), "
                              f"got {sensor!r}", key="sensor")
        else:
            da = da.isel(sensor=[str(s) for s in names].index(str(sensor)))
        da = da.drop_vars("sensor", errors="ignore")
    if not isinstance(da.attrs.get("units"), str):
        raise UnitError(f"{label}: variable {variable!r} has no 'units' attribute")
    return da


def _band(band, fs: float, nperseg: int, labels_rates) -> tuple[float, float]:
    df = fs / nperseg
    if band is None:
        return _BAND_LOW_BINS * df, _BAND_HIGH_FRACTION * fs / 2
    try:
        f_lo, f_hi = (float(b) for b in band)
    except (TypeError, ValueError):
        raise ConfigError(f"band must be two numbers (f_lo, f_hi) [Hz], got {band!r}", key="band") from None
    if not (np.isfinite(f_lo) and np.isfinite(f_hi) and 0 <= f_lo < f_hi):
        raise ConfigError(f"band [{f_lo!r}, {f_hi!r}] Hz must satisfy 0 <= f_lo < f_hi", key="band")
    for label, rate in labels_rates:
        if f_hi > rate / 2:
            raise ConfigError(f"band upper frequency {f_hi!r} Hz is beyond the Nyquist frequency {rate / 2!r} Hz "
                              f"of the {label} (sampled at {rate!r} Hz)", key="band")
    if f_hi - f_lo < 3 * df:
        raise ConfigError(f"band [{f_lo!r}, {f_hi!r}] Hz spans fewer than 3 PSD bins of {df!r} Hz "
                          f"(fs {fs!r} Hz / nperseg {nperseg}); widen it or raise nperseg", key="band")
    return f_lo, f_hi


@dataclass(frozen=True)
class WelchOptions:
    """The Welch settings of the scores besides the segment length (:func:`fivid.signal.welch_psd`).

    Attributes
    ----------
    noverlap : int or None
        Overlap of consecutive segments [samples]; None: 50 %.
    window : str
        Taper (default Hann).
    detrend : {"constant", "linear", "none"}
        Per-segment detrending (default constant).
    backend : {"pyfftw", "numpy"} or None
        FFT implementation (None: pyfftw when available).
    """

    noverlap: int | None = None
    window: str = "hann"
    detrend: str = "constant"
    backend: str | None = None


@dataclass(frozen=True)
class PeakMatching:
    """How the peaks of the two PSDs are found and paired.

    Attributes
    ----------
    prominence_db : float or None
        Prominence of peaks on the log-PSD [dB]; None: ``max(3, 6 σ)`` with σ the standard deviation of one
        estimate's log-PSD, so that noise seldom makes a peak.
    match_tolerance : float
        A simulated peak matches a measured one within this relative frequency distance [-] (default 0.2).
    max_peaks : int
        Most prominent measured peaks to match (default 10).
    """

    prominence_db: float | None = None
    match_tolerance: float = 0.2
    max_peaks: int = 10


def score_runs(measured, simulated, *, variable="acceleration", band=None, nperseg=None, sensor=None, steady=False,
               confidence=0.95, welch: WelchOptions = WelchOptions(), peak_matching: PeakMatching = PeakMatching()):
    """PSD scores of a simulated run against a measured one over a frequency band.

    Parameters
    ----------
    measured, simulated : xarray.Dataset
        RunDatasets with ``variable`` on a uniform ``time`` [s] in the same units.
    variable : str, default "acceleration"
        Variable to compare.
    band : (float, float), optional
        ``(f_lo, f_hi)`` [Hz]; default from 4 PSD bins to 80 % of the lower Nyquist frequency.
        ``f_hi`` beyond either run's Nyquist frequency is an error.
    nperseg : int, optional
        Welch segment length [samples] at the common rate; default
        :func:`fivid.signal.welch.default_nperseg` of the shorter record at the common rate (the same for
        both runs). The scores' attrs ``nperseg`` and ``nperseg_rule`` say which was used.
    sensor : str, optional
        Which sensor when ``variable`` has a ``sensor`` dimension with several.
    steady : bool, default False
        Crop each run to its steady part first (:func:`fivid.signal.steady_part`: a measured run to its
        steady-sliding window, a simulated run to ``time >= transient_end``).
    confidence : float, default 0.95
        Probability that scores of two estimates of the same spectrum stay under their thresholds.
    welch : WelchOptions
        The other Welch settings (:func:`fivid.signal.welch_psd`); default 50 % overlap, Hann, constant detrend.
    peak_matching : PeakMatching
        Peak prominence [dB] (default from the estimator's spread), relative frequency tolerance of a match [-] and
        the most measured peaks matched.

    Returns
    -------
    xarray.Dataset
        Scalars ``lsd_db``, ``level_diff_db``, ``band_level_rms_error_db``, ``shape_correlation``, each
        with ``<name>_threshold`` and ``<name>_significant``; per 1/3-octave band (dim ``band_centre``)
        ``band_level_error_db`` with thresholds; per matched peak (dim ``peak``) frequencies, relative
        frequency error and level difference with flags; the two band-limited PSDs on ``frequency``.
        Attrs record both runs, every setting and the degrees of freedom.

    Raises
    ------
    SchemaError, UnitError
        A run lacks ``variable``, or the runs' units differ.
    ConfigError
        A band beyond a Nyquist frequency or narrower than 3 bins; rates without a rational ratio.
    DataQualityError
        NaN, non-uniform time, a record shorter than one segment (naming the run and the value).
    """
    from scipy.stats import norm

    noverlap, window, detrend, backend = welch.noverlap, welch.window, welch.detrend, welch.backend
    peak_prominence_db, peak_match_tolerance = peak_matching.prominence_db, peak_matching.match_tolerance
    max_peaks = peak_matching.max_peaks
    nperseg_given = nperseg is not None
    if nperseg_given:
        nperseg = check_nperseg(nperseg)
    lm, ls = _label(measured, "measured"), _label(simulated, "simulated")
    if steady:
        measured, simulated = steady_part(measured, label=lm), steady_part(simulated, label=ls)
    da_m, da_s = _signal(measured, variable, sensor, lm), _signal(simulated, variable, sensor, ls)
    if sensor is not None and not any("sensor" in ds[variable].dims for ds in (measured, simulated)):
        raise ConfigError(f"sensor {sensor!r} given, but {variable!r} has no 'sensor' dimension in the {lm} nor "
                          f"in the {ls}; drop sensor= (--sensor)", key="sensor")
    if da_m.attrs["units"] != da_s.attrs["units"]:
        raise UnitError(f"{variable!r} is in {da_m.attrs['units']!r} in the {lm} but in {da_s.attrs['units']!r} "
                        f"in the {ls}; convert one (fivid stores SI units from the registry)")
    fs_m = sample_rate_of(da_m["time"].values, label=lm, declared=measured.attrs.get("sample_rate"))
    fs_s = sample_rate_of(da_s["time"].values, label=ls, declared=simulated.attrs.get("sample_rate"))
    fs = min(fs_m, fs_s)
    if not nperseg_given:  # one rule, on the shorter record at the common rate, so both PSDs share one grid
        nperseg = default_nperseg(fs, min(da_m.sizes["time"] * fs / fs_m, da_s.sizes["time"] * fs / fs_s))
    f_lo, f_hi = _band(band, fs, int(nperseg), [(lm, fs_m), (ls, fs_s)])
    resampled = "none"
    if abs(fs_m / fs_s - 1) > 1e-9:
        if fs_m > fs:
            da_m = resample_to(da_m.to_dataset(name=variable).assign_attrs(measured.attrs), fs)[variable]
            resampled = f"measured {fs_m:.10g} Hz -> {fs:.10g} Hz"
        else:
            da_s = resample_to(da_s.to_dataset(name=variable).assign_attrs(simulated.attrs), fs)[variable]
            resampled = f"simulated {fs_s:.10g} Hz -> {fs:.10g} Hz"
    settings = dict(nperseg=int(nperseg), noverlap=noverlap, window=window, detrend=detrend, confidence=confidence,
                    backend=backend)
    psd_m = welch_psd(da_m, fs=fs, label=lm, **settings)
    psd_s = welch_psd(da_s, fs=fs, label=ls, **settings)

    f = psd_m["frequency"].values
    df = f[1] - f[0]
    pm, ps = psd_m.values, psd_s.values
    nu_m, nu_s = psd_m.attrs["equivalent_degrees_of_freedom"], psd_s.attrs["equivalent_degrees_of_freedom"]
    dof_m, dof_s = bin_degrees_of_freedom(nu_m, int(nperseg)), bin_degrees_of_freedom(nu_s, int(nperseg))
    r = bin_correlation(segment_window(window, int(nperseg)))
    z2 = norm.ppf(0.5 + confidence / 2.0)  # two-sided
    inband = (f >= f_lo) & (f <= f_hi)
    fb, pmb, psb = f[inband], pm[inband], ps[inband]
    log_m, log_s = log_psd_db(pmb, label=f"{lm}: {variable}"), log_psd_db(psb, label=f"{ls}: {variable}")
    diff = log_s - log_m
    sig_m, sig_s = log_psd_std_db(dof_m[inband]), log_psd_std_db(dof_s[inband])
    sigma = np.hypot(sig_m, sig_s)
    bias = log_psd_bias_db(dof_s[inband]) - log_psd_bias_db(dof_m[inband])

    lsd = log_spectral_distance(pmb, psb)
    lsd_thr = rms_threshold_db(sigma, bias, confidence, r)

    level, level_thr = _level_difference(pm, ps, bin_weights(f, f_lo, f_hi), dof_m, dof_s, r, z2)
    bands, lev_m, lev_s, band_sd = _third_octave_levels(pm, ps, f, f_lo, f_hi, dof_m, dof_s, r)
    band_err = lev_s - lev_m
    if band_err.size:
        band_rms = float(np.sqrt(np.mean(band_err**2)))
        band_rms_thr = rms_threshold_db(band_sd, np.zeros_like(band_sd), confidence)
    else:
        band_rms = band_rms_thr = float("nan")

    corr = shape_correlation(pmb, psb)
    n_eff = fb.size / (1.0 + 2.0 * float(np.sum(r[1:])))
    corr_expected, corr_lowest = correlation_ceiling(log_m, log_s, float(np.median(sig_m)), float(np.median(sig_s)),
                                                     confidence, n_eff)

    sigma_one = float(max(np.max(sig_m), np.max(sig_s)))
    prominence = max(3.0, 6.0 * sigma_one) if peak_prominence_db is None else float(peak_prominence_db)
    peaks = _peaks(fb, log_m, log_s, sig_m, sig_s, bias, r, z2, prominence=prominence,
                   tolerance=peak_match_tolerance, max_peaks=max_peaks)

    results = dict(
        band_err=band_err,
        band_rms=band_rms,
        band_rms_thr=band_rms_thr,
        band_sd=band_sd,
        bands=bands,
        confidence=confidence,
        corr=corr,
        corr_expected=corr_expected,
        corr_lowest=corr_lowest,
        df=df,
        diff=diff,
        f_hi=f_hi,
        f_lo=f_lo,
        fb=fb,
        fs=fs,
        lev_m=lev_m,
        lev_s=lev_s,
        level=level,
        level_thr=level_thr,
        lsd=lsd,
        lsd_thr=lsd_thr,
        n_eff=n_eff,
        nu_m=nu_m,
        nu_s=nu_s,
        peak_match_tolerance=peak_match_tolerance,
        peaks=peaks,
        pmb=pmb,
        prominence=prominence,
        psb=psb,
        psd_m=psd_m,
        psd_s=psd_s,
        resampled=resampled,
        sensor=sensor,
        sigma=sigma,
        steady=steady,
        nperseg_rule="given" if nperseg_given else NPERSEG_RULE,
        z2=z2,
    )
    return _assemble(results, measured=measured, simulated=simulated, variable=variable, units=da_m.attrs["units"])


def _level_difference(pm, ps, weights, dof_m, dof_s, r, z2) -> tuple[float, float]:
    """Band level difference [dB] and its two-sided threshold (z times the combined std of the two levels)."""
    level = level_difference_db(pm, ps, weights)
    sd = _DB * np.hypot(relative_power_std(pm, weights, dof_m, r), relative_power_std(ps, weights, dof_s, r))
    return level, float(z2 * sd)


def _third_octave_levels(pm, ps, f, f_lo, f_hi, dof_m, dof_s, r):
    """IEC 1/3-octave bands inside the band, the two runs' band levels [dB] and the std of their difference."""
    # a band narrower than one bin would rest on a fraction of one estimate
    bands, wb = third_octave_weights(f, f_lo, f_hi, min_bins=1.0)
    if not bands["centre"].size:
        empty = np.zeros(0)
        return bands, empty, empty, empty
    sd = _DB * np.hypot(relative_power_std(pm, wb, dof_m, r), relative_power_std(ps, wb, dof_s, r))
    return bands, band_levels_db(pm, wb), band_levels_db(ps, wb), sd


def _peaks(fb, log_m, log_s, sig_m, sig_s, bias, r, z2, *, prominence, tolerance, max_peaks) -> dict:
    """Matched peaks: refined frequencies [Hz], log-PSD levels [dB] and thresholds of their differences."""
    pairs = match_peaks(fb, spectral_peaks(log_m, prominence_db=prominence, max_peaks=max_peaks),
                        spectral_peaks(log_s, prominence_db=prominence), relative_tolerance=tolerance)
    im, js = pairs[:, 0], pairs[:, 1]
    matched = js >= 0
    jj = np.where(matched, js, 0)
    nan = np.nan
    inflation = 1.0 + 2.0 * float(np.sum(r[1:]))
    fit_m = np.array([refine_peak(fb, log_m, i, sig_m[i], inflation) for i in im]).reshape(-1, 2)
    fit_s = np.array([refine_peak(fb, log_s, j, sig_s[j], inflation) if j >= 0 else (nan, nan)
                      for j in js]).reshape(-1, 2)
    df = fb[1] - fb[0]
    return {
        "fm": fit_m[:, 0],
        "fs": fit_s[:, 0],
        # z times the combined standard error of the two peak frequencies, never below one bin
        "freq_thr": np.maximum(z2 * np.hypot(fit_m[:, 1], fit_s[:, 1]), df),
        "lm": log_m[im],
        "ls": np.where(matched, log_s[jj], nan),
        "level_thr": np.abs(bias[im]) + z2 * np.hypot(sig_m[im], np.where(matched, sig_s[jj], nan)),
    }


def _flag(value, threshold, larger_is_bad=True):
    value, threshold = np.asarray(value, dtype=float), np.asarray(threshold, dtype=float)
    with np.errstate(invalid="ignore"):
        out = value > threshold if larger_is_bad else value < threshold
    return np.where(np.isfinite(value) & np.isfinite(threshold), out, False)


_THRESHOLD = "{} of two estimates of one spectrum is below this with probability 'confidence'"


def _significant(score: str, side: str = "above") -> dict:
    """CF attrs of a significance flag (stored as 0/1: xarray writes booleans as int8)."""
    return {"long_name": f"{score} {side} its threshold: significant at the 'confidence' level",
            "flag_values": np.array([0, 1], dtype=np.int8), "flag_meanings": "within_uncertainty significant"}


def _assemble(v: dict, *, measured, simulated, variable, units):
    import xarray as xr

    psd_units = power_units(units)
    db = {"units": "dB"}
    pk = v["peaks"]
    ds = xr.Dataset(
        {
            "lsd_db": ((), v["lsd"], {**db, "long_name": "log-spectral distance: RMS of 10 log10(P_sim/P_meas) "
                                      "over the band"}),
            "lsd_db_threshold": ((), v["lsd_thr"], {**db, "long_name": "lsd of two estimates of one spectrum is "
                                                    "below this with probability 'confidence'"}),
            "lsd_db_significant": ((), _flag(v["lsd"], v["lsd_thr"]), _significant("lsd_db")),
            "level_diff_db": ((), v["level"], {**db, "long_name": "10 log10 of band power ratio sim/meas"}),
            "level_diff_db_threshold": ((), v["level_thr"], {**db,
                                                             "long_name": "two-sided threshold of |level_diff_db|"}),
            "level_diff_db_significant": ((), _flag(abs(v["level"]), v["level_thr"]), _significant("|level_diff_db|")),
            "band_level_rms_error_db": ((), v["band_rms"], {**db, "long_name": "RMS over 1/3-octave bands of "
                                                            "band_level_error_db"}),
            "band_level_rms_error_db_threshold": ((), v["band_rms_thr"], {**db, "long_name": _THRESHOLD.format(
                "band_level_rms_error_db")}),
            "band_level_rms_error_db_significant": ((), _flag(v["band_rms"], v["band_rms_thr"]),
                                                    _significant("band_level_rms_error_db")),
            "shape_correlation": ((), v["corr"], {"units": "1", "long_name": "Pearson correlation of the log-PSDs"}),
            "shape_correlation_expected": ((), v["corr_expected"], {"units": "1", "long_name":
                                           "correlation of two noisy estimates of one spectrum (noise attenuation)"}),
            "shape_correlation_threshold": ((), v["corr_lowest"], {"units": "1", "long_name":
                                            "lowest correlation two estimates of one spectrum reach with "
                                            "probability 'confidence'"}),
            "shape_correlation_significant": ((), _flag(v["corr"], v["corr_lowest"], larger_is_bad=False),
                                              _significant("shape_correlation", "below")),
            "psd_measured": ("frequency", v["pmb"], {"units": psd_units, "long_name": f"PSD of measured {variable}"}),
            "psd_simulated": ("frequency", v["psb"], {"units": psd_units, "long_name": f"PSD of simulated {variable}"}),
            "log_psd_difference_db": ("frequency", v["diff"], {**db, "long_name": "10 log10(P_sim/P_meas)"}),
            "log_psd_difference_std_db": ("frequency", v["sigma"], {**db, "long_name": "standard deviation of "
                                          "log_psd_difference_db for one true spectrum"}),
            "band_level_measured_db": ("band_centre", v["lev_m"], {**db, "long_name": f"band power level re 1 "
                                       f"({units})2"}),
            "band_level_simulated_db": ("band_centre", v["lev_s"], {**db, "long_name": f"band power level re 1 "
                                        f"({units})2"}),
            "band_level_error_db": ("band_centre", v["band_err"], {**db, "long_name": "simulated minus measured "
                                    "1/3-octave band level"}),
            "band_level_error_db_threshold": ("band_centre", v["z2"] * v["band_sd"], {
                **db, "long_name": _THRESHOLD.format("|band_level_error_db|")}),
            "band_level_error_db_significant": ("band_centre", _flag(np.abs(v["band_err"]), v["z2"] * v["band_sd"]),
                                                _significant("|band_level_error_db|")),
            "peak_frequency_measured": ("peak", pk["fm"], {"units": "Hz", "long_name": "frequency of a prominent "
                                        "peak of the measured PSD in the band"}),
            "peak_frequency_simulated": ("peak", pk["fs"], {"units": "Hz", "long_name": "matched simulated peak "
                                         "(NaN: none within peak_match_tolerance)"}),
            "peak_frequency_error": ("peak", (pk["fs"] - pk["fm"]) / pk["fm"],
                                     {"units": "1", "long_name": "relative frequency error (f_sim - f_meas)/f_meas"}),
            "peak_frequency_error_threshold": ("peak", pk["freq_thr"] / pk["fm"], {
                "units": "1", "long_name": "relative frequency difference within the peaks' resolution"}),
            "peak_frequency_error_significant": ("peak", _flag(np.abs(pk["fs"] - pk["fm"]), pk["freq_thr"]),
                                                 _significant("|peak_frequency_error|")),
            "peak_level_diff_db": ("peak", pk["ls"] - pk["lm"], {**db, "long_name": "log-PSD at the simulated "
                                   "peak minus at the measured peak"}),
            "peak_level_diff_db_threshold": ("peak", pk["level_thr"], {**db, "long_name": _THRESHOLD.format(
                "|peak_level_diff_db|")}),
            "peak_level_diff_db_significant": ("peak", _flag(np.abs(pk["ls"] - pk["lm"]), pk["level_thr"]),
                                               _significant("|peak_level_diff_db|")),
        },
        coords={
            "frequency": ("frequency", v["fb"], {"units": "Hz", "long_name": "frequency"}),
            "band_centre": ("band_centre", v["bands"]["centre"], {"units": "Hz", "long_name": "IEC 61260-1 base-10 "
                            "exact mid-band frequency"}),
            "band_lower": ("band_centre", v["bands"]["lower"], {"units": "Hz", "long_name": "lower band-edge "
                           "frequency"}),
            "band_upper": ("band_centre", v["bands"]["upper"], {"units": "Hz", "long_name": "upper band-edge "
                           "frequency"}),
            "peak": ("peak", np.arange(pk["fm"].size), {"units": "1", "long_name": "peak number, by measured "
                     "frequency"}),
        },
    )
    psd_m, psd_s = v["psd_m"], v["psd_s"]
    ds.attrs = {
        "title": f"PSD scores of simulated against measured {variable}",
        "measured_run_id": str(measured.attrs.get("run_id", "")),
        "simulated_run_id": str(simulated.attrs.get("run_id", "")),
        "measured_source": str(measured.attrs.get("source", measured.encoding.get("source", ""))),
        "simulated_source": str(simulated.attrs.get("source", simulated.encoding.get("source", ""))),
        "variable": variable,
        "variable_units": units,
        "band_lower": v["f_lo"],
        "band_upper": v["f_hi"],
        "band_units": "Hz",
        "sample_rate": v["fs"],
        "sample_rate_units": "Hz",
        "resampled": v["resampled"],
        "steady_only": int(bool(v["steady"])),
        "sensor": "" if v["sensor"] is None else str(v["sensor"]),
        "nperseg": psd_m.attrs["nperseg"],
        "nperseg_rule": v["nperseg_rule"],
        "noverlap": psd_m.attrs["noverlap"],
        "window": psd_m.attrs["window"],
        "detrend": psd_m.attrs["detrend"],
        "scaling": "density",
        "frequency_resolution": v["df"],
        "measured_equivalent_degrees_of_freedom": v["nu_m"],
        "simulated_equivalent_degrees_of_freedom": v["nu_s"],
        "effective_independent_bins": v["n_eff"],
        "confidence": v["confidence"],
        "peak_prominence_db": v["prominence"],
        "peak_match_tolerance": v["peak_match_tolerance"],
        "fft_backend": psd_m.attrs["fft_backend"],
        "significance": "a score is significant when it exceeds what two Welch estimates of one spectrum reach "
                        "with probability 'confidence' (chi-square statistics of the estimates; "
                        "fivid.score.uncertainty)",
        "history": new_history(f"score_runs({variable!r}, band=[{v['f_lo']:g}, {v['f_hi']:g}] Hz, "
                               f"nperseg={psd_m.attrs['nperseg']})"),
    }
    return apply_cf_attrs(ds)  # Conventions, fivid_version
