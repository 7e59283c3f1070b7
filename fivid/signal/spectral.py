"""Welch-averaged auto- and cross-spectral densities on plain numpy arrays (no units, no xarray).

The pure computation layer under :mod:`fivid.signal.welch`: segments are strided views of the
signal (:func:`numpy.lib.stride_tricks.sliding_window_view`), detrended and windowed in blocks and
transformed by :class:`fivid.signal.fft.SegmentTransform` (planned pyfftw, or numpy). Scaling and
segmentation follow :func:`scipy.signal.welch` / :func:`scipy.signal.csd` exactly (``average="mean"``,
no boundary padding, last partial segment dropped), so the numbers agree to round-off.

References
----------
P. D. Welch, "The use of fast Fourier transform for the estimation of power spectra", IEEE Trans.
Audio Electroacoust. 15(2), 70-73, 1967.
D. B. Percival and A. T. Walden, *Spectral Analysis for Physical Applications*, Cambridge, 1993,
§6.17 (equivalent degrees of freedom of WOSA estimates, eq. 292b).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError
from fivid.signal.fft import SegmentTransform

__all__ = [
    "DETRENDS",
    "check_nperseg",
    "segment_window",
    "segment_count",
    "SpectralSettings",
    "averaged_spectra",
    "welch_density",
    "equivalent_degrees_of_freedom",
    "bin_correlation",
    "bin_degrees_of_freedom",
    "chi2_interval",
]

DETRENDS = ("constant", "linear", "none")
_BLOCK_VALUES = 1 << 19  # samples per block of segments (4 MiB of float64): measured fastest on 2 cores


def segment_window(window, nperseg: int) -> np.ndarray:
    """The taper of ``nperseg`` samples, periodic (DFT-even) as :func:`scipy.signal.welch` uses it.

    ``window`` is a name or tuple understood by :func:`scipy.signal.get_window` (``"hann"``,
    ``("tukey", 0.25)``) or an array of length ``nperseg``.
    """
    import scipy.signal

    if isinstance(window, (str, tuple)):
        try:
            return np.asarray(scipy.signal.get_window(window, nperseg, fftbins=True), dtype=np.float64)
        except (ValueError, TypeError) as exc:
            raise ConfigError(f"unknown window {window!r} ({exc}); use e.g. 'hann', 'hamming', ('tukey', 0.25)",
                              key="window") from None
    w = np.asarray(window, dtype=np.float64)
    if w.shape != (nperseg,):
        raise ConfigError(f"window array has shape {w.shape}; expected ({nperseg},) = nperseg samples", key="window")
    return w


def segment_count(n: int, nperseg: int, noverlap: int) -> int:
    """Number of full segments of ``nperseg`` samples, advancing by ``nperseg - noverlap``, in ``n`` samples."""
    if n < nperseg:
        return 0
    return (n - noverlap) // (nperseg - noverlap)


def check_nperseg(nperseg) -> int:
    """``nperseg`` as an int; :class:`~fivid.errors.ConfigError` unless it is an integer >= 2 [samples]."""
    if isinstance(nperseg, bool) or int(nperseg) != nperseg or nperseg < 2:
        raise ConfigError(f"nperseg must be an integer >= 2, got {nperseg!r}", key="nperseg")
    return int(nperseg)


@dataclass(frozen=True)
class SpectralSettings:
    """Welch settings, all explicit.

    Attributes
    ----------
    fs : float
        Sampling rate [Hz].
    nperseg : int
        Segment length [samples].
    noverlap : int
        Overlap of consecutive segments [samples], ``0 <= noverlap < nperseg``.
    window : str, tuple or ndarray
        Taper (see :func:`segment_window`).
    detrend : {"constant", "linear", "none"}
        Per-segment detrending.
    backend : {"pyfftw", "numpy"} or None
        FFT implementation (None: pyfftw when available).
    threads : int or None
        FFTW threads (None: :data:`fivid.signal.fft.FFTW_THREADS`, 1, the fastest on a loaded machine).
    """

    fs: float
    nperseg: int
    noverlap: int
    window: object = "hann"
    detrend: str = "constant"
    backend: str | None = None
    threads: int | None = None

    def __post_init__(self):
        if not (np.isfinite(self.fs) and self.fs > 0):
            raise ConfigError(f"sampling rate must be a positive number of Hz, got {self.fs!r}", key="fs")
        check_nperseg(self.nperseg)
        if int(self.noverlap) != self.noverlap or not 0 <= self.noverlap < self.nperseg:
            raise ConfigError(
                f"noverlap must be an integer in [0, nperseg) = [0, {self.nperseg}), got {self.noverlap!r}",
                key="noverlap",
            )
        if self.threads is not None and (int(self.threads) != self.threads or self.threads < 1):
            raise ConfigError(f"threads must be a positive integer, got {self.threads!r}", key="threads")
        if self.detrend not in DETRENDS:
            raise ConfigError(f"unknown detrend {self.detrend!r}; choose one of {', '.join(DETRENDS)}", key="detrend")

    @property
    def step(self) -> int:
        """Hop between segment starts [samples]."""
        return int(self.nperseg) - int(self.noverlap)

    def frequencies(self) -> np.ndarray:
        """The one-sided frequency grid [Hz]: ``k fs / nperseg``, k = 0 … nperseg // 2."""
        return np.arange(self.nperseg // 2 + 1) * (self.fs / self.nperseg)


def _transformer(settings: SpectralSettings, w: np.ndarray) -> SegmentTransform:
    rows = max(1, _BLOCK_VALUES // settings.nperseg)
    detrend = None if settings.detrend == "none" else settings.detrend
    return SegmentTransform(w, detrend, rows, settings.backend, settings.threads)


def _one_sided_density(acc: np.ndarray, settings: SpectralSettings, w: np.ndarray, k: int) -> np.ndarray:
    scale = 1.0 / (settings.fs * np.dot(w, w) * k)
    out = acc * scale
    stop = -1 if settings.nperseg % 2 == 0 else None  # the Nyquist bin (even n) is not doubled
    out[1:stop] *= 2.0
    return out


def averaged_spectra(x: np.ndarray, settings: SpectralSettings, y: np.ndarray | None = None):
    """Welch-averaged one-sided spectral densities of ``x`` (and ``y``).

    Parameters
    ----------
    x : ndarray, shape (n,)
        Uniformly sampled signal, finite, in some unit [u].
    settings : SpectralSettings
        Sampling rate and Welch settings.
    y : ndarray, shape (n,), optional
        A second signal [v] for cross-spectra.

    Returns
    -------
    frequency : ndarray [Hz]
    pxx : ndarray [u2 Hz-1]
        Auto-spectral density of ``x``.
    pyy, pxy : ndarray or None
        With ``y``: auto-spectral density of ``y`` [v2 Hz-1] and the cross-spectral density
        ``E[conj(X) Y]`` [u v Hz-1] (the convention of :func:`scipy.signal.csd`).
    nsegments : int
        Number of averaged segments.
    """
    from numpy.lib.stride_tricks import sliding_window_view

    x = np.ascontiguousarray(x, dtype=np.float64)
    n, nperseg = x.size, int(settings.nperseg)
    k_total = segment_count(n, nperseg, int(settings.noverlap))
    if k_total < 1:
        raise ConfigError(f"signal of {n} samples is shorter than one segment (nperseg = {nperseg})", key="nperseg")
    w = segment_window(settings.window, nperseg)
    transform = _transformer(settings, w)
    nfreq = nperseg // 2 + 1
    xs = sliding_window_view(x, nperseg)[:: settings.step][:k_total]
    if y is None:
        acc = np.zeros(2 * nfreq)
        with transform.locked():
            for start in range(0, k_total, transform.rows):
                spec = transform.transform(xs[start:start + transform.rows])
                flat = spec.view(np.float64)  # (k, 2 nfreq): re, im interleaved; squared in place
                np.square(flat, out=flat)
                acc += flat.sum(axis=0)
        power = acc[0::2] + acc[1::2]
        return settings.frequencies(), _one_sided_density(power, settings, w, k_total), None, None, k_total
    y = np.ascontiguousarray(y, dtype=np.float64)
    if y.shape != x.shape:
        raise ConfigError(f"x and y must have the same length, got {x.size} and {y.size} samples")
    ys = sliding_window_view(y, nperseg)[:: settings.step][:k_total]
    sxx = np.zeros(nfreq)
    syy = np.zeros(nfreq)
    sxy = np.zeros(nfreq, dtype=np.complex128)
    with transform.locked():
        for start in range(0, k_total, transform.rows):
            stop = start + transform.rows
            fx = np.array(transform.transform(xs[start:stop]))  # copy: the next call reuses the buffer
            fy = transform.transform(ys[start:stop])
            sxx += (fx.real**2 + fx.imag**2).sum(axis=0)
            syy += (fy.real**2 + fy.imag**2).sum(axis=0)
            sxy += (np.conj(fx) * fy).sum(axis=0)
    f = settings.frequencies()
    return (
        f,
        _one_sided_density(sxx, settings, w, k_total),
        _one_sided_density(syy, settings, w, k_total),
        _one_sided_density(sxy, settings, w, k_total),
        k_total,
    )


def welch_density(x, fs: float, *, nperseg: int, noverlap: int | None = None, window="hann",
                  detrend="constant") -> tuple[np.ndarray, np.ndarray]:
    """One-sided Welch PSD of a plain array: ``(frequency [Hz], density [u2 Hz-1])``.

    The array-level entry of fivid's spectra for code that holds numbers, not DataArrays (study points, profiles
    over ``x`` with ``fs = 1 / dx`` [m-1]): :func:`scipy.signal.welch` with every setting explicit
    (``scaling="density"``, ``average="mean"``, one-sided, no padding). The DataArray entry with units, χ² bounds
    and recorded settings is :func:`fivid.signal.welch_psd` (:func:`averaged_spectra`, pyfftw), which agrees with
    it to round-off (tests/signal/test_signal_compare.py).

    Parameters
    ----------
    x : array_like, shape (n,)
        Uniformly sampled signal [u], finite, ``n >= nperseg``.
    fs : float
        Sampling rate [Hz] (or samples per unit of whatever ``x`` is sampled over).
    nperseg : int
        Segment length [samples].
    noverlap : int, optional
        Overlap [samples]; default ``nperseg // 2``.
    window : str, tuple or ndarray, default "hann"
        Taper (:func:`segment_window`).
    detrend : {"constant", "linear", "none"} or False, default "constant"
        Per-segment detrending.

    Returns
    -------
    (ndarray, ndarray)
        Frequencies ``k fs / nperseg`` and the density; ``sum(p) * fs / nperseg`` is the variance of the
        detrended signal.

    Examples
    --------
    White noise of variance 1 sampled at 1 kHz has the density 2 / fs = 2e-3 Hz-1:

    >>> x = np.random.default_rng(0).standard_normal(2**16)
    >>> f, p = welch_density(x, 1000.0, nperseg=256)
    >>> bool(abs(p[1:-1].mean() / 2e-3 - 1) < 0.02)
    True
    """
    import scipy.signal

    nperseg = check_nperseg(nperseg)
    noverlap = nperseg // 2 if noverlap is None else int(noverlap)
    detrend = "none" if detrend in (None, False) else detrend
    SpectralSettings(fs=float(fs), nperseg=nperseg, noverlap=noverlap, window=window, detrend=detrend)  # checks
    x = np.asarray(x, dtype=np.float64)
    if x.size < nperseg:
        raise ConfigError(f"signal of {x.size} samples is shorter than one segment (nperseg = {nperseg})",
                          key="nperseg")
    return scipy.signal.welch(x, fs=float(fs), window=window, nperseg=nperseg, noverlap=noverlap,
                              detrend=False if detrend == "none" else detrend, scaling="density",
                              return_onesided=True, average="mean")


def equivalent_degrees_of_freedom(window: np.ndarray, nsegments: int, step: int) -> float:
    """Equivalent degrees of freedom ν of a Welch (WOSA) estimate of a locally flat spectrum.

    Percival & Walden (1993) eq. (292b), after Welch (1967):
    ``ν = 2 K / (1 + 2 Σ_{m=1}^{K-1} (1 - m/K) ρ(m S)²)`` with ``ρ(j) = Σ_t w_t w_{t+j} / Σ_t w_t²``
    the overlap correlation of the window at a shift of ``j`` samples, ``K`` segments, hop ``S``.
    Each interior-bin estimate is then distributed as ``S ν⁻¹ χ²_ν``. Hann at 50 % overlap gives
    ρ = 1/6 (continuous limit) and ν ≈ 1.89 K for large K.
    """
    w = np.asarray(window, dtype=np.float64)
    n = w.size
    norm = np.dot(w, w)
    k = int(nsegments)
    total = 0.0
    for m in range(1, k):
        lag = m * int(step)
        if lag >= n:
            break
        rho = np.dot(w[: n - lag], w[lag:]) / norm
        total += (1.0 - m / k) * rho * rho
    return 2.0 * k / (1.0 + 2.0 * total)


def bin_degrees_of_freedom(nu: float, nperseg: int) -> np.ndarray:
    """Degrees of freedom per one-sided bin: ν inside; ν/2 at 0 Hz and (even ``nperseg``) at Nyquist,
    where a real signal's DFT ordinate is real (one χ² degree of freedom per segment instead of two)."""
    dof = np.full(nperseg // 2 + 1, float(nu))
    dof[0] = nu / 2.0
    if nperseg % 2 == 0:
        dof[-1] = nu / 2.0
    return dof


def bin_correlation(window: np.ndarray, max_shift: int | None = None) -> np.ndarray:
    """Correlation of two periodogram ordinates ``m`` bins apart, for a locally flat spectrum.

    For Gaussian data ``corr(|X_k|², |X_{k+m}|²) = |Σ_t w_t² e^{-2πi m t/N}|² / (Σ_t w_t²)²``
    (Percival & Walden 1993, §6.6); averaging segments keeps the ratio. Hann: 1, 4/9, 1/36, 0, …

    Returns
    -------
    ndarray, shape (max_shift + 1,)
        ``r[m]`` for m = 0 … max_shift (default: where it falls below 1e-6, at most N/2).
    """
    w2 = np.asarray(window, dtype=np.float64) ** 2
    spectrum = np.fft.rfft(w2)
    r = np.abs(spectrum) ** 2 / np.abs(spectrum[0]) ** 2
    if max_shift is None:
        above = np.nonzero(r > 1e-6)[0]
        max_shift = int(above[-1]) if above.size else 0
    return r[: max_shift + 1]


def chi2_interval(estimate: np.ndarray, dof, confidence: float) -> tuple[np.ndarray, np.ndarray]:
    """Two-sided χ² confidence interval of a spectral density from its degrees of freedom.

    ``[ν P / χ²_ν((1+c)/2), ν P / χ²_ν((1-c)/2)]`` (Percival & Walden 1993, eq. 258).
    """
    from scipy.stats import chi2

    if not 0.0 < confidence < 1.0:
        raise ConfigError(f"confidence must be in (0, 1), got {confidence!r}", key="confidence")
    dof = np.asarray(dof, dtype=np.float64)
    lower = estimate * dof / chi2.ppf(0.5 + confidence / 2.0, dof)
    upper = estimate * dof / chi2.ppf(0.5 - confidence / 2.0, dof)
    return lower, upper
