"""``--json`` on every command that prints results: one JSON document on stdout, shapes of docs/cli.md."""

import json
from pathlib import Path

import pytest

from fivid.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[2]
SAMPLE = ROOT / "sample_data" / "R001_v10_ra08.csv"
PRINTING = ["ingest", "psd", "score", "run", "simulate", "modes", "cea", "study", "profile", "identify"]


def _options(parser):
    return {s for a in parser._actions for s in a.option_strings}


def _reads_json_flag(module: str) -> bool:
    """Whether the command module's code reads ``args.json`` (its handler acts on the flag, not only declares it)."""
    import ast
    import importlib

    tree = ast.parse(Path(importlib.import_module(module).__file__).read_text(encoding="utf-8"))
    return any(isinstance(n, ast.Attribute) and n.attr == "json" and isinstance(n.value, ast.Name)
               and n.value.id == "args" for n in ast.walk(tree))


@pytest.mark.parametrize("command", PRINTING)
def test_every_printing_command_has_json(command):
    """The parser offers ``--json`` (dest ``json``) and the command's handler reads it: a flag declared but ignored
    fails here. The JSON documents themselves are checked per command (this file, tests/fe/test_fe_cli.py,
    tests/study/, tests/surface/test_surface.py, tests/signal/test_signal_nperseg_rule.py)."""
    sub = next(a for a in build_parser()._actions if a.dest == "command").choices[command]
    flag = next((a for a in sub._actions if "--json" in a.option_strings), None)
    assert flag is not None and flag.dest == "json" and flag.default in (False, None), command
    module = sub.get_default("func").__module__
    assert module.startswith("fivid.cli.commands."), module
    assert _reads_json_flag(module), f"{module} declares --json but never reads args.json"


def test_damper_actions_have_json():
    damper = next(a for a in build_parser()._actions if a.dest == "command").choices["damper"]
    actions = next(a for a in damper._actions if a.dest == "damper_command").choices
    assert all("--json" in _options(p) for p in actions.values())


def test_ingest_and_psd_json(tmp_path, capsys):
    assert main(["ingest", str(SAMPLE), "-o", str(tmp_path), "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["rejected"] == [] and len(j["written"]) == 1
    rec = j["written"][0]
    assert set(rec) == {"input", "output", "run_id", "samples", "sample_rate_hz"}
    assert Path(rec["output"]).is_file() and rec["input"] == str(SAMPLE)

    psd_path = tmp_path / "psd.nc"
    assert main(["psd", rec["output"], "--nperseg", "1024", "-o", str(psd_path), "--json", "-q"]) == 0
    p = json.loads(capsys.readouterr().out)
    assert p["output"] == str(psd_path) and p["run_id"] == rec["run_id"] and p["variable"] == "acceleration"
    assert p["frequency_resolution_hz"] == pytest.approx(rec["sample_rate_hz"] / 1024)
    assert p["n_frequencies"] == 513 and p["settings"]["nperseg"] == 1024 and p["steady_window_s"] is None
    assert 0 < p["peak_frequency_hz"] <= rec["sample_rate_hz"] / 2


def test_ingest_json_lists_rejections(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("not a rig file\n")
    assert main(["ingest", str(bad), str(SAMPLE), "-o", str(tmp_path / "out"), "--json"]) == 2
    captured = capsys.readouterr()
    j = json.loads(captured.out)
    assert len(j["written"]) == 1 and j["rejected"][0]["input"] == str(bad) and j["rejected"][0]["error"]


def test_run_dry_run_json(tmp_path, capsys):
    status = main(["run", str(ROOT / "pipelines" / "calibration.yaml"), "-c", str(ROOT / "configs/runs/sample.yaml"),
                   "-o", str(tmp_path / "out"), "--dry-run", "--json"])
    assert status == 0
    j = json.loads(capsys.readouterr().out)
    assert j["dry_run"] is True and any("output folder" in line for line in j["plan"])
