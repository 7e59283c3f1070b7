"""Scoring one test condition: every simulation seed against every measured run at that condition.

The scores themselves come from :func:`fivid.score.score_runs` (DESIGN §6). This module picks the
steady-sliding part of each record, pairs runs with seeds, averages the headline scores over the
pairs (the Monte-Carlo seeds give their spread) and keeps the Welch PSDs with their χ² bounds for the
report, on one common frequency grid.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import DataQualityError
from fivid.io import read_run
from fivid.schema import new_history
from fivid.score import score_runs, scores_to_json
from fivid.signal import welch_psd
from fivid.signal.sampling import sample_rate_of
from fivid.signal.steady import steady_part
from fivid.signal.welch import default_nperseg

__all__ = ["score_condition", "acceleration_psd"]

HEADLINE = ("lsd_db", "level_diff_db", "band_level_rms_error_db", "shape_correlation")


def _acceleration(ds):
    da = ds["acceleration"]
    if "sensor" in da.dims:
        da = da.isel(sensor=0)
    return da


def acceleration_psd(ds, *, nperseg: int):
    """Welch PSD of the acceleration (first sensor) with χ² 95 % bounds."""
    return welch_psd(_acceleration(ds), nperseg=nperseg, window="hann", detrend="constant", confidence=0.95)


def score_condition(measured: list, simulated: list, *, band, nperseg: int | None = None, settle: float = 0.0):
    """Scores of every (measured run, simulation) pair and their mean; the PSDs for the report.

    Parameters
    ----------
    measured, simulated : list of path-like
        RunDataset netCDF files of one test condition.
    band : (float, float)
        Scoring band [Hz].
    nperseg : int, optional
        Welch segment length [samples]; default :func:`fivid.signal.welch.default_nperseg` of the shortest steady
        record at the lowest sample rate, one for every pair and PSD (the scores state it).
    settle : float
        Time skipped after the start of steady sliding [s] (see :func:`fivid.signal.steady_part`).

    Returns
    -------
    scores : dict
        ``pairs`` (per pair: names and :func:`fivid.score.scores_to_json` content) and ``summary``
        (mean and min/max over pairs of each headline score).
    psd : xarray.Dataset
        ``psd_measured(measured, frequency)``, ``psd_simulated(simulated, frequency)`` and their
        ``_lower``/``_upper`` bounds [m2 s-4 Hz-1]; labels ``measured_run(measured)``,
        ``simulated_seed(simulated)`` (file stems) and the condition's scalar coordinates.
    """
    from pathlib import Path

    import xarray as xr

    def steady(p):  # a measured run without a steady-sliding window is used whole (logged)
        return steady_part(read_run(p), label=Path(p).name, settle=settle, whole_record_if_none=True)

    meas = {Path(p).stem: steady(p) for p in measured}
    sims = {Path(p).stem: steady(p) for p in simulated}
    if nperseg is None:  # one segment for the whole condition, so that every PSD is on one grid
        rates = {k: sample_rate_of(d["time"].values, label=k) for k, d in {**meas, **sims}.items()}
        fs = min(rates.values())
        nperseg = default_nperseg(fs, min(d.sizes["time"] * fs / rates[k] for k, d in {**meas, **sims}.items()))
    pairs = []
    for mname, m in meas.items():
        for sname, s in sims.items():
            sc = score_runs(m, s, variable="acceleration", band=tuple(band), nperseg=nperseg)
            pairs.append({"measured": mname, "simulated": sname, "scores": scores_to_json(sc)})
    summary = {}
    for key in HEADLINE:
        vals = np.array([p["scores"].get(key) for p in pairs if p["scores"].get(key) is not None], float)
        summary[key] = float(np.mean(vals)) if vals.size else None
        summary[f"{key}_min"] = float(np.min(vals)) if vals.size else None
        summary[f"{key}_max"] = float(np.max(vals)) if vals.size else None
    summary["n_pairs"] = len(pairs)

    pm = [acceleration_psd(m, nperseg=nperseg) for m in meas.values()]
    ps = [acceleration_psd(s, nperseg=nperseg) for s in sims.values()]
    f = pm[0]["frequency"].values
    for p in ps:
        if p.sizes["frequency"] != f.size or not np.allclose(p["frequency"].values, f):
            raise DataQualityError(
                f"simulated sample rate {p.attrs['sample_rate']:g} Hz differs from the measured "
                f"{pm[0].attrs['sample_rate']:g} Hz: set simulate.sample_rate to the rig's rate")
    units = pm[0].attrs["units"]

    def stack(spectra, name, dim, role):
        bound = {"": "", "_lower": f"lower {pm[0].attrs['confidence']:.0%} chi2 bound of the ",
                 "_upper": f"upper {pm[0].attrs['confidence']:.0%} chi2 bound of the "}
        return {f"{name}{suffix}": ((dim, "frequency"), np.array([p.values if not suffix else p[f"psd{suffix}"].values
                                                                   for p in spectra]),
                                    {"units": units, "long_name": f"{bound[suffix]}Welch PSD of the {role} acceleration"})
                for suffix in ("", "_lower", "_upper")}

    conditions = {n: pm[0].coords[n].variable for n in ("sliding_velocity", "normal_load", "roughness_ra")
                  if n in pm[0].coords}  # .variable: a coordinate DataArray would bring the run's run_id along
    # text labels along plain dimensions: a text coordinate variable would be a 2-D char array, not CF
    psd = xr.Dataset(
        {**stack(pm, "psd_measured", "measured", "measured"), **stack(ps, "psd_simulated", "simulated", "simulated")},
        coords={"frequency": ("frequency", f, {"units": "Hz", "long_name": "frequency"}),
                "measured_run": ("measured", list(meas), {"long_name": "measured run (file name without .nc)"}),
                "simulated_seed": ("simulated", list(sims), {"long_name": "simulation (file name without .nc)"}),
                **conditions},
        attrs={**{k: pm[0].attrs[k] for k in ("nperseg", "noverlap", "window", "detrend", "equivalent_averages",
                                              "sample_rate", "confidence")},
               "title": "Welch PSDs of the measured and simulated acceleration of one test condition",
               "Conventions": "CF-1.8",
               "history": new_history(f"score_condition(band=[{band[0]:g}, {band[1]:g}] Hz, nperseg={nperseg}, "
                                      f"settle={settle:g} s)")},
    )
    return {"band": list(band), "nperseg": nperseg, "settle": settle, "pairs": pairs, "summary": summary}, psd
