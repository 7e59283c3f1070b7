"""Band-limited Rayleigh damping (fivid.fe.damping): stable step, modal damping of free decays, energy balance."""

import numpy as np
import pytest

from fivid.errors import ConfigError
from fivid.fe import load_model
from fivid.fe.damping import damping_ratio, modal_root, rayleigh_through_two_ratios
from fivid.solver import OutputOptions, RunSchedule, simulate, stable_step
from fivid.solver.timestep import _largest_stable_step, amplification_matrix, stable_step_bound
from tests.helpers.solver_models import cantilever


def _with_damping(cfg, **damping):
    cfg = dict(cfg)
    cfg["damping"] = damping
    return cfg


def test_classic_step_from_the_amplification_matrix_is_the_closed_form():
    """For classic Rayleigh the bisection on the kernel's amplification matrix must reproduce Belytschko &
    Hughes' (2/omega)(sqrt(1+xi^2) - xi) to the bisection's resolution (2^-60 of the bracket) and the 1e-12
    slack on the spectral radius (a relative step change of ~1e-12 / (omega dt) per unit radius)."""
    for beta in (1e-8, 3.05e-7, 1e-6):
        w = 2 * np.pi * 3.5e6
        xi = beta * w / 2
        exact = 2 / w * (np.sqrt(1 + xi * xi) - xi)
        assert _largest_stable_step(w, 50.0, beta, np.inf) == pytest.approx(exact, rel=1e-6)


def test_band_limited_step_approaches_courant():
    """Far above the cut-off beta K v_f acts as a stiffness beta omega_c K: the step is the Courant step of
    omega sqrt(1 + beta omega_c) (to O(omega_c / omega_max)), and just above it the scheme is unstable."""
    w, beta, fc = 2 * np.pi * 3.5e6, 3.1e-7, 6e4
    dt = _largest_stable_step(w, 50.0, beta, fc)
    courant = 2 / (w * np.sqrt(1 + beta * 2 * np.pi * fc))
    assert dt == pytest.approx(courant, rel=2 * fc / 3.5e6)
    rho = np.abs(np.linalg.eigvals(amplification_matrix(w, 1.01 * dt, 50.0, beta, fc))).max()
    assert rho > 1.0


def test_fit_gives_the_configured_ratios_exactly():
    for fc in (None, 2e4, 6e4):
        a, b = rayleigh_through_two_ratios(1e3, 0.005, 1e4, 0.01, cutoff=fc)
        np.testing.assert_allclose(damping_ratio([1e3, 1e4], a, b, fc), [0.005, 0.01], rtol=1e-10)


def test_config_cutoff_key():
    cfg = _with_damping(cantilever(), ratios=[{"frequency": "1 kHz", "ratio": 0.005},
                                              {"frequency": "10 kHz", "ratio": 0.01}], cutoff="60 kHz")
    model = load_model(cfg)
    assert model.damping_cutoff == 6e4
    np.testing.assert_allclose(damping_ratio([1e3, 1e4], model.rayleigh_alpha, model.rayleigh_beta, 6e4),
                               [0.005, 0.01], rtol=1e-10)
    assert np.isinf(load_model(cantilever()).damping_cutoff)
    with pytest.raises(ConfigError, match="damping.cutoff"):
        load_model(_with_damping(cantilever(), beta="1e-7 s", cutoff="60 m"))
    with pytest.raises(ConfigError, match="damping.cutoff"):
        load_model(_with_damping(cantilever(), beta="1e-7 s", cutoff="-5 kHz"))


def _decay_rate(t, y, f0, fs, sigma_expected):
    """Decay rate sigma [s-1] of the component of y near f0 [Hz]: zero-phase band-pass (an LTI filter maps each
    damped exponential onto itself with the same sigma), Hilbert envelope, straight-line fit of its log over
    [2/B, 2/B + 2.5/sigma] (B the pass band: the filter's start-up transient is over; 2.5 time constants of
    decay, where the mode still dominates its band)."""
    from scipy.signal import butter, hilbert, sosfiltfilt

    lo, hi = f0 / 1.25, f0 * 1.25
    z = sosfiltfilt(butter(4, [lo, hi], btype="bandpass", fs=fs, output="sos"), y)
    env = np.abs(hilbert(z))
    t0 = 2.0 / (hi - lo)
    sel = (t >= t0) & (t <= t0 + 2.5 / sigma_expected)
    assert sel.sum() > 100 and t[-1] > t0 + 2.5 / sigma_expected + t0  # the end transient is outside too
    return -np.polyfit(t[sel], np.log(env[sel]), 1)[0]


def test_free_decay_damping_follows_the_scheme_at_three_modes():
    """A cantilever released with a uniform transverse velocity rings in its bending modes; the decay rate of
    each of the first three (4.8, 26 and 64 kHz on this mesh with the lumped mass the solver uses: below, near
    and above the 30 kHz cut-off, where the ratio is a third of classic Rayleigh's) must be the exact modal
    root's ``-Re(s)`` of the band-limited scheme.

    Tolerance 2 %: the estimator is unbiased for an isolated exponential; what remains is the leakage of the
    neighbouring modes through the band-pass (attenuated to < 1e-3: that ripple on a log-envelope fitted over
    2.5 time constants biases the slope by < 0.1 %), and the scheme's discretisation, O((omega dt)^2) <= 0.3 %
    at the third mode. The same estimator on classic Rayleigh damping (closed form) agrees to 0.1 %.
    """
    from fivid.fe.modal import modal_analysis

    cfg = _with_damping(cantilever(nx=32, ny=4, v0=0.5),
                        ratios=[{"frequency": "5 kHz", "ratio": 0.02}, {"frequency": "25 kHz", "ratio": 0.02}],
                        cutoff="30 kHz")
    model = load_model(cfg)
    modes = modal_analysis(model, n_modes=8, mass="lumped")  # the explicit solver's mass
    shape = modes["mode_shape"].transpose("mode", "node", "component").values
    bending = (shape[..., 1] ** 2).sum(axis=1) > (shape[..., 0] ** 2).sum(axis=1)
    f_bend = modes["frequency"].values[bending][:3]
    fs = 1.0e6
    ds = simulate(model, schedule=RunSchedule(duration=8e-3, sample_rate=fs),
                  output=OutputOptions(oversample=1, progress=False))
    assert ds.attrs["damping_scheme"] == "band_limited"
    t = ds["time"].values
    y = ds["acceleration"].values.ravel()
    classic_ratio = damping_ratio(f_bend, model.rayleigh_alpha, model.rayleigh_beta)
    ratio = damping_ratio(f_bend, model.rayleigh_alpha, model.rayleigh_beta, model.damping_cutoff)
    assert ratio[2] < 0.5 * classic_ratio[2]  # the third mode is well into the filter's roll-off
    for f0 in f_bend:
        s = modal_root(f0, model.rayleigh_alpha, model.rayleigh_beta, model.damping_cutoff)
        measured = _decay_rate(t, y, abs(s.imag) / (2 * np.pi), fs, -s.real)
        assert measured == pytest.approx(-s.real, rel=0.02), f0


def test_energy_balance_closes_with_band_limited_damping():
    """KE - KE0 = W_ext + W_cn + W_ct - W_int - D_alpha holds to round-off whatever the damping force is, since
    W_int accumulates the force the kernel applied; the inferred damping loss W_int - U is positive."""
    cfg = _with_damping(cantilever(nx=16, ny=3), beta="2e-7 s", alpha="100 s-1", cutoff="20 kHz")
    ds = simulate(load_model(cfg), schedule=RunSchedule(duration=2e-3, sample_rate=2e5),
                  output=OutputOptions(oversample=1, progress=False))
    ke0 = ds.kinetic_energy.values[0]
    assert np.abs(ds.energy_balance_error.values).max() <= 1e-10 * ke0
    assert ds.damping_dissipation.values[-1] > 0


def test_band_limited_step_is_longer_and_recorded():
    base = cantilever(nx=16, ny=3)
    classic = stable_step(load_model(_with_damping(base, beta="3e-7 s")))
    fast = stable_step(load_model(_with_damping(base, beta="3e-7 s", cutoff="50 kHz")))
    assert classic.damping_scheme == "rayleigh" and fast.damping_scheme == "band_limited"
    assert fast.critical_time_step > 0.9 * fast.undamped_time_step > classic.critical_time_step


@pytest.mark.parametrize("name", ["triboair_coarse", "ring"])
def test_stable_step_bound_is_below_the_stable_step(name):
    """Gershgorin's bound of omega_max is >= the Lanczos value, so the bounded step is <= the stable step (the
    memory/work guard of fivid simulate relies on it: never fewer steps than the run takes)."""
    model = load_model(name)
    bound, exact = stable_step_bound(model), stable_step(model)
    assert bound.omega_max >= exact.omega_max * (1.0 - 1e-9)  # Lanczos converged to tol 1e-10
    assert bound.critical_time_step <= exact.critical_time_step * (1.0 + 1e-9)
