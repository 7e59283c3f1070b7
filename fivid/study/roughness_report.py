"""The roughness-noise section of a study report (seed 003): the fitted exponents, Lv against Ra, V and Rz/Rsm,
shocks, friction power and the transducer's friction fluctuation, with what the numbers came from."""

from __future__ import annotations

import numpy as np

from fivid.report.html import Page, figure_data_uri, new_figure, table

__all__ = ["roughness_section"]


def _fmt(x, digits=4):
    return None if x is None or not np.isfinite(x) else float(f"{x:.{digits}g}")


def _by(ds, name, axis, group):
    """(x, y, label) per value of ``group`` for ``name`` against ``axis`` (points with finite positive y)."""
    x, y, g = ds[axis].values, ds[name].values, ds[group].values
    for v in np.unique(g):
        sel = (g == v) & np.isfinite(y)
        order = np.argsort(x[sel])
        yield x[sel][order], y[sel][order], v


def _panels(ds, name: str, label: str, *, log_y: bool = False) -> str:
    """``name`` against Ra (one line per V) and against V (one line per Ra); markers by replicate."""
    import matplotlib.ticker

    fig, (ax1, ax2) = new_figure(9.0, 3.6, 1, 2)
    seeds = np.unique(ds["seed"].values) if "seed" in ds.coords else [None]
    for ax, axis, group, unit, scale in ((ax1, "roughness_ra", "sliding_velocity", "um", 1e6),
                                         (ax2, "sliding_velocity", "roughness_ra", "cm/s", 1e2)):
        for k, s in enumerate(seeds):
            sub = ds.where(ds["seed"] == s, drop=True) if s is not None else ds
            for j, (x, y, v) in enumerate(_by(sub, name, axis, group)):
                gu, gs = ("cm/s", 1e2) if group == "sliding_velocity" else ("um", 1e6)
                ax.plot(x * scale, y, "os"[k % 2] + "-", color=f"C{j}", lw=0.8,
                        label=f"{group.split('_')[0]} {v * gs:g} {gu}" + (f", replicate {int(s)}" if s is not None
                                                                         else ""))
        ax.set_xscale("log")
        ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
        ax.xaxis.set_minor_formatter(matplotlib.ticker.ScalarFormatter())
        if log_y:
            ax.set_yscale("log")
        ax.set_xlabel(("Ra" if axis == "roughness_ra" else "V") + f" [{unit}]")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    return figure_data_uri(fig)


def _rz_rsm_figure(ds, fit) -> str:
    fig, ax = new_figure(6.0, 3.8)
    r = np.log10(ds["profile_Rz"].values / ds["profile_Rsm"].values)
    v = ds["sliding_velocity"].values
    for j, vv in enumerate(np.unique(v)):
        sel = v == vv
        ax.plot(r[sel], ds["vibration_level"].values[sel], "o", color=f"C{j}", label=f"V {vv * 1e2:g} cm/s")
    if fit:
        xx = np.linspace(r.min(), r.max(), 2)
        ax.plot(xx, fit["intercept"] + fit["slope"] * xx, "-", color="0.3", lw=1,
                label=f"fit: {fit['slope']:.3g} dB/decade, r² {fit['r2']:.2f}")
    ax.set_xlabel("log10(Rz / Rsm) of the lower profile")
    ax.set_ylabel("Lv [dB re 1e-9 m/s]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    return figure_data_uri(fig)


def roughness_section(page: Page, ds, summary: dict) -> None:
    """Add the roughness-noise results (summary.json's ``n``, ``m``, ``fits`` and ``roughness_settings``, and the
    study Dataset's points) to ``page``."""
    page.heading("Roughness noise (seed 003)", level=3)
    fits = summary.get("fits") or {}
    rows = []
    for key, what, lv in (("n", "Ra exponent n", "Lv"), ("m", "V exponent m", "Lv"),
                          ("n_band", "Ra exponent n", "Lv 1-20 kHz"), ("m_band", "V exponent m", "Lv 1-20 kHz")):
        e = summary.get(key)
        if e:
            rows.append([f"{what} ({lv} = 20 n log Ra + 20 m log V + c)", _fmt(e["value"]), _fmt(e["ci"][0]),
                         _fmt(e["ci"][1]), _fmt(e.get("r2")), e.get("n")])
    rz = fits.get("vibration_level_vs_rz_rsm")
    if rz:
        rows.append(["Lv vs log10(Rz/Rsm): slope [dB/decade]", _fmt(rz["slope"]), _fmt(rz["ci"][0]), _fmt(rz["ci"][1]),
                     _fmt(rz["r2"]), rz["n"]])
    for key, f in sorted((fits.get("vibration_level_vs_rz_rsm_per_speed") or {}).items()):
        rows.append([f"Lv vs log10(Rz/Rsm) at {f['sliding_velocity'] * 100:g} cm/s: slope [dB/decade]",
                     _fmt(f["slope"]), _fmt(f["ci"][0]), _fmt(f["ci"][1]), _fmt(f["r2"]), f["n"]])
    for name, what in (("shock_rate", "shock frequency"), ("shock_impulse", "impulse per shock"),
                       ("shock_energy", "vibratory energy per shock"), ("vibratory_power", "vibratory power"),
                       ("friction_power", "friction power"), ("friction_coefficient_rms", "mu(t) RMS")):
        f = fits.get(name)
        for axis, sym in (("roughness_ra", "Ra"), ("sliding_velocity", "V")):
            if f and axis in f["exponents"]:
                e = f["exponents"][axis]
                rows.append([f"{what} ∝ {sym}^k: k", _fmt(e["value"]), _fmt(e["ci"][0]), _fmt(e["ci"][1]),
                             _fmt(f["r2"]), f["n"]])
    page.raw(table(["quantity", "value", "95 % CI low", "95 % CI high", "r²", "points"], rows))
    design = summary.get("design") or {}
    if design.get("sigma_db") is not None:
        page.paragraph(f"Design: Lv scatters by {_fmt(design.get('replicate_sd_db'))} dB between replicates "
                       f"({design.get('replicate_dof')} dof) and {_fmt(design.get('residual_sd_db'))} dB about the "
                       f"plane ({design.get('residual_dof')} dof); with sigma = {_fmt(design['sigma_db'])} dB this "
                       f"Ra x V grid needs {design.get('replicates_for_half_width_0.15')} replicate(s) for 95 % "
                       "half-widths of n and m <= 0.15 (fivid.study.fits.replicates_for_exponents).")
    st = summary.get("roughness_settings") or {}
    if st:
        mesh = "; ".join(f"{b}: {m['divisions'][0]} x {m['divisions'][1]}" for b, m in st.get("mesh", {}).items())
        prof = st.get("profiles", {})
        rec = st.get("record", {})
        page.paragraph(f"Model {st.get('model')} (divisions {mesh}); profiles: {prof.get('generator')}, Rsm levels "
                       f"{prof.get('rsm_levels')} m, correlation lengths {prof.get('correlation_length')} m, seeds "
                       f"{prof.get('seeds')} ({prof.get('replicates')}); record {rec.get('duration')} s at "
                       f"{rec.get('sample_rate')} Hz, window: {rec.get('window')}. The exponents are results of "
                       "this model: nothing is tuned toward seed 003's values.")
    if not ds.sizes.get("point") or "vibration_level" not in ds:
        return
    ds = ds.where(np.isfinite(ds["vibration_level"]), drop=True)
    page.figure(_panels(ds, "vibration_level", "Lv [dB re 1e-9 m/s]"),
                "Vibration level of the back face against Ra (per V) and against V (per Ra); circles replicate 0, "
                "squares replicate 1.", "Lv")
    if "band_vibration_level" in ds and np.any(np.isfinite(ds["band_vibration_level"].values)):
        page.figure(_panels(ds, "band_vibration_level", "Lv 1-20 kHz [dB re 1e-9 m/s]"),
                    "Vibration level of the back face in the audible band (1-20 kHz, "
                    "fivid.score.roughness.band_vibration_level) against Ra and V.", "Lv 1-20 kHz")
    if {"profile_Rz", "profile_Rsm"} <= set(ds.data_vars):
        page.figure(_rz_rsm_figure(ds, rz), "Lv against the lower profile's Rz/Rsm, per V.", "Lv vs Rz/Rsm")
    page.figure(_panels(ds, "shock_rate", "shocks per second", log_y=True),
                "Shock rate (contact closing events) against Ra and V.", "shock rate")
    page.figure(_panels(ds, "shock_impulse", "mean impulse per shock [N s]", log_y=True),
                "Mean impulse per shock against Ra and V.", "shock impulse")
    for name, label, what in (("shock_energy", "vibratory energy per shock [J]", "shock intensity"),
                              ("vibratory_power", "vibratory power [W]", "vibratory power")):
        if name in ds and np.any(np.isfinite(ds[name].values)):
            page.figure(_panels(ds, name, label, log_y=True), f"{label} against Ra and V (seed 003 Figs. 6, 7).", what)
    page.figure(_panels(ds, "friction_power", "friction power [W]", log_y=True),
                "Friction power against Ra and V.", "power")
    if "friction_coefficient_rms" in ds and np.any(np.isfinite(ds["friction_coefficient_rms"].values)):
        page.figure(_panels(ds, "friction_coefficient_rms", "RMS of mu(t) (transducer)", log_y=True),
                    "Fluctuation of the friction coefficient the transducer reads (the perturbation amplitude "
                    "the identification chain injects) against Ra and V.", "mu fluctuation")
