"""Self-contained HTML: sections, tables and figures embedded as ``data:`` URIs (no external resources).

The page has no script and no external stylesheet, font or image: it opens from a mail attachment,
an archive or a file share with no network, and renders identically in ten years.
"""

from __future__ import annotations

import base64
import html
import io

__all__ = ["Page", "figure_data_uri", "new_figure", "table", "Formatted", "fmt", "general_number"]

_CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:2em auto;max-width:72em;padding:0 1em;color:#222}
h1{font-size:1.6em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}
table{border-collapse:collapse;margin:.5em 0 1em}td,th{border:1px solid #ccc;padding:.25em .6em;text-align:left;
vertical-align:top;font-size:.9em}th{background:#f3f3f3}td.num{text-align:right;font-variant-numeric:tabular-nums}
.pass{color:#11691b;font-weight:600}.fail{color:#b00020;font-weight:600}.verdict{font-size:1.3em;padding:.6em 1em;
border-radius:.3em;display:inline-block}.verdict.pass{background:#e3f4e5}.verdict.fail{background:#fbe4e7}
figure{margin:1em 0}figure img{max-width:100%;height:auto;border:1px solid #eee}figcaption{font-size:.9em;color:#555}
code,pre{font-family:ui-monospace,monospace;font-size:.85em}pre{background:#f7f7f7;padding:.6em;overflow-x:auto}
.synthetic{background:#fff4d6;border:1px solid #e0b84c;padding:.5em 1em}
.warning{background:#fbe4e7;border:1px solid #d9899a;padding:.5em 1em}
"""


def new_figure(width: float = 7.0, height: float = 4.0, nrows: int = 1, ncols: int = 1, **subplots):
    """A matplotlib figure and its axes on the Agg backend, ``width`` x ``height`` [inch], constrained layout
    (``nrows`` x ``ncols`` axes; ``subplots`` passed to :func:`matplotlib.pyplot.subplots`, e.g. ``sharex``).
    Every report figure starts here and ends in :func:`figure_data_uri`."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    return plt.subplots(nrows, ncols, figsize=(width, height), layout="constrained", **subplots)


def figure_data_uri(fig, *, fmt: str = "png", dpi: int = 110) -> str:
    """A matplotlib figure as a ``data:image/png;base64,...`` URI (the figure is closed)."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format=fmt, dpi=dpi, bbox_inches="tight", metadata={"Software": None} if fmt == "png" else None)
    plt.close(fig)
    mime = {"png": "image/png", "svg": "image/svg+xml"}[fmt]
    return f"data:{mime};base64," + base64.b64encode(buf.getvalue()).decode("ascii")


class Formatted(str):
    """A number already formatted (:func:`fmt`): right-aligned in a table like numbers, shown as given."""


def fmt(value, spec: str):
    """``value`` formatted with ``spec`` (e.g. ``".2f"``) as a table cell; None for None or NaN (a dash)."""
    if value is None or (isinstance(value, float) and value != value):
        return None
    return Formatted(format(value, spec))


def general_number(x: float) -> str:
    """4 significant digits without an exponent between 1e-4 and 1e6 (10170, 0.5274, 0.03156), else ``.4g``."""
    import math

    if x == 0:
        return "0"
    if 1e-4 <= abs(x) < 1e6:
        return f"{x:.{max(0, 3 - math.floor(math.log10(abs(x))))}f}"
    return f"{x:.4g}"


def _cell(value) -> str:
    if isinstance(value, Formatted):
        return f'<td class="num">{html.escape(value)}</td>'
    if isinstance(value, float):
        if value != value:  # NaN: not computed (e.g. an amplitude form that was not fitted)
            return "<td>—</td>"
        return f'<td class="num">{general_number(value)}</td>'
    if isinstance(value, bool):
        cls = "pass" if value else "fail"
        return f'<td class="{cls}">{"pass" if value else "FAIL"}</td>'
    if isinstance(value, int):
        return f'<td class="num">{value}</td>'
    if value is None:
        return "<td>—</td>"
    return f"<td>{html.escape(str(value))}</td>"


def table(header: list[str], rows: list[list]) -> str:
    """An HTML table; floats to 4 significant digits (:func:`general_number`), :func:`fmt` cells as formatted,
    booleans as pass/FAIL, None as a dash."""
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(_cell(v) for v in row) + "</tr>" for row in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


class Page:
    """An HTML document built section by section."""

    def __init__(self, title: str):
        self.title = title
        self.parts: list[str] = []
        self.n_figures = 0

    def heading(self, text: str, level: int = 2) -> None:
        """Append a heading ``<hN>`` with an anchor made from its text."""
        anchor = "".join(c if c.isalnum() else "-" for c in text.lower()).strip("-")
        self.parts.append(f'<h{level} id="{anchor}">{html.escape(text)}</h{level}>')

    def paragraph(self, text: str, cls: str | None = None) -> None:
        """Append a paragraph of text (HTML-escaped), with an optional CSS class."""
        c = f' class="{cls}"' if cls else ""
        self.parts.append(f"<p{c}>{html.escape(text)}</p>")

    def raw(self, fragment: str) -> None:
        """Append an HTML fragment as is (the caller escapes it)."""
        self.parts.append(fragment)

    def pre(self, text: str) -> None:
        """Append preformatted text (HTML-escaped)."""
        self.parts.append(f"<pre>{html.escape(text)}</pre>")

    def figure(self, uri: str, caption: str, alt: str) -> None:
        """Append a numbered figure: an image URI with its caption and alt text."""
        self.n_figures += 1
        self.parts.append(f'<figure><img src="{uri}" alt="{html.escape(alt)}">'
                          f"<figcaption>Figure {self.n_figures}. {html.escape(caption)}</figcaption></figure>")

    def render(self) -> str:
        """The whole self-contained HTML document."""
        return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                f"<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
                f"<title>{html.escape(self.title)}</title><style>{_CSS}</style></head><body>"
                f"<h1>{html.escape(self.title)}</h1>" + "\n".join(self.parts) + "</body></html>\n")
