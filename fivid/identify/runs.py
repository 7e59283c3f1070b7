"""Per-run analysis of the friction coefficient: μ(t) = Ft/Fn on the steady-sliding window.

For one RunDataset: optional tare (subtract force-sensor offsets measured on an unloaded interval),
the steady-sliding window (:func:`fivid.signal.steady_sliding_window`), checks of the normal force,
μ(t), its mean with a batch-means confidence interval, the Welch PSD of μp = μ − mean with mains
lines removed and an optional force-chain transfer function divided out, and the band RMS A with
its standard error. DAQ glitches (spikes, dropouts) of the force channels are replaced first and
counted (:mod:`fivid.identify.glitches`). Runs that cannot be used are returned with ``used=False``
and a reason.

Uncertainties
-------------
mean μ
    Batch means (e.g. Law & Kelton): the window is cut into ``n_batches`` equal batches whose means
    are nearly independent when a batch is much longer than the correlation time of μp; the interval
    is ``mean ± t_{B-1} sd(batch means)/sqrt(B)``.
band mean square A^2
    For a Gaussian stationary process observed over T seconds, the band power estimate has variance
    ``(1/T) ∫_band S(f)^2 df`` (the time average of x^2 has variance ``(1/T) ∫ S_1^2 df`` for a
    one-sided S_1; Bendat & Piersol, Random Data, §8.2); S is replaced by its Welch estimate.
    ``se(A) = se(A^2) / (2A)``.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from fivid.errors import DataQualityError, FividError, SchemaError
from fivid.identify.glitches import replace_glitches
from fivid.identify.shape import octave_median
from fivid.io.plausibility import MU_RANGE
from fivid.signal import measured_window, welch_psd
from fivid.signal.welch import NPERSEG_RULE, default_nperseg  # the one segment rule (used by identify.friction)

__all__ = ["RunAnalysisSettings", "RunAnalysis", "analyse_run", "band_weights", "mains_line_bins", "batch_means_interval",
           "mains_lines_resolved"]

_log = logging.getLogger("fivid")


@dataclass(frozen=True)
class RunAnalysisSettings:
    """Settings of the per-run analysis (all recorded in the law file); the band is passed separately.

    Parameters
    ----------
    nperseg : int or None
        Welch segment length [samples]; None: :func:`fivid.signal.welch.default_nperseg` with the mains frequency.
    tolerance : float
        Relative velocity tolerance of the steady-sliding window [-].
    min_normal_force : float
        Runs whose mean normal force on the window is below this [N] are excluded.
    tare : (float, float) or None
        Unloaded interval [s] whose mean forces are subtracted as sensor offsets.
    window : (float, float) or None
        Steady-sliding window [s] given by hand for every run; None: from the encoder signal
        (``velocity`` or ``position``), or from the forces when a run has neither
        (:func:`fivid.signal.measured_window`).
    mains_frequency : float or None
        Mains frequency [Hz] whose harmonics are removed from the PSD when they stand out; None: off.
    noise_correction : bool
        With a tare interval, subtract the force-sensor noise PSD measured on it (see
        :func:`analyse_run`).
    glitch_repair : bool or None
        Replace DAQ glitches (spikes, dropouts) of the force channels (:mod:`fivid.identify.glitches`). None (the
        default): on for measured runs, off for simulated runs (attribute ``transient_end``) -- a simulation has no
        DAQ, and the asperity impacts of a rough contact are physics that the spike detector would take for glitches.
    n_batches : int
        Batches of the batch-means interval of the mean μ.
    confidence : float
        Level of every interval.
    allow_implausible : bool
        Identify from a run whose mean Ft/Fn is outside ``±MU_RANGE[1]`` (:mod:`fivid.io.plausibility`:
        2); by default that is an error (a swapped column or a unit, and a sign that would be lost).
    """

    nperseg: int | None = None
    tolerance: float = 0.05
    min_normal_force: float = 0.1
    tare: tuple | None = None
    window: tuple | None = None
    mains_frequency: float | None = 50.0
    noise_correction: bool = True
    glitch_repair: bool | None = None
    n_batches: int = 20
    confidence: float = 0.95
    allow_implausible: bool = False

    def to_dict(self) -> dict:
        """The settings as plain values (recorded in the law file and the JSON report)."""
        return {
            "nperseg": self.nperseg or "auto",
            "tolerance": self.tolerance,
            "min_normal_force": self.min_normal_force,
            "tare": self.tare,
            "window": self.window,
            "mains_frequency": self.mains_frequency,
            "noise_correction": self.noise_correction,
            "glitch_repair": "auto" if self.glitch_repair is None else self.glitch_repair,
            "n_batches": self.n_batches,
            "allow_implausible": self.allow_implausible,
            "confidence": self.confidence,
        }


DEFAULT_BAND_LOW = 20.0  # [Hz] above drift and the loading device's rigid-body modes
DEFAULT_BAND_HIGH = 2000.0  # [Hz] placeholder for where a TRIBOAIR-like force chain is dynamic-free


@dataclass
class RunAnalysis:
    """Result of :func:`analyse_run` for one run (all SI; μ quantities dimensionless)."""

    run_id: str
    sliding_velocity: float
    roughness_ra: float
    normal_load: float
    source: str = ""
    used: bool = False
    reason: str = ""
    t_start: float = np.nan
    t_stop: float = np.nan
    window_source: str = ""
    normal_force_mean: float = np.nan
    mu_mean: float = np.nan
    mu_mean_ci: tuple = (np.nan, np.nan)
    mu_rms: float = np.nan
    mu_rms_stderr: float = np.nan
    mu_rms_total: float = np.nan
    frequency: np.ndarray = field(default_factory=lambda: np.zeros(0))
    psd: np.ndarray = field(default_factory=lambda: np.zeros(0))
    weights: np.ndarray = field(default_factory=lambda: np.zeros(0))
    mains_bins_removed: int = 0
    mains_removal: str = ""
    glitches_replaced: int = 0
    noise_fraction: float = np.nan
    psd_attrs: dict = field(default_factory=dict)

    def table_row(self) -> dict:
        """The per-run JSON record."""
        return {
            "run_id": self.run_id,
            "source": self.source,
            "sliding_velocity": self.sliding_velocity,
            "roughness_ra": self.roughness_ra,
            "normal_load": self.normal_load,
            "used": self.used,
            "reason": self.reason,
            "window": [self.t_start, self.t_stop],
            "window_source": self.window_source,
            "normal_force_mean": self.normal_force_mean,
            "mu_mean": self.mu_mean,
            "mu_mean_ci": list(self.mu_mean_ci),
            "mu_rms": self.mu_rms,
            "mu_rms_stderr": self.mu_rms_stderr,
            "mu_rms_total": self.mu_rms_total,
            "mains_bins_removed": self.mains_bins_removed,
            "mains_removal": self.mains_removal,
            "glitches_replaced": self.glitches_replaced,
            "noise_fraction": self.noise_fraction,
            "nperseg": self.psd_attrs.get("nperseg"),  # the Welch segment [samples] this run's PSD used
        }


def mains_lines_resolved(resolution: float, mains_frequency: float | None) -> bool:
    """True when Welch bins of width ``resolution`` [Hz] resolve mains lines: ``Δf <= f_m / 4``.

    See :func:`fivid.signal.welch.default_nperseg`; coarser bins make :func:`mains_line_bins` take broadband power
    for lines.
    """
    return bool(mains_frequency) and resolution <= mains_frequency / 4 * (1 + 1e-9)


def band_weights(frequency: np.ndarray, band: tuple) -> np.ndarray:
    """Trapezoid quadrature weights [Hz] of the bins inside ``band`` (0 outside).

    The band edges are snapped to the bins nearest inside; the integral ``Σ w P`` is then the
    trapezoid rule over ``[f_first, f_last]`` of the bins kept.
    """
    f = np.asarray(frequency, float)
    df = f[1] - f[0]
    inside = (f >= band[0] - 1e-9 * df) & (f <= band[1] + 1e-9 * df)
    w = np.where(inside, df, 0.0)
    idx = np.nonzero(inside)[0]
    if idx.size >= 2:
        w[idx[0]] = w[idx[-1]] = df / 2
    return w


def mains_line_bins(frequency, psd, dof, mains_frequency, band, *, p_false=1e-2):
    """Bins of mains harmonics that stand out of the broadband floor.

    A Hann-windowed line at frequency ``f_k = k f_m`` puts its power into the bins within two bins
    of ``f_k`` (the main lobe; 2.5 bins away the leakage is below −31 dB). For each harmonic in the
    band, the bins with ``|f − f_k| <= 2 Δf`` are compared with the local floor, the higher of the
    medians of the bins 5 to 15 bins away on each side (the edge of a steep broadband feature, low on
    one side and high on the other, is then not a line). A line is declared when the largest of them
    exceeds the floor by more than a broadband bin would with probability ``p_false`` over the whole
    band (near 0 Hz the floor window is clipped to the bins above 0 Hz):
    the χ² quantile ``chi2.ppf(1 − p_false/M, dof)/dof`` (Bonferroni over the M bins tested), times
    ``1 + 3 sd`` of the floor's own estimate (the median of n bins of relative sd ``sqrt(2/dof)``
    has relative sd ``1.253 sqrt(2/dof) / sqrt(n)``, n = 11 per side). Lines are resolved only
    when ``Δf <= f_m / 4`` (:func:`mains_lines_resolved`); :func:`analyse_run` does not call this
    with coarser bins on the PSD of μp (it does on the smooth sensor-noise PSD of the tare interval).
    A line is narrow: the peak must also exceed, by the same factor, the median of its shoulders 4 and
    5 bins away (outside the main lobe), so a broad resonance near a mains harmonic is not taken for
    hum (seen on real friction-damper data).

    Returns
    -------
    ndarray of bool
        True for the bins to replace.
    """
    from scipy import stats

    f = np.asarray(frequency, float)
    p = np.asarray(psd, float)
    df = f[1] - f[0]
    mask = np.zeros(f.size, dtype=bool)
    if mains_frequency is None:
        return mask
    k_lo = max(1, int(np.ceil((band[0] - 2 * df) / mains_frequency)))
    k_hi = int(np.floor((band[1] + 2 * df) / mains_frequency))
    fk = np.arange(k_lo, k_hi + 1) * mains_frequency
    centre = np.rint(fk / df).astype(int)
    offsets = np.arange(-3, 4)
    near = centre[:, None] + offsets[None, :]  # candidate bins; kept where |f - f_k| <= 2 df
    floor_off = np.r_[np.arange(-17, -6), np.arange(7, 18)]  # 5 to 15 bins beyond the +-2-bin lobe
    # near 0 Hz and Nyquist the floor window is clipped to the spectrum (repeating its end bins)
    around = np.clip(centre[:, None] + floor_off[None, :], 1, f.size - 1)
    ok = (near.min(axis=1) >= 1) & (near.max(axis=1) < f.size)
    if not ok.any():
        return mask
    fk, centre, near, around = fk[ok], centre[ok], near[ok], around[ok]
    in_lobe = np.abs(f[near] - fk[:, None]) <= 2 * df
    n_tested = int(in_lobe.sum())
    chi = stats.chi2.ppf(1.0 - p_false / n_tested, dof) / dof
    half = around.shape[1] // 2  # the floor on each side; a line stands above the higher one, so that the
    # edge of a steep broadband feature (one side low, one side high) is not taken for a line
    threshold = chi * (1.0 + 3.0 * 1.253 * np.sqrt(2.0 / dof) / np.sqrt(half))
    floor = np.maximum(np.median(p[around[:, :half]], axis=1), np.median(p[around[:, half:]], axis=1))
    shoulder = np.median(p[np.clip(centre[:, None] + np.array([-5, -4, 4, 5])[None, :], 1, f.size - 1)], axis=1)
    peak = np.where(in_lobe, p[near], -np.inf).max(axis=1)
    line = (floor > 0) & (peak > threshold * floor) & (peak > threshold * shoulder)
    for i in np.nonzero(line)[0]:
        mask[near[i][in_lobe[i]]] = True
    return mask


def _replace_lines(frequency, psd, mask):
    """Linear interpolation across masked bins from the nearest unmasked bins (never from 0 Hz)."""
    if not mask.any():
        return psd
    out = psd.copy()
    keep = ~mask
    keep[0] = False
    if not keep.any():  # nothing to interpolate from
        return psd
    out[mask] = np.interp(frequency[mask], frequency[keep], psd[keep])
    return out


def batch_means_interval(x, n_batches, confidence):
    """Mean of ``x`` and its batch-means interval: ``mean ± t_{B-1} sd(batch means)/sqrt(B)``.

    Returns (mean, (lower, upper)); the batches are ``n_batches`` equal consecutive parts of ``x``.
    """
    from scipy import stats

    b = int(n_batches)
    m = x.size // b
    means = x[: m * b].reshape(b, m).mean(axis=1)
    half = stats.t.ppf(0.5 + confidence / 2, b - 1) * means.std(ddof=1) / np.sqrt(b)
    return float(x.mean()), (float(x.mean() - half), float(x.mean() + half))


def _check_units(ds, label):
    for name in ("friction_force", "normal_force"):
        if name not in ds.data_vars:
            raise SchemaError(f"{label}: variable {name!r} is missing; a run needs friction_force and normal_force [N]")
        units = ds[name].attrs.get("units")
        if units != "N":
            raise SchemaError(
                f"{label}: variable {name!r} has units {units!r}; expected 'N' (re-ingest the run so that "
                "forces are in newtons)"
            )


def _check_mu_plausible(mean_mu: float, run_id, ds, settings) -> None:
    """Refuse a mean Ft/Fn beyond ``±MU_RANGE[1]`` unless allowed: its magnitude and its sign would be lost."""
    if abs(mean_mu) <= MU_RANGE[1] or settings.allow_implausible:
        return
    raise DataQualityError(
        f"run {run_id}: mean friction coefficient Ft/Fn = {mean_mu:+.4g} on the steady window is outside the "
        f"plausible [-{MU_RANGE[1]:g}, {MU_RANGE[1]:g}] (dry friction 0.1-1, rubber up to ~2; fivid.io.plausibility): "
        "a swapped column, a unit or a sensitivity; correct the run, or pass --allow-implausible (recorded in the "
        "law file) to identify from it", file=ds.attrs.get("source", "").split(" sha256:")[0] or None,
        key="friction_force")


def analyse_run(ds, settings: RunAnalysisSettings, *, band: tuple, transfer_function=None) -> RunAnalysis:
    """μ(t) on the steady window of one run: mean with CI, PSD of μp in ``band``, band RMS with stderr.

    Parameters
    ----------
    ds : xarray.Dataset
        A RunDataset (SI units).
    settings : RunAnalysisSettings
    band : (float, float)
        Valid band [Hz] (checked against the run's Nyquist frequency).
    transfer_function : xarray.DataArray, optional
        Force-chain transfer function over dim ``frequency`` [Hz] (complex or magnitude, [-]); the PSD
        is divided by ``|H|^2`` interpolated to the Welch bins.

    Returns
    -------
    RunAnalysis
        ``used`` False with a ``reason`` for a run that is not in steady sliding or whose normal force
        is near zero.

    Raises
    ------
    SchemaError
        Forces missing or not in newtons.
    FividError
        ``band`` beyond the run's Nyquist frequency.
    """
    import xarray as xr

    run_id = str(ds.attrs.get("run_id", "?"))
    label = f"run {run_id!r}"
    _check_units(ds, label)
    res = RunAnalysis(
        run_id=run_id,
        sliding_velocity=float(ds.attrs.get("sliding_velocity", np.nan)),
        roughness_ra=float(ds.attrs.get("roughness_ra", np.nan)),
        normal_load=float(ds.attrs.get("normal_load", np.nan)),
        source=str(ds.attrs.get("source", "")),
    )
    t = np.asarray(ds["time"].values, float)
    fs = float(ds.attrs.get("sample_rate", 1.0 / np.mean(np.diff(t))))
    if band[1] > fs / 2:
        raise FividError(
            f"{label}: band upper edge {band[1]:g} Hz is beyond the Nyquist frequency {fs / 2:g} Hz of this run "
            f"(sample rate {fs:g} Hz); choose --band below {fs / 2:g} Hz"
        )
    if not res.normal_load > 0:
        res.reason = f"nominal normal load {res.normal_load!r} N is not > 0"
        return res

    repair = settings.glitch_repair if settings.glitch_repair is not None else "transient_end" not in ds.attrs
    if repair:
        (ft, fn), glitch = replace_glitches(ds["friction_force"].values, ds["normal_force"].values)
        res.glitches_replaced = int(glitch.sum())
    else:
        ft, fn = (np.asarray(ds[v].values, float) for v in ("friction_force", "normal_force"))
    tare_sel = None
    if settings.tare is not None:
        ft, fn, tare_sel = _tare(t, ft, fn, settings, label)
    if settings.window is not None:
        t0, t1 = _given_window(t, settings.window, label)
        res.window_source = "given (--window)"
    else:
        try:
            t0, t1 = measured_window(ds, tolerance=settings.tolerance)
        except DataQualityError as exc:
            res.reason = f"not in steady sliding: {exc.message}"
            return res
        encoder = "velocity" in ds.variables or "position" in ds.variables
        res.window_source = "encoder" if encoder else "forces (no encoder signal)"
    if settings.tare is not None and settings.tare[0] < t1 and settings.tare[1] > t0:
        raise FividError(
            f"{label}: tare interval {settings.tare[0]:g}-{settings.tare[1]:g} s overlaps the steady-sliding window "
            f"{t0:g}-{t1:g} s, where the load is on: a tare must be an unloaded interval (before the preload); "
            f"choose --tare inside {t[0]:g}-{t0:g} s")
    res.t_start, res.t_stop = t0, t1
    win = (t >= t0) & (t <= t1)
    fn_w, ft_w = fn[win], ft[win]
    res.normal_force_mean = float(fn_w.mean())
    if not res.normal_force_mean >= settings.min_normal_force:
        res.reason = (
            f"normal force near zero: mean {res.normal_force_mean:.4g} N on the steady window "
            f"(minimum {settings.min_normal_force:g} N)"
        )
        return res
    lost = np.count_nonzero(fn_w <= 0)
    if lost:
        res.reason = f"contact lost: normal force <= 0 N at {lost} of {fn_w.size} samples of the steady window"
        return res
    mu = ft_w / fn_w
    _check_mu_plausible(float(np.mean(mu)), run_id, ds, settings)
    if np.mean(mu) < 0:  # friction force recorded with the opposite sign convention
        _log.warning("run %s: mean Ft/Fn = %.4g on the steady window is negative: taken as the opposite sign "
                     "convention (mu0 > 0)", run_id, float(np.mean(mu)))
        mu = -mu
    res.mu_mean, res.mu_mean_ci = batch_means_interval(mu, settings.n_batches, settings.confidence)
    mup = mu - res.mu_mean
    res.mu_rms_total = float(np.sqrt(np.mean(mup**2)))
    nperseg = settings.nperseg or default_nperseg(fs, mup.size, settings.mains_frequency)
    da = xr.DataArray(mup, dims="time", coords={"time": t[win]}, name="friction_perturbation",
                      attrs={"units": "1", "run_id": run_id})
    if mup.size < 2 * nperseg:
        res.reason = (f"steady window too short: {mup.size} samples ({t1 - t0:.4g} s) for Welch segments of "
                      f"{nperseg} samples (at least two are needed; lower nperseg or record longer)")
        return res
    p = welch_psd(da, nperseg=nperseg, fs=fs, confidence=settings.confidence)
    f = np.asarray(p["frequency"].values, float)
    dof = float(p.attrs["equivalent_degrees_of_freedom"])
    values = np.asarray(p.values, float)
    res.mains_removal = _mains_removal_state(f[1] - f[0], settings.mains_frequency, mup.size, fs)
    mains = settings.mains_frequency if res.mains_removal == "on" else None
    mask = mains_line_bins(f, values, dof, mains, band)
    values = _replace_lines(f, values, mask)
    res.mains_bins_removed = int(np.count_nonzero(mask & (f >= band[0]) & (f <= band[1])))
    noise = None
    if tare_sel is not None and settings.noise_correction:
        noise = _tare_noise_psd(t[tare_sel], ft[tare_sel], fn[tare_sel], res.mu_mean, res.normal_force_mean,
                                f, nperseg, fs, band, settings)
        if noise is not None:
            noise_psd, tare_duration = noise
            w_all = band_weights(f, band)
            res.noise_fraction = float(np.sum(w_all * noise_psd) / max(np.sum(w_all * values), np.finfo(float).tiny))
            values = np.maximum(values - noise_psd, 0.0)
    if transfer_function is not None:
        h2 = _transfer_magnitude_squared(transfer_function, f, band, label)
        values = np.where(h2 > 0, values / np.where(h2 > 0, h2, 1.0), 0.0)
    w = band_weights(f, band)
    if np.count_nonzero(w) < 3:
        raise FividError(
            f"{label}: band {band[0]:g}-{band[1]:g} Hz holds {np.count_nonzero(w)} Welch bins "
            f"(resolution {f[1] - f[0]:g} Hz); widen the band or use a longer nperseg"
        )
    a2 = float(np.sum(w * values))
    duration = t1 - t0
    var_a2 = float(np.sum(w * values**2)) / duration
    if noise is not None:  # the subtracted noise estimate adds its own variance (same formula, tare length)
        var_a2 += float(np.sum(w * noise[0] ** 2)) / noise[1]
    res.mu_rms = float(np.sqrt(a2))
    res.mu_rms_stderr = float(np.sqrt(var_a2) / (2 * res.mu_rms)) if a2 > 0 else np.nan
    res.frequency, res.psd, res.weights = f, values, w
    res.psd_attrs = {k: p.attrs[k] for k in ("nperseg", "noverlap", "window", "detrend", "equivalent_degrees_of_freedom",
                                               "frequency_resolution") if k in p.attrs}
    res.used = True
    return res


def _mains_removal_state(resolution, mains_frequency, n_samples, fs):
    """``"on"``, ``"off"`` (no mains frequency) or why lines are left in (bins too coarse)."""
    if not mains_frequency:
        return "off"
    if mains_lines_resolved(resolution, mains_frequency):
        return "on"
    return (f"not done: Welch resolution {resolution:.4g} Hz > mains/4 = {mains_frequency / 4:.4g} Hz would take "
            f"broadband power for lines (needs segments of >= {int(np.ceil(4 * fs / mains_frequency))} samples; "
            f"the window has {n_samples}); the hum power stays in A")


def _given_window(t, window, label):
    """The first and last sample times [s] of a window given by hand, checked against the record."""
    lo, hi = float(window[0]), float(window[1])
    half = 0.5 / _rate_of(t)
    if not (lo < hi and lo >= t[0] - half and hi <= t[-1] + half):
        raise FividError(f"{label}: --window {lo:g} s {hi:g} s must be an increasing interval inside the record "
                         f"{t[0]:g}-{t[-1]:g} s")
    sel = t[(t >= lo) & (t <= hi)]
    return float(sel[0]), float(sel[-1])


def _rate_of(t) -> float:
    """Sample rate [Hz] of the time vector ``t`` [s] (mean step)."""
    return 1.0 / float(np.mean(np.diff(t)))


def _tare(t, ft, fn, settings, label):
    """Subtract the mean forces of the tare interval (cut to whole mains periods, so hum averages out)."""
    lo, hi = settings.tare
    if not lo < hi or lo < t[0] - 0.5 / _rate_of(t) or hi > t[-1] + 0.5 / _rate_of(t):
        raise FividError(
            f"{label}: tare interval {lo:g}-{hi:g} s must be an increasing interval inside the record "
            f"{t[0]:g}-{t[-1]:g} s")
    if settings.mains_frequency:
        period = 1.0 / settings.mains_frequency
        cycles = np.floor((hi - lo) / period)
        if cycles >= 1:
            hi = lo + cycles * period
    sel = (t >= lo) & (t < hi)
    if sel.sum() < 10:
        raise FividError(
            f"{label}: tare interval {settings.tare[0]:g}-{settings.tare[1]:g} s holds {int(sel.sum())} samples; "
            f"the record spans {t[0]:g}-{t[-1]:g} s"
        )
    return ft - ft[sel].mean(), fn - fn[sel].mean(), sel


def _tare_noise_psd(t, ft, fn, mu_mean, fn_mean, f, nperseg, fs, band, settings):
    """Sensor-noise PSD of μ [Hz-1] on the grid ``f``, from the unloaded (tared) interval, or None.

    With no load the sensors read only their noise e_t, e_n; during sliding these enter μ = Ft/Fn as
    ``(e_t − μ e_n) / Fn`` to first order. Its Welch PSD on the tare interval (segments of up to
    ``nperseg`` samples, at least 4 of them), with mains lines removed, is smoothed by a 1/3-octave
    running median (the noise floor is broadband; the median ignores lines that were not removed)
    divided by the median of χ²_ν/ν, ``chi2.ppf(0.5, ν)/ν``, which makes it unbiased for a smooth
    floor; it is interpolated onto ``f``. Returns (psd, tare duration [s]).
    """
    import xarray as xr
    from scipy import stats

    m = nperseg
    while m > 64 and 4 * m > t.size:
        m //= 2
    if 2 * m > t.size:
        _log.info("tare interval of %d samples is too short for a noise PSD; no noise correction", t.size)
        return None
    e = (ft - mu_mean * fn) / fn_mean
    da = xr.DataArray(e - e.mean(), dims="time", coords={"time": t}, name="sensor_noise", attrs={"units": "1"})
    p = welch_psd(da, nperseg=m, fs=fs)
    fq = np.asarray(p["frequency"].values, float)
    v = np.asarray(p.values, float)
    nu = float(p.attrs["equivalent_degrees_of_freedom"])
    # at any resolution: interpolating over a sensor-noise floor, smooth by nature and median-smoothed
    # below, takes no broadband structure away (unlike on the PSD of μp, see fivid.signal.welch.default_nperseg)
    mask = mains_line_bins(fq, v, nu, settings.mains_frequency, (fq[1], fq[-1]))
    v = _replace_lines(fq, v, mask)
    v[1:] = octave_median(fq[1:], v[1:], 1.0 / 3.0) * nu / stats.chi2.ppf(0.5, nu)
    return np.interp(f, fq, v), float(t[-1] - t[0])


def _transfer_magnitude_squared(h, f, band, label):
    if "frequency" not in getattr(h, "dims", ()):
        raise FividError(f"{label}: the transfer function must be a DataArray over dim 'frequency' [Hz]")
    hf = np.asarray(h["frequency"].values, float)
    mag2 = np.abs(np.asarray(h.values)) ** 2
    if hf[0] > band[0] or hf[-1] < band[1]:
        raise FividError(
            f"{label}: the transfer function covers {hf[0]:g}-{hf[-1]:g} Hz, not the whole band {band[0]:g}-{band[1]:g} Hz"
        )
    return np.interp(f, hf, mag2)
