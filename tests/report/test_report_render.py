"""The validation report: self-contained HTML, correct intervals and peaks, renders in real Chromium."""

import base64
import json
import os
import re
import shutil

import numpy as np
import pytest


def _law():
    from fivid.friction import AmplitudeModel, PerturbedCoulombLaw

    # A linear-in-V amplitude law per roughness level with a known diagonal covariance.
    model = AmplitudeModel(
        form="linear_velocity",
        coefficients=np.array([0.002, 0.3, 0.004, 0.5]),
        names=("intercept[0]", "velocity_slope[0]", "intercept[1]", "velocity_slope[1]"),
        stderr=np.array([1e-4, 0.02, 2e-4, 0.03]),
        covariance=np.diag([1e-4, 0.02, 2e-4, 0.03]) ** 2,
        terms=("sliding_velocity", "roughness_ra"),
        roughness_levels=(0.4e-6, 1.6e-6),
    )
    f = np.linspace(200.0, 20000.0, 200)
    return PerturbedCoulombLaw(0.3, f, 1.0 / (1.0 + (f / 3000.0) ** 2), model, (200.0, 20000.0))


def _signal(fs, n, peaks, seed):
    """SYNTHETIC test signal: white noise (1 m s-2 RMS) plus sines at ``peaks`` [Hz]."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    x = rng.standard_normal(n)
    for fp in peaks:
        x += 3.0 * np.sin(2 * np.pi * fp * t)
    return t, x


@pytest.fixture(scope="module")
def report_inputs(tmp_path_factory):
    import xarray as xr

    from fivid.friction import law_dataset
    from fivid.signal import welch_psd

    tmp_path = tmp_path_factory.mktemp("report_inputs")
    law_path = tmp_path / "law.nc"
    law_dataset(_law(), mu0_ci=(0.29, 0.31)).to_netcdf(law_path)
    modal_path = tmp_path / "modal.nc"
    xr.Dataset({"frequency": ("mode", [830.0, 2278.0, 4982.0], {"units": "Hz"})}).to_netcdf(modal_path)
    fs, n = 51200.0, 2**16
    runs, conditions, psd_files, score_files, checks = {}, {}, {}, {}, []
    for k, (v, ra) in enumerate([(0.01, 0.4e-6), (0.02, 1.6e-6)]):
        cond = f"c{k}"
        spectra = {}
        for role, seed in (("measured", 10 + k), ("simulated", 20 + k)):
            t, x = _signal(fs, n, [850.0, 2300.0, 5000.0], seed)
            da = xr.DataArray(x, dims="time", coords={"time": t}, name="acceleration", attrs={"units": "m s-2"})
            spectra[role] = welch_psd(da, nperseg=4096)
        p = spectra["measured"]
        ds = xr.Dataset(
            {f"psd_{role}{sfx}": ((f"{'measured_run' if role == 'measured' else 'simulated_seed'}", "frequency"),
                                  [(spectra[role] if not sfx else spectra[role][f"psd{sfx}"]).values])
             for role in ("measured", "simulated") for sfx in ("", "_lower", "_upper")},
            coords={"frequency": p["frequency"].values, "measured_run": [f"R{k}"], "simulated_seed": ["seed0"]},
            attrs={"nperseg": 4096, "equivalent_averages": p.attrs["equivalent_averages"]})
        ds["psd_measured"].attrs["units"] = p.attrs["units"]
        psd_files[cond] = tmp_path / f"{cond}-psd.nc"
        ds.to_netcdf(psd_files[cond])
        score = {"lsd_db": 1.2, "level_diff_db": 0.1, "band_level_rms_error_db": 0.8, "shape_correlation": 0.97}
        score_files[cond] = tmp_path / f"{cond}.json"
        score_files[cond].write_text(json.dumps({"pairs": [{"measured": f"R{k}", "simulated": "seed0",
                                                            "scores": score}], "summary": score}))
        runs[f"R{k}"] = {"run_id": f"R{k}", "sliding_velocity": v, "normal_load": 5.0, "roughness_ra": ra}
        conditions[cond] = {"sliding_velocity": v, "normal_load": 5.0, "roughness_ra": ra, "runs": [f"R{k}"]}
        checks.append({"condition": cond, "score": "lsd_db", "value": 1.2, "threshold": "lsd_db <= 6", "pass": True})
    return {
        "title": "fivid validation report — test (SYNTHETIC inputs)",
        "provenance": {"pipeline": {"path": "p.yaml", "sha256": "0" * 64},
                       "config": {"path": "c.yaml", "sha256": "1" * 64, "content": {"a": 1}},
                       "inputs": {"R0.csv": "2" * 64, "R1.csv": "3" * 64}},
        "runs": runs, "conditions": conditions, "law_path": law_path, "modal_path": modal_path,
        "psd_files": psd_files, "score_files": score_files, "band": (500.0, 20000.0), "checks": checks,
    }


@pytest.fixture(scope="module")
def report(tmp_path_factory, report_inputs):
    from fivid.report import render_report

    return render_report(tmp_path_factory.mktemp("report") / "report.html", report_inputs)


EXPECTED_FIGURES = 1 + 1 + 2 + 1  # law shape, amplitude, one PSD overlay per condition, modes vs peaks


def test_report_is_self_contained_with_every_figure_embedded(report):
    text = report.read_text(encoding="utf-8")
    srcs = re.findall(r'(?:src|href)="([^"]*)"', text)
    assert len(srcs) == EXPECTED_FIGURES
    for src in srcs:
        assert src.startswith("data:image/png;base64,")
        assert base64.b64decode(src.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
    assert "<script" not in text and "http://" not in text and "https://" not in text
    assert "PASS" in text and "Provenance" in text and "2" * 64 in text


def test_verdict_fails_when_a_check_fails(tmp_path, report_inputs):
    from fivid.report import render_report

    checks = [dict(c) for c in report_inputs["checks"]]
    checks[0].update(value=9.0, **{"pass": False})
    text = render_report(tmp_path / "r.html", {**report_inputs, "checks": checks}).read_text()
    assert "FAIL: 1 of 2 threshold checks fail" in text


def test_amplitude_interval_is_the_delta_method_closed_form():
    from fivid.report import amplitude_interval

    law = _law()
    v = np.array([0.005, 0.02])
    a, lo, hi = amplitude_interval(law.amplitude_model, v, np.full(2, 0.4e-6))
    # A = a0 + b0 V, Var A = s_a0^2 + V^2 s_b0^2 (diagonal covariance), 95 % normal interval.
    sigma = np.sqrt(1e-4**2 + v**2 * 0.02**2)
    np.testing.assert_allclose(a, 0.002 + 0.3 * v, rtol=1e-12)
    np.testing.assert_allclose(hi - a, 1.959963984540054 * sigma, rtol=1e-12)
    np.testing.assert_allclose(a - lo, 1.959963984540054 * sigma, rtol=1e-12)


def test_measured_peaks_find_the_sines_within_one_bin():
    import xarray as xr

    from fivid.report import measured_peaks
    from fivid.signal import welch_psd

    fs = 51200.0
    t, x = _signal(fs, 2**17, [850.0, 2300.0, 5000.0], 1)
    p = welch_psd(xr.DataArray(x, dims="time", coords={"time": t}, name="a", attrs={"units": "m s-2"}), nperseg=4096)
    peaks = measured_peaks(p["frequency"].values, p.values, (500.0, 20000.0))
    # Each sine gives a Hann main lobe; its maximum is within one bin (fs/nperseg = 12.5 Hz) of the tone.
    # White noise of 63 averages scatters about ±1 dB, far below the 6 dB prominence required.
    assert peaks.size == 3
    np.testing.assert_allclose(peaks, [850.0, 2300.0, 5000.0], atol=fs / 4096)


CHROMIUM = "/usr/bin/chromium"
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def browser_check(html_path, user_data_dir) -> dict:
    """Open ``html_path`` in real headless Chromium (playwright, the Debian browser, no download).

    Returns the page's JavaScript errors, console errors, failed requests and, per <img>, whether it
    decoded (complete and naturalWidth > 0).
    """
    missing = None
    try:
        from playwright import sync_api
    except ImportError:
        missing = "playwright is not installed (pip install -e '.[test]')"
    if shutil.which(CHROMIUM) is None:
        missing = f"{CHROMIUM} is not installed (apt-get install -y chromium)"
    if missing:
        # In CI (CI=true) the browser test must run: a missing browser is a failure, not a skip.
        (pytest.fail if os.environ.get("CI") else pytest.skip)(missing)
    errors, console, failed = [], [], []
    with sync_api.sync_playwright() as pw:
        ctx = pw.chromium.launch_persistent_context(
            str(user_data_dir), executable_path=CHROMIUM, headless=True, args=CHROMIUM_FLAGS)
        try:
            page = ctx.new_page()
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            page.on("console", lambda msg: console.append(msg.text) if msg.type == "error" else None)
            page.on("requestfailed", lambda req: failed.append(req.url[:80]))
            page.goto(html_path.resolve().as_uri(), wait_until="load")
            images = page.evaluate(
                "Array.from(document.images).map(i => ({alt: i.alt, ok: i.complete && i.naturalWidth > 0,"
                " width: i.naturalWidth}))")
            title = page.title()
        finally:
            ctx.close()
    return {"errors": errors, "console": console, "failed": failed, "images": images, "title": title}


@pytest.mark.browser
def test_report_renders_in_headless_chromium(report, tmp_path):
    res = browser_check(report, tmp_path / "chromium-profile")
    assert res["errors"] == [] and res["console"] == [] and res["failed"] == []
    assert len(res["images"]) == EXPECTED_FIGURES
    assert all(img["ok"] and img["width"] > 100 for img in res["images"]), res["images"]
    assert "fivid validation report" in res["title"]


@pytest.mark.browser
def test_browser_check_detects_a_broken_figure_and_a_script_error(tmp_path):
    bad = tmp_path / "bad.html"
    bad.write_text('<!DOCTYPE html><html><body><img src="data:image/png;base64,iVBORw0KGgoAAAAA" alt="x">'
                   "<script>undefined_function()</script></body></html>")
    res = browser_check(bad, tmp_path / "chromium-profile")
    assert res["errors"] and not res["images"][0]["ok"]


def test_report_draws_the_monte_carlo_envelope_and_its_coverage(tmp_path, report_inputs):
    """An envelope of 19 PSDs of the same SYNTHETIC signal (other seeds) for condition c0: one more figure, and
    the coverage table; the same envelope 20 dB up leaves every band outside (0 %)."""
    import xarray as xr

    from fivid.report import render_report
    from fivid.score.envelope import envelope_dataset
    from fivid.signal import welch_psd

    fs, n = 51200.0, 2**16
    psds = []
    for seed in range(100, 119):
        t, x = _signal(fs, n, [850.0, 2300.0, 5000.0], seed)
        psds.append(welch_psd(xr.DataArray(x, dims="time", coords={"time": t}, attrs={"units": "m s-2"}),
                              nperseg=4096))
    f = psds[0]["frequency"].values
    texts = {}
    for name, gain in (("same", 1.0), ("loud", 100.0)):
        env = envelope_dataset(f, gain * np.stack([p.values for p in psds]), "m s-2",
                               attrs={"variable": "acceleration", "not_sampled": "mu0"})
        path = tmp_path / f"{name}.nc"
        env.to_netcdf(path)
        inputs = {**report_inputs, "envelope_files": {"c0": path}}
        texts[name] = render_report(tmp_path / f"{name}.html", inputs).read_text(encoding="utf-8")
    srcs = re.findall(r'(?:src|href)="([^"]*)"', texts["same"])
    assert len(srcs) == EXPECTED_FIGURES + 1 and "Monte-Carlo envelope" in texts["same"]
    assert "bands inside the 5-95 % envelope" in texts["same"]
    row = re.search(r"<td>measured R0</td><td>(\d+) of (\d+)</td>", texts["same"])
    assert row and int(row.group(1)) >= 0.7 * int(row.group(2))  # 18/20 expected inside; 0.7 leaves 3 sd
    loud = re.search(r"<td>measured R0</td><td>(\d+) of (\d+)</td>", texts["loud"])
    assert loud and int(loud.group(1)) == 0
