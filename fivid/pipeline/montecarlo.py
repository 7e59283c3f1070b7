"""Run a Monte-Carlo over a friction law's uncertainty on dask → the PSD envelope (issue 16 item 3).

The samples (:func:`fivid.identify.montecarlo.monte_carlo_laws`) are simulated with
:func:`fivid.identify.montecarlo.sample_spectrum` as tasks of :func:`fivid.execution.cluster.map_tasks`
(the LocalCluster or the scheduler of the sweeps and studies), or in this process with ``workers=0``;
their PSDs become the envelope (:func:`fivid.score.envelope.envelope_dataset`). The result does not
depend on the number of workers nor on the order in which the samples finish.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from fivid.errors import ConfigError, FividError
from fivid.execution.cluster import check_scheduler_address, map_tasks
from fivid.friction.inputs import FrictionInput, OperatingCondition
from fivid.identify.montecarlo import NOT_SAMPLED, SAMPLED, EnvelopeSpectrum, monte_carlo_laws, sample_spectrum
from fivid.score.envelope import envelope_dataset
from fivid.solver.options import IntegrationOptions, RunSchedule

__all__ = ["run_monte_carlo", "SampleExecution"]

log = logging.getLogger("fivid")


@dataclass(frozen=True)
class SampleExecution:
    """Where the Monte-Carlo samples run.

    Attributes
    ----------
    workers : int
        dask worker processes (default 2); 0 runs the samples in this process.
    scheduler : str or None
        ``tcp://host:port`` of a running dask scheduler.
    progress : bool or None
        Progress bar over the samples (None: when the terminal is interactive).
    """

    workers: int = 2
    scheduler: str | None = None
    progress: bool | None = None


def run_monte_carlo(model, law, condition: OperatingCondition, schedule: RunSchedule, *, samples: int, seed: int = 0,
                    integration: IntegrationOptions = IntegrationOptions(),
                    spectrum: EnvelopeSpectrum = EnvelopeSpectrum(),
                    execution: SampleExecution = SampleExecution(), attrs: dict | None = None):
    """Simulate ``samples`` draws of ``law`` at one condition and return their PSD envelope (a Dataset).

    Parameters
    ----------
    model : Model
    law : PerturbedCoulombLaw
    condition, schedule : OperatingCondition, RunSchedule
        As :func:`fivid.solver.simulate` (sliding velocity [m s-1], normal load [N], Ra [m]; duration [s], sample
        rate [Hz]).
    samples : int
        Number of Monte-Carlo samples (>= 2).
    seed : int
        Seed of the whole Monte-Carlo (coefficient draws and every sample's synthesis seed).
    integration : IntegrationOptions
        The time step and the solver path, as :func:`fivid.solver.simulate` (``reduced="auto"``: reduced when its
        estimated in-band error is within the tolerance [dB] over ``error_band`` [Hz]). The samples share one
        model, so with a reduced path the basis is built once (the first worker, under the cache's lock) and read
        by the others.
    spectrum : EnvelopeSpectrum
        The signal whose PSD is taken (as ``fivid score``), the Welch segment length [samples] (the analysed record,
        ``(duration - settle) * sample_rate``, must hold one), the time [s] skipped after each simulation's
        transient, and the band [Hz] of the stored 1/3-octave band levels.
    execution : SampleExecution
        dask workers (0: in this process) or a scheduler's address, and the progress bar.
    attrs : dict, optional
        More provenance for the file (law file name and sha256, model, command line).
    """
    from tqdm.auto import tqdm

    duration, sample_rate = schedule.duration, schedule.sample_rate
    nperseg, settle = spectrum.nperseg, spectrum.settle
    workers, scheduler, progress = execution.workers, execution.scheduler, execution.progress
    n_steady = int(np.floor((float(duration) - float(settle)) * float(sample_rate) + 1e-9))
    if n_steady < int(nperseg):
        raise ConfigError(f"the analysed record of {duration:g} s (less {settle:g} s settling) at {sample_rate:g} Hz has "
                          f"{n_steady} samples, fewer than one Welch segment (nperseg {int(nperseg)}); lengthen the "
                          "duration or lower nperseg", key="nperseg")
    if scheduler is not None:
        check_scheduler_address(scheduler)
    draws = monte_carlo_laws(law, samples, seed)
    schedule = replace(schedule, duration=float(duration), sample_rate=float(sample_rate))
    spectrum = replace(spectrum, nperseg=int(nperseg), settle=float(settle))
    items = {f"mc{i:04d}": (model, FrictionInput(law=draws["laws"][i], seed=int(draws["seeds"][i])), condition,
                            schedule, integration, spectrum) for i in range(int(samples))}
    results = {}
    bar = tqdm(total=len(items), desc="Monte-Carlo", unit="sample", leave=False, disable=None if progress is None
               else not progress)
    try:
        for name, out, seconds, pid in map_tasks(sample_spectrum, items, workers=int(workers), scheduler=scheduler):
            log.info("Monte-Carlo %s: %.3g s on worker pid %d", name, seconds, pid)
            results[name] = out
            bar.update(1)
    finally:
        bar.close()
    ordered = [results[name] for name in items]  # sample order, whatever the finishing order
    freq = ordered[0]["frequency"]
    if any(r["frequency"].shape != freq.shape for r in ordered):
        raise FividError("the Monte-Carlo samples' PSDs are on different frequency grids")
    settings = ordered[0]["settings"]
    meta = {
        "seed": int(seed),
        "sampled": SAMPLED,
        "not_sampled": NOT_SAMPLED,
        "coefficient_covariance_sampled": int(draws["covariance_sampled"]),
        "law_sha256": str(law.sha256),
        "variable": spectrum.variable,
        "sensor": "" if spectrum.sensor is None else str(spectrum.sensor),
        "duration": float(duration),
        "duration_units": "s",
        "sample_rate": float(sample_rate),
        "sample_rate_units": "Hz",
        "scaling": "density",
        "steady_part": f"each sample from its simulation's transient_end (after preload, settling and base ramp) "
                       f"+ {float(settle):g} s",
        "settle": float(settle),
        "settle_units": "s",
        **{k: v for k, v in settings.items() if k != "equivalent_degrees_of_freedom"},
        "sample_equivalent_degrees_of_freedom": float(settings.get("equivalent_degrees_of_freedom", np.nan)),
    }
    paths = sorted({r.get("solver", {}).get("solver_path", "full") for r in ordered})
    meta.update({k: v for k, v in ordered[0].get("solver", {}).items()})  # the same model and settings for all
    meta["solver_path"] = "+".join(paths)
    for name, value in (("sliding_velocity", condition.sliding_velocity), ("normal_load", condition.normal_load),
                        ("roughness_ra", condition.roughness_ra)):
        if value is not None:
            meta[name] = float(value)
    meta.update(attrs or {})
    return envelope_dataset(freq, np.stack([r["psd"] for r in ordered]), ordered[0]["units"], band=spectrum.band,
                            seeds=draws["seeds"], coefficients=draws["coefficients"],
                            coefficient_names=draws["names"], amplitudes=[r["amplitude"] for r in ordered],
                            attrs=meta)
