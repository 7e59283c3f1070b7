"""SYNTHETIC rig runs generated from a known friction law, for the identification tests.

Not measured data. Each run mimics a TRIBOAIR-like record at 25.6 kHz: an unloaded interval 0-0.6 s
(tare: use 0-0.5 s), a normal-load ramp, a velocity ramp, steady sliding and a ramp down. The friction force is
``Ft = (μ0 + μp(t)) Fn(t)`` with μp drawn from the true law (:meth:`PerturbedCoulombLaw.sample`) and a
normal force fluctuating by ~1 %. The friction force reaches its Coulomb value once the base moves at 30 % of the plateau velocity.
The force sensors add white noise, offsets and mains hum
(50.02 Hz, odd harmonics); the encoder velocity has 1 % noise. The truth a test compares with:

- ``mu0`` of the law;
- the band RMS over the analysis band ``A_band = A(V, Ra, Fn) sqrt(∫_band s df)`` (:func:`band_amplitude`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from fivid.friction import AmplitudeModel, PerturbedCoulombLaw, synthesise_perturbation
from fivid.schema import apply_cf_attrs, new_history, validate_run

__all__ = ["true_law", "edge_law", "twin_law", "synthetic_run", "run_grid", "band_fraction", "band_amplitude", "FS",
           "ANALYSIS_BAND", "MU0", "TWIN_MU0"]

FS = 25600.0  # [Hz]
ANALYSIS_BAND = (100.0, 5000.0)  # [Hz], multiples of the Welch resolution 12.5 Hz (nperseg 2048)
SHAPE_F = np.linspace(0.0, 12000.0, 4001)  # flat down to 0 Hz: batch means of μ are then independent
CORNER, ORDER = 1500.0, 2.0
SHAPE = 1.0 / (1.0 + (SHAPE_F / CORNER) ** (2 * ORDER))
MU0 = 0.3


def true_law(form="linear_velocity", injection="uniform") -> PerturbedCoulombLaw:
    """The known law: μ0 = 0.3, a 4th-order roll-off at 1.5 kHz, and an amplitude law of ``form``.

    ``linear_velocity``: A = a_r + b_r V at Ra 0.4 and 1.6 µm; ``power_law_load``:
    A = 0.002 (Ra/1 µm)^0.5 (V/1 mm/s)^0.6 (Fn/1 N)^-0.15.
    """
    if form == "linear_velocity":
        model = AmplitudeModel(
            "linear_velocity", np.array([0.002, 0.25, 0.003, 0.5]),
            ("intercept[0]", "velocity_slope[0]", "intercept[1]", "velocity_slope[1]"),
            np.zeros(4), np.zeros((4, 4)), terms=("sliding_velocity", "roughness_ra"),
            roughness_levels=(0.4e-6, 1.6e-6),
        )
    elif form == "power_law_load":
        model = AmplitudeModel(
            "power_law_load", np.array([np.log(0.002), 0.5, 0.6, -0.15]),
            ("log_prefactor", "roughness_exponent", "velocity_exponent", "load_exponent"),
            np.zeros(4), np.zeros((4, 4)), terms=("roughness_ra", "sliding_velocity", "normal_load"),
        )
    else:
        raise ValueError(form)
    return PerturbedCoulombLaw(MU0, SHAPE_F, SHAPE, model, (SHAPE_F[0], SHAPE_F[-1]), injection=injection,
                               reference_velocity=0.01 if injection == "convected" else None)


TWIN_MU0 = 0.32


def twin_law(injection="uniform") -> PerturbedCoulombLaw:
    """The 8-run twin's known law (issue 16): μ0 = 0.32, RMS amplitude A = 0.004 (V/10 mm/s)(Ra/1 µm)^0.9
    (a power law: log_prefactor ln 0.0004 at V_ref = 1 mm/s), the 4th-order roll-off at 1.5 kHz."""
    model = AmplitudeModel("power_law", np.array([np.log(0.0004), 0.9, 1.0]),
                           ("log_prefactor", "roughness_exponent", "velocity_exponent"), np.zeros(3), np.zeros((3, 3)),
                           terms=("roughness_ra", "sliding_velocity"))
    return PerturbedCoulombLaw(TWIN_MU0, SHAPE_F, SHAPE, model, (SHAPE_F[0], SHAPE_F[-1]), injection=injection,
                               reference_velocity=0.01 if injection == "convected" else None)


def band_fraction(law, band=ANALYSIS_BAND, velocity=None) -> float:
    """∫_band s df of the law's normalised shape (fine trapezoid; the shape is piecewise linear)."""
    f = np.linspace(band[0], band[1], 200001)
    return float(np.trapezoid(law.normalised_shape(f, velocity), f))


def band_amplitude(law, velocity, roughness, normal_load, band=ANALYSIS_BAND) -> float:
    """True band RMS of μp [-] over ``band``."""
    return law.amplitude(velocity, roughness, normal_load) * np.sqrt(band_fraction(law, band, velocity))


def _smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def synthetic_run(law, *, velocity, roughness, normal_load, seed, run_id="S1", duration=3.2, fs=FS,
                  noise=1e-3, offsets=(0.02, -0.05), hum=(4e-3, 1.5e-3, 6e-4), mains=50.02, acceleration_psd=None,
                  unloaded=0.6, drift=0.0, glitches=0):
    """A SYNTHETIC RunDataset from ``law`` (see the module docstring).

    Parameters
    ----------
    velocity, roughness, normal_load : float
        [m s-1], [m], [N].
    seed : int
        Seeds μp (law.sample) and every sensor disturbance.
    noise : float
        RMS white noise of each force sensor [N].
    offsets : (float, float)
        Offsets of the friction and normal force sensors [N].
    hum : sequence of float
        Amplitudes [N] of the mains hum at the 1st, 3rd, 5th... harmonics of ``mains`` [Hz].
    unloaded : float
        Duration [s] of the unloaded start (the load ramps up over the next 0.1 s, the base over the 0.1 s after).
    drift : float
        Thermal drift of both force sensors' offsets [N s-1] (linear from t = 0, friction channel; the
        normal channel drifts by -drift/2), as measured rigs show.
    glitches : int
        DAQ glitches: this many single-sample spikes of ±(2 to 10) N on a random force channel, and
        ``glitches // 3`` dropouts where both force channels read 0 N for 1 to 3 samples.
    acceleration_psd : callable, optional
        One-sided PSD [m2 s-4 Hz-1] of the acceleration (default: white, 0.5 m s-2 RMS).
    """
    rng = np.random.default_rng(seed + 1_000_003)
    n = int(round(duration * fs))
    t = np.arange(n) / fs
    load = _smoothstep((t - unloaded) / 0.1)
    slide = _smoothstep((t - unloaded - 0.1) / 0.1) * _smoothstep((duration - 0.05 - t) / 0.1)
    v = velocity * slide
    fn = normal_load * load * (1 + 0.01 * np.sin(2 * np.pi * 3.1 * t + rng.uniform(0, 6.28)))
    # the synthesis is periodic over its record with an exactly zero mean; drawn over 8 record lengths
    # and cut, the low frequencies that set the variance of a window mean are represented
    mup = law.sample(8 * duration, fs, velocity, roughness, seed=seed, normal_load=normal_load)[0, :n]
    ft = (law.mu0 + mup) * fn * _smoothstep(slide / 0.3)  # full Coulomb friction once sliding has started
    hum_t = sum(a * np.sin(2 * np.pi * (2 * k + 1) * mains * t + rng.uniform(0, 6.28)) for k, a in enumerate(hum))
    hum_n = sum(0.5 * a * np.sin(2 * np.pi * (2 * k + 1) * mains * t + rng.uniform(0, 6.28)) for k, a in enumerate(hum))
    ft_m = ft + offsets[0] + noise * rng.standard_normal(n) + hum_t + drift * t
    fn_m = fn + offsets[1] + noise * rng.standard_normal(n) + hum_n - 0.5 * drift * t
    if glitches:
        grng = np.random.default_rng(seed + 2_000_003)  # glitches do not change the other draws
        for k in grng.integers(0, n, glitches):
            channel = ft_m if grng.random() < 0.5 else fn_m
            channel[k] += grng.choice([-1.0, 1.0]) * grng.uniform(2.0, 10.0)
        for k in grng.integers(0, n - 3, glitches // 3):
            width = int(grng.integers(1, 4))
            ft_m[k:k + width] = 0.0
            fn_m[k:k + width] = 0.0
    v_m = v + 0.01 * velocity * rng.standard_normal(n)
    ds = xr.Dataset(
        {
            "acceleration": ("time", 0.5 * rng.standard_normal(n) if acceleration_psd is None else
                             synthesise_perturbation(acceleration_psd, duration, fs, seed=seed + 7)[0]),
            "friction_force": ("time", ft_m),
            "normal_force": ("time", fn_m),
            "velocity": ("time", v_m),
            "position": ("time", np.cumsum(v) / fs),
        },
        coords={"time": ("time", t)},
        attrs={
            "run_id": run_id,
            "rig": "synthetic",
            "sliding_velocity": float(velocity),
            "normal_load": float(normal_load),
            "roughness_ra": float(roughness),
            "sample_rate": float(fs),
            "source": f"SYNTHETIC: tests/helpers/synthetic_friction_runs.py seed={seed} law sha256 {law.sha256[:16]}",
            "history": new_history("synthetic run for tests"),
        },
    )
    return validate_run(apply_cf_attrs(ds))


def run_grid(law, seed, *, velocities=(0.005, 0.01, 0.02), roughnesses=(0.4e-6, 1.6e-6), loads=(5.0,), **kw):
    """Runs on the full grid of velocities × roughnesses × loads; run i is seeded ``seed * 1000 + i``."""
    runs = []
    for ra in roughnesses:
        for fn in loads:
            for v in velocities:
                i = len(runs)
                runs.append(synthetic_run(law, velocity=v, roughness=ra, normal_load=fn, seed=seed * 1000 + i,
                                          run_id=f"S{i:02d}", **kw))
    return runs


def edge_law() -> PerturbedCoulombLaw:
    """A known law like the twin's (sample_data/ground_truth.yaml): s ∝ 1/(1 + (f/1 kHz)²) on 100 Hz–10 kHz,
    zero below 100 Hz (a steep spectral edge next to the mains harmonics), μ0 = 0.3, and the linear
    amplitude law of :func:`true_law`.
    """
    f = np.r_[0.0, 99.0, np.linspace(100.0, 10000.0, 3961), 10001.0, 12000.0]
    s = np.where((f >= 100.0) & (f <= 10000.0), 1.0 / (1.0 + (f / 1000.0) ** 2), 0.0)
    base = true_law("linear_velocity")
    return PerturbedCoulombLaw(MU0, f, s, base.amplitude_model, (f[0], f[-1]))
