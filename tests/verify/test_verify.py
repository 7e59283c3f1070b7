"""``fivid verify``: the catalogue, the runner's verdicts, the exit codes, the manual in a real browser.

The toy cases below are SYNTHETIC test hooks (a case made to pass and one made to fail), registered for one test
and removed after it; the shipped cases are exercised by the tests of the code they check (one home per oracle).
"""

import json
import math

import pytest

from fivid.cli import main
from fivid.verify import Case, Outcome, Plot, Curve, register_case, registered_cases, unregister_case
from fivid.verify.case import ERROR_KINDS
from fivid.verify.runner import evaluate_case

from tests.report.test_report_render import browser_check


def _toy_value(quick, data):
    """A toy 'computation': 1.0 against the reference 1.0 + 3e-3 (relative error ~3e-3)."""
    return Outcome(1.0, 1.0 + 3e-3, 1e-2, Plot("x [-]", "y [-]", (Curve([0.0, 1.0], [0.0, 1.0], "toy"),)))


def _toy_failing(quick, data):
    return Outcome(1.0, 1.0 + 3e-3, 1e-3, Plot("x [-]", "y [-]", (Curve([0.0, 1.0], [1.0, 0.0], "toy"),)))


def _toy_raises(quick, data):
    raise RuntimeError("toy failure inside the computation")


def _toy(name, compute, **kw):
    return Case(name=name, title=f"Toy case {name}", quantity="toy ratio", unit="", reference="1.003 (toy)",
                source="test hook in tests/verify/test_verify.py", method="returns a constant",
                tolerance_basis="chosen to pass or fail on purpose", compute=compute, **kw)


@pytest.fixture
def toy_cases():
    cases = [_toy("toy_passing", _toy_value), _toy("toy_failing", _toy_failing), _toy("toy_raises", _toy_raises),
             _toy("toy_needs_data", _toy_value, real_data="no/such/file.csv")]
    for c in cases:
        register_case(c)
    yield {c.name: c for c in cases}
    for c in cases:
        unregister_case(c.name)


def test_catalogue_has_at_least_15_documented_cases():
    """Every shipped case names its reference, its source and the basis of its tolerance."""
    cases = [c for c in registered_cases() if c.compute.__module__.startswith("fivid.verify.cases.")]
    assert len(cases) >= 15
    assert len({c.name for c in cases}) == len(cases)
    for c in cases:
        assert c.reference and c.source and c.method and c.tolerance_basis and c.quantity, c.name
        assert c.error in ERROR_KINDS


def test_verdicts_of_the_runner(toy_cases):
    """Within tolerance passes, outside fails with the error computed as the case says, a raising computation fails
    with its exception as the reason, missing data skip with the path named."""
    ok = evaluate_case(toy_cases["toy_passing"], True, None)
    assert ok.status == "passed" and ok.passed is True
    assert ok.error == pytest.approx(3e-3 / 1.003, rel=1e-12)
    bad = evaluate_case(toy_cases["toy_failing"], True, None)
    assert bad.status == "failed" and bad.passed is False and "outside its tolerance" in bad.reason
    raised = evaluate_case(toy_cases["toy_raises"], True, None)
    assert raised.status == "failed" and "RuntimeError: toy failure" in raised.reason and math.isnan(raised.error)
    skipped = evaluate_case(toy_cases["toy_needs_data"], True, None)
    assert skipped.status == "skipped" and skipped.passed is None and "no/such/file.csv" in skipped.reason


def test_bad_case_definitions_are_refused():
    with pytest.raises(ValueError, match="error"):
        _toy("toy_x", _toy_value, error="percent")
    with pytest.raises(ValueError, match="lower-case"):
        _toy("Toy X", _toy_value)
    register_case(_toy("toy_dup", _toy_value))
    try:
        with pytest.raises(ValueError, match="already registered"):
            register_case(_toy("toy_dup", _toy_failing))
    finally:
        unregister_case("toy_dup")


def test_json_exit_0_when_all_pass(toy_cases, tmp_path, capsys):
    status = main(["verify", "--case", "toy_passing", "--case", "toy_needs_data", "--workers", "0", "--json",
                   "-o", str(tmp_path / "v"), "--no-progress"])
    doc = json.loads(capsys.readouterr().out)
    assert status == 0 and doc["passed"] is True
    assert [c["name"] for c in doc["cases"]] == ["toy_passing", "toy_needs_data"]
    entry = doc["cases"][0]
    assert {"name", "quantity", "reference", "source", "value", "error", "tolerance", "passed"} <= set(entry)
    assert entry["reference"] == pytest.approx(1.003) and entry["value"] == 1.0 and entry["passed"] is True
    assert doc["cases"][1]["passed"] is None and doc["cases"][1]["status"] == "skipped"
    assert json.loads((tmp_path / "v" / "verification.json").read_text()) == doc
    env = doc["environment"]
    assert env["fivid_version"] and env["git_revision"] and env["cpu"] and env["date"]
    assert {"numpy", "scipy", "numba"} <= set(env["packages"])


def test_a_failing_case_exits_3_and_is_red_in_the_manual(toy_cases, tmp_path, capsys):
    status = main(["verify", "--case", "toy_passing", "--case", "toy_failing", "--case", "toy_raises", "--workers",
                   "0", "-o", str(tmp_path / "v"), "--no-progress"])
    out = capsys.readouterr().out
    assert status == 3
    assert "FAILED: 1 passed, 2 failed" in out and "toy_failing" in out
    html = (tmp_path / "v" / "verification.html").read_text()
    assert 'class="verdict fail"' in html and "FAILED" in html
    # the summary's two FAIL cells, and the numbers table of the case outside tolerance (the raising one has none)
    assert html.count('<td class="fail">FAIL</td>') == 3
    assert ".fail{color:#b00020" in html  # red


def test_bad_input_exits_2(tmp_path, capsys):
    assert main(["verify", "--case", "no_such_case", "-o", str(tmp_path / "v")]) == 2
    assert "no_such_case" in capsys.readouterr().err
    (tmp_path / "file").write_text("x")
    assert main(["verify", "--case", "welch_parseval", "-o", str(tmp_path / "file"), "--workers", "0"]) == 2
    assert "is a file" in capsys.readouterr().err
    assert main(["verify", "--workers", "-1"]) == 2
    assert main(["verify", "--real-data", str(tmp_path / "absent"), "--case", "dektak_ra"]) == 2
    assert not (tmp_path / "v").exists()


def test_list_names_every_case(capsys):
    assert main(["verify", "--list"]) == 0
    out = capsys.readouterr().out
    assert all(c.name in out for c in registered_cases())


@pytest.mark.browser
def test_manual_opens_in_headless_chromium_with_every_figure(toy_cases, tmp_path, capsys):
    """Two shipped cases, a failing and a skipped toy case in one manual (in this process: the toy cases live in
    this test module, which dask's worker processes cannot import)."""
    status = main(["verify", "--quick", "--case", "welch_parseval", "--case", "gaussian_filter_cutoff", "--workers",
                   "0", "--case", "toy_failing", "--case", "toy_needs_data", "-o", str(tmp_path / "v"),
                   "--no-progress"])
    assert status == 3
    res = browser_check(tmp_path / "v" / "verification.html", tmp_path / "chromium-profile")
    assert res["errors"] == [] and res["console"] == [] and res["failed"] == []
    assert len(res["images"]) == 3  # one per computed case; the skipped case has none
    assert all(img["ok"] and img["width"] > 100 for img in res["images"]), res["images"]
    assert "fivid verification manual" in res["title"]


def test_shipped_cases_run_on_dask(tmp_path, capsys):
    """The default path: a LocalCluster of two worker processes, the cases pickled to them by reference."""
    status = main(["verify", "--quick", "--case", "welch_parseval", "--case", "sine_roughness_ra", "--json", "-o",
                   str(tmp_path / "v"), "--no-progress"])
    doc = json.loads(capsys.readouterr().out)
    assert status == 0 and doc["passed"] and [c["status"] for c in doc["cases"]] == ["passed", "passed"]


def test_the_docs_list_every_shipped_case(root):
    """docs/verification.md's catalogue names every case the registry ships (and no other)."""
    import re

    text = (root / "docs" / "verification.md").read_text(encoding="utf-8")
    table = text.split("## The catalogue", 1)[1].split("\n\n", 2)[1]
    documented = set(re.findall(r"^\| `(\w+)` \|", table, flags=re.M))
    shipped = {c.name for c in registered_cases() if c.compute.__module__.startswith("fivid.verify.cases.")}
    assert documented == shipped
