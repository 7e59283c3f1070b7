"""DAQ glitches in force records: isolated spikes and short dropouts, found and replaced before analysis.

A glitch (a single-sample spike of a few newtons, or both channels reading 0 N for a few samples when the
DAQ drops a buffer) is not friction: one 5 N spike in a 2 s record at 25.6 kHz adds as much band power
as the whole friction perturbation of a smooth contact, and a dropout of the normal force reads as lost
contact. Each force channel's local second difference ``r_i = x_i − (x_{i−1} + x_{i+1})/2`` is linear in
the signal, so it is Gaussian where the signal and the sensor noise are (a running median's residual is
not: it is heavy-tailed on a broadband signal), and a spike of height h gives ``r = h`` at it. Its scale
is estimated robustly and locally, ``σ = 1.4826 MAD(r)`` over consecutive blocks of 512 samples (a
record mixes quiet unloaded parts with sliding; the standard deviation where the MAD is 0, e.g. a
quantised constant). A sample is a glitch when ``|r| > z σ`` with ``z`` the two-sided normal quantile
for a false-alarm probability of ``false_alarm`` over the whole record (Bonferroni over its n samples:
``z = Φ⁻¹(1 − false_alarm / (2n))``, 5.9 for n = 61 440 at 1 %). Flagged samples up to ``gap`` samples
apart are joined (the inside of a dropout has no second difference; its edges have). Glitch samples in
either channel are replaced in both by linear interpolation from their neighbours; the count is
reported per run (never silent).
"""

from __future__ import annotations

import numpy as np

__all__ = ["glitch_mask", "replace_glitches", "GLITCH_WINDOW", "GLITCH_FALSE_ALARM"]

GLITCH_WINDOW = 5  # [samples] flagged samples closer than this are joined (dropouts up to 4 samples)
GLITCH_FALSE_ALARM = 0.01  # probability of flagging a sample of a glitch-free Gaussian record
GLITCH_BLOCK = 512  # [samples] blocks of the local scale estimate (MAD relative sd ~ 1.13/sqrt(512) = 5 %)


def glitch_mask(x, *, window: int = GLITCH_WINDOW, false_alarm: float = GLITCH_FALSE_ALARM) -> np.ndarray:
    """True for the samples of ``x`` that are glitches (see the module docstring); ``window`` is the gap
    [samples] across which flagged samples are joined."""
    from scipy import ndimage, stats

    x = np.asarray(x, float)
    n = x.size
    if n < 2 * GLITCH_BLOCK:
        return np.zeros(n, bool)
    r = np.zeros(n)
    r[1:-1] = x[1:-1] - 0.5 * (x[:-2] + x[2:])
    sigma = np.empty(n)
    for start in range(0, n, GLITCH_BLOCK):
        b = r[start:start + GLITCH_BLOCK] if n - start >= 2 * GLITCH_BLOCK else r[start:]
        s = 1.4826 * np.median(np.abs(b - np.median(b)))
        sigma[start:start + b.size] = s if s > 0 else np.std(b)
        if b.size > GLITCH_BLOCK:
            break
    z = stats.norm.isf(false_alarm / (2 * n))
    mask = (sigma > 0) & (np.abs(r) > z * sigma)
    if mask.any():
        mask |= ndimage.binary_closing(mask, structure=np.ones(window, bool))
    return mask


def replace_glitches(*channels, window: int = GLITCH_WINDOW, false_alarm: float = GLITCH_FALSE_ALARM):
    """The channels with the glitch samples of any channel interpolated over, and the mask.

    Returns
    -------
    (list of ndarray, ndarray of bool)
    """
    chans = [np.asarray(c, float) for c in channels]
    mask = np.zeros(chans[0].size, bool)
    for c in chans:
        mask |= glitch_mask(c, window=window, false_alarm=false_alarm)
    if not mask.any() or mask.all():
        return chans, mask
    idx = np.arange(mask.size)
    good = ~mask
    return [np.where(mask, np.interp(idx, idx[good], c[good]), c) for c in chans], mask
