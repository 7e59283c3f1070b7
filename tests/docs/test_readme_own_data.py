"""The README's "Your own rig data" section (issue 32 item 2) says what the reader does: its minimal template is
read by ``fivid ingest``, and every line or column its table calls required is refused when missing, every optional
one accepted. (Its commands run in tests/docs/test_doc_commands.py like every documented command.)"""

import re

import pytest

from fivid.cli import main


@pytest.fixture
def section(root):
    text = (root / "README.md").read_text(encoding="utf-8")
    start = text.index("## Your own rig data")
    return text[start:text.index("\n## ", start + 5)]


@pytest.fixture
def template(section):
    return re.search(r"```text\n(.*?)```", section, re.S).group(1)


def _ingest(tmp_path, text, name="run.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return main(["ingest", str(path), "-o", str(tmp_path / "out"), "--overwrite"])


def test_the_template_ingests(template, tmp_path, capsys):
    assert _ingest(tmp_path, template) == 0
    assert "R01.nc" in capsys.readouterr().out


def _required_rows(section):
    """Names in backticks of the table rows marked ``| yes |``, and of those marked ``| no |``."""
    rows = [ln for ln in section.splitlines() if ln.startswith("| ") and ln.count("|") == 4]
    pick = {"yes": [], "no": []}
    for ln in rows:
        cells = [c.strip() for c in ln.strip("|").split("|")]
        if cells[1] in pick:
            pick[cells[1]] += re.findall(r"`([^`]+)`", cells[0])
    return pick["yes"], pick["no"]


def test_each_required_item_is_required(section, template, tmp_path, capsys):
    required, optional = _required_rows(section)
    lines = template.splitlines(keepends=True)
    header = next(i for i, ln in enumerate(lines) if ln.startswith("time ["))
    columns = lines[header].rstrip("\n").split(",")
    checked = 0
    for item in required:
        if item.startswith("# ") and item.endswith(":") or item.startswith("# fivid-rig-csv"):
            key = item.split(":")[0]
            kept = [ln for ln in lines if not ln.startswith(key + ":")]
            assert len(kept) == len(lines) - 1, item
            text = "".join(kept)
        else:
            name = item.split(" [")[0]
            idx = [i for i, c in enumerate(columns) if c.split(" [")[0] == name]
            if not idx:
                continue  # "time [s]" matches "time"; other named columns are all in the template
            i = idx[0]
            text = "".join(",".join(f for j, f in enumerate(ln.rstrip("\n").split(",")) if j != i) + "\n"
                           if k >= header else ln for k, ln in enumerate(lines))
        assert _ingest(tmp_path, text) == 2, item
        capsys.readouterr()
        checked += 1
    assert checked >= 8  # magic line, run_id, rig, three conditions, time and the three signals
    for item in optional:
        if item == "# sample_rate:":
            text = template.replace("# roughness_ra:", "# sample_rate: 51.28 kHz\n# roughness_ra:")
        elif item in ("position", "velocity"):
            unit = {"position": "mm", "velocity": "mm/s"}[item]
            text = template.replace("normal_force [N]\n", f"normal_force [N],{item} [{unit}]\n")
            text = re.sub(r"(\n0\.\d+,[^\n]+)", r"\1,0.0", text)
        else:
            continue
        assert _ingest(tmp_path, text) == 0, (item, capsys.readouterr().err)
        capsys.readouterr()
