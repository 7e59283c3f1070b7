"""The shape score of DESIGN §6 on plain arrays: two one-sided PSDs on one frequency grid.

``P_m`` is the measured PSD, ``P_s`` the simulated one, both restricted to the scoring band. Pure
functions, no uncertainty (that is :mod:`fivid.score.uncertainty`) and no xarray. The other spectral measures
the scores use (log-spectral distance, level difference, band levels, peaks) live in :mod:`fivid.signal.compare`
and :mod:`fivid.signal.peaks`, their one home.
"""

from __future__ import annotations

import numpy as np

from fivid.signal.compare import log_psd_db

__all__ = ["shape_correlation"]


def shape_correlation(p_m: np.ndarray, p_s: np.ndarray) -> float:
    """Pearson correlation of the two log-PSDs [-] (1: same shape, whatever the level)."""
    a = log_psd_db(p_m, label="measured")
    b = log_psd_db(p_s, label="simulated")
    a = a - a.mean()
    b = b - b.mean()
    den = np.sqrt(np.dot(a, a) * np.dot(b, b))
    if den == 0:
        return float("nan")
    return float(np.clip(np.dot(a, b) / den, -1.0, 1.0))
