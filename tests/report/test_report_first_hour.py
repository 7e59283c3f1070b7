"""A report that agrees with itself and reads well (issue 32 item 5), on the SYNTHETIC report inputs of
test_report_render.py plus a law file with a candidate-form table: μ0's interval shown to the digits that separate
its ends, a compact candidate table that fits a 1400 px page, a caption for the simulated PSD's drop above the law's
band, modes paired with peaks only within a tolerance, one number format per score."""

import re

import numpy as np
import pytest
import xarray as xr
from tests.report.test_report_render import _law, browser_check, report_inputs  # noqa: F401  (the shared module fixture)

from fivid.report import render_report
from fivid.report.build import PEAK_PAIRING_TOLERANCE

FORMS = ["constant", "power_law", "linear_velocity_power_law"]


def _law_with_forms(path, ci=(0.300093, 0.300145), reasons=("", "", "its AICc needs at least 6 runs for 3 "
                                                                 "coefficients, 4 given")):
    from fivid.friction import law_dataset

    ds = law_dataset(_law(), mu0_ci=ci)
    ds["mu0"] = ds["mu0"].copy(data=0.300119)
    n = len(FORMS)
    ds = ds.assign_coords(form=FORMS)
    for name, values in {"form_aicc": [-18.3, np.nan, np.nan], "form_delta_aicc": [0.0, np.nan, np.nan],
                         "form_akaike_weight": [1.0, np.nan, np.nan], "form_cv_error": [0.63, 0.05, 0.06],
                         "form_aic": [-20.0, -30.0, -31.0], "form_bic": [-21.0, -31.0, -32.0],
                         "form_loglik": [11.0, 18.0, 18.5]}.items():
        ds[name] = ("form", np.array(values, float))
    ds["form_chosen"] = ("form", np.array([1, 0, 0]))
    ds["form_fitted"] = ("form", np.array([1, 1, 1]))
    ds["form_n_params"] = ("form", np.array([1, 3, 3]))
    ds["form_reason"] = ("form", np.array(list(reasons), dtype=object))
    ds["form_cv_reason"] = ("form", np.array([""] * n, dtype=object))
    ds.attrs["selection_why"] = "constant is the only form with an AICc (-18.30): the others need more runs"
    ds.attrs["warnings"] = "a constant amplitude law was chosen although the runs' amplitudes spread 3.2x"
    ds.to_netcdf(path)
    return path


@pytest.fixture(scope="module")
def rendered(tmp_path_factory, report_inputs):  # noqa: F811
    tmp = tmp_path_factory.mktemp("first_hour")
    modal = tmp / "modal.nc"  # 7000 Hz: 40 % from the nearest peak (5000 Hz), so not paired
    xr.Dataset({"frequency": ("mode", [830.0, 2278.0, 4982.0, 7000.0], {"units": "Hz"})}).to_netcdf(modal)
    inputs = {**report_inputs, "law_path": _law_with_forms(tmp / "law.nc"), "modal_path": modal,
              "band": (500.0, 10000.0)}
    path = render_report(tmp / "report.html", inputs)
    return path, path.read_text(encoding="utf-8")


def _table_after(html, marker):
    start = html.index(marker)
    return html[html.index("<table>", start):html.index("</table>", start)]


def test_mu0_interval_shows_the_digits_that_separate_its_ends(rendered):
    _, html = rendered
    assert "μ0 = 0.300119 (95 % interval 0.300093–0.300145)" in html
    assert "0.3001–0.3001" not in html


def test_law_paragraphs_are_sentences_and_the_warning_shows(rendered):
    _, html = rendered
    assert "Why this form: constant is the only form with an AICc" in html
    assert '<p class="warning">Warning: a constant amplitude law was chosen' in html
    assert "source: " not in html.split("Identified friction law")[1].split("<table>")[0]  # no run-on describe()


def test_candidate_table_is_compact_and_says_why_a_form_was_left_out(rendered):
    _, html = rendered
    table = _table_after(html, "Candidate amplitude forms")
    headers = re.findall(r"<th>(.*?)</th>", table)
    assert headers == ["form", "", "coefficients", "AICc", "ΔAICc", "Akaike weight", "CV error",
                       "not compared because"]
    assert "its AICc needs at least 6 runs for 3 coefficients, 4 given" in table
    assert "could be fitted" not in table and "-18.30" in table and "0.630" in table


def test_candidate_table_drops_an_all_empty_column(tmp_path, report_inputs):  # noqa: F811
    law = _law_with_forms(tmp_path / "law.nc", reasons=("", "", ""))
    html = render_report(tmp_path / "r.html", {**report_inputs, "law_path": law}).read_text(encoding="utf-8")
    assert "not compared because" not in _table_after(html, "Candidate amplitude forms")


def test_psd_drop_above_the_law_band_has_a_caption(rendered, report_inputs):  # noqa: F811
    _, html = rendered
    upper = _law().band[1]  # 20 kHz: the test PSDs end at 25.6 kHz, beyond it
    assert f"Above {upper:g} Hz the simulated PSD drops: the identified friction law holds no perturbation" in html


def test_modes_are_paired_only_within_the_tolerance(rendered):
    _, html = rendered
    table = _table_after(html, "Modal frequencies against measured peaks")
    rows = re.findall(r"<tr>(.*?)</tr>", table)[1:]
    paired = [re.findall(r"<td[^>]*>(.*?)</td>", r)[-1] for r in rows]
    assert paired[:3] == ["yes", "yes", "yes"]
    assert paired[3].startswith(f"no: the nearest measured peak is 40 % away, more than "
                                f"{PEAK_PAIRING_TOLERANCE * 100:.0f} %")
    assert "e+0" not in table  # frequencies as plain numbers


def test_scores_have_one_format(rendered):
    _, html = rendered
    verdict = _table_after(html, "Verdict")
    values = re.findall(r'<td class="num">([^<]*)</td>', verdict)
    assert values and all(re.fullmatch(r"-?\d+\.\d\d", v) for v in values), values  # lsd_db: 0.01 dB


@pytest.mark.browser
def test_report_fits_a_1400_px_page(rendered, tmp_path):
    from playwright import sync_api

    from tests.report.test_report_render import CHROMIUM, CHROMIUM_FLAGS

    path, _ = rendered
    browser_check(path, tmp_path / "profile-check")  # skips (or fails in CI) without Chromium
    with sync_api.sync_playwright() as pw:
        ctx = pw.chromium.launch_persistent_context(str(tmp_path / "profile"), executable_path=CHROMIUM,
                                                    headless=True, args=CHROMIUM_FLAGS,
                                                    viewport={"width": 1400, "height": 900})
        try:
            page = ctx.new_page()
            page.goto(path.resolve().as_uri(), wait_until="load")
            width = page.evaluate("document.documentElement.scrollWidth")
            widest = page.evaluate("Math.max(...Array.from(document.querySelectorAll('table')).map("
                                   "t => t.getBoundingClientRect().right))")
            page.screenshot(path=str(tmp_path / "report.png"), full_page=True)
        finally:
            ctx.close()
    assert width <= 1400 and widest <= 1400, (width, widest)
