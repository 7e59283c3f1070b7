"""The verification manual: one self-contained HTML page (the report machinery of :mod:`fivid.report.html`).

A verdict, the summary table (case, quantity, reference, fivid, error, tolerance, pass), the environment the
cases ran on, then one section per case: what is checked, the reference and its source, how fivid computes
it, where the tolerance comes from, the numbers and the case's figure. Failed cases show in red.
"""

from __future__ import annotations

import html
import importlib.util

import numpy as np

from fivid.report.html import Page, figure_data_uri, table
from fivid.storage import write_text
from fivid.verify.case import Plot, Result

__all__ = ["render_manual", "plot_data_uri", "summary_rows", "SUMMARY_HEADER"]

SUMMARY_HEADER = ["case", "quantity", "reference", "fivid", "error", "tolerance", "pass"]


def plot_data_uri(plot: Plot) -> str:
    """Draw a case's :class:`~fivid.verify.case.Plot` (matplotlib, Agg); a ``data:`` URI."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 3.8), layout="constrained")
    for i, c in enumerate(plot.curves):
        x, y = np.asarray(c.x, float), np.asarray(c.y, float)
        if c.style == "points":
            ax.plot(x, y, "o", ms=5, mfc="none", color=f"C{i}", label=c.label)
        else:
            ax.plot(x, y, "--" if c.style == "dashed" else "-", lw=1.4 if c.style == "dashed" else 1.0,
                    color="k" if c.style == "dashed" else f"C{i}", label=c.label)
    ax.set_xscale(plot.xscale)
    ax.set_yscale(plot.yscale)
    ax.set_xlabel(plot.xlabel)
    ax.set_ylabel(plot.ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return figure_data_uri(fig)


def _pass_cell(result: Result):
    return "skipped" if result.passed is None else result.passed


def summary_rows(results: list[Result]) -> list[list]:
    """Rows of the summary table (:data:`SUMMARY_HEADER`), as the command line also prints them."""
    rows = []
    for r in results:
        o = r.outcome
        unit = f" [{r.case.unit}]" if r.case.unit else ""
        rows.append([r.case.name, r.case.quantity + unit, None if o is None else float(o.reference),
                     None if o is None else float(o.value), None if o is None else float(r.error),
                     None if o is None else f"{o.tolerance:.3g} ({r.case.error})", _pass_cell(r)])
    return rows


def _case_section(page: Page, r: Result) -> None:
    c = r.case
    page.heading(f"{c.name}: {c.title}")
    if r.status == "passed":
        page.paragraph(f"passed: error {r.error:.3g} within the tolerance {r.outcome.tolerance:.3g} ({c.error}).",
                       cls="verdict pass")
    elif r.status == "skipped":
        page.paragraph(f"skipped: {r.reason}.")
    else:
        page.paragraph("FAILED: " + (f"error {r.error:.3g} against the tolerance {r.outcome.tolerance:.3g} "
                                     f"({c.error}); {r.reason}." if r.outcome is not None else r.reason + "."),
                       cls="verdict fail")
    unit = f" [{c.unit}]" if c.unit else ""
    rows = [["quantity", c.quantity + unit], ["reference", c.reference], ["source", c.source],
            ["how fivid computes it", c.method], ["tolerance and its basis", c.tolerance_basis]]
    if c.real_data:
        rows.append(["measured data", c.real_data])
    page.raw(table(["", "description"], rows))
    o = r.outcome
    if o is None:
        return
    numbers = [["reference", float(o.reference)], ["fivid", float(o.value)], [f"error ({c.error})", float(r.error)],
               ["tolerance", float(o.tolerance)], ["pass", r.passed], ["resolution", "quick" if r.quick else "full"],
               ["wall time [s]", round(r.seconds, 2)]]
    numbers += [[k, v] for k, v in o.details.items()]
    page.raw(table(["", "value"], numbers))
    if o.plot is not None and importlib.util.find_spec("matplotlib") is not None:
        page.figure(plot_data_uri(o.plot), f"{c.title}: {c.quantity}.", c.name)
    elif o.plot is not None:
        page.paragraph("(The figure needs matplotlib: pip install 'fivid[report]'.)")


def render_manual(path, results: list[Result], env: dict, *, quick: bool):
    """Write the manual (atomically); returns the path."""
    page = Page("fivid verification manual")
    n_fail = sum(r.status == "failed" for r in results)
    n_skip = sum(r.status == "skipped" for r in results)
    n_pass = len(results) - n_fail - n_skip
    ok = n_fail == 0
    page.paragraph(f"{'PASSED' if ok else 'FAILED'}: {n_pass} of {len(results)} cases passed, {n_fail} failed, "
                   f"{n_skip} skipped" + (" (--quick resolution)" if quick else "") + f"; {env['date']}.",
                   cls="verdict " + ("pass" if ok else "fail"))
    page.paragraph("Each case compares a quantity fivid computes with a reference nobody here wrote: a closed form, "
                   "a published benchmark, a standard or a measurement made by others. The tolerance of each is "
                   "derived from the method (convergence order, estimator variance, float resolution, the "
                   "reference's own precision), not tuned to pass.")
    page.raw(table(SUMMARY_HEADER, summary_rows(results)))
    page.heading("Environment")
    rows = [["fivid", env["fivid_version"]], ["git revision", env["git_revision"]], ["python", env["python"]]]
    rows += [[k, v] for k, v in env["packages"].items()]
    rows += [["platform", env["platform"]], ["CPU", env["cpu"]], ["CPU count", env["cpu_count"]],
             ["date (UTC)", env["date"]]]
    page.raw(table(["", "version or value"], rows))
    for r in results:
        _case_section(page, r)
    page.raw(f"<p><small>fivid {html.escape(env['fivid_version'])} · fivid verify"
             f"{' --quick' if quick else ''}</small></p>")
    return write_text(path, page.render())
