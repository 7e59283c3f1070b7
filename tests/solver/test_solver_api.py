"""The solver's driver and CLI: time-step checks, friction injection, loading sequence, outputs, guards."""

import dataclasses
import shlex
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from fivid.errors import ConfigError
from fivid.fe import load_model
from fivid.solver import (
    FrictionInput,
    IntegrationOptions,
    OperatingCondition,
    OutputOptions,
    RunSchedule,
    SimulationDiverged,
    critical_time_step,
    simulate,
    stable_step,
)
from fivid.units import conversion
from tests.helpers.solver_models import block_on_base, cantilever


class StandInLaw:
    """A duck-typed friction law (the fivid.friction interface): mu0 + a band-limited random mu_p.

    Synthetic: white noise smoothed by a 5-sample moving average, RMS ``rms``, reproducible from the seed.
    """

    def __init__(self, mu0=0.3, rms=0.02, injection="uniform"):
        self.mu0, self.rms, self.injection = mu0, rms, injection
        self.sha256 = "0" * 64

    def amplitude(self, velocity, roughness, normal_load=None):
        return self.rms

    def sample(self, duration, sample_rate, velocity, roughness, seed, n_signals=1, normal_load=None):
        n = int(round(duration * sample_rate))
        x = np.random.default_rng(seed).standard_normal((n_signals, n + 4))
        x = np.stack([np.convolve(r, np.ones(5) / 5, mode="valid") for r in x])
        return self.rms * x / x.std(axis=1, keepdims=True)

    def describe(self):
        return f"stand-in law mu0={self.mu0} rms={self.rms}"


def test_single_dof_critical_step_closed_form():
    """A cantilever's dt_crit obeys (2/omega_max)(sqrt(1+xi^2) - xi) with omega_max from dense eigenvalues."""
    import scipy.linalg

    from fivid.fe import lumped_mass, stiffness_matrix

    model = load_model(cantilever(nx=6, ny=2, beta=1e-7))
    free = model.free_dofs
    K = stiffness_matrix(model).toarray()[np.ix_(free, free)]
    m = lumped_mass(model)[free]
    w2 = scipy.linalg.eigvalsh(K / np.sqrt(np.outer(m, m)))
    omega = np.sqrt(w2.max())
    xi = 1e-7 * omega / 2
    st = stable_step(model)
    assert st.omega_max == pytest.approx(omega, rel=1e-8)
    assert critical_time_step(model) == pytest.approx(2 / omega * (np.sqrt(1 + xi * xi) - xi), rel=1e-8)


def test_time_step_above_critical_is_refused():
    model = load_model(cantilever())
    dt = critical_time_step(model)
    with pytest.raises(ConfigError, match="above the critical step"):
        simulate(model, schedule=RunSchedule(duration=1e-4, sample_rate=1e5),
                 integration=IntegrationOptions(time_step=1.01 * dt), output=OutputOptions(progress=False))


def test_divergence_is_diagnosed():
    """Forcing a step above critical (bypassing the check) trips the guard with step, time and node."""
    from fivid.solver import driver

    model = load_model(cantilever(nx=8, ny=2))
    prep = driver.prepare_run(model, schedule=RunSchedule(duration=2e-4, sample_rate=2e5))
    s = prep.settings
    bad = driver.IntegrationSettings(2.5 * s.critical_time_step, s.critical_time_step, s.omega_max,
                             s.steps_per_interval, s.oversample, s.n_intervals, s.gs_max_iterations, s.gs_tolerance)
    with pytest.raises(SimulationDiverged, match=r"diverged at step \d+ \(t = .* node \d+ \(body 'beam'"):
        dataclasses.replace(prep, settings=bad).run(progress=False)


@pytest.mark.parametrize("group, bad", [("schedule", dict(duration=-1.0)), ("schedule", dict(sample_rate=0.0)),
                                        ("friction", dict(mu=-0.1)), ("integration", dict(safety=1.5)),
                                        ("friction", dict(mu=0.3, law=StandInLaw())), ("friction", dict(seed=-1)),
                                        ("friction", dict(seed=1.5)), ("output", dict(oversample=0)),
                                        ("schedule", dict(sample_rate=1e4))])  # 1e-4 s x 1e4 Hz: one sample
def test_bad_settings_are_refused(group, bad):
    kw = dict(friction=FrictionInput(), schedule=RunSchedule(duration=1e-4, sample_rate=1e5),
              integration=IntegrationOptions(), output=OutputOptions(progress=False))
    kw[group] = dataclasses.replace(kw[group], **bad)
    with pytest.raises(ConfigError):
        simulate(load_model(block_on_base()), **kw)


def test_a_group_of_the_wrong_type_is_refused_by_name():
    """The groups are typed: a dict (the old keywords) where a RunSchedule belongs is refused, naming the group."""
    with pytest.raises(ConfigError, match=r"schedule must be a fivid\.solver\.options\.RunSchedule, got dict"):
        simulate(load_model(block_on_base()), schedule=dict(duration=1e-4, sample_rate=1e5))


def test_friction_injection_modes():
    """uniform: one signal; per_node: independent signals; convected: node k sees node 0's signal delayed by
    (x_k - x_0)/V (a field frozen on the surface moving at V, mu_p(x - V t))."""
    from fivid.friction.injection import friction_table

    model = load_model(block_on_base())
    pairs = np.zeros(3, dtype=np.int64)
    x = np.array([0.018, 0.020, 0.022])
    kw = dict(total_time=0.01, dt=1e-7, sample_rate=5e4)
    cond = OperatingCondition(sliding_velocity=2.0, normal_load=5.0, roughness_ra=1e-6)
    uni = friction_table(model, pairs, x, FrictionInput(law=StandInLaw(injection="uniform"), seed=3), cond, **kw)
    assert uni.rate == pytest.approx(4e5) and np.ptp(uni.mu - uni.mu[:, :1]) == 0.0
    assert uni.mu.mean() == pytest.approx(0.3, abs=3 * 0.02 * np.sqrt(5 / uni.mu.shape[0]))
    per = friction_table(model, pairs, x, FrictionInput(law=StandInLaw(injection="per_node"), seed=3), cond, **kw)
    c = np.corrcoef(per.mu.T)
    assert np.abs(c[np.triu_indices(3, 1)]).max() < 0.05  # independent: |r| ~ 1/sqrt(N/5) = 0.008
    con = friction_table(model, pairs, x, FrictionInput(law=StandInLaw(injection="convected"), seed=3), cond, **kw)
    lag = int(round((x[2] - x[0]) / 2.0 * con.rate))  # 1e-3 m / 2 m/s = 0.5 ms = 200 samples
    # the downstream node (larger x) sees the same surface point later: mu_2(t) = mu_0(t - (x_2 - x_0)/V)
    np.testing.assert_allclose(con.mu[lag:, 2], con.mu[:-lag, 0], atol=1e-12)
    again = friction_table(model, pairs, x, FrictionInput(law=StandInLaw(injection="per_node"), seed=3), cond, **kw)
    np.testing.assert_array_equal(again.mu, per.mu)  # reproducible from the seed


def test_friction_law_protocol():
    """The laws and a duck-typed stand-in satisfy fivid.friction.FrictionLaw; an object lacking members is refused
    with the members named (not an AttributeError deep in the solver)."""
    from fivid.friction import CoulombLaw, FrictionLaw
    from fivid.friction.injection import friction_table

    assert isinstance(CoulombLaw(0.3), FrictionLaw) and isinstance(StandInLaw(), FrictionLaw)

    class NoSample:
        mu0, injection = 0.3, "uniform"

    model = load_model(block_on_base())
    with pytest.raises(ConfigError, match="NoSample.*'sha256', 'amplitude', 'sample', 'describe'"):
        friction_table(model, np.zeros(1, dtype=np.int64), np.zeros(1), FrictionInput(law=NoSample()),
                       OperatingCondition(sliding_velocity=1.0), total_time=0.01, dt=1e-7, sample_rate=5e4)


def test_run_is_a_scoreable_rundataset_and_reproducible(tmp_path):
    """A short preload-and-slide run with a stand-in law: valid RunDataset, written and read back, the energy
    balance closes to round-off, and the same seed gives the same run."""
    from fivid.io import read_run, write_run

    model = load_model(block_on_base(base_velocity=0.02))
    kw = dict(condition=OperatingCondition(sliding_velocity=0.02, roughness_ra=0.8e-6),
              schedule=RunSchedule(duration=2e-3, sample_rate=51200.0), output=OutputOptions(progress=False))
    friction = FrictionInput(law=StandInLaw(injection="per_node"), seed=7)
    ds = simulate(model, friction=friction, **kw)
    path = write_run(ds, tmp_path / "sim.nc")
    back = read_run(path)
    for name in ("acceleration", "friction_force", "normal_force", "contact_normal_force", "stick_fraction",
                 "kinetic_energy", "energy_balance_error"):
        assert name in back
    assert back.attrs["sample_rate"] == 51200.0 and "seed 7" in back.attrs["source"]
    scale = float(np.abs(ds.external_work).max() + ds.kinetic_energy.max() + ds.friction_dissipation.max())
    assert np.abs(ds.energy_balance_error.values).max() < 1e-9 * scale
    np.testing.assert_array_equal(simulate(model, friction=friction, **kw).acceleration.values, ds.acceleration.values)
    other = simulate(model, friction=dataclasses.replace(friction, seed=8), **kw)
    assert not np.array_equal(other.acceleration.values, ds.acceleration.values)


def test_rig_preload_reaches_target_load(root):
    """Coarse rig: the static preload gives the target transducer force; the explicit run settles to it
    (before sliding: friction only sticks), and in steady sliding Ft/Fn = mu (slip at the tip)."""
    model = load_model(root / "configs/models/triboair_coarse.yaml")
    ds = simulate(model, OperatingCondition(sliding_velocity=0.01, normal_load=5.0), FrictionInput(mu=0.3),
                  schedule=RunSchedule(duration=2e-3, sample_rate=51200.0), output=OutputOptions(progress=False))
    t = ds.time.values
    load_end = model.motion("load").ramp_time
    settled = (t > load_end + 0.5e-3) & (t < ds.attrs["base_start"])
    # the loading clamp ramps smoothly; once settled, the transducer reads the target (tip vibration decays)
    assert ds.normal_force.values[settled].mean() == pytest.approx(5.0, rel=0.02)
    steady = t > ds.attrs["transient_end"]
    ratio = ds.friction_force.values[steady].mean() / ds.normal_force.values[steady].mean()
    assert ratio == pytest.approx(0.3, rel=0.02)
    assert ds.slip_fraction.values[steady].mean() > 0


def test_cli_simulate_writes_a_run(tmp_path, root, capsys):
    from fivid.cli import main

    out = tmp_path / "sim.nc"
    args = ["simulate", str(root / "configs/models/triboair_coarse.yaml"), "--mu", "0.3", "--velocity", "10 mm/s",
            "--load", "5 N", "--duration", "1 ms", "--sample-rate", "51.2 kHz"]
    res = subprocess.run([sys.executable, "-m", "fivid", *args, "-o", str(out), "--json"], capture_output=True,
                         text=True, cwd=root, timeout=600)
    assert res.returncode == 0, res.stderr
    assert '"mean_normal_force_n"' in res.stdout and out.is_file()
    # in-process (argv is not sys.argv): the history records this command, quoted so that it runs again
    assert main(args + ["-o", str(tmp_path / "in.nc")]) == 0
    capsys.readouterr()
    with xr.open_dataset(tmp_path / "in.nc") as ds:
        last = ds.attrs["history"].splitlines()[-1]
    assert last.endswith(shlex.join(["fivid", "simulate", args[1], "--mu", "0.3", "--velocity", "10 mm/s",
                                     "--load", "5 N", "--duration", "1 ms", "--sample-rate", "51.2 kHz",
                                     "--seed", "0", "--reduced-tolerance", "0.5", "-o", str(tmp_path / "in.nc")])), last
    assert main(args + ["--time-step", "1 s", "-o", str(tmp_path / "x.nc")]) == 2
    assert "above the critical step" in capsys.readouterr().err and not (tmp_path / "x.nc").exists()
    assert main(args + ["--velocity", "10 N", "-o", str(tmp_path / "y.nc")]) == 2
    assert "--velocity" in capsys.readouterr().err


def test_time_step_halving_on_a_linear_model():
    """Undamped cantilever (no contact, linear): halving dt changes the first-mode frequency by the
    central-difference error (omega dt)^2/24 ~ 1e-7 and leaves the band power unchanged; the study must report
    the two steps and a level difference within 0.1 dB (Welch variance cancels: same signal both runs)."""
    from fivid.solver import time_step_halving

    model = load_model(cantilever(nx=8, ny=2, v0=0.5, beta=1e-8))
    res = time_step_halving(model, schedule=RunSchedule(duration=5e-3, sample_rate=200e3),
                            output=OutputOptions(oversample=1, progress=False), nperseg=256, band=(1e3, 50e3))
    assert res.attrs["time_step_fine"] == pytest.approx(res.attrs["time_step_coarse"] / 2, rel=0.01)
    assert abs(res.attrs["level_diff_db"]) < 0.1
    assert res.psd_coarse.size == res.psd_fine.size and res.frequency.attrs["units"] == "Hz"
    # the PSD units come from fivid.units.power_units; the old hand-built "(m s-2)2 Hz-1" read back through
    # fivid.units as m s-2 times 2 per Hz, i.e. the wrong dimension
    assert res.psd_coarse.attrs["units"] == "m2 s-4 Hz-1"
    assert conversion(res.psd_fine.attrs["units"], "m2 s-4 Hz-1") == (1.0, 0.0)
