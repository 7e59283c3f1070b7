"""Small rig-CSV writers shared by the ingest tests (tests/io/)."""

from __future__ import annotations

from pathlib import Path

STANDARD_GRAVITY = 9.80665  # [m s-2], CGPM 1901 (3rd CGPM), exact by definition
SAMPLE_RATE = 51200.0  # [Hz]

GOOD_META = {
    "run_id": "R001",
    "rig": "triboair",
    "sliding_velocity": "10 mm/s",
    "normal_load": "5 N",
    "roughness_ra": "0.8 um",
}
HEADER = "time [s],acceleration [g],friction_force [N],normal_force [N],position [mm]"
N_META_LINES = 1 + len(GOOD_META)  # magic line + metadata: the header is line N_META_LINES + 1


def rig_rows(n: int = 50, sample_rate: float = SAMPLE_RATE) -> list[str]:
    """``n`` data rows of a plausible run (times written to 9 decimals)."""
    rows = []
    for i in range(n):
        t = i / sample_rate
        rows.append(f"{t:.9f},{0.01 * ((i * 7) % 11 - 5):.4f},{1.5 + 0.001 * (i % 3):.4f},5.0{i % 10},{0.01 * i / sample_rate * 1e3:.6f}")
    return rows


def rig_text(rows=None, *, meta=None, header: str = HEADER, magic: str = "# fivid-rig-csv: 1", extra_meta=()) -> str:
    """The text of a fivid-rig-csv file; ``rows`` default :func:`rig_rows`."""
    meta = GOOD_META if meta is None else meta
    lines = [magic] if magic is not None else []
    lines += [f"# {k}: {v}" for k, v in meta.items()] + list(extra_meta)
    lines.append(header)
    lines += rig_rows() if rows is None else rows
    return "\n".join(lines) + "\n"


def write_rig(path: Path, text: str | None = None, **kw) -> Path:
    """Write :func:`rig_text` (or ``text``) to ``path`` and return it."""
    path = Path(path)
    path.write_text(rig_text(**kw) if text is None else text, encoding="utf-8", newline="")
    return path


def data_line(row: int) -> int:
    """The file's line number of 0-based data row ``row`` in a :func:`rig_text` file."""
    return N_META_LINES + 2 + row


def with_field(row: str, index: int, value: str, delimiter: str = ",") -> str:
    """``row`` with field ``index`` replaced by ``value``."""
    fields = row.split(delimiter)
    fields[index] = value
    return delimiter.join(fields)
