"""Issue 16 item 5: spectral convergence (band levels, PSD peaks, observed orders) and the pipeline's record of its
mesh and estimated discretisation error.

References nobody here wrote: the level of a white PSD over a band (density x width), the vertex of a parabola
(a Gaussian peak is a parabola in log scale), and q(h) = q_inf + C h^p with known p (the order must come back to
the root finder's tolerance, as in test_study.test_observed_order_on_known_convergence).
"""

import json
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from fivid.signal.compare import band_levels_db
from fivid.signal.levels import bin_weights, third_octave_bands
from fivid.signal.peaks import parabolic_peaks
from fivid.study.convergence import band_level_grid, convergence_summary

ROOT = Path(__file__).resolve().parents[2]
COARSE = ROOT / "configs" / "models" / "triboair_coarse.yaml"


def test_band_level_grid_is_the_scores_iec_thirds_and_the_whole_range():
    """The convergence study's bands are the PSD scores' (IEC 61260-1 base-10 thirds inside the PSD's range), so
    its errors qualify the scores' band levels; the last band is the whole range."""
    f = np.arange(100.0, 10_000.0, 25.0)
    bands, weights = band_level_grid(f)
    iec = third_octave_bands(100.0, 9975.0)
    assert [b[0] for b in bands[:-1]] == list(iec["lower"]) and [b[1] for b in bands[:-1]] == list(iec["upper"])
    assert bands[-1] == (100.0, 9975.0) and weights.shape == (f.size, len(bands))
    for lo, hi in bands[:-1]:
        assert hi / lo == pytest.approx(10 ** 0.1, rel=1e-12)  # G^(1/3), G = 10^(3/10)
    # a white PSD: each band's power is density x width (bin rectangles), the whole range's (n - 1) bins' worth
    np.testing.assert_allclose(np.ones(f.size) @ weights, [hi - lo for lo, hi in bands], rtol=1e-12)


@pytest.mark.parametrize("centre", [1000.0, 1010.0, 1012.5, 1024.9])
def test_peak_of_a_gaussian_is_found_between_bins_exactly(centre):
    """A Gaussian in linear scale is a parabola in dB: the three-point vertex is exact (float round-off)."""
    f = np.arange(0.0, 5000.0, 25.0)
    p = np.exp(-0.5 * ((f - centre) / 40.0) ** 2) + np.exp(-0.5 * ((f - 3000.0) / 60.0) ** 2)
    peaks = parabolic_peaks(f, p, 20.0)  # no floor: log(p) is exactly a sum of two parabolas, each dominant near its peak
    assert peaks[0] == pytest.approx(centre, abs=1e-6) and peaks[1] == pytest.approx(3000.0, abs=1e-6)


def _fake_study(h_factors, psd_of_h, steps=(0.9,)):
    """A study Dataset and point table over mesh factor (element size 2 mm / factor x 0.25) and time step."""
    f = np.arange(100.0, 10_000.0, 25.0)
    table, psd, hs = [], [], []
    for m in h_factors:
        for s in steps:
            h = 0.5e-3 / m
            table.append({"mesh": m, "time_step": s, "seed": 1.0})
            psd.append(psd_of_h(f, h, s))
            hs.append(h)
    n = len(table)
    ds = xr.Dataset({"element_size": (("point",), np.array(hs)), "psd": (("point", "frequency"), np.array(psd))},
                    coords={"point": np.arange(n), "frequency": f})
    return ds, table


def _gaussian_psd(f, h, s, *, p_f=2.0, p_l=1.5):
    """A floor and a peak at 4 kHz + 1e7 h^p_f [Hz] (h in m), scaled by 10^((3 + 2e3 h^p_l) / 10)."""
    peak = 4000.0 + 1e7 * h**p_f
    base = 1e-8 + np.exp(-0.5 * ((f - peak) / 40.0) ** 2)
    return base * 10 ** ((3.0 + 2e3 * h**p_l) / 10)


def test_convergence_summary_recovers_the_orders_of_peaks_and_band_levels():
    ds, table = _fake_study((0.25, 0.5, 1.0), _gaussian_psd)
    conv = convergence_summary(ds, table, list(range(len(table))))
    (entry,) = conv["mesh"]
    (peak,) = entry["psd_peak_frequency"]
    assert peak["order"] == pytest.approx(2.0, rel=1e-6) and peak["extrapolated"] == pytest.approx(4000.0, abs=1e-5)
    # the 2 mm mesh's shift: 1e7 * (2e-3)^2 = 40 Hz
    assert peak["deviation"][2] == pytest.approx(40.0, abs=1e-4)
    # a uniform scale 10^(C h^1.5 / 10): the level is L_inf + C h^1.5 exactly where the peak does not cross the
    # band's edges: the floor-only bands below 3 kHz (the Gaussian is below 1e-200 there) and the whole range
    exact = [b for b in entry["band_level_db"] if b["band"][1] < 3000.0] + [entry["band_level_db"][-1]]
    assert len(exact) > 10 and entry["band_level_db"][-1]["band"] == [100.0, 9975.0]
    for b in exact:
        assert b["order"] == pytest.approx(1.5, rel=1e-6), b
        assert b["deviation"][2] == pytest.approx(2e3 * (2e-3) ** 1.5, rel=1e-6)


def test_time_step_orders_with_three_steps():
    def psd(f, h, s):
        return _gaussian_psd(f, 0.0, s) * 10 ** (0.01 * s**2 / 10)  # level off by 0.01 dB x (step fraction)^2

    ds, table = _fake_study((1.0,), psd, steps=(0.9, 0.45, 0.225))
    conv = convergence_summary(ds, table, list(range(len(table))))
    (entry,) = conv["time_step_order"]
    assert entry["time_step"] == [0.225, 0.45, 0.9]
    whole = entry["band_level_db"][-1]
    assert whole["order"] == pytest.approx(2.0, rel=1e-6)
    assert len(conv["time_step"]) == 2 and all(s["lsd_db"] < 0.01 for s in conv["time_step"])


def _table(tmp_path, *, psd=False, **models):
    """A convergence table from the fake study (2, 1, 0.5 mm) for the named models (with the PSDs at the largest
    step, as write_convergence_table stores them, when ``psd``)."""
    ds, table = _fake_study((0.25, 0.5, 1.0), _gaussian_psd, steps=(0.9, 0.45))
    conv = convergence_summary(ds, table, list(range(len(table))))
    data = {"fivid-convergence": 1, "source": {"study": "fake"}, "models": models, "convergence": conv}
    if psd:
        at = [k for k, c in enumerate(table) if c["time_step"] == 0.9][::-1]  # finest first
        data["psd"] = {"time_step": 0.9, "element_size": ds["element_size"].values[at].tolist(),
                       "frequency": ds["frequency"].values.tolist(), "psd": ds["psd"].values[at].tolist()}
    path = tmp_path / ("convergence_psd.json" if psd else "convergence.json")
    path.write_text(json.dumps(data))
    return path


def test_discretisation_estimate_of_the_coarse_model(tmp_path):
    from fivid.pipeline.discretisation import discretisation_estimate

    path = _table(tmp_path, **{COARSE.name: {"element_size": 0.002, "mesh": 0.25}})
    est = discretisation_estimate(COARSE, (800.0, 5000.0), path, bin_width=25.0)
    assert est["covered"] and est["model"]["element_size"] == pytest.approx(0.002, rel=1e-9)
    assert est["model"]["dofs"] == 984 and est["model"]["name"] == "triboair_coarse"
    # IEC thirds overlapping 800-5000 Hz: from 708-891 to 4467-5623; the peak moves inside 3548-4467 (1e7 h^2 Hz)
    parts = est["third_octaves"]
    assert round(parts[0]["band"][0]) == 708 and round(parts[-1]["band"][0]) == 4467 and len(parts) == 9
    assert est["band_level_error_db"] == pytest.approx(2e3 * 0.002**1.5, rel=1e-3)  # the uniform scale's error
    assert est["band_level_deviation_db"] is None  # no PSDs in this table: the bound over the thirds only
    (peak,) = est["peaks"]
    assert peak["frequency"] == pytest.approx(4000.0, abs=1e-5) and peak["shift_bins"] == pytest.approx(1.6, rel=1e-5)
    assert est["time_step_lsd_db"] == pytest.approx(0.0, abs=1e-9)  # the fake PSD does not depend on the step


def test_discretisation_estimate_from_the_tables_psds_is_exact_for_the_band(tmp_path):
    """With the meshes' PSDs the band level of exactly the scoring band is extrapolated: the fake PSD's whole
    peak is inside 800-5000 Hz, so the level is L_inf + C h^1.5 exactly and the order comes back."""
    from fivid.pipeline.discretisation import discretisation_estimate

    path = _table(tmp_path, psd=True, **{COARSE.name: {"element_size": 0.002, "mesh": 0.25}})
    est = discretisation_estimate(COARSE, (800.0, 5000.0), path, bin_width=25.0)
    assert est["band_level_order"] == pytest.approx(1.5, rel=1e-6)
    assert est["band_level_deviation_db"] == pytest.approx(2e3 * 0.002**1.5, rel=1e-6)
    assert est["band_level_error_db"] == pytest.approx(est["band_level_deviation_db"])
    assert est["band_lsd_db"] > 2e3 * (0.002**1.5 - 0.0005**1.5)  # the floor's offset, plus the shifted peak
    # the breakdown is on the scores' grid: the IEC thirds score_runs reports for this band (third_octave_weights)
    from fivid.signal.levels import third_octave_weights

    thirds, _ = third_octave_weights(np.arange(100.0, 10_000.0, 25.0), 800.0, 5000.0, min_bins=1.0)
    assert [b["band"] for b in est["third_octaves"]] == [[lo, hi] for lo, hi in zip(thirds["lower"], thirds["upper"])]
    assert len(est["third_octaves"]) == 7  # 891-1122 ... 3548-4467 Hz
    floor_only = [b for b in est["third_octaves"] if b["band"][1] < 3000.0]  # a uniform scale: exact there
    assert floor_only and all(b["deviation_db"] == pytest.approx(2e3 * 0.002**1.5, rel=1e-6) for b in floor_only)


def test_uncovered_model_or_missing_table_is_said_not_guessed(tmp_path):
    from fivid.pipeline.discretisation import discretisation_estimate

    path = _table(tmp_path, **{COARSE.name: {"element_size": 0.002, "mesh": 0.25}})
    fine = ROOT / "configs" / "models" / "triboair.yaml"
    est = discretisation_estimate(fine, (800.0, 5000.0), path, bin_width=25.0)
    assert not est["covered"] and "triboair.yaml" in est["reason"] and est["model"]["element_size"] == pytest.approx(5e-4)
    est = discretisation_estimate(COARSE, (800.0, 5000.0), tmp_path / "none.json", bin_width=25.0)
    assert not est["covered"] and "no convergence table" in est["reason"]
    wrong = _table(tmp_path, **{COARSE.name: {"element_size": 0.001, "mesh": 0.5}})  # a table lying about h
    assert not discretisation_estimate(COARSE, (800.0, 5000.0), wrong, bin_width=25.0)["covered"]


def test_shipped_table_covers_the_pipelines_model():
    """configs/runs/convergence.json (from configs/studies/convergence.yaml) covers the sample runs' coarse model;
    it says how many of the study's points it was made from (all 9 when shipped: the three finest meshes 2, 1 and
    0.5 mm carry the Richardson estimate, see docs/pipeline.md)."""
    from fivid.pipeline.discretisation import discretisation_estimate

    table = ROOT / "configs" / "runs" / "convergence.json"
    data = json.loads(table.read_text())
    assert data["source"]["study"] == "convergence" and not data["source"].get("quick")
    assert 0 < data["source"]["n_done"] <= data["source"]["n_points"]
    est = discretisation_estimate(COARSE, (800.0, 8000.0), table, bin_width=25.0)
    assert est["covered"] and est["band_level_error_db"] is not None and est["third_octaves"]
    assert est["band_lsd_db"] is not None and est["time_step_lsd_db"] < 0.2


def test_report_states_the_mesh_and_its_error(tmp_path):
    from fivid.pipeline.discretisation import discretisation_estimate
    from fivid.report.build import _discretisation
    from fivid.report.html import Page

    path = _table(tmp_path, **{COARSE.name: {"element_size": 0.002, "mesh": 0.25}})
    est = discretisation_estimate(COARSE, (800.0, 5000.0), path, bin_width=25.0)
    page = Page("t")
    _discretisation(page, est)  # the provenance section's mesh and error lines
    html = page.render()
    assert "largest element side 2 mm, 984 dofs" in html and "band level within 0.18 dB" in html
    path = _table(tmp_path, psd=True, **{COARSE.name: {"element_size": 0.002, "mesh": 0.25}})
    page = Page("t")
    _discretisation(page, discretisation_estimate(COARSE, (800.0, 5000.0), path, bin_width=25.0))
    assert "band level +0.18 dB, PSD log-spectral distance to the finest mesh" in page.render()
    assert "4000 Hz: +40.0 Hz (1.6 bins)" in html


def test_estimate_uses_the_three_finest_meshes_of_a_four_mesh_table(tmp_path):
    """A table with four meshes (the shipped study adds 5 mm to 2/1/0.5 mm) gives the Richardson estimate of the
    three finest that include the model's mesh; with exact h^2 levels it recovers the order 2 and the limit."""
    from fivid.pipeline.discretisation import discretisation_estimate

    table = json.loads((ROOT / "configs" / "runs" / "convergence.json").read_text())
    f = np.asarray(table["psd"]["frequency"], float)
    hs = [0.0005, 0.001, 0.002, 0.005]
    table["psd"]["element_size"] = hs
    # a white PSD whose level in dB is 100 + 1e6 h^2 (h in m): the 2 mm mesh is 4 dB above the limit
    table["psd"]["psd"] = [(np.full(f.size, 10 ** ((100 + 1e6 * h * h) / 10))).tolist() for h in hs]
    path = tmp_path / "convergence.json"
    path.write_text(json.dumps(table))
    est = discretisation_estimate(COARSE, (800.0, 8000.0), path, bin_width=25.0)
    assert est["band_level_order"] == pytest.approx(2.0, abs=1e-6)
    assert est["band_level_deviation_db"] == pytest.approx(4.0, abs=1e-6)
