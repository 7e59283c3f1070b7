"""The ring kind (``kind: ring``, seed 002): a ring's instability regimes over mu -- transients classified as
stable, mode coupling or stick-slip, each beside the study-level CEA at the same mu (critical mu, the coalescing
doublet, the CEA's growth rate and frequency)."""

from __future__ import annotations

from fivid.report.html import table
from fivid.study.kinds.sweep import FeSweep

__all__ = ["RingRegimes", "KIND"]


class RingRegimes(FeSweep):
    """Regimes of the transients against the CEA (:class:`fivid.study.kind.StudyKind`)."""

    name = "ring"
    description = "instability regimes over mu (seed 002): transients classified and compared with the CEA"

    def guess(self, data: dict) -> bool:
        """An FE study with a CEA and transients."""
        return bool(data.get("cea")) and "transient" in (data.get("points") or {})

    def report(self, page, ds, summary: dict) -> None:
        """Each transient's regime and growth rate beside the CEA's at the same mu."""
        rows = [[p.get("mu"), p.get("regime"), p.get("growth_rate"), p.get("cea_growth_rate"), p.get("frequency"),
                 p.get("cea_frequency")] for p in summary["points"] if "regime" in p and "mu" in p]
        if not rows:
            return
        page.heading("Transients against the CEA", level=3)
        page.raw(table(["mu", "regime", "growth rate [1/s]", "CEA growth rate [1/s]", "frequency [Hz]",
                        "CEA frequency [Hz]"], rows))


#: the registered instance
KIND = RingRegimes()
