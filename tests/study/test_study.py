"""Parametric studies (fivid.study): the 2-DOF mode-coupling oracle, resumption, coordinates, failures, dask."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from fivid.cli import main
from fivid.errors import ConfigError
from fivid.signal.levels import third_octave_bands
from fivid.study import HoffmannSystem, load_study, open_study, run_study

ROOT = Path(__file__).resolve().parents[2]
HOFFMANN = ROOT / "configs" / "studies" / "hoffmann_mu_sweep.yaml"
PARAMS = {"mass": "1 kg", "k1": "1e6 N/m", "k2": "1.6e6 N/m", "k3": "0.8e6 N/m", "damping": "20 N s/m",
          "preload": "100 N", "belt_velocity": "1 m/s"}


def _study(mu, *, cea=True, duration="0.6 s", extra_sweep=None, combine=None):
    sweep = {"mu": {"values": list(mu)}, **(extra_sweep or {})}
    if combine:
        sweep["combine"] = combine
    cfg = {"fivid-study": 1, "name": "hoffmann", "system": {"lumped": "hoffmann", "parameters": PARAMS},
           "sweep": sweep, "points": {"transient": {"duration": duration, "sample_rate": "20 kHz",
                                                    "perturbation": "1e-7 m"}}}
    if cea:
        cfg["cea"] = {"mu": {"start": 0, "stop": 2, "num": 41}}
    return load_study(cfg)


def test_cea_finds_the_closed_form_threshold_and_transients_follow_it(tmp_path):
    """Hoffmann et al. (2002): the study's CEA gives mu_c in closed form (damped; Brent to ~sqrt(eps) on Re,
    as in tests/fe/test_fe_cea.py); a transient 5 % above it grows at the CEA's rate, one 5 % below decays.

    Growth within 2 %: the envelope fit is unbiased for one exponential; the window (last factor 30 of the
    growth, ended at the first loss of continuous sliding) leaves the decaying partner mode below 1/30 ** (|Re
    partner| / Re) of the growing one, and the explicit step (200 per period) changes Re(lambda) by O((w dt)^2).
    """
    mc = HoffmannSystem().critical_mu()
    summary = run_study(_study([0.95 * mc, 1.05 * mc]), tmp_path / "out", workers=0, progress=False)
    assert summary["critical_mu"]["value"] == pytest.approx(mc, rel=1e-6)
    assert summary["critical_mu"]["partner_mode"] == 3 - summary["critical_mu"]["mode"]
    below, above = summary["points"]
    assert below["regime"] == "stable" and below["growth_rate"] < 0
    assert above["regime"] == "mode_coupling"
    assert above["cea_growth_rate"] > 0
    assert above["growth_rate"] == pytest.approx(above["cea_growth_rate"], rel=0.02)
    assert above["onset_time"] > 0
    assert below["growth_rate"] == pytest.approx(below["cea_growth_rate"], rel=0.1)  # two modes beat: coarser
    # every per-point quantity carries its CF unit beside the plain key (issue 32 item 5; the keys are the contract)
    units = summary["units"]
    assert {k: units[k] for k in ("mu", "growth_rate", "frequency", "onset_time", "cea_growth_rate",
                                  "cea_frequency")} == {"mu": "1", "growth_rate": "s-1", "frequency": "Hz",
                                                        "onset_time": "s", "cea_growth_rate": "s-1",
                                                        "cea_frequency": "Hz"}
    assert set(units) >= {k for p in summary["points"] for k, v in p.items() if isinstance(v, float)}


def test_regimes_across_the_threshold_and_stick_slip():
    """Far above mu_c the limit cycle reaches the belt speed: stick phases (stick_slip); mu_s > mu_k below mu_c
    with a small disturbance stays stable (a run that never sticks cannot show static friction)."""
    mc = HoffmannSystem().critical_mu()
    study = _study([1.6 * mc], cea=False, duration="0.3 s")
    kind = study.kind
    ds = kind.evaluate(kind.system(study), study.points, {"mu": 1.6 * mc})
    assert str(ds["regime"].values) == "stick_slip" and float(ds["stick_fraction"]) > 0.01
    ds = kind.evaluate(kind.system(study), study.points, {"mu": 0.5, "mu_static": 0.8})
    assert str(ds["regime"].values) == "stable"


def test_points_are_coordinates_and_select_by_condition(tmp_path):
    out = tmp_path / "out"
    study = _study([0.5, 1.2], cea=False, duration="0.2 s", extra_sweep={"seed": {"values": [1, 2]}})
    summary = run_study(study, out, workers=0, progress=False)
    assert summary["n_points"] == 4 and summary["n_done"] == 4
    ds = open_study(out / "study.nc")
    assert ds["mu"].attrs["units"] == "1" and ds.sizes["point"] == 4
    sel = ds.sel(mu=1.2)
    assert sel.sizes["point"] == 2 and set(sel["seed"].values.tolist()) == {1, 2}
    assert set(ds["regime"].values.astype(str)) <= {"stable", "mode_coupling", "stick_slip"}
    # the summary's points carry their conditions in SI and the regime
    assert [(p["mu"], p["seed"]) for p in summary["points"]] == [(0.5, 1), (0.5, 2), (1.2, 1), (1.2, 2)]
    assert all(p["status"] == "done" and "regime" in p for p in summary["points"])
    assert (out / "report.html").read_text().count("<figure>") >= 1


def test_rerun_computes_nothing_and_a_lost_point_only(tmp_path):
    out = tmp_path / "out"
    study = _study([0.5, 0.9, 1.2], cea=False, duration="0.2 s")
    first = run_study(study, out, workers=0, progress=False)
    assert first["timing"]["computed_points"] == 3
    again = run_study(study, out, workers=0, progress=False)
    assert again["timing"]["computed_points"] == 0 and again["points"] == first["points"]
    victim = sorted((out / "points").glob("p0001-*.nc"))[0]
    victim.unlink()
    third = run_study(study, out, workers=0, progress=False)
    assert third["timing"]["computed_points"] == 1 and third["points"] == first["points"]


_KILLABLE = """
import sys
from fivid.study import load_study, run_study
run_study(load_study(sys.argv[1]), sys.argv[2], workers=0, progress=False)
"""


def test_killed_study_resumes_and_equals_an_uninterrupted_run(tmp_path):
    """SIGKILL while points are being computed: the points written are complete files (atomic), the re-run
    computes the rest only, and study.nc equals that of a run never interrupted."""
    cfg = tmp_path / "s.yaml"
    cfg.write_text(HOFFMANN.read_text().replace("duration: 0.6 s", "duration: 1.5 s"))
    out = tmp_path / "killed"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.Popen([sys.executable, "-c", _KILLABLE, str(cfg), str(out)], cwd=ROOT, env=env)
    deadline = time.time() + 120
    while time.time() < deadline and not list((out / "points").glob("p0001-*.nc")):
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    n_before = len(list((out / "points").glob("*.nc")))
    assert 2 <= n_before < 5, "the kill came too late to test resumption"
    for f in (out / "points").glob("*.nc"):
        xr.open_dataset(f).close()  # every written point opens
    resumed = run_study(load_study(cfg), out, workers=0, progress=False)
    assert resumed["timing"]["computed_points"] == 5 - n_before
    clean = run_study(load_study(cfg), tmp_path / "clean", workers=0, progress=False)
    assert resumed["points"] == clean["points"]
    a = xr.open_dataset(out / "study.nc")
    b = xr.open_dataset(tmp_path / "clean" / "study.nc")
    xr.testing.assert_identical(a.drop_attrs(), b.drop_attrs())


def test_a_failing_point_is_reported_and_the_others_finish(tmp_path, capsys):
    """mu_static below mu is refused inside that point only; the CLI exits 1 and names it."""
    cfg = {"fivid-study": 1, "name": "fails", "system": {"lumped": "hoffmann", "parameters": PARAMS},
           "sweep": {"mu": {"values": [0.5, 0.5]}, "mu_static": {"values": [0.8, 0.2]}, "combine": "zip"},
           "points": {"transient": {"duration": "0.1 s", "sample_rate": "20 kHz"}}}
    path = tmp_path / "fails.yaml"
    import yaml

    path.write_text(yaml.safe_dump(cfg))
    rc = main(["study", str(path), "-o", str(tmp_path / "out"), "--workers", "0", "--json", "--no-progress"])
    assert rc == 1
    summary = json.loads(capsys.readouterr().out)
    assert [p["status"] for p in summary["points"]] == ["done", "failed"]
    assert summary["failed"][0]["point"] == 1 and "mu_kinetic <= mu_static" in summary["failed"][0]["error"]
    assert len(list((tmp_path / "out" / "points").glob("*.nc"))) == 1


@pytest.mark.parametrize("key, value, where", [
    ("sweep", {"mu": {"start": 0, "num": 3}}, "sweep.mu"),
    ("sweep", {"velocity": {"values": [1]}}, "sweep.velocity"),
    ("sweep", {"normal_load": {"values": ["5 m"]}}, "sweep.normal_load.values[0]"),
    ("points", {"psd": {"nperseg": 256}}, "points.psd"),
    ("cea", {"mu": {"values": [1, 0.5]}}, "cea.mu"),
])
def test_config_errors_name_the_key(tmp_path, key, value, where):
    import yaml

    cfg = {"fivid-study": 1, "name": "x", "system": {"lumped": "hoffmann"}, "sweep": {"mu": {"values": [1.0]}}}
    cfg[key] = value
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(cfg))
    with pytest.raises(ConfigError) as err:
        load_study(path)
    assert err.value.key.startswith(where) and err.value.file == str(path) and err.value.line is not None


def test_cli_help_and_bad_config_exit_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        main(["study", "--help"])
    assert e.value.code == 0 and "resumes" in capsys.readouterr().out
    bad = tmp_path / "bad.yaml"
    bad.write_text("fivid-study: 2\n")
    assert main(["study", str(bad), "-o", str(tmp_path / "o")]) == 2
    assert "fivid-study" in capsys.readouterr().err


def test_external_dask_scheduler(tmp_path):
    """--scheduler: the points go to an existing cluster (here a LocalCluster started by the test)."""
    from distributed import LocalCluster

    study = _study([0.5, 1.2], cea=False, duration="0.1 s")
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster:
        summary = run_study(study, tmp_path / "out", scheduler=cluster.scheduler_address, progress=False)
    assert summary["n_done"] == 2 and "parallel_efficiency" not in summary["timing"]
    ref = run_study(study, tmp_path / "ref", workers=0, progress=False)
    assert summary["points"] == ref["points"]


def _block_model(stiffness):
    """A block pressed flat on a clamped base (tests/helpers/solver_models.py) with a given contact penalty [N/m^3]."""
    from tests.helpers.solver_models import block_on_base

    cfg = block_on_base(load=-2e-6)
    cfg["bodies"]["block"]["divisions"] = [4, 2]
    cfg["contacts"][0]["normal_stiffness"] = f"{stiffness} N/m^3"
    cfg["bodies"]["block"]["clamp"] = ["top"]  # the loading clamp (its y dofs follow the load motion)
    cfg["reactions"] = [{"name": "loader", "body": "block", "edge": "top", "tangential": "x", "normal": "y"}]
    return cfg


def test_coupling_indicator_spans_uncoupled_to_tied():
    """Rayleigh's monotonicity: every preloaded frequency lies between its uncoupled and tied bounds, so kappa
    is in [0, 1]; a vanishing contact stiffness gives kappa ~ 0 (the uncoupled frequencies), a stiffness far
    above the bodies' (every slave node closed) kappa ~ 1; kappa grows with the stiffness in between."""
    from fivid.fe import load_model
    from fivid.fe.modal import modal_analysis
    from fivid.study.coupling import coupling_bounds, coupling_indicator

    kappas = []
    for k in (1e8, 1e13, 1e15, 1e18):
        model = load_model(_block_model(k))
        f0, fi = coupling_bounds(model, 8)
        assert np.all(fi >= f0 * (1 - 1e-9))
        f = modal_analysis(model, 8, include_contact=True, normal_load=1.0)["frequency"].values
        assert np.all(f >= f0 * (1 - 1e-9)) and np.all(f <= fi * (1 + 1e-6))
        kappas.append(coupling_indicator(f, f0, fi))
    assert kappas[0] < 1e-3 and kappas[-1] > 0.99
    assert np.all(np.diff(kappas) > 0)


def test_transition_load_is_bracketed():
    from fivid.study.kinds.weak_strong import _transition_load

    pts = [{"normal_load": f, "coupling_response": k} for f, k in ((0.5, 0.1), (2.0, 0.3), (8.0, 0.7), (32.0, 0.9))]
    t = _transition_load(pts)
    assert t["bracket"] == [2.0, 8.0] and t["criterion"].startswith("response")
    assert t["value"] == pytest.approx(np.exp(np.log(2.0) + 0.5 * np.log(4.0)))  # halfway in log load
    assert _transition_load(pts[2:])["value"] is None


def test_power_law_fit_recovers_known_exponents_with_honest_intervals():
    """rms = 2 F^0.5 V^1.2 e with log-normal noise of known sigma: statsmodels' 95 % intervals cover the true
    exponents in about 95 % of 200 repetitions (binomial: 183..197 is the 99.9 % range for p = 0.95)."""
    from fivid.study.fits import power_law_fit

    rng = np.random.default_rng(5)
    F, V = np.meshgrid(np.geomspace(0.5, 20, 5), np.geomspace(1e-3, 2e-2, 4), indexing="ij")
    covered = 0
    for _ in range(200):
        rms = 2 * F**0.5 * V**1.2 * np.exp(0.1 * rng.standard_normal(F.shape))
        pts = [{"status": "done", "normal_load": f, "sliding_velocity": v, "rms": r}
               for f, v, r in zip(F.ravel(), V.ravel(), rms.ravel())]
        fit = power_law_fit(pts)
        e = fit["exponents"]
        covered += (e["normal_load"]["ci"][0] <= 0.5 <= e["normal_load"]["ci"][1])
    assert fit["axes"] == ["normal_load", "sliding_velocity"] and fit["n"] == 20
    assert 183 <= covered <= 197
    assert power_law_fit(pts[:2]) is None  # one varying axis, 2 points, 2 parameters: no residual freedom


@pytest.mark.slow
def test_fe_load_sweep_with_a_law_and_its_coulomb_reference(tmp_path):
    """The coarse rig over two loads with the sample twin's ground-truth law (synthetic): preloaded modes and the
    modal coupling index per point, and the law's response against Coulomb mu0 alone at the same point: steady
    Coulomb sliding of this model excites almost nothing, the perturbation does (gain > 20 dB)."""
    sys.path.insert(0, str(ROOT / "sample_data"))
    import yaml
    from generate import load_truth, truth_law

    from fivid.friction import write_law

    law_path = tmp_path / "law.nc"
    write_law(truth_law(load_truth()), law_path)
    cfg = {"fivid-study": 1, "name": "coarse_load",
           "system": {"model": str(ROOT / "configs" / "models" / "triboair_coarse.yaml")},
           "sweep": {"normal_load": {"values": ["2 N", "5 N"]}, "sliding_velocity": {"values": ["10 mm/s"]},
                     "roughness_ra": {"values": ["1.6 um"]}},
           "points": {"modes": {"n_modes": 6},
                      "transient": {"duration": "0.12 s", "sample_rate": "51.2 kHz", "law": str(law_path),
                                    "coulomb_reference": True}}}
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(cfg))
    summary = run_study(load_study(path), tmp_path / "out", workers=0, progress=False)
    assert summary["n_done"] == 2
    for p in summary["points"]:
        assert 0 < p["coupling_modal"] < 1
        assert p["perturbation_gain_db"] > 20, p
    ds = open_study(tmp_path / "out" / "study.nc")
    assert ds.sel(normal_load=5.0)["mode_frequency"].sizes["mode"] == 6
    # the automatic path, as fivid simulate (issue 30): reduced within its 0.5 dB tolerance, recorded per point
    assert list(ds["solver_path"].values) == ["reduced", "reduced"]
    assert np.all(ds["reduced_error_estimate_db"].values <= 0.5)


def test_study_points_take_the_automatic_path_unless_forced():
    """points.transient.solver: auto (default) passes reduced='auto' with the tolerance; full/reduced force one; a
    point refining the mesh or the time step studies the full model's discretisation (auto -> full)."""
    from fivid.study.tasks import solver_choice

    assert solver_choice({}, {"mu": 0.3}) == {"reduced": "auto", "reduced_tolerance": 0.5}
    assert solver_choice({"reduced_tolerance": 0.2}, {}) == {"reduced": "auto", "reduced_tolerance": 0.2}
    assert solver_choice({"solver": "full"}, {}) == {"reduced": None}
    assert solver_choice({"solver": "reduced"}, {"mesh": 2.0}) == {"reduced": "reduced"}
    assert solver_choice({}, {"mesh": 2.0}) == {"reduced": None}
    assert solver_choice({}, {"time_step": 0.5}) == {"reduced": None}
    study = load_study({"fivid-study": 1, "name": "s", "system": {"model": str(ROOT / "configs/models/triboair_coarse.yaml")},
                        "sweep": {"mu": {"values": [0.3]}},
                        "points": {"transient": {"duration": "0.1 s", "solver": "full", "reduced_tolerance": 1}}})
    assert study.points["transient"]["solver"] == "full" and study.points["transient"]["reduced_tolerance"] == 1.0


def test_observed_order_on_known_convergence():
    """q = q_inf + C h^p on unevenly spaced meshes: the order and the extrapolation are recovered to the root
    finder's tolerance; non-monotone values give no order and the finest-step difference as the error."""
    from fivid.study.convergence import observed_order

    for p in (1.0, 2.0, 3.5):
        h = [0.005, 0.002, 0.001]
        r = observed_order(h, [10.0 - 4e3 * x**p for x in h])
        assert r["order"] == pytest.approx(p, rel=1e-9) and r["extrapolated"] == pytest.approx(10.0, rel=1e-9)
        assert r["h"] == [0.001, 0.002, 0.005]
    r = observed_order([1, 2, 4], [1.0, 1.2, 1.1])
    assert r["order"] is None and r["error"] == pytest.approx(0.2)


def test_committed_sample_law_is_the_ground_truth():
    """configs/laws/sample_truth.nc (written by configs/laws/make_sample_truth.py) is the twin's known law."""
    sys.path.insert(0, str(ROOT / "sample_data"))
    from generate import load_truth, truth_law

    from fivid.friction import load_law

    truth = truth_law(load_truth())
    law = load_law(ROOT / "configs" / "laws" / "sample_truth.nc")
    assert law.mu0 == truth.mu0 and law.band == truth.band
    for v, ra in ((0.005, 0.4e-6), (0.02, 1.6e-6)):
        assert law.amplitude(v, ra) == pytest.approx(truth.amplitude(v, ra), rel=1e-12)
    np.testing.assert_allclose(law.shape, truth.shape, rtol=1e-12)


@pytest.mark.slow
def test_convergence_study_quick(tmp_path):
    """configs/studies/convergence.yaml --quick: three meshes x two steps, a third step on two of them, a 10 mm point; each
    mode's frequency falls as the mesh is refined (Q4 is too stiff in bending: convergence from above), an order
    and an error are reported, halving the step changes the PSD by well under 1 dB, and the one-third-octave
    band levels and the PSD peaks are reported against the element size and the step (issue 16 item 5)."""
    summary = run_study(load_study(ROOT / "configs" / "studies" / "convergence.yaml", quick=True), tmp_path / "o",
                        workers=2, progress=False)
    assert summary["n_done"] == 9
    mesh = summary["convergence"]["mesh"]
    assert len(mesh) == 2  # one per time step computed on all three meshes
    for m in mesh[0]["mode_frequency"][:3]:
        f1, f2, f3 = m["values"]
        assert f1 < f2 < f3 and m["order"] is not None and m["error"] > 0
    for s in summary["convergence"]["time_step"]:
        assert s["lsd_db"] < 1.0
    # the scores' one band grid (issue 29 item 1): the IEC base-10 thirds lying inside the study's PSD band
    # 100 Hz - 9.95 kHz that are at least one 50 Hz bin wide (the 250 Hz to 8 kHz bands), then the whole band;
    # the first mode's peak is tracked (the whole band's edges are PSD bin frequencies: equal to float resolution)
    iec = third_octave_bands(100.0, 9950.0)
    wide = iec["upper"] - iec["lower"] >= 50.0
    bands = mesh[0]["band_level_db"]
    assert len(bands) == wide.sum() + 1 == 17
    np.testing.assert_allclose([b["band"] for b in bands[:-1]], np.c_[iec["lower"][wide], iec["upper"][wide]],
                               rtol=1e-12)
    assert bands[-1]["band"] == pytest.approx([100.0, 9950.0], rel=1e-12)
    modes = [m["values"][0] for m in mesh[0]["mode_frequency"]]
    assert any(abs(p["values"][0] - modes[0]) < 0.05 * modes[0] for p in mesh[0]["psd_peak_frequency"])
    steps = summary["convergence"]["time_step_order"]  # one per mesh with three steps
    assert len(steps) == 2 and steps[0]["time_step"] == [0.225, 0.45, 0.9] and steps[0]["band_level_db"]


def test_study_files_pass_the_cf_checker(tmp_path, request):
    """study.nc and every point file: no CF error and no warning (text as char arrays, long names, units)."""
    from tests.helpers import cf_checks

    table = cf_checks.table_or_skip(request.config)
    study = _study([0.5, 1.2], duration="0.1 s")
    run_study(study, tmp_path / "out", workers=0, progress=False)
    for f in [tmp_path / "out" / "study.nc", *sorted((tmp_path / "out" / "points").glob("*.nc"))]:
        errors, warnings, out = cf_checks.cf_check(f, table)
        assert (errors, warnings) == (0, 0), out[-2000:]
