"""The study's report section: the points table, the regime map and the CEA, then the kind's own section
(:meth:`fivid.study.kind.StudyKind.report`), as one self-contained HTML page."""

from __future__ import annotations

import numpy as np

from fivid.report.html import Page, figure_data_uri, new_figure, table
from fivid.storage import write_text
from fivid.study.axes import AXES
from fivid.study.kind import study_kind

__all__ = ["render_study_report", "study_section"]

_COLOURS = {"stable": "C2", "mode_coupling": "C1", "stick_slip": "C3"}


def _response_figure(ds, axis: str, name: str, label: str, cea_curve=None) -> str:
    """``name`` against the swept ``axis``, one marker per point coloured by regime."""
    fig, ax = new_figure()
    x = ds[axis].values
    y = ds[name].values
    regimes = ds["regime"].values.astype(str) if "regime" in ds else np.array(["point"] * x.size)
    for reg in dict.fromkeys(regimes):
        sel = regimes == reg
        ax.plot(x[sel], y[sel], "o", color=_COLOURS.get(reg, "C0"), label=reg.replace("_", " "))
    if cea_curve is not None:
        ax.plot(*cea_curve, "-", color="0.4", lw=1, label="CEA: largest Re(λ)")
    units = ds[axis].attrs.get("units", "")
    ax.set_xlabel(f"{ds[axis].attrs.get('long_name', axis)} [{units}]")
    ax.set_ylabel(label)
    if axis in ("normal_load", "sliding_velocity", "roughness_ra") and np.all(x > 0):
        ax.set_xscale("log")
    ax.grid(True, alpha=0.3)
    ax.legend()
    return figure_data_uri(fig)


def _cea_figure(ds) -> str:
    fig, (a1, a2) = new_figure(7.0, 6.0, 2, 1, sharex=True)
    mu = ds["cea_mu"].values
    for k in range(ds.sizes["cea_mode"]):
        a1.plot(mu, ds["cea_frequency"].values[:, k], lw=1)
        a2.plot(mu, ds["cea_real_part"].values[:, k], lw=1)
    a2.axhline(0.0, color="0.3", lw=0.8)
    a1.set_ylabel("frequency [Hz]")
    a2.set_ylabel("Re(λ) [1/s]  (> 0 unstable)")
    a2.set_xlabel("friction coefficient μ [-]")
    for a in (a1, a2):
        a.grid(True, alpha=0.3)
    return figure_data_uri(fig)


#: units of the points table's result columns (the swept axes take theirs from fivid.study.axes.AXES)
_RESULT_UNITS = {"growth_rate": "s-1", "cea_growth_rate": "s-1", "frequency": "Hz", "onset_time": "s",
                 "level_db": "dB re 1e-6 m s-2"}


def _with_units(name: str) -> str:
    """A column header with its units, ``normal_load [N]`` (none for a pure number or a label)."""
    units = AXES[name][0] if name in AXES else _RESULT_UNITS.get(name, "1")
    return name if units == "1" else f"{name} [{units}]"


def _transition_paragraph(page: Page, summary: dict) -> None:
    """The weak/strong transition load of a load sweep (summary ``transition_load``, ``transition_loads``)."""
    t = summary.get("transition_load")
    if not t:
        return

    def one(x) -> str:
        if x.get("value") is None:
            return x.get("note", "no transition in the swept loads")
        return f"at {x['value']:.3g} N (between the swept loads {x['bracket'][0]:g} and {x['bracket'][1]:g} N)"

    text = f"Weak/strong contact transition ({t.get('criterion_label', 'coupling indicator κ')} = {t['threshold']:g}): {one(t)}"
    groups = summary.get("transition_loads", [])
    if groups:
        text += "; per condition: " + "; ".join(
            ", ".join(f"{k} {v:g}" + ("" if AXES[k][0] == "1" else f" {AXES[k][0]}") for k, v in g.items() if k in AXES)
            + f": {one(g)}" for g in groups)
    page.paragraph(text + ".")


def study_section(page: Page, ds, summary: dict, kind=None) -> None:
    """Add the study's section to ``page`` (a study report, or a pipeline report that embeds one): the points, the
    growth and level figures, the CEA, then the section of the study's kind (``kind``, default the registered kind
    named in ``summary["kind"]``; none for a summary without one)."""
    page.heading(f"Study {summary['study']}")
    if summary.get("description"):
        page.paragraph(summary["description"])
    page.paragraph(f"{summary['n_done']} of {summary['n_points']} points done"
                   + (" (--quick resolution)" if summary.get("quick") else "") + f"; source {summary['source']}.")
    crit = summary.get("critical_mu", "absent")
    if crit != "absent":
        page.paragraph("CEA: stable over the analysed μ range." if crit is None else
                       f"CEA: critical μ = {crit['value']:.4g} (mode {crit['mode']}, coalescing with mode "
                       f"{crit['partner_mode']}, {crit['frequency']:.4g} Hz).")
    axes = [a for a in ("normal_load", "sliding_velocity", "roughness_ra", "mu", "mu_static", "seed", "mesh",
                        "time_step") if any(a in p for p in summary["points"])]
    cols = ["regime", "growth_rate", "cea_growth_rate", "frequency", "onset_time", "level_db", "status"]
    cols = [c for c in cols if any(c in p for p in summary["points"])]
    rows = [[p.get(a) for a in axes] + [p.get(c) for c in cols] for p in summary["points"]]
    page.raw(table([_with_units(c) for c in axes + cols], rows))
    _transition_paragraph(page, summary)
    if summary["failed"]:
        page.paragraph("Failed points: " + "; ".join(f"point {f['point']}: {f['error']}" for f in summary["failed"]),
                       cls="fail")
    varying = [a for a in axes if a in ds.coords and np.unique(ds[a].values).size > 1]
    if ds.sizes.get("point", 0) and varying:
        axis = varying[0]
        if "growth_rate" in ds:
            curve = None
            if "cea_mu" in ds.coords and axis == "mu":
                curve = (ds["cea_mu"].values, ds["cea_real_part"].values.max(axis=1))
            page.figure(_response_figure(ds, axis, "growth_rate", "envelope growth rate [1/s]", curve),
                        "Growth rate of each transient (fitted on its envelope) against the swept condition, by "
                        "regime" + (", with the CEA's largest real part." if curve else "."), "growth rates")
        if "level_db" in ds:
            page.figure(_response_figure(ds, axis, "level_db", "acceleration level [dB re 1e-6 m/s²]"),
                        "Response level of each point's steady part.", "levels")
    if "cea_mu" in ds.coords:
        page.figure(_cea_figure(ds), "CEA: frequencies and real parts of the eigenvalues against μ.", "CEA")
    kind = kind or (study_kind(summary["kind"]) if "kind" in summary else None)
    if kind is not None:
        kind.report(page, ds, summary)  # the kind's own section


def render_study_report(path, study, ds, summary: dict):
    """Write ``report.html`` for a study (atomically); returns the path."""
    page = Page(f"fivid study report: {study.name}")
    study_section(page, ds, summary, study.kind)
    return write_text(path, page.render())
