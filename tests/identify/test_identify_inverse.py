"""Inverse route (seed 001): amplitude scale from matching acceleration levels in a band.

Fast: a linear SYNTHETIC response (acceleration = c μp) as the simulator, where the right scale is
known exactly. Slow: the FE solver on the coarse TRIBOAIR model, with a "measurement" simulated at
twice the law's amplitude.
"""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from tests.helpers.synthetic_friction_runs import synthetic_run, true_law

from fivid.identify import inverse_amplitude_scale
from fivid.schema import apply_cf_attrs, new_history

GAIN = 300.0  # acceleration per unit μp [m s-2] of the linear SYNTHETIC response


def linear_response(friction, condition, schedule):
    """SYNTHETIC simulator: acceleration = GAIN μp(t), a RunDataset whose steady part starts at 0."""
    law, seed = friction.law, friction.seed
    velocity, roughness, normal_load = condition.sliding_velocity, condition.roughness_ra, condition.normal_load
    duration, sample_rate = schedule.duration, schedule.sample_rate
    x = GAIN * law.sample(duration, sample_rate, velocity, roughness, seed=seed, normal_load=normal_load)[0]
    t = np.arange(x.size) / sample_rate
    ds = xr.Dataset({"acceleration": ("time", x), "friction_force": ("time", np.zeros_like(x)),
                     "normal_force": ("time", np.full_like(x, normal_load))}, coords={"time": t},
                    attrs={"transient_end": 0.0, "run_id": "sim", "rig": "synthetic", "sliding_velocity": velocity,
                           "normal_load": normal_load, "roughness_ra": roughness, "sample_rate": sample_rate,
                           "source": "SYNTHETIC linear response", "history": new_history("test")})
    return apply_cf_attrs(ds)


def test_inverse_scale_recovers_a_known_amplitude_ratio():
    law = true_law()
    truth = 1.7
    measured = synthetic_run(law.scaled(truth), velocity=0.01, roughness=0.4e-6, normal_load=5.0, seed=3,
                             acceleration_psd=lambda f: GAIN**2 * law.scaled(truth).psd(f, 0.01, 0.4e-6, 5.0))
    res = inverse_amplitude_scale(law, measured, band=(200.0, 4000.0), duration=1.0, nperseg=2048,
                                  simulator=linear_response, tolerance_db=0.2)
    assert res.converged, res.iterations
    # a linear response: the first proportional update lands on the truth up to the two PSD estimates'
    # band-level error (~0.1 dB for ~1 s records over 3.8 kHz); the loop stops at |d| < 0.2 dB
    assert abs(20 * np.log10(res.scale / truth)) < 0.3, res.iterations
    assert len(res.iterations) <= 3
    assert res.inverse_amplitude == pytest.approx(res.scale * res.forward_amplitude)


def test_scaled_law_scales_amplitude_and_psd():
    law = true_law("power_law_load")
    s = law.scaled(2.5)
    assert s.amplitude(0.01, 0.8e-6, 5.0) == pytest.approx(2.5 * law.amplitude(0.01, 0.8e-6, 5.0), rel=1e-12)
    f = np.array([100.0, 1000.0])
    np.testing.assert_allclose(s.psd(f, 0.01, 0.8e-6, 5.0), 6.25 * law.psd(f, 0.01, 0.8e-6, 5.0), rtol=1e-12)


@pytest.mark.slow
def test_identified_law_file_drives_the_fe_solver(tmp_path):
    """The law file written by identify, loaded by load_law, is what the solver samples (its sha recorded)."""
    from tests.helpers.synthetic_friction_runs import ANALYSIS_BAND, run_grid

    from fivid.fe import load_model
    from fivid.friction import load_law
    from fivid.identify import identify_friction_law
    from fivid.solver import FrictionInput, OperatingCondition, OutputOptions, RunSchedule, simulate

    res = identify_friction_law(run_grid(true_law(), seed=2), band=ANALYSIS_BAND, tare=(0.0, 0.5), nperseg=2048)
    law = load_law(res.write(tmp_path / "law.nc"))
    model = load_model(Path(__file__).resolve().parents[2] / "configs" / "models" / "triboair_coarse.yaml")
    sim = simulate(model, OperatingCondition(0.01, 5.0, 0.4e-6), FrictionInput(law=law, seed=1),
                   schedule=RunSchedule(duration=0.02, sample_rate=51200.0), output=OutputOptions(progress=False))
    steady = sim.sel(time=slice(sim.attrs["transient_end"], None))
    mu = steady["friction_force"] / steady["normal_force"]
    assert law.sha256 in str(sim.attrs)
    # the mean friction coefficient of the contact follows μ0 of the law: within a few times A
    assert abs(float(mu.mean()) - law.mu0) < 5 * law.amplitude(0.01, 0.4e-6)


@pytest.mark.slow
def test_inverse_route_with_the_fe_solver():
    from fivid.fe import load_model
    from fivid.solver import FrictionInput, OperatingCondition, OutputOptions, RunSchedule, simulate

    model = load_model(Path(__file__).resolve().parents[2] / "configs" / "models" / "triboair_coarse.yaml")
    # at the synthetic law's own amplitude (A ~ 0.004) the coarse model's acceleration in 1-15 kHz is
    # dominated by its deterministic sliding vibration (measured: -27.1 dB without perturbation, -26.0 dB
    # with it); from x8 on the level grows by 20 log10 of the amplitude (x8 -> x64: +16.6 dB vs 18.1).
    # The test works where the perturbation dominates: forward law x10, "measurement" x20.
    law = true_law().scaled(10.0)
    measured = simulate(model, OperatingCondition(0.01, 5.0, 0.4e-6), FrictionInput(law=law.scaled(2.0), seed=11),
                        schedule=RunSchedule(duration=0.08, sample_rate=51200.0), output=OutputOptions(progress=False))
    res = inverse_amplitude_scale(law, measured, model, band=(1000.0, 15000.0), duration=0.08, seed=12,
                                  nperseg=512, max_iterations=3, tolerance_db=0.5)
    print("inverse route iterations", res.iterations)
    # different seeds: the band power of each 0.08 s record is a random estimate with relative sd
    # 1/sqrt(T B_eff), B_eff = (∫P)^2 / ∫P^2 the equivalent bandwidth of a response made of a few
    # resonance peaks (Bendat & Piersol §8.2); the two records differ by sqrt(2) of that, 4.34 dB per unit
    # relative power; plus the 0.5 dB stopping tolerance and the deterministic part (-12 dB: +0.3 dB)
    from fivid.signal import welch_psd

    steady = measured.sel(time=slice(measured.attrs["transient_end"], None))
    p = welch_psd(steady["acceleration"], nperseg=512)
    f = p["frequency"].values
    band = (f >= 1000.0) & (f <= 15000.0)
    df = f[1] - f[0]
    b_eff = (p.values[band].sum() * df) ** 2 / (np.sum(p.values[band] ** 2) * df)
    t_rec = float(steady["time"][-1] - steady["time"][0])
    tol = 3.29 * 4.34 * np.sqrt(2.0 / (t_rec * b_eff)) + 0.5 + 0.3
    print(f"B_eff {b_eff:.0f} Hz, T {t_rec:.3f} s, tolerance {tol:.2f} dB")
    assert abs(20 * np.log10(res.scale / 2.0)) < tol


def test_peak_summary_counts_only_matched_peaks():
    from fivid.identify.inverse import _peak_summary

    # score_runs marks a measured peak with no simulated partner within the tolerance by NaN
    scores = xr.Dataset({"peak_frequency_measured": ("peak", [800.0, 2300.0, 5000.0]),
                         "peak_frequency_simulated": ("peak", [805.0, np.nan, 4990.0]),
                         "peak_level_diff_db": ("peak", [0.5, np.nan, -1.0])})
    out = _peak_summary(scores)
    assert out["n_measured"] == 3 and out["n_matched"] == 2


@pytest.mark.parametrize("kw, match", [({"max_iterations": 0}, "inverse-iterations"),
                                       ({"duration": 0.0}, "inverse-duration")])
def test_bad_iteration_settings_are_named(kw, match):
    from fivid.errors import ConfigError

    # max_iterations 0 used to return scale 1 'not converged in 0 iterations' without simulating
    with pytest.raises(ConfigError, match=match):
        inverse_amplitude_scale(true_law(), xr.Dataset(), band=(200.0, 4000.0), simulator=linear_response, **kw)
