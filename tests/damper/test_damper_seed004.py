"""Seed 004 reproduced with the identified rubbing-device compliance (issue 25 acceptance).

The device's tangential stiffness (a massless spring in series with the Jenkins contact) is identified from
one datum, the stuck FRF peak at 40 N (86 Hz); mu and k_d of Models 1 and 2 stay as the paper gives them.
The free peak (0.1 N) and Model 2's offset are then predictions, checked against the paper's figures
within the issue's acceptance bands (24 +- 1 Hz, 10 +- 3 Hz).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from fivid.cli import main
from fivid.damper.model import load_damper_model
from fivid.damper.peaks import frf_peak
from fivid.verify.registry import registered_cases
from fivid.verify.runner import evaluate_case

CONFIGS = Path(__file__).resolve().parents[2] / "configs" / "dampers"


@pytest.fixture(scope="module")
def models():
    return {n: load_damper_model(CONFIGS / f"seed004_model{n}.yaml") for n in (1, 2)}


def test_series_stiffness(models):
    m = models[1]
    assert m.series_stiffness == pytest.approx(1 / (1 / 3.9e5 + 1 / 2.815e5), rel=1e-12)
    assert m.with_parameters(device_stiffness=np.inf).series_stiffness == 3.9e5


def test_peak_of_a_stuck_contact_is_the_linear_resonance(models):
    """mu Fn far above the contact force: the model is linear, its FRF peak the eigenfrequency with the
    series spring, shifted by damping (displacement peak f_r sqrt(1 - 2 zeta^2), other modes' background:
    same order, 10 zeta^2 f_r as in test_damper_hbm)."""
    m = models[1].with_parameters(friction_coefficient=1e6)
    f_r = m.modal.with_contact_spring(m.series_stiffness)[0] / (2 * np.pi)
    p = frf_peak(m, 40.0)
    assert abs(p.frequency - f_r) <= 10 * 0.005**2 * f_r


def test_seed004_acceptance():
    """The issue's acceptance bands, from the verification catalogue (one home per oracle):
    stuck 86 +- 3 Hz (the identification datum), Model 2 - Model 1 = 10 +- 3 Hz (prediction; fivid 11.6 Hz),
    free 24 +- 1 Hz (tip-mass placeholder; fivid 24.09 Hz)."""
    cases = {c.name: c for c in registered_cases() if c.name.startswith("seed004_")}
    assert set(cases) == {"seed004_stuck_peak", "seed004_model2_offset", "seed004_free_peak"}
    for case in cases.values():
        result = evaluate_case(case, False, None)
        assert result.passed, (case.name, result.outcome, result.reason)
    stuck = evaluate_case(cases["seed004_stuck_peak"], False, None)
    assert stuck.outcome.value == pytest.approx(86.0, abs=0.05)  # what the identification fitted (4-digit rounding)


@pytest.mark.slow
def test_update_identifies_the_device_from_the_stuck_peak(tmp_path, capsys):
    """fivid update from 1e6 N/m finds the shipped value, within its 95 % interval."""
    start = tmp_path / "start.yaml"
    start.write_text((CONFIGS / "seed004_model1.yaml").read_text().replace("device_stiffness: 2.815e5 N/m",
                                                                           "device_stiffness: 1e6 N/m"))
    out = tmp_path / "updated.yaml"
    assert main(["update", str(start), "--targets", str(CONFIGS / "targets" / "seed004_stuck.yaml"), "-o", str(out),
                 "--json"]) == 0
    p = json.loads(capsys.readouterr().out)["parameters"][0]
    assert abs(p["value"] - 2.815e5) < 0.001 * 2.815e5 < p["ci95"]
