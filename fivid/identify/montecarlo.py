"""Monte-Carlo over an identified friction law's uncertainty: the laws to simulate and one sample's spectrum.

What is sampled (issue 16 item 3):

- the amplitude-law coefficients β, drawn from the multivariate normal N(β̂, Σ) of the law file
  (``amplitude_coefficient``, ``amplitude_covariance``): the uncertainty of the law's *mean* amplitude
  A(V, Ra, Fn). For the forms fitted on ln A the drawn amplitude is log-normal; linear forms are
  clipped at 0 by the law. Σ is symmetrised and its negative eigenvalues (round-off of a
  rank-deficient fit) set to 0; a non-finite Σ (an exact fit) is not sampled (recorded);
- the synthesis seed of μp(t): every sample has its own (independent streams from
  :class:`numpy.random.SeedSequence`), so the spread also holds the randomness of the process and the
  Welch estimation variance of a finite record.

Not sampled (the law file carries no distribution for them): μ0 (its confidence interval is only
recorded), the spectral shape s(f) (a point estimate), and the run-to-run scatter of a new run's
amplitude (the residual variance of the amplitude fit, which ``fivid law eval`` adds to its
prediction interval). The envelope is therefore that of runs simulated with the law *as identified*,
not a prediction interval for one new measurement's amplitude.
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError
from fivid.friction import PerturbedCoulombLaw
from fivid.friction.inputs import FrictionInput, OperatingCondition
from fivid.score.runs import _signal
from fivid.signal.steady import steady_part
from fivid.signal.welch import welch_psd
from fivid.solver import simulate
from fivid.solver.options import IntegrationOptions, OutputOptions, RunSchedule

__all__ = ["draw_coefficients", "law_with_coefficients", "sample_seeds", "monte_carlo_laws", "sample_spectrum",
           "EnvelopeSpectrum", "SAMPLED", "NOT_SAMPLED"]

log = logging.getLogger("fivid")

#: what a Monte-Carlo sample varies and what it keeps (recorded in the envelope file)
SAMPLED = ("amplitude-law coefficients drawn from N(coefficients, covariance) of the law file; "
           "an independent synthesis seed per sample")
NOT_SAMPLED = "mu0, the spectral shape, the run-to-run residual scatter of the amplitude (no distribution recorded)"


def draw_coefficients(mean, covariance, n: int, rng) -> tuple[np.ndarray, bool]:
    """``n`` draws of N(``mean``, ``covariance``): an array (n, p) and whether the covariance was used.

    The covariance is symmetrised and its eigenvalues clipped at 0 (a fit with a rank-deficient design
    has round-off negatives); a covariance with NaN or inf gives ``n`` copies of ``mean`` and False.
    """
    beta = np.asarray(mean, dtype=float).reshape(-1)
    p = beta.size
    cov = np.asarray(covariance, dtype=float).reshape(p, p)
    if not np.all(np.isfinite(cov)):
        return np.repeat(beta[None, :], n, axis=0), False
    w, v = np.linalg.eigh(0.5 * (cov + cov.T))
    root = v * np.sqrt(np.clip(w, 0.0, None))  # root @ root.T == cov (PSD part)
    z = rng.standard_normal((n, p))
    return beta[None, :] + z @ root.T, True


def law_with_coefficients(law, coefficients):
    """The law with its amplitude-model coefficients replaced (shape, band, μ0, injection kept)."""
    model = dataclasses.replace(law.amplitude_model, coefficients=np.asarray(coefficients, dtype=float))
    return PerturbedCoulombLaw(law.mu0, law.shape_frequency, law.shape, model, law.band, injection=law.injection,
                               reference_velocity=law.reference_velocity, source=law.source,
                               condition_shapes=law.condition_shapes)


def sample_seeds(seed: int, n: int) -> np.ndarray:
    """``n`` synthesis seeds (int64 >= 0) of independent streams spawned from ``seed``."""
    children = np.random.SeedSequence(int(seed)).spawn(int(n))
    return np.array([int(c.generate_state(1, dtype=np.uint32)[0]) for c in children], dtype=np.int64)


def monte_carlo_laws(law, n: int, seed: int = 0) -> dict:
    """The ``n`` samples of a Monte-Carlo over ``law`` (see the module docstring).

    Returns
    -------
    dict
        ``laws`` (list of law objects), ``coefficients`` (n, p), ``names`` (p), ``seeds`` (n,) synthesis seeds,
        ``covariance_sampled`` (bool).

    Raises
    ------
    ConfigError
        ``n`` < 2, or a law without a perturbation (Coulomb: nothing to sample).
    """
    if isinstance(n, bool) or int(n) != n or n < 2:
        raise ConfigError(f"samples = {n!r}; a Monte-Carlo envelope needs an integer number of samples >= 2",
                          key="samples")
    if not isinstance(law, PerturbedCoulombLaw):
        raise ConfigError(f"a Monte-Carlo over a law needs a perturbed Coulomb law (mu0 + mu_p(t)); got "
                          f"{type(law).__name__}, which has no uncertainty to sample", key="samples")
    if isinstance(seed, bool) or int(seed) != seed or seed < 0:
        raise ConfigError(f"seed = {seed!r}; expected an integer >= 0", key="seed")
    n = int(n)
    m = law.amplitude_model
    # one stream for the coefficients, independent of the synthesis seeds (SeedSequence spawn keys)
    rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(2**31,)))
    beta, used = draw_coefficients(m.coefficients, m.covariance, n, rng)
    if not used:
        log.warning("the law's coefficient covariance is not finite (an exact fit?): the coefficients are not "
                    "sampled, only the synthesis seed")
    return {"laws": [law_with_coefficients(law, b) for b in beta], "coefficients": beta, "names": list(m.names),
            "seeds": sample_seeds(seed, n), "covariance_sampled": used}


@dataclass(frozen=True)
class EnvelopeSpectrum:
    """The spectrum taken of each Monte-Carlo sample, and the band of the envelope's band levels.

    Attributes
    ----------
    variable, sensor : str, str or None
        Which signal (as ``fivid score``: ``sensor`` when the variable has several; default acceleration).
    nperseg : int
        Welch segment length [samples] (default 8192, as ``fivid score``).
    noverlap, window, detrend
        The other Welch settings (:func:`fivid.signal.welch_psd`; default half-overlapping Hann segments, constant
        detrend).
    settle : float
        Time [s] skipped after the end of each simulation's transient (as the pipeline's scores skip it).
    band : (float, float) or None
        Band [Hz] of the stored 1/3-octave band levels (None: that of the scores).
    """

    variable: str = "acceleration"
    sensor: str | None = None
    nperseg: int = 8192
    noverlap: int | None = None
    window: str = "hann"
    detrend: str = "constant"
    settle: float = 0.0
    band: tuple[float, float] | None = None


def sample_spectrum(model, friction: FrictionInput, condition: OperatingCondition, schedule: RunSchedule,
                    integration: IntegrationOptions = IntegrationOptions(),
                    spectrum: EnvelopeSpectrum = EnvelopeSpectrum()) -> dict:
    """One Monte-Carlo sample (runs on a worker): simulate, keep the steady part, Welch PSD.

    Parameters
    ----------
    model : Model
    friction : FrictionInput
        This sample's law (:func:`monte_carlo_laws`) and synthesis seed.
    condition, schedule, integration
        As :func:`fivid.solver.simulate` (no progress bar).
    spectrum : EnvelopeSpectrum
        The signal and the Welch settings.

    Returns
    -------
    dict
        ``frequency`` [Hz], ``psd`` [u2 Hz-1], ``units`` (of the signal), ``amplitude`` (the law's A at the
        condition [-]), the Welch ``settings``, the simulation's ``transient_end`` [s] and ``solver`` (its
        solver-path attrs: ``solver_path``, ``reduced_error_estimate_db``...).
    """
    law = friction.law
    ds = simulate(model, condition, friction, schedule=schedule, integration=integration,
                  output=OutputOptions(progress=False))
    steady = steady_part(ds, settle=spectrum.settle)  # from the simulation's transient_end
    label = f"Monte-Carlo sample (seed {friction.seed})"
    da = _signal(steady, spectrum.variable, spectrum.sensor, label)
    psd = welch_psd(da, nperseg=int(spectrum.nperseg), noverlap=spectrum.noverlap, window=spectrum.window,
                    detrend=spectrum.detrend, fs=float(schedule.sample_rate), label=label)
    amp = law.amplitude(ds.attrs["sliding_velocity"], condition.roughness_ra, condition.normal_load)
    keys = ("nperseg", "noverlap", "window", "detrend", "equivalent_degrees_of_freedom", "fft_backend")
    return {"frequency": psd["frequency"].values, "psd": np.asarray(psd.values, dtype=float),
            "units": da.attrs["units"], "amplitude": float(np.asarray(amp).reshape(-1)[0]),
            "settings": {k: psd.attrs[k] for k in keys if k in psd.attrs},
            "transient_end": float(ds.attrs["transient_end"]),
            "solver": {k: v for k, v in ds.attrs.items() if k.startswith(("solver_", "reduced_error"))}}
