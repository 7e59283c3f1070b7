"""Spectral analysis of rig and simulation signals (layer L2).

Welch PSD and cross-spectra with χ² bounds (:func:`welch_psd`, :func:`csd`), FRF estimators and
coherence, band and 1/3-octave levels, the vibration level Lv(dB), the steady-sliding window and
resampling to a common rate. Pure numpy computations live in :mod:`fivid.signal.spectral`; the
functions here wrap DataArrays/Datasets and record units and settings in attrs.
"""

from fivid.signal.steady import steady_sliding_window
from fivid.signal.unit_strings import power_units
from fivid.signal.welch import csd, welch_psd

__all__ = ["welch_psd", "csd", "power_units", "steady_sliding_window"]
