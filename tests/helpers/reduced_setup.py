"""The reduced-path tests' shared set-up (tests/solver/test_solver_reduced.py, tests/solver/test_reduced_auto.py): the coarse
rig and the sliding condition both families run it at."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
COARSE = ROOT / "configs/models/triboair_coarse.yaml"


def run_inputs(duration: float, **integration) -> dict:
    """The inputs of :func:`fivid.solver.simulate`/``prepare_run`` of the reduced-vs-full comparisons: mu 0.3 at
    10 mm/s and 5 N, ``duration`` [s] at 51.2 kHz after short ramps (0.2 ms preload, 0.1 ms base), no progress bar;
    ``integration``: :class:`fivid.solver.IntegrationOptions` fields (the solver path)."""
    from fivid.solver import FrictionInput, IntegrationOptions, OperatingCondition, OutputOptions, RunSchedule

    return dict(condition=OperatingCondition(sliding_velocity=0.01, normal_load=5.0), friction=FrictionInput(mu=0.3),
                schedule=RunSchedule(duration=duration, sample_rate=51200.0, preload_time=2e-4, settle_time=0.0,
                                     base_ramp_time=1e-4),
                integration=IntegrationOptions(**integration), output=OutputOptions(progress=False))


@pytest.fixture(scope="module")
def coarse():
    """The coarse rig's model, loaded once per test module."""
    from fivid.fe import load_model

    return load_model(COARSE)
