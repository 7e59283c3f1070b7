"""The pipeline's simulate stage on dask.distributed (through :mod:`fivid.execution.cluster`).

By default an embedded :class:`distributed.LocalCluster` (worker *processes*, one thread each, on the
loopback interface, ``n_workers`` from ``--workers``) is started for the sweep and closed after it;
with ``--scheduler tcp://host:port`` the tasks go to an existing cluster (``dask scheduler`` and
``dask worker tcp://host:port`` started by hand, see docs/pipeline.md). Tasks are coarse: one whole
simulation each. Workers receive the model and the law as Python objects and return the simulated
RunDataset; the client writes each file (atomically) and records it in the cache as soon as it
arrives, so a sweep interrupted half-way keeps the simulations already done and needs no shared
file system between the workers and the client.

dask is imported by :mod:`fivid.execution.cluster` only, when a sweep runs.
"""

from __future__ import annotations

import logging

from fivid.execution.cluster import call, map_tasks
from fivid.fe import load_model
from fivid.friction import load_law
from fivid.friction.inputs import FrictionInput, OperatingCondition
from fivid.io import write_run
from fivid.solver import simulate
from fivid.solver.options import IntegrationOptions, OutputOptions, RunSchedule

__all__ = ["simulation_inputs", "simulate_condition", "run_simulations"]

log = logging.getLogger("fivid")

def simulation_inputs(params: dict) -> tuple[OperatingCondition, RunSchedule, IntegrationOptions]:
    """The condition, schedule and solver path of a pipeline simulate task's flat ``params`` (its cache record:
    ``sliding_velocity`` [m s-1], ``normal_load`` [N], ``roughness_ra`` [m], ``duration`` [s], ``sample_rate``
    [Hz], ``reduced``, ``reduced_tolerance`` [dB], ``error_band`` [Hz])."""
    return (OperatingCondition(params["sliding_velocity"], params["normal_load"], params["roughness_ra"]),
            RunSchedule(duration=params["duration"], sample_rate=params["sample_rate"]),
            IntegrationOptions(reduced=params["reduced"], reduced_tolerance=params["reduced_tolerance"],
                               error_band=params["error_band"]))


def simulate_condition(model, law, params: dict):
    """One simulation (runs on a worker) of a simulate task's ``params`` (:func:`simulation_inputs`, ``seed`` of
    the law's synthesis, ``run_id``) with ``law``."""
    condition, schedule, integration = simulation_inputs(params)
    return simulate(model, condition, FrictionInput(law=law, seed=params["seed"]), schedule=schedule,
                    integration=integration, output=OutputOptions(run_id=params["run_id"], progress=False))


def run_simulations(ctx, tasks) -> None:
    """Run the simulate stage's tasks on dask, writing each result and its cache record as it arrives."""
    from tqdm.auto import tqdm

    model = load_model(ctx.config.model)
    law = load_law(ctx.data["law_path"])
    by_name = {t.name: t for t in tasks}
    items = {t.name: (simulate_condition, model, law, dict(t.params)) for t in tasks}
    bar = tqdm(total=len(tasks), desc="simulate", unit="sim", leave=False,
               disable=None if ctx.progress is None else not ctx.progress)
    try:
        for name, ds, seconds, pid in map_tasks(call, items, workers=ctx.workers, scheduler=ctx.scheduler):
            task = by_name[name]
            log.info("simulate/%s computed by worker pid %d", name, pid)
            write_run(ds, task.outputs["sim"], overwrite=True)
            ctx.finish(task, seconds)
            bar.update(1)
    finally:
        bar.close()
