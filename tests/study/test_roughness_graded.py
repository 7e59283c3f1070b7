"""The roughness-noise study's pair (configs/models/rough_pair_graded*.yaml): profiles tied to Rsm, the
transducer-spring carriage, flat = smooth, Lv grows with Ra, and the identify bridge (slow).

The runs use the study's --quick model (rough_pair_graded_quick.yaml: 544 dofs, 50 um along the contact, a
6.3e-9 s step): 0.8 ms records, about 10-50 s each on a shared 2-core machine."""

import copy
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from fivid.fe import load_model
from fivid.fe.config import read_config
from fivid.solver import IntegrationOptions, OperatingCondition, OutputOptions, RunSchedule, simulate
from fivid.fe.rough_pair import rough_pair_config
from fivid.score.roughness import roughness_metrics, vibration_level
from fivid.study.roughness import RSM_LEVELS, ROUGHNESS_TASK, build_point_model, point_profiles_design
from fivid.surface.rough_pair import RSM_PER_CORRELATION_LENGTH, synthetic_rough_profiles

ROOT = Path(__file__).resolve().parents[2]
QUICK = ROOT / "configs/models/rough_pair_graded_quick.yaml"
COARSE = ROOT / "configs/models/rough_pair_graded_coarse.yaml"  # 100 um: the bridge's 0.1 s runs
#: the runs' settings: 2 MHz records after 0.05 ms settling, 30 contact sweeps at most
SCHEDULE = RunSchedule(duration=0.0, sample_rate=2e6, settle_time=0.05e-3)
RUN = dict(integration=IntegrationOptions(gs_tolerance=1e-6, gs_max_iterations=30),
           output=OutputOptions(progress=False))


def test_rsm_per_correlation_length_is_rices_zero_crossing_spacing():
    """A synthesised Gaussian-ACF profile crosses its mean every pi xi / sqrt(2) on average (Rice 1944), so two
    crossings (a peak and a valley: one profile element) span RSM_PER_CORRELATION_LENGTH x xi. Tolerance: 4
    standard errors of the mean spacing, from the spacings' own scatter over the ~1000 crossings."""
    xi = 200e-6 / RSM_PER_CORRELATION_LENGTH
    for seed in (1, 2):
        p = synthetic_rough_profiles(4.5e-6, 100e-3, correlation_length=xi, step=5e-6, seeds=(seed, seed + 1))[0]
        z, x = p.values - p.values.mean(), p["x"].values
        i = np.nonzero(np.sign(z[:-1]) != np.sign(z[1:]))[0]
        xc = x[i] - z[i] * (x[i + 1] - x[i]) / (z[i + 1] - z[i])
        spacing = np.diff(xc)
        se = spacing.std() / np.sqrt(spacing.size)
        assert 2 * spacing.mean() == pytest.approx(RSM_PER_CORRELATION_LENGTH * xi, abs=4 * 2 * se)


def test_replicates_take_their_own_rsm_level_and_realisation():
    spec = dict(ROUGHNESS_TASK)
    d0, d1 = (point_profiles_design(spec, {"seed": s}) for s in (0, 1))
    assert (d0["rsm"], d1["rsm"]) == RSM_LEVELS
    assert d0["correlation_length"] == pytest.approx(RSM_LEVELS[0] / (np.sqrt(2) * np.pi), rel=1e-12)
    assert d0["seeds"] == (3, 4) and d1["seeds"] == (103, 104)
    assert point_profiles_design(spec, {})["rsm"] == RSM_LEVELS[0]  # no seed axis: replicate 0
    fixed = point_profiles_design({**spec, "correlation_length": 0.5e-3}, {"seed": 1})
    assert fixed["correlation_length"] == 0.5e-3  # an explicit correlation length wins


def test_builder_lifts_the_carriage_and_its_springs_with_the_slider():
    """The carriage block and the transducer springs' upper ends rise with the upper block (rough_pair_config's
    lift), so each spring still joins a carriage node to the upper block's left-edge node at the same height."""
    lo, up = synthetic_rough_profiles(10e-6, 2.2e-3, correlation_length=45e-6, step=5e-6)
    cfg, info = rough_pair_config(QUICK, lo, up, normal_load=1.0)
    assert info["lift"] > 5e-6
    model = load_model(cfg)
    assert len(model.springs) == 4
    a = model.coords[[s.node_a for s in model.springs]]
    b = model.coords[[s.node_b for s in model.springs]]
    assert np.allclose(a[:, 0], 0.15e-3) and np.allclose(b[:, 0], 0.2e-3)  # carriage right edge, upper left edge
    assert np.all(np.diff(a[:, 1]) > 0) and np.all(np.diff(b[:, 1]) > 0)  # four distinct node pairs, in order
    # each pair at one height up to the profile's share at the upper block's corner (its smallest layer is 97 um)
    assert np.all(np.abs(a[:, 1] - b[:, 1]) < 20e-6)
    assert a[0, 1] == pytest.approx(0.5e-3 + info["lift"], abs=1e-12)  # the carriage rose with the slider


def _smooth_quick_model():
    """rough_pair_graded_quick.yaml without its profile keys (plain graded rectangles), sensors and load as the
    builder's flat pair."""
    data = copy.deepcopy(read_config(QUICK)[0])
    built = rough_pair_config(QUICK, *synthetic_rough_profiles(0.0, 2.2e-3), sensor_every=4, normal_load=1.0)[0]
    for b in data["bodies"].values():
        if "profile" in b:
            b["grading"] = {**b["grading"], "edge": b.pop("profile")["edge"]}
    for key in ("sensors", "contacts", "loads"):
        data[key] = built[key]
    return load_model(data)


def test_flat_profiles_give_no_shocks_and_the_smooth_transducer_result():
    """Ra = 0 on the study's pair: the model is the plain rectangles' (same nodes), the run identical to theirs;
    no closing events; in steady sliding the transducer spring carries the Coulomb force mu Fn = 0.2 x 1 N (the
    slider neither accelerates nor moves relative to the carriage: only the decaying ring of the 25 kHz
    slider-on-spring mode, damped 5 %, differs; 1e-3 N is 40x its size after the 0.2 ms ramps), and the friction
    power is mu Fn V."""
    flat, _, _, _ = build_point_model(QUICK, {}, {"roughness_ra": 0.0, "normal_load": 1.0})
    smooth = _smooth_quick_model()
    assert np.array_equal(flat.coords, smooth.coords)
    kw = dict(RUN, condition=OperatingCondition(sliding_velocity=0.1), schedule=replace(SCHEDULE, duration=0.6e-3))
    a, b = simulate(flat, **kw), simulate(smooth, **kw)
    for name in ("friction_force", "sensor_velocity", "contact_normal_force"):
        np.testing.assert_array_equal(a[name].values, b[name].values)
    r = roughness_metrics(a, flat.contacts[0].slave_nodes.size)
    assert r["shock_count"] == 0
    steady = a.time.values >= a.attrs["transient_end"]
    assert np.ptp(a.open_fraction.values[steady]) == 0.0
    assert r["mean_normal_force"] == pytest.approx(1.0, rel=1e-3)  # the dead load
    assert abs(r["mean_friction_force"]) == pytest.approx(0.2 * r["mean_normal_force"], abs=1e-3)
    assert r["friction_coefficient"] == pytest.approx(0.2, abs=1e-3)
    assert r["friction_power"] == pytest.approx(0.2 * r["mean_normal_force"] * 0.1, rel=0.01)


def test_lv_grows_with_roughness_at_fixed_velocity():
    """At 10 cm/s and 1 N, Ra 10 um gives a higher back-face level than Ra 2 um on the study's --quick pair (a
    result of the model, not tuned; the study's numbers are in docs/roughness.md)."""
    lv = {}
    for ra in (2e-6, 10e-6):
        model, _, _, _ = build_point_model(QUICK, {}, {"roughness_ra": ra, "normal_load": 1.0})
        ds = simulate(model, OperatingCondition(sliding_velocity=0.1, roughness_ra=ra),
                      schedule=replace(SCHEDULE, duration=0.8e-3), **RUN)
        lv[ra] = vibration_level(ds)[0]
        assert np.all(np.isfinite(ds.friction_force.values))
    assert lv[10e-6] > lv[2e-6]


def test_identification_run_takes_the_transducer_force_over_the_dead_load():
    """A transducer along x only: its y reading is round-off (1e-12 N), so normal_force becomes the steady mean
    of the contact normal force (a constant: the dead load as the interface carries it) and friction_force its
    magnitude; without a transducer (friction_force round-off too) the interface's own forces are used."""
    import xarray as xr

    from fivid.study.roughness import identification_run

    t = np.arange(400) * 1e-5
    rng = np.random.default_rng(0)
    fn = 1.0 + 0.3 * rng.standard_normal(t.size)
    ft = -(0.2 + 0.05 * rng.standard_normal(t.size))
    ds = xr.Dataset({"friction_force": ("time", ft), "normal_force": ("time", 1e-12 * rng.standard_normal(t.size)),
                     "contact_normal_force": ("time", fn), "contact_tangential_force": ("time", 0.2 * fn)},
                    coords={"time": t}, attrs={"transient_end": t[100], "sliding_velocity": 0.01})
    run = identification_run(ds)
    assert run.sizes["time"] == 300 and np.all(run.normal_force.values == fn[100:].mean())
    np.testing.assert_array_equal(run.friction_force.values, np.abs(ft[100:]))
    bare = identification_run(ds.assign(friction_force=ds.normal_force))
    np.testing.assert_array_equal(bare.friction_force.values, 0.2 * fn[100:])
    np.testing.assert_array_equal(bare.normal_force.values, fn[100:])


@pytest.mark.slow
def test_a_rough_run_with_a_transducer_goes_through_fivid_identify(tmp_path):
    """Item 4's bridge: the transducer's force over the dead load is a mu(t) with dynamics: identify returns
    mu0 = the run's mean |Ft| / Fn and a perturbation amplitude far above round-off (the transducer-less
    interface forces gave A = 3e-17). identify smooths the velocity over 0.05 s, so the record is 0.1025 s:
    8e6 steps of the coarse pair (216 dofs; about a minute of CPU). At 8 mm/s (the default rig's range) the
    slider moves 0.8 mm of the lower block's 2.2 mm; at 10 cm/s it slid off its end."""
    from fivid.cli import main
    from fivid.friction import load_law
    from fivid.storage import write_netcdf
    from fivid.study.roughness import simulate_rough_run

    run = simulate_rough_run(COARSE, {"roughness_ra": 4.5e-6, "sliding_velocity": 0.008, "normal_load": 1.0},
                             duration=0.1025, sample_rate=200e3, run_id="rough-ra4.5um-v8mm")
    assert np.ptp(run.normal_force.values) == 0.0  # the dead load as the interface carries it
    path = tmp_path / "run.nc"
    write_netcdf(run, path)
    law_path = tmp_path / "law.nc"
    assert main(["identify", str(path), "-o", str(law_path), "--band", "500", "20000", "--mains-frequency", "0"]) == 0
    law = load_law(law_path)
    assert law.mu0 == pytest.approx(np.mean(run.friction_force.values / run.normal_force.values), rel=0.05)
    assert float(law.amplitude(velocity=0.008, roughness=4.5e-6)) > 1e-3


@pytest.mark.slow
def test_the_quick_roughness_study_writes_exponents_fits_and_its_report_section(tmp_path):
    """Issue 15's done-when on the --quick variant (4 points of the 50 um pair, about a minute on two free
    cores): summary.json has n and m with their intervals, the Rz/Rsm fit, shock statistics and the settings;
    report.html has the roughness section with its figures."""
    import json

    from fivid.cli import main

    assert main(["study", str(ROOT / "configs/studies/roughness_noise.yaml"), "-o", str(tmp_path), "--quick",
                 "--no-progress"]) == 0
    s = json.loads((tmp_path / "summary.json").read_text())
    for key in ("n", "m"):
        lo, hi = s[key]["ci"]
        assert lo < s[key]["value"] < hi
    assert {"vibration_level_vs_rz_rsm", "shock_rate", "friction_power"} <= set(s["fits"])
    assert all(p["shock_count"] >= 0 and np.isfinite(p["vibration_level"]) for p in s["points"])
    assert s["roughness_settings"]["profiles"]["rsm_levels"] == list(RSM_LEVELS)
    html = (tmp_path / "report.html").read_text()
    assert "Roughness noise (seed 003)" in html and html.count("data:image/png") >= 5
