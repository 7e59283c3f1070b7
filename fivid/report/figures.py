"""The report's figures (matplotlib, Agg backend), each returned as a ``data:`` URI.

Pure plotting: the caller passes arrays in SI units; axes are labelled in the units people read
(Hz, mm/s, µm, dB).
"""

from __future__ import annotations

import numpy as np

from fivid.report.html import figure_data_uri, new_figure

__all__ = ["law_shape_figure", "amplitude_figure", "psd_overlay_figure", "psd_envelope_figure", "modal_figure",
           "psd_axis_limits", "PSD_DYNAMIC_RANGE_DB"]


def law_shape_figure(frequency, shape, band) -> str:
    """Normalised perturbation spectrum s(f) [Hz-1] (∫ s df = 1) on log axes, valid band shaded."""
    fig, ax = new_figure()
    ax.loglog(frequency, shape, color="C0", lw=1.5, label="identified shape s(f)")
    ax.axvspan(band[0], band[1], color="C2", alpha=0.08, label="valid band")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("s(f) [Hz$^{-1}$]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    return figure_data_uri(fig)


def amplitude_figure(curves: list[dict], points: list[dict]) -> str:
    """Amplitude A [-] (RMS of μp) against sliding velocity per roughness.

    Parameters
    ----------
    curves : list of dict
        ``label, velocity [m s-1], amplitude, lower, upper`` — the fitted law and its interval.
    points : list of dict
        ``label, velocity [m s-1], amplitude`` and optional ``error`` (half-width) — per-run estimates.
    """
    fig, ax = new_figure()
    for i, c in enumerate(curves):
        color = f"C{i}"
        v = np.asarray(c["velocity"]) * 1e3
        ax.plot(v, c["amplitude"], color=color, lw=1.5, label=f"fit, {c['label']}")
        ax.fill_between(v, c["lower"], c["upper"], color=color, alpha=0.2, lw=0)
        for p in points:
            if p["label"] == c["label"]:
                err = p.get("error")
                err = None if err is None or not np.all(np.isfinite(err)) else err
                ax.errorbar(np.asarray(p["velocity"]) * 1e3, p["amplitude"], yerr=err, fmt="o", color=color, ms=5,
                            mfc="none", capsize=3, label=f"runs, {p['label']}")
    ax.set_xlabel("sliding velocity [mm/s]")
    ax.set_ylabel("amplitude A = RMS of $\\mu_p$ [-]")
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return figure_data_uri(fig)


#: dynamic range shown on the PSD figures: decades below the highest level in view (80 dB). Below it lie
#: window leakage, the noise floor and the numerical floor of a simulation, which would squeeze the peaks.
PSD_DYNAMIC_RANGE_DB = 80.0


def psd_axis_limits(f, curves, xlim) -> tuple[float, float] | None:
    """y limits of a PSD plot: from ``PSD_DYNAMIC_RANGE_DB`` below the highest level inside ``xlim`` to a
    little above it (None when nothing positive is in view)."""
    f = np.asarray(f, float)
    inside = (f >= xlim[0]) & (f <= xlim[1])
    levels = [np.asarray(c, float)[inside] for c in curves]
    peak = max((np.nanmax(v[v > 0]) for v in levels if np.any(v > 0)), default=None)
    if peak is None:
        return None
    return peak * 10 ** (-PSD_DYNAMIC_RANGE_DB / 10), peak * 2.0


def _finish_psd(fig, ax, f, band, units: str, curves) -> str:
    """Common axes of the PSD figures: the band (with margins), the dynamic range of ``curves`` in view,
    labels, grid, legend; the data URI."""
    xlim = (max(f[1], band[0] / 2), min(f[-1], band[1] * 1.1))
    ax.set_xlim(*xlim)
    ylim = psd_axis_limits(f, curves, xlim)
    if ylim is not None:
        ax.set_ylim(*ylim)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel(f"acceleration PSD [{units}]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return figure_data_uri(fig)


def psd_overlay_figure(frequency, measured: list[dict], simulated: list[dict], band, units: str) -> str:
    """Measured and simulated acceleration PSDs with their χ² confidence bands.

    ``measured``/``simulated``: dicts with ``label, psd, lower, upper`` on the common ``frequency`` [Hz].
    """
    fig, ax = new_figure(7.5, 4.2)
    f = np.asarray(frequency)
    for i, m in enumerate(measured):
        ax.fill_between(f, m["lower"], m["upper"], color="k", alpha=0.15, lw=0)
        ax.semilogy(f, m["psd"], color="k", lw=1.0, label=m["label"] if i < 3 else None)
    for i, s in enumerate(simulated):
        color = f"C{3 + i % 6}"
        ax.fill_between(f, s["lower"], s["upper"], color=color, alpha=0.2, lw=0)
        ax.semilogy(f, s["psd"], color=color, lw=1.0, label=s["label"])
    ax.axvspan(band[0], band[1], color="C2", alpha=0.05)
    return _finish_psd(fig, ax, f, band, units, [c["psd"] for c in measured + simulated])


def psd_envelope_figure(env_frequency, p05, median, p95, n_samples: int, frequency, measured: list[dict], band,
                        units: str) -> str:
    """The Monte-Carlo envelope of the simulated PSD (5-95 % shaded, median line) with the measured PSDs.

    ``env_frequency`` [Hz] and ``p05``, ``median``, ``p95`` [units] are the envelope's; ``measured``: dicts with
    ``label, psd`` on ``frequency`` [Hz].
    """
    fig, ax = new_figure(7.5, 4.2)
    fe = np.asarray(env_frequency)
    ax.fill_between(fe, p05, p95, color="C0", alpha=0.25, lw=0, label=f"simulated 5-95 % ({n_samples} samples)")
    ax.semilogy(fe, median, color="C0", lw=1.2, label="simulated median")
    for i, m in enumerate(measured):
        ax.semilogy(frequency, m["psd"], color="k", lw=0.9, label=m["label"] if i < 3 else None)
    ax.axvspan(band[0], band[1], color="C2", alpha=0.05)
    return _finish_psd(fig, ax, fe, band, units, [np.asarray(p95)] + [m["psd"] for m in measured])


def modal_figure(frequency, psd, modal_frequencies, peak_frequencies, band, units: str) -> str:
    """A measured PSD with the model's modal frequencies (dashed) and the detected peaks (markers)."""
    fig, ax = new_figure(7.5, 4.0)
    f = np.asarray(frequency)
    ax.semilogy(f, psd, color="k", lw=1.0, label="measured (mean over runs)")
    for i, fm in enumerate(modal_frequencies):
        ax.axvline(fm, color="C1", ls="--", lw=1.0, label="model modes" if i == 0 else None)
    if len(peak_frequencies):
        idx = np.searchsorted(f, peak_frequencies).clip(0, f.size - 1)
        ax.plot(f[idx], np.asarray(psd)[idx], "v", color="C3", ms=7, label="measured peaks")
    return _finish_psd(fig, ax, f, band, units, [psd])
