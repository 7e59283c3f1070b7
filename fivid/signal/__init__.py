"""Spectral analysis of rig and simulation signals (layer L2).

Welch PSD and cross-spectra with χ² bounds (:func:`welch_psd`, :func:`csd`), FRF estimators H1/H2 and
coherence, band RMS, IEC 61260-1 1/3-octave levels, the vibration level Lv(dB), the steady-sliding
window and resampling to a common rate; the comparison of two spectra (log-spectral distance, level
difference, band levels: :mod:`fivid.signal.compare`) and their peaks (:mod:`fivid.signal.peaks`). It is the one
home of spectra: no other package calls scipy.signal.welch/csd (tests/project/test_architecture.py). The pure numpy computations live in
:mod:`fivid.signal.spectral` (and :mod:`fivid.signal.fft` for the planned FFTs); the functions here
wrap DataArrays/Datasets and record units and settings in attrs.
"""

from fivid.signal.compare import band_distance, level_difference_db, log_spectral_distance
from fivid.signal.frf import coherence, frf
from fivid.signal.levels import band_rms, third_octave_bands, third_octave_levels, vibration_level_db
from fivid.signal.resample import resample_to
from fivid.signal.steady import measured_window, steady_force_window, steady_part, steady_sliding_window
from fivid.units import power_units
from fivid.signal.spectral import welch_density
from fivid.signal.welch import csd, welch_psd

__all__ = [
    "welch_psd",
    "welch_density",
    "csd",
    "frf",
    "coherence",
    "band_rms",
    "third_octave_bands",
    "third_octave_levels",
    "vibration_level_db",
    "steady_sliding_window",
    "steady_part",
    "steady_force_window",
    "measured_window",
    "resample_to",
    "power_units",
    "log_spectral_distance",
    "level_difference_db",
    "band_distance",
]
