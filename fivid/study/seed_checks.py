"""Seeds 000/001's checks as study outputs (issue 27 item 4), on the twin data set (SYNTHETIC, sample_data/twin):

- :func:`twin_amplitude_linearity`: the identified perturbation amplitude ``A`` is linear in the sliding
  velocity (seed 000): per run ``A`` is the band RMS of mu(t) (:func:`fivid.identify.runs.analyse_run`), then
  ``A = a_r + b_r V + c V^2`` (an intercept and slope per roughness level, one common quadratic term) by weighted
  least squares with the estimator's standard errors as known variances; the quadratic term is significant when
  its two-sided z-test gives p < 0.05;
- :func:`twin_broadband_levels`: the "measured" (twin) acceleration power off the reference modes' bands, per
  run, to compare with the study's Coulomb-only and law responses at the nearest condition (seed 000: Coulomb
  alone under-predicts the measured broadband level).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fivid.identify.runs import RunAnalysisSettings, analyse_run
from fivid.io.rig_csv import read_rig_csv
from fivid.signal.peaks import near_frequencies
from fivid.signal.spectral import welch_density
from fivid.signal.steady import measured_window

__all__ = ["twin_amplitude_linearity", "twin_broadband_levels", "TWIN_BAND", "TWIN_SETTINGS"]

#: the twin's perturbation band [Hz] (sample_data/ground_truth.yaml)
TWIN_BAND = (100.0, 10e3)
#: the per-run analysis of the twin's records: its 20 ms unloaded pre-trigger as tare, 50 Hz mains removed
TWIN_SETTINGS = RunAnalysisSettings(tare=(0.0, 0.015), mains_frequency=50.0)


def _runs(folder):
    files = sorted(Path(folder).glob("*.csv"))
    return [(f, read_rig_csv(f)) for f in files]


def twin_amplitude_linearity(folder) -> dict:
    """The quadratic term of the amplitude over velocity on the twin runs in ``folder`` (module docstring).

    Returns ``{"runs": [{file, sliding_velocity [m s-1], roughness_ra [m], amplitude, amplitude_stderr}],
    "intercept" [-] and "slope" [s m-1] per roughness level, "quadratic" [s2 m-2], "quadratic_stderr",
    "p_value", "significant", "test"}``.
    """
    from scipy.stats import norm

    rows = []
    for f, ds in _runs(folder):
        r = analyse_run(ds, TWIN_SETTINGS, band=TWIN_BAND)
        if r.used:
            rows.append({"file": f.name, "sliding_velocity": float(r.sliding_velocity),
                         "roughness_ra": float(r.roughness_ra), "amplitude": float(r.mu_rms),
                         "amplitude_stderr": float(r.mu_rms_stderr)})
    v = np.array([r["sliding_velocity"] for r in rows])
    ra = np.array([r["roughness_ra"] for r in rows])
    a = np.array([r["amplitude"] for r in rows])
    se = np.array([r["amplitude_stderr"] for r in rows])
    levels = np.unique(ra)
    cols = [(ra == lv).astype(float) for lv in levels] + [v * (ra == lv) for lv in levels] + [v**2]
    X = np.column_stack(cols)
    w = 1.0 / se**2
    cov = np.linalg.inv(X.T @ (X * w[:, None]))
    beta = cov @ (X.T @ (w * a))
    z = beta[-1] / np.sqrt(cov[-1, -1])
    p = float(2.0 * norm.sf(abs(z)))
    n = len(levels)
    return {"runs": rows, "roughness_levels": levels.tolist(), "intercept": beta[:n].tolist(),
            "slope": beta[n:2 * n].tolist(), "quadratic": float(beta[-1]), "quadratic_stderr": float(np.sqrt(cov[-1, -1])),
            "p_value": p, "significant": p < 0.05,
            "test": "A = a_r + b_r V + c V^2, WLS with the estimator's variances as known, z-test of c (two-sided)"}


def twin_broadband_levels(folder, modes, band_width: float, band) -> list[dict]:
    """Per twin run in ``folder``: the acceleration PSD power [(m s-2)^2] inside ``band`` [Hz] but off
    ``band_width`` (relative) of the frequencies ``modes`` [Hz], and in the modes' bands, over the steady window
    (Welch, Hann, 4096 samples)."""
    out = []
    for f, ds in _runs(folder):
        t0, t1 = measured_window(ds)
        sel = (ds["time"].values >= t0) & (ds["time"].values <= t1)
        acc = ds["acceleration"]
        x = (acc.isel(sensor=0) if "sensor" in acc.dims else acc).values[sel]
        fs = 1.0 / float(np.median(np.diff(ds["time"].values)))
        fr, p = welch_density(x, fs, nperseg=min(4096, x.size))
        inb = (fr >= band[0]) & (fr <= band[1])
        near = near_frequencies(fr, modes, band_width)
        df = float(fr[1] - fr[0])
        out.append({"file": f.name, "sliding_velocity": float(ds.attrs.get("sliding_velocity", np.nan)),
                    "roughness_ra": float(ds.attrs.get("roughness_ra", np.nan)),
                    "normal_load": float(ds.attrs.get("normal_load", np.nan)),
                    "power_rest": float(p[inb & ~near].sum() * df), "power_modes": float(p[inb & near].sum() * df)})
    return out
