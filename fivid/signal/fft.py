"""Batched real FFTs of signal segments: planned pyfftw transforms, with a numpy fallback.

A Welch estimate transforms thousands of segments of the same length. FFTW is fastest when it is
planned once for a shape and reused: :class:`SegmentTransform` keeps one plan per (segments per
block, segment length, threads), a 2-D real-to-complex transform along the last axis over a whole
block of segments. The ``"numpy"`` backend (:func:`scipy.fft.rfft`) computes the same transform and
gives the same numbers to round-off; tests run one body on both.

Planner settings, measured twice on the project machine (2 cores, load average 8-10, 64 x 8192
float64 block): FFTW_ESTIMATE plans in 2-10 ms and executes in 1.26-1.41 ms; FFTW_MEASURE plans in
1.1 s and executes in 1.16-1.34 ms (5-8 % faster, not worth a second per shape in short CLI runs and
tests); two threads took 9-20 ms under that load (thread hand-off when the cores are busy), so the
default is one thread (:data:`FFTW_THREADS`; ``threads=`` asks for more); scipy.fft took 2.0-2.2 ms.

pyfftw is imported on first use (``import fivid`` stays light; pyfftw itself imports dask.array when
dask is installed, ~2-3 s once per process). Plans are cached per process (the
:data:`_MAX_PLANS` most recent) and guarded by a lock, so threads (dask workers) can share them.
"""

from __future__ import annotations

import threading

import numpy as np

from fivid.errors import ConfigError

__all__ = ["BACKENDS", "FFTW_THREADS", "default_backend", "check_backend", "SegmentTransform"]

BACKENDS = ("pyfftw", "numpy")

FFTW_THREADS = 1  # see the module docstring for the measurements behind these two
_FFTW_FLAGS = ("FFTW_ESTIMATE",)
_MAX_PLANS = 16
_plans: dict = {}
_plans_lock = threading.Lock()


def default_backend() -> str:
    """``"pyfftw"`` when pyfftw imports, else ``"numpy"``."""
    try:
        import pyfftw  # noqa: F401
    except ImportError:  # pragma: no cover - pyfftw is a dependency
        return "numpy"
    return "pyfftw"


def check_backend(backend: str | None) -> str:
    """The backend to use: ``None`` means :func:`default_backend`; unknown names raise ConfigError."""
    if backend is None:
        return default_backend()
    if backend not in BACKENDS:
        raise ConfigError(f"unknown FFT backend {backend!r}; choose one of {', '.join(BACKENDS)}", key="backend")
    return backend


class _FFTWPlan:
    """One planned pyfftw 2-D real FFT along the last axis, with its aligned buffers and a lock."""

    def __init__(self, rows: int, n: int, dtype: np.dtype, threads: int):
        import pyfftw

        cdtype = np.result_type(dtype, np.complex64)
        self.input = pyfftw.empty_aligned((rows, n), dtype=dtype)
        self.output = pyfftw.empty_aligned((rows, n // 2 + 1), dtype=cdtype)
        self.fftw = pyfftw.FFTW(
            self.input, self.output, axes=(-1,), direction="FFTW_FORWARD",
            flags=_FFTW_FLAGS, threads=threads,
        )
        self.lock = threading.Lock()


def _plan(rows: int, n: int, dtype: np.dtype, threads: int) -> _FFTWPlan:
    key = (rows, n, np.dtype(dtype).str, threads)
    with _plans_lock:
        plan = _plans.get(key)
        if plan is None:
            plan = _plans[key] = _FFTWPlan(rows, n, np.dtype(dtype), threads)
            while len(_plans) > _MAX_PLANS:  # forget the oldest; a caller holding it keeps it alive
                del _plans[next(iter(_plans))]
    return plan


class SegmentTransform:
    """Real FFT of blocks of segments, windowed and detrended on the way in.

    Parameters
    ----------
    window : ndarray, shape (n,)
        Taper applied to every segment after detrending.
    detrend : {"constant", "linear", None}
        Per-segment detrending: remove the mean, the least-squares line, or nothing.
    rows : int
        Segments per block (the planned first dimension).
    backend : {"pyfftw", "numpy"}
        FFT implementation.
    threads : int, optional
        FFTW threads (default :data:`FFTW_THREADS`).

    Use :meth:`transform` inside ``with transform.locked():`` when using the pyfftw backend from
    several threads; the returned array is the plan's output buffer, valid until the next call.
    """

    def __init__(self, window: np.ndarray, detrend: str | None, rows: int, backend: str, threads: int | None = None):
        self.window = np.asarray(window, dtype=np.float64)
        self.n = self.window.size
        self.detrend = detrend
        self.rows = int(rows)
        self.backend = check_backend(backend)
        if detrend == "linear":
            ramp = np.arange(self.n, dtype=np.float64) - (self.n - 1) / 2.0
            self._ramp = ramp / np.dot(ramp, ramp)  # slope = segments @ ramp / (ramp·ramp)
            self._ramp_raw = ramp
        threads = FFTW_THREADS if threads is None else int(threads)
        self._plan = _plan(self.rows, self.n, np.float64, threads) if self.backend == "pyfftw" else None

    def locked(self):
        """A context manager holding the plan's lock (a no-op lock for the numpy backend)."""
        return self._plan.lock if self._plan is not None else _NULL_LOCK

    def _prepare(self, segments: np.ndarray, out: np.ndarray) -> None:
        w = self.window
        if self.detrend == "constant":
            mean = segments.mean(axis=1)
            np.multiply(segments, w, out=out)
            out -= np.multiply.outer(mean, w)
        elif self.detrend == "linear":
            mean = segments.mean(axis=1)
            slope = segments @ self._ramp
            np.multiply(segments, w, out=out)
            out -= np.multiply.outer(mean, w)
            out -= np.multiply.outer(slope, self._ramp_raw * w)
        else:
            np.multiply(segments, w, out=out)

    def transform(self, segments: np.ndarray) -> np.ndarray:
        """Complex one-sided spectra, shape (k, n//2 + 1), of ``segments`` (k ≤ rows, n)."""
        k = segments.shape[0]
        if self._plan is None:
            import scipy.fft

            buf = np.empty((k, self.n), dtype=np.float64)
            self._prepare(segments, buf)
            return scipy.fft.rfft(buf, axis=-1)
        plan = self._plan
        self._prepare(segments, plan.input[:k])
        if k < self.rows:
            plan.input[k:] = 0.0
        plan.fftw()
        return plan.output[:k]


class _NullLock:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


_NULL_LOCK = _NullLock()
