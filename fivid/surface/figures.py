"""Figure of a profile evaluation: profile with its window, roughness (and waviness), PSD. matplotlib, Agg, lazy."""

from __future__ import annotations


from fivid.storage import atomic_path
from fivid.surface.profile import make_profile
from fivid.surface.statistics import profile_psd

__all__ = ["plot_evaluation"]


def plot_evaluation(profile, evaluation, path) -> None:
    """Write a PNG: (1) the profile as read with the window shaded, (2) roughness [and waviness] over the
    evaluation length, (3) the Welch PSD of the roughness profile (:func:`fivid.surface.profile_psd`)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ev, s = evaluation, evaluation.settings
    fig, (a1, a2, a3) = plt.subplots(3, 1, figsize=(8, 9))
    a1.plot(profile["x"].values * 1e6, profile.values * 1e6, lw=0.6)
    a1.axvspan(s["window_start"] * 1e6, s["window_end"] * 1e6, color="0.85", label="evaluation window")
    a1.set_xlabel("x [µm]")
    a1.set_ylabel("z [µm]")
    a1.set_title(f"{profile.attrs.get('source', 'profile')[:60]}")
    a1.legend(loc="best")
    a2.plot(ev.x * 1e6, ev.roughness * 1e9, lw=0.6, label=f"roughness ({s['form']} form removed)")
    if ev.waviness is not None:
        a2.plot(ev.x * 1e6, (ev.waviness - ev.waviness.mean()) * 1e9, lw=1.0, label="waviness (mean line)")
    p = ev.parameters
    a2.set_title(f"Ra {p['Ra'] * 1e9:.4g} nm, Rq {p['Rq'] * 1e9:.4g} nm, Rz {p['Rz'] * 1e9:.4g} nm, "
                 f"Rsk {p['Rsk']:.3g}")
    a2.set_xlabel("x [µm]")
    a2.set_ylabel("z [nm]")
    a2.legend(loc="best")
    psd = profile_psd(make_profile(ev.x, ev.roughness))
    f = psd["spatial_frequency"].values
    a3.loglog(f[1:] * 1e-3, psd.values[1:] * 1e21, lw=0.8)
    a3.set_xlabel("spatial frequency [mm⁻¹]")
    a3.set_ylabel("PSD [nm² mm]")
    a3.set_title(f"Welch PSD of the roughness, nperseg {psd.attrs['nperseg']}, {psd.attrs['window']} window")
    a3.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    plt.close(fig)
