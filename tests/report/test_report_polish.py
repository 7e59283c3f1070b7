"""Report polish of issue 19: date and version, long names, numeric order, PSD dynamic range, effective settings."""

import re

import numpy as np
import pytest
from tests.report.test_report_render import report_inputs  # noqa: F401  (the shared module fixture)

from fivid import __version__


@pytest.fixture(scope="module")
def polished(tmp_path_factory, report_inputs):  # noqa: F811
    from fivid.report import render_report

    conditions = dict(report_inputs["conditions"])
    # keys that sort as strings in the wrong numeric order: c10 (5 mm/s) before c2 (20 mm/s)
    conditions = {"c2": conditions["c1"], "c10": {**conditions["c0"], "sliding_velocity": 0.005}}
    checks = [{**c, "condition": "c2" if c["condition"] == "c1" else "c10"} for c in report_inputs["checks"]]
    inputs = {**report_inputs, "conditions": conditions, "checks": checks,
              "psd_files": {"c2": report_inputs["psd_files"]["c1"], "c10": report_inputs["psd_files"]["c0"]},
              "score_files": {"c2": report_inputs["score_files"]["c1"], "c10": report_inputs["score_files"]["c0"]},
              "generated": "2026-01-02 03:04 UTC",
              "provenance": {**report_inputs["provenance"],
                             "config": {"path": "c.yaml", "sha256": "1" * 64, "content": {"output": "written/out"}},
                             "settings": {"output folder": "/override/out", "scoring band [Hz]": [800.0, 5000.0]}}}
    path = tmp_path_factory.mktemp("polished") / "report.html"
    return render_report(path, inputs).read_text(encoding="utf-8")


def test_report_states_its_date_and_fivid_version(polished):
    assert f"Generated 2026-01-02 03:04 UTC by fivid {__version__}." in polished


def test_scores_have_long_names_not_column_names(polished):
    headers = re.findall(r"<th>([^<]*)</th>", polished)
    assert "log-spectral distance [dB]" in headers
    assert not {"lsd_db", "level_diff_db", "band_level_rms_error_db", "shape_correlation"} & set(headers)


def test_conditions_are_in_numeric_order(polished):
    h3 = re.findall(r"<h3[^>]*>([^<]*)</h3>", polished)
    assert h3 == ["5 mm/s, 5 N, Ra 0.4 µm", "20 mm/s, 5 N, Ra 1.6 µm"]
    verdict = polished.split('id="identified-friction-law"')[0]
    assert verdict.index("5 mm/s, 5 N") < verdict.index("20 mm/s, 5 N")  # checks: titled and in the same order


def test_provenance_shows_the_effective_settings_before_the_file(polished):
    prov = polished.split('id="provenance"')[1]
    assert "Effective settings" in prov and "/override/out" in prov and "800, 5000" in prov
    assert prov.index("/override/out") < prov.index("written/out")


def test_psd_axes_span_80_db_below_the_peak_in_view():
    from fivid.report.figures import PSD_DYNAMIC_RANGE_DB, psd_axis_limits

    f = np.linspace(0.0, 10000.0, 1001)
    psd = np.full(f.size, 1e-20)  # a numerical floor far below anything measured
    psd[(f > 900) & (f < 1100)] = 1e-2
    psd[f > 8000] = 1.0  # out of view: must not set the scale
    lo, hi = psd_axis_limits(f, [psd], (100.0, 5000.0))
    assert PSD_DYNAMIC_RANGE_DB == 80.0
    assert lo == pytest.approx(1e-2 * 1e-8) and hi == pytest.approx(2e-2)
    assert psd_axis_limits(f, [np.zeros_like(f)], (100.0, 5000.0)) is None
