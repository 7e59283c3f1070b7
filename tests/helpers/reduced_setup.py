"""The reduced-path tests' shared set-up (tests/solver/test_solver_reduced.py, tests/solver/test_reduced_auto.py): the coarse
rig and the sliding condition both families run it at."""

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
COARSE = ROOT / "configs/models/triboair_coarse.yaml"
#: the sliding condition of the reduced-vs-full comparisons (SI: -, m/s, N, Hz, s)
RUN = dict(mu=0.3, sliding_velocity=0.01, normal_load=5.0, sample_rate=51200.0, preload_time=2e-4, settle_time=0.0,
           base_ramp_time=1e-4)


@pytest.fixture(scope="module")
def coarse():
    """The coarse rig's model, loaded once per test module."""
    from fivid.fe import load_model

    return load_model(COARSE)
