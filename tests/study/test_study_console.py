"""``fivid study`` on the console (issue 32 item 5): every swept quantity with its units, and the weak/strong
transition load of a load sweep as the summary holds it (fivid.study.runner's ``transition_load(s)``)."""

import fivid.study
from fivid.cli import main


def _summary():
    """A summary as fivid.study.run_study returns it (keys used by the console), for a load x Ra sweep."""
    points = [{"normal_load": fn, "roughness_ra": ra, "status": "done", "regime": regime}
              for fn, regime in ((0.5, "weak"), (5.0, "strong")) for ra in (4e-7, 1.6e-6)]
    return {"study": "ws", "n_done": 4, "n_points": 4, "timing": {"wall_s": 1.0}, "points": points, "failed": [],
            "transition_load": {"value": 1.58, "bracket": [0.5, 5.0], "threshold": 0.5},
            "transition_loads": [{"roughness_ra": 4e-7, "value": 1.58, "bracket": [0.5, 5.0], "threshold": 0.5},
                                 {"roughness_ra": 1.6e-6, "value": None, "bracket": None, "threshold": 0.5,
                                  "note": "strong at every swept load"}]}


def test_study_console_gives_units_and_the_transition(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(fivid.study, "load_study", lambda path, quick=False: object())
    monkeypatch.setattr(fivid.study, "run_study", lambda *a, **k: _summary())
    assert main(["study", "unused.yaml", "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "weak/strong contact transition: at normal_load 1.58 N (between the swept 0.5 and 5 N" in out
    assert "    roughness_ra 4e-07 m: at normal_load 1.58 N" in out
    assert "    roughness_ra 1.6e-06 m: strong at every swept load" in out
    assert "  normal_load 0.5 N, roughness_ra 4e-07 m: weak" in out


def test_no_transition_lines_without_a_load_sweep(monkeypatch, tmp_path, capsys):
    summary = {**_summary(), "points": [{"mu": 0.3, "status": "done", "regime": "stable"}]}
    del summary["transition_load"], summary["transition_loads"]
    monkeypatch.setattr(fivid.study, "load_study", lambda path, quick=False: object())
    monkeypatch.setattr(fivid.study, "run_study", lambda *a, **k: summary)
    assert main(["study", "unused.yaml", "-o", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "weak/strong" not in out and "  mu 0.3: stable" in out


def test_study_report_gives_units_and_the_transition():
    """The study report's points table names every quantity with its units and says where the contact turns
    strong (fivid.study.report, the section every study report has)."""
    import xarray as xr

    from fivid.report.html import Page
    from fivid.study.report import study_section

    summary = {**_summary(), "source": "ws.yaml"}
    summary["points"] = [{**p, "level_db": 80.0} for p in summary["points"]]
    page = Page("t")
    study_section(page, xr.Dataset(), summary)
    html = page.render()
    assert "<th>normal_load [N]</th><th>roughness_ra [m]</th><th>regime</th><th>level_db [dB re 1e-6 m s-2]</th>" in html
    assert ("Weak/strong contact transition (coupling indicator κ = 0.5): at 1.58 N (between the swept loads 0.5 and "
            "5 N); per condition: roughness_ra 4e-07 m: at 1.58 N") in html
    assert "roughness_ra 1.6e-06 m: strong at every swept load" in html
