"""Docs a newcomer trusts (issue 32 item 7): what sample_data/README.md says feeds the main command is what the
shipped run config reads; the README's roughness paragraph keeps results, not one machine's timings; X3P names
its extra package; a semicolon-separated fivid-rig-csv file gets a delimiter hint."""

import re

import yaml

from fivid.cli import main


def test_sample_data_readme_names_what_the_main_command_reads(root):
    config = yaml.safe_load((root / "configs/runs/sample.yaml").read_text(encoding="utf-8"))
    folder = (root / "configs/runs" / config["inputs"]["folder"]).resolve()
    assert folder == (root / "sample_data/twin").resolve()
    text = (root / "sample_data/README.md").read_text(encoding="utf-8")
    ingest_section = text[:text.index("## Twin data set")]
    assert "README's main command (the calibration pipeline)" in ingest_section
    assert "use the twin data set `twin/` below, not these" in ingest_section
    assert "fivid run pipelines/calibration.yaml --config configs/runs/sample.yaml" in text[text.index("## Twin"):]


def _roughness_paragraph(readme: str) -> str:
    start = readme.index("Roughness noise (seed 003)")
    return readme[start:readme.index("\n\n", start)]


def test_readme_roughness_paragraph_has_results_not_timings(root):
    para = _roughness_paragraph((root / "README.md").read_text(encoding="utf-8"))
    assert "n = 0.93 [0.64, 1.21]" in para and "docs/roughness.md" in para
    assert not re.search(r"\bload\s*~|\d+(\.\d+)?\s*min\b|CPU per", para), para
    doc = (root / "docs/roughness.md").read_text(encoding="utf-8")
    assert "44 min at load ~24" in doc and "AMD EPYC" in doc  # the timings moved there, with the machine


def test_x3p_names_its_extra_package(root):
    readme = (root / "README.md").read_text(encoding="utf-8")
    assert "X3P needs the extra package `x3pio`: `python -m pip install x3pio`" in readme


def test_semicolon_csv_gets_a_delimiter_hint(root, tmp_path, capsys):
    lines = (root / "sample_data/R001_v10_ra08.csv").read_text(encoding="utf-8").splitlines(keepends=True)
    header = next(i for i, ln in enumerate(lines) if ln.startswith("time ["))
    semi = lines[:header] + [ln.replace(",", ";") for ln in lines[header:header + 200]]
    path = tmp_path / "semi.csv"
    path.write_text("".join(semi), encoding="utf-8")
    assert main(["ingest", str(path), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "the header is separated by semicolons, not ','" in err and "delimiter ';'" in err
    good = tmp_path / "comma.csv"  # a comma file with a wrong column gets no such hint
    good.write_text("".join(lines[:header] + [lines[header].replace("normal_force", "normal_farce")]
                            + lines[header + 1:header + 200]), encoding="utf-8")
    assert main(["ingest", str(good), "-o", str(tmp_path / "out2")]) == 2
    assert "separated by" not in capsys.readouterr().err
