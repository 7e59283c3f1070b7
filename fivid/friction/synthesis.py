"""Synthesis of the friction perturbation μp(t) with a target one-sided PSD.

Spectral synthesis on the FFT grid of the requested record: for ``n`` samples at ``fs`` the rfft bins
are ``f_k = k fs / n``. A real series ``x`` with rfft ``X_k`` has the one-sided periodogram
``P_k = 2 |X_k|^2 / (fs n)`` (``0 < k < n/2``), so a coefficient with ``E|X_k|^2 = S(f_k) fs n / 2``
gives ``E[P_k] = S(f_k)`` and a variance ``(1/n) sum x^2 = sum_k S(f_k) Δf`` = the band power.

Two ways of drawing the coefficients:

``"gaussian"`` (default)
    ``X_k = sqrt(S_k fs n / 2) (g1 + i g2) / sqrt(2)`` with independent standard normals: the exact
    spectral representation of a stationary Gaussian process, periodic with period ``n / fs``
    (filtered white noise by circular convolution). Welch estimates of it follow the χ² law.
``"random_phase"``
    ``|X_k| = sqrt(S_k fs n / 2)`` with a uniform random phase: the periodogram and the RMS equal
    their targets exactly (no amplitude scatter), the series is asymptotically Gaussian.

The DC and Nyquist bins are zero: μp is zero-mean. The inverse FFT uses pyfftw when it can be
imported and numpy otherwise; both get the same random coefficients, so they give the same numbers
to floating-point rounding (``~ eps log2(n)`` relative). Random numbers come from
``numpy.random.default_rng(seed)``: the same seed gives the same series on every machine.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import FividError

__all__ = ["synthesise_perturbation", "fft_frequencies", "SYNTHESIS_METHODS", "inverse_rfft", "check_sampling"]

SYNTHESIS_METHODS = ("gaussian", "random_phase")


def fft_frequencies(n_samples: int, sample_rate: float) -> np.ndarray:
    """The rfft bin frequencies ``k fs / n`` [Hz] of a record of ``n_samples`` at ``sample_rate`` [Hz]."""
    return np.arange(n_samples // 2 + 1) * (float(sample_rate) / n_samples)


def check_sampling(duration, sample_rate, n_signals) -> int:
    """Validate a record request; return its number of samples ``round(duration * sample_rate)`` (>= 4).

    Parameters
    ----------
    duration : float
        Record length [s], finite and > 0.
    sample_rate : float
        [Hz], finite and > 0.
    n_signals : int
        Number of series, a positive integer.
    """
    duration, sample_rate = float(duration), float(sample_rate)
    if not (np.isfinite(sample_rate) and sample_rate > 0):
        raise FividError(f"sample_rate = {sample_rate!r} Hz; it must be a positive number")
    if not (np.isfinite(duration) and duration > 0):
        raise FividError(f"duration = {duration!r} s; it must be a positive number")
    if int(n_signals) != n_signals or n_signals < 1:
        raise FividError(f"n_signals = {n_signals!r}; it must be a positive integer")
    n = int(round(duration * sample_rate))
    if n < 4:
        raise FividError(f"duration {duration} s at {sample_rate} Hz gives {n} samples; at least 4 are needed")
    return n


def inverse_rfft(coefficients: np.ndarray, n_samples: int, *, backend: str = "auto") -> np.ndarray:
    """Inverse real FFT along the last axis (pyfftw if available, else numpy).

    Parameters
    ----------
    coefficients : ndarray, complex
        rfft coefficients, shape ``(..., n_samples // 2 + 1)``.
    n_samples : int
        Length of the real output.
    backend : {"auto", "pyfftw", "numpy"}
        ``"auto"`` uses pyfftw when it can be imported.
    """
    if backend not in ("auto", "pyfftw", "numpy"):
        raise FividError(f"FFT backend {backend!r} is not one of 'auto', 'pyfftw', 'numpy'")
    if backend in ("auto", "pyfftw"):
        try:
            import pyfftw.interfaces.numpy_fft as pyfftw_fft
        except ImportError:
            if backend == "pyfftw":
                raise FividError("FFT backend 'pyfftw' asked for but pyfftw cannot be imported") from None
        else:
            return pyfftw_fft.irfft(coefficients, n=n_samples, axis=-1)
    return np.fft.irfft(coefficients, n=n_samples, axis=-1)


def synthesise_perturbation(
    psd,
    duration: float,
    sample_rate: float,
    seed: int,
    *,
    n_signals: int = 1,
    method: str = "gaussian",
    backend: str = "auto",
) -> np.ndarray:
    """Zero-mean series whose one-sided PSD is ``psd(f)``.

    Parameters
    ----------
    psd : callable
        ``psd(frequency)`` -> one-sided PSD [unit^2 Hz-1] at the given frequencies [Hz] (an ndarray);
        values must be finite and non-negative.
    duration : float
        Record length [s]; ``n = round(duration * sample_rate)`` samples.
    sample_rate : float
        [Hz].
    seed : int
        Seed of ``numpy.random.default_rng``; the series are a pure function of it.
    n_signals : int, default 1
        Number of independent series (rows of the output).
    method : {"gaussian", "random_phase"}
        See the module docstring.
    backend : {"auto", "pyfftw", "numpy"}
        Inverse-FFT implementation.

    Returns
    -------
    ndarray, shape (n_signals, n)
        The series [unit]; periodic with period ``n / sample_rate``.

    Examples
    --------
    >>> x = synthesise_perturbation(lambda f: np.full(f.shape, 1e-6), 1.0, 1000.0, seed=1)
    >>> x.shape
    (1, 1000)
    """
    n = check_sampling(duration, sample_rate, n_signals)
    sample_rate = float(sample_rate)
    if method not in SYNTHESIS_METHODS:
        raise FividError(f"synthesis method {method!r} is not one of {', '.join(SYNTHESIS_METHODS)}")
    n_signals = int(n_signals)
    f = fft_frequencies(n, sample_rate)
    target = np.asarray(psd(f), dtype=float)
    if target.shape != f.shape:
        raise FividError(f"psd(frequency) returned shape {target.shape}; expected {f.shape}")
    if not np.all(np.isfinite(target)) or np.any(target < 0):
        raise FividError("psd(frequency) returned negative or non-finite values; a PSD is finite and >= 0")
    scale = np.sqrt(target * sample_rate * n / 2.0)
    scale[0] = 0.0
    if n % 2 == 0:
        scale[-1] = 0.0  # the Nyquist bin of an even record is real: leave it empty
    rng = np.random.default_rng(seed)
    if method == "gaussian":
        g = rng.standard_normal((n_signals, 2, f.size))
        coeff = scale * (g[:, 0] + 1j * g[:, 1]) / np.sqrt(2.0)
    else:
        phase = rng.uniform(0.0, 2.0 * np.pi, (n_signals, f.size))
        coeff = scale * np.exp(1j * phase)
    return inverse_rfft(coeff, n, backend=backend)
