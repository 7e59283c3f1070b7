"""The convergence kind (``kind: convergence``, DESIGN §9): an FE model on several meshes and time steps; the
observed orders, Richardson-extrapolated values and every mesh's deviation of the modal frequencies, the level,
the dominant frequency, the one-third-octave band levels and the PSD peaks (:mod:`fivid.study.convergence`).
The calibration pipeline reads the result as its convergence table (:mod:`fivid.pipeline.discretisation`)."""

from __future__ import annotations

from fivid.report.html import table
from fivid.study.convergence import convergence_summary
from fivid.study.kinds.sweep import FeSweep

__all__ = ["Convergence", "KIND"]


class Convergence(FeSweep):
    """Mesh and time-step convergence (:class:`fivid.study.kind.StudyKind`)."""

    name = "convergence"
    description = "mesh and time-step convergence: observed orders, Richardson values, PSD changes"

    def guess(self, data: dict) -> bool:
        """An FE study sweeping ``mesh`` or ``time_step`` over more than one value (one mesh factor only sets the
        mesh of another kind's study)."""
        sweep = data.get("sweep") or {}
        return any(_count(sweep.get(axis)) > 1 for axis in ("mesh", "time_step"))

    def check(self, cfg) -> list[tuple[str, str]]:
        """Something to refine: a ``mesh`` or ``time_step`` axis."""
        return [] if {"mesh", "time_step"} & cfg.sweep.model_fields_set else [
            ("sweep", "a convergence study sweeps 'mesh' (divisions x factor) or 'time_step' (x critical step)")]

    def summarise(self, study, ds, points: list[dict]) -> dict:
        """The power law of the response, and ``convergence`` (:func:`fivid.study.convergence.convergence_summary`)."""
        out = super().summarise(study, ds, points)
        done = [i for i, p in enumerate(points) if p["status"] == "done"]
        conv = convergence_summary(ds, study.point_table(), done)
        if conv is not None:
            out["convergence"] = conv
        return out

    def report(self, page, ds, summary: dict) -> None:
        """The orders, extrapolated values and errors per mesh series and time-step series."""
        conv = summary.get("convergence")
        if not conv:
            return
        page.heading("Convergence", level=3)
        for entry in conv.get("mesh", []):
            h = ", ".join(f"{x * 1e3:.3g}" for x in entry["element_size"])
            page.paragraph(f"Meshes of element size {h} mm at " + ", ".join(f"{k} {v:g}" for k, v in
                                                                             entry["conditions"].items()) + ".")
            rows = []
            for name, items in (("mode", entry.get("mode_frequency", [])), ("level [dB]", [entry.get("level_db")]),
                                ("dominant frequency [Hz]", [entry.get("response_frequency")])):
                for it in items:
                    if it is None:
                        continue
                    label = f"mode {it['mode']} [Hz]" if name == "mode" else name
                    rows.append([label, *(round(v, 6) for v in it["values"]), it["order"], it["extrapolated"],
                                 it["error"]])
            rows += _spectral_rows(entry)
            page.raw(table(["quantity", "finest", "middle", "coarsest", "observed order", "extrapolated",
                            "error of finest"], rows))
        for entry in conv.get("time_step_order", []):
            page.paragraph("Time steps " + ", ".join(f"{x:g}" for x in entry["time_step"]) + " of the critical step "
                           "at " + ", ".join(f"{k} {v:g}" for k, v in entry["conditions"].items()) + ".")
            page.raw(table(["quantity", "smallest step", "middle", "largest step", "observed order", "extrapolated",
                            "error of smallest"], _spectral_rows(entry)))
        if conv.get("time_step"):
            rows = [[", ".join(f"{k} {v:g}" for k, v in s["conditions"].items()), s["time_step"],
                     s["reference_time_step"], s["lsd_db"], s["level_diff_db"]] for s in conv["time_step"]]
            page.raw(table(["conditions", "step (x critical)", "reference step", "PSD LSD [dB]", "level diff [dB]"],
                           rows))


def _count(spec) -> int:
    """Number of values of a raw sweep axis (a list, ``{values: [...]}`` or ``{num: n, ...}``), 0 if absent."""
    if isinstance(spec, (list, tuple)):
        return len(set(map(str, spec)))
    if isinstance(spec, dict):
        return len(set(map(str, spec.get("values") or []))) if "values" in spec else int(spec.get("num") or 0)
    return 0


def _spectral_rows(entry) -> list[list]:
    """Table rows of the one-third-octave band levels and PSD peak frequencies of a convergence entry."""
    rows = []
    for b in entry.get("band_level_db", []):
        rows.append([f"level {b['band'][0]:.0f}–{b['band'][1]:.0f} Hz [dB]", *(round(v, 3) for v in b["values"]),
                     b["order"], b["extrapolated"], b["error"]])
    for p in entry.get("psd_peak_frequency", []):
        rows.append([f"PSD peak near {p['peak']:.0f} Hz [Hz]", *(round(v, 2) for v in p["values"]), p["order"],
                     p["extrapolated"], p["error"]])
    return rows


#: the registered instance
KIND = Convergence()
