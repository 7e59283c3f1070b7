"""Damping identification: modal damping ratios from PSD/FRF peaks, and a Rayleigh (α, β) fit.

Peaks of a response PSD (or of |H|^2 of an FRF) are located in a band, then each is measured two ways:

half-power bandwidth
    ``ζ = (f2 − f1) / (2 f_n)`` with f1, f2 the frequencies where the peak falls to half its height
    (linear interpolation between bins). Exact to O(ζ^2) for a lightly damped mode of |H|^2; it is
    biased upward when the peak is not resolved (Welch smoothing widens it), so peaks whose
    half-power width is below 5 bins are flagged ``resolved=False``.
curve fit
    The single-mode model ``P(f) = c f^q / ((f_n^2 − f^2)^2 + (2 ζ f_n f)^2) + b`` (``|H|^2`` of a
    mode times ``f^q`` — q = 0, 2, 4 for a displacement, velocity, acceleration response — plus a
    flat floor) is convolved with the spectral window of the Welch estimate (the expected
    value of a Welch PSD is the true PSD convolved with the window's |W(f)|^2) and fitted on
    ln P over ±6 half-power widths by :func:`scipy.optimize.curve_fit`. Fitting the window-smoothed
    model removes the resolution bias. ln P̂ has a constant variance (χ²), so unweighted least
    squares is right; adjacent Hann bins are correlated (|ρ|^2 = 4/9, 1/36), which inflates the
    parameter variances by ``1 + 2 (4/9 + 1/36) = 1.94``: the standard errors are scaled by sqrt(1.94).

Rayleigh damping (DESIGN §4): ``ζ_i = α / (2 ω_i) + β ω_i / 2`` is linear in (α, β); it is fitted by
weighted least squares (statsmodels WLS, weights 1/se(ζ_i)^2; :func:`fivid.fe.damping.fit_rayleigh_least_squares`). The covariance takes the ratios'
standard errors as known, ``(X' W X)^-1``; with more modes than two a χ² goodness-of-fit p-value says
whether Rayleigh damping describes the measured ratios within their errors, and the covariance is
scaled by the reduced χ² when it exceeds 1 (Birge ratio). Without standard errors (half-power
ratios), the residual variance is estimated (at least three modes are needed for an error).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from fivid.errors import ConfigError, DataQualityError, FividError
from fivid.fe.damping import RayleighFit, fit_rayleigh_least_squares
from fivid.signal import welch_psd
from fivid.signal.welch import default_nperseg

__all__ = [
    "ModalPeak",
    "DampingIdentification",
    "find_resonance_peaks",
    "half_power_damping",
    "fit_mode",
    "identify_damping",
    "HANN_CORRELATION_INFLATION",
]

#: variance inflation of least-squares parameters from correlated adjacent Hann bins: 1 + 2 (4/9 + 1/36)
HANN_CORRELATION_INFLATION = 1.0 + 2.0 * (4.0 / 9.0 + 1.0 / 36.0)


@dataclass
class ModalPeak:
    """One resonance: frequency [Hz] and damping ratio [-] by half-power and by curve fit."""

    frequency: float
    zeta_half_power: float
    resolved: bool
    frequency_fit: float = np.nan
    frequency_fit_stderr: float = np.nan
    zeta_fit: float = np.nan
    zeta_fit_stderr: float = np.nan
    fit_message: str = ""

    def to_json(self) -> dict:
        """A JSON-ready dict of the fields: frequencies [Hz], damping ratios [-] and their standard errors."""
        return dict(self.__dict__)


@dataclass
class DampingIdentification:
    """Peaks, the ratios used for the Rayleigh fit, and the fit."""

    peaks: list
    rayleigh: RayleighFit | None
    method: str
    band: tuple
    messages: list = field(default_factory=list)

    def to_json(self) -> dict:
        """A JSON-ready dict: the method, band [Hz], every peak and the Rayleigh fit."""
        return {
            "method": self.method,
            "band": list(self.band),
            "peaks": [p.to_json() for p in self.peaks],
            "rayleigh": None if self.rayleigh is None else self.rayleigh.to_json(),
            "messages": list(self.messages),
        }

    def to_yaml(self) -> str:
        """A model-config fragment ``damping: {alpha: ..., beta: ...}`` with the evidence as comments."""
        if self.rayleigh is None:
            raise FividError("no Rayleigh fit (fewer than two usable peaks): " + "; ".join(self.messages))
        r = self.rayleigh
        lines = [
            f"# Rayleigh damping identified by fivid from {r.n_modes} resonance peaks ({self.method}):",
        ]
        for p in self.peaks:
            z, se = _zeta_of(p, self.method)
            lines.append(f"#   f = {p.frequency:.6g} Hz, zeta = {z:.4g} +- {se:.2g}")
        lines += [
            f"# alpha stderr {r.alpha_stderr:.3g} s-1, beta stderr {r.beta_stderr:.3g} s, "
            f"correlation {r.covariance[0, 1] / np.sqrt(r.covariance[0, 0] * r.covariance[1, 1]):.3f}"
            if np.all(np.diag(r.covariance) > 0) else "# (covariance not available)",
            "damping:",
            f"  alpha: {r.alpha:.6g} s-1",
            f"  beta: {r.beta:.6g} s",
            "",
        ]
        return "\n".join(lines)

    def summary(self) -> str:
        """Human-readable lines: each peak's frequency [Hz] and damping ratios [-], then the Rayleigh fit."""
        lines = [f"damping ({self.method}, band {self.band[0]:g}-{self.band[1]:g} Hz):"]
        for p in self.peaks:
            lines.append(f"  f {p.frequency:10.2f} Hz  zeta half-power {p.zeta_half_power:.4g}"
                         f"{'' if p.resolved else ' (unresolved)'}  fit {p.zeta_fit:.4g} ± {p.zeta_fit_stderr:.2g}")
        if self.rayleigh is not None:
            r = self.rayleigh
            lines.append(f"  Rayleigh alpha {r.alpha:.4g} ± {r.alpha_stderr:.2g} s-1, beta {r.beta:.4g} ± "
                         f"{r.beta_stderr:.2g} s")
        lines += [f"  note: {m}" for m in self.messages]
        return "\n".join(lines)


def _zeta_of(peak, method):
    if method == "curve_fit" and np.isfinite(peak.zeta_fit):
        return peak.zeta_fit, peak.zeta_fit_stderr
    return peak.zeta_half_power, np.nan


def find_resonance_peaks(frequency, psd, band, n_peaks):
    """Indices of the ``n_peaks`` most prominent maxima of ln P in ``band`` (ascending frequency)."""
    from scipy.signal import find_peaks

    f = np.asarray(frequency, float)
    inside = np.nonzero((f >= band[0]) & (f <= band[1]))[0]
    if inside.size < 5:
        raise FividError(f"band {band[0]:g}-{band[1]:g} Hz holds {inside.size} spectral bins; widen it")
    logp = np.log(np.maximum(np.asarray(psd, float)[inside], np.finfo(float).tiny))
    idx, props = find_peaks(logp, prominence=np.log(4.0))  # 6 dB above the surrounding valleys
    if idx.size == 0:
        return np.array([], dtype=int)
    order = np.argsort(props["prominences"])[::-1][:n_peaks]
    return np.sort(inside[idx[order]])


def half_power_damping(frequency, psd, k):
    """Half-power damping ratio of the peak at bin ``k``; returns (ζ, f1, f2, width in bins) or NaNs."""
    f = np.asarray(frequency, float)
    p = np.asarray(psd, float)
    half = p[k] / 2
    i = k
    while i > 0 and p[i] > half:
        i -= 1
    j = k
    while j < p.size - 1 and p[j] > half:
        j += 1
    if p[i] > half or p[j] > half:
        return np.nan, np.nan, np.nan, np.nan
    f1 = np.interp(half, [p[i], p[i + 1]], [f[i], f[i + 1]])
    f2 = np.interp(half, [p[j], p[j - 1]], [f[j], f[j - 1]])
    return (f2 - f1) / (2 * f[k]), f1, f2, (f2 - f1) / (f[1] - f[0])


def _window_kernel(window: str, nperseg: int, oversample: int = 16, half_width_bins: int = 6):
    """Offsets [bins] and normalised |W|^2 of the Welch window (sums to 1), for the smoothed model."""
    from scipy.signal import get_window

    w = get_window(window, nperseg)
    spec = np.abs(np.fft.fft(w, nperseg * oversample)) ** 2
    spec = np.fft.fftshift(spec)
    offs = (np.arange(spec.size) - spec.size // 2) / oversample
    keep = np.abs(offs) <= half_width_bins
    k = spec[keep]
    return offs[keep], k / k.sum()


def fit_mode(frequency, psd, k, zeta0, *, window="hann", nperseg=None, response_power=4):
    """Curve fit of one mode at bin ``k`` (see the module docstring).

    ``response_power`` is q of the model (4: acceleration PSD or accelerance).
    Returns (f_n, se f_n, ζ, se ζ, message); NaNs and a message when the fit fails.
    """
    from scipy.optimize import curve_fit

    f = np.asarray(frequency, float)
    p = np.asarray(psd, float)
    df = f[1] - f[0]
    fn0 = f[k]
    zeta0 = zeta0 if np.isfinite(zeta0) and zeta0 > 0 else 3 * df / fn0
    half = max(6 * zeta0 * fn0, 8 * df)
    sel = np.nonzero((f >= fn0 - half) & (f <= fn0 + half) & (p > 0))[0]
    if sel.size < 6:
        return np.nan, np.nan, np.nan, np.nan, "too few bins around the peak"
    offs, ker = (np.zeros(1), np.ones(1)) if nperseg is None else _window_kernel(window, nperseg)
    fx = f[sel]
    grid = fx[:, None] + offs[None, :] * df
    gq = (np.abs(grid) / fn0) ** response_power

    def model(x, lnc, fn, lnzeta, lnb):
        z = np.exp(lnzeta)
        s = np.exp(lnc) * gq / ((fn**2 - grid**2) ** 2 + (2 * z * fn * grid) ** 2) + np.exp(lnb)
        return np.log(s @ ker)

    peak_height = p[k] * ((2 * zeta0 * fn0**2) ** 2)
    floor = max(np.percentile(p[sel], 5) / 10, np.finfo(float).tiny)
    p0 = (np.log(peak_height), fn0, np.log(zeta0), np.log(floor))
    y = np.log(p[sel])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            popt, pcov = curve_fit(model, fx, y, p0=p0, maxfev=20000)
            if not np.all(np.isfinite(np.diag(pcov)[1:3])):
                # a floor far below the peak is not identifiable (singular covariance): keep it fixed at
                # its fitted value and refit the three mode parameters
                lnb = popt[3]
                popt3, pcov3 = curve_fit(lambda x, a, b, c: model(x, a, b, c, lnb), fx, y, p0=popt[:3], maxfev=20000)
                popt = np.r_[popt3, lnb]
                pcov = np.pad(pcov3, ((0, 1), (0, 1)))
    except (RuntimeError, ValueError) as exc:
        return np.nan, np.nan, np.nan, np.nan, f"curve fit failed: {exc}"
    se = np.sqrt(np.diag(pcov) * HANN_CORRELATION_INFLATION)
    zeta = float(np.exp(popt[2]))
    if not np.all(np.isfinite(se[1:3])):
        return float(popt[1]), np.nan, zeta, np.nan, "curve fit gave no covariance"
    return float(popt[1]), float(se[1]), zeta, float(zeta * se[2]), ""


def _response_power(units: str) -> int:
    """q of the mode model from the spectrum's units: 4 acceleration, 2 velocity, 0 displacement.

    A PSD (units with ``Hz-1``) of acceleration has ``s-4``, of velocity ``s-2``; an FRF of
    acceleration has ``s-2``, of velocity ``s-1``.
    """
    tokens = units.split()
    if "Hz-1" in tokens:
        return 4 if "s-4" in tokens else 2 if "s-2" in tokens else 0
    return 4 if "s-2" in tokens else 2 if "s-1" in tokens else 0


def _spectrum_from(source, nperseg):
    """(frequency, power-like spectrum, window, nperseg, q) from runs, a PSD DataArray or a complex FRF."""
    if hasattr(source, "dims") and "frequency" in source.dims:
        values = np.asarray(source.values)
        if values.ndim > 1:
            other = [d for d in source.dims if d != "frequency"]
            values = np.moveaxis(values, source.dims.index("frequency"), -1).reshape(-1, source.sizes["frequency"])
            values = (np.abs(values) ** 2 if np.iscomplexobj(values) else values).mean(axis=0)
            del other
        elif np.iscomplexobj(values):
            values = np.abs(values) ** 2
        n = source.attrs.get("nperseg")
        return (np.asarray(source["frequency"].values, float), values, source.attrs.get("window", "hann"), n,
                _response_power(str(source.attrs.get("units", ""))))
    runs = list(source)
    if not runs:
        raise FividError("no runs given for the damping identification")
    acc = []
    for ds in runs:
        if "acceleration" not in ds:
            raise DataQualityError(f"run {ds.attrs.get('run_id')!r} has no 'acceleration' to identify damping from")
        fs = float(ds.attrs["sample_rate"])
        n = nperseg or default_nperseg(fs, ds.sizes["time"])
        p = welch_psd(ds["acceleration"], nperseg=n, fs=fs)
        values = np.asarray(p.values, float)
        if values.ndim > 1:
            values = values.reshape(-1, values.shape[-1]).mean(axis=0)
        acc.append((np.asarray(p["frequency"].values, float), values / values.sum(), n))
    f0 = acc[0][0]
    if any(a[0].shape != f0.shape or not np.allclose(a[0], f0) for a in acc):
        raise FividError("the runs have different sample rates or lengths; give nperseg so their PSD grids agree")
    return f0, np.mean([a[1] for a in acc], axis=0), "hann", acc[0][2], 4


def identify_damping(source, *, band, n_peaks: int = 4, nperseg: int | None = None,
                     method: str = "curve_fit") -> DampingIdentification:
    """Modal damping ratios from the resonance peaks in ``band`` and a Rayleigh (α, β) fit.

    Parameters
    ----------
    source : sequence of RunDataset, or xarray.DataArray
        Runs (the averaged normalised acceleration PSD is used), a PSD on dim ``frequency``, or a
        complex FRF on dim ``frequency`` (|H|^2 is used).
    band : (float, float)
        Band searched for peaks [Hz].
    n_peaks : int
        Number of most prominent peaks kept.
    nperseg : int, optional
        Welch segment length for runs [samples].
    method : {"curve_fit", "half_power"}
        Which ζ goes into the Rayleigh fit (both are reported).
    """
    if method not in ("curve_fit", "half_power"):
        raise FividError(f"damping method {method!r} is not one of 'curve_fit', 'half_power'")
    if isinstance(n_peaks, bool) or not isinstance(n_peaks, (int, np.integer)) or n_peaks < 1:
        raise ConfigError(f"n_peaks (--damping-peaks) must be an integer >= 1 (a Rayleigh fit needs 2), "
                          f"got {n_peaks!r}", key="n_peaks")
    f, p, window, n, q = _spectrum_from(source, nperseg)
    band = (float(band[0]), float(band[1]))
    if band[1] > f[-1] or not band[0] < band[1]:
        raise FividError(f"damping band {band[0]:g}-{band[1]:g} Hz must lie within 0-{f[-1]:g} Hz (Nyquist)")
    idx = find_resonance_peaks(f, p, band, n_peaks)
    peaks, messages = [], []
    for k in idx:
        zhp, f1, f2, width = half_power_damping(f, p, k)
        fn, fn_se, zf, zf_se, msg = fit_mode(f, p, k, zhp, window=window, nperseg=n, response_power=q)
        peaks.append(ModalPeak(float(f[k]), float(zhp), bool(np.isfinite(width) and width >= 5.0),
                               fn, fn_se, zf, zf_se, msg))
    usable = [pk for pk in peaks if np.isfinite(_zeta_of(pk, method)[0])
              and (np.isfinite(pk.zeta_fit_stderr) if method == "curve_fit" else pk.resolved)]
    if len(peaks) < 2:
        messages.append(f"{len(peaks)} resonance peak(s) found in the band (prominence 6 dB); Rayleigh needs two")
    rayleigh = None
    if len(usable) >= 2:
        freq = [pk.frequency_fit if method == "curve_fit" else pk.frequency for pk in usable]
        zs = [_zeta_of(pk, method) for pk in usable]
        rayleigh = fit_rayleigh_least_squares(freq, [z for z, _ in zs], [s for _, s in zs] if method == "curve_fit" else None)
    elif len(peaks) >= 2:
        messages.append("fewer than two peaks have a usable damping ratio (unresolved or failed fits)")
    return DampingIdentification(peaks=peaks, rayleigh=rayleigh, method=method, band=band, messages=messages)
