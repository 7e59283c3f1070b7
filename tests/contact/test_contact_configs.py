"""The shipped contact configs run through the CLI (issue 13): the rough two-beam rig's modes move with the load,
the ring on its rotating cylinder is preloaded to seed 002's 40 MPa and has unstable CEA doublets."""

import json
from pathlib import Path

import numpy as np
import pytest

from fivid.cli import main

MODELS = Path(__file__).resolve().parents[2] / "configs" / "models"


def _modes(capsys, *args):
    assert main(["modes", *args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_rough_rig_modes_move_with_the_normal_load(capsys):
    """Greenwood-Williamson contact: the normal stiffness grows with load, so do the coupled frequencies (the
    rigid-contact rig's closed set and frequencies do not change with the load's size)."""
    light = _modes(capsys, str(MODELS / "triboair_rough.yaml"), "-n", "3", "--load", "0.5 N")
    heavy = _modes(capsys, str(MODELS / "triboair_rough.yaml"), "-n", "3", "--load", "20 N")
    (c_light,), (c_heavy,) = light["contact"], heavy["contact"]
    assert c_light["normal_force_n"] == pytest.approx(0.5, rel=1e-6)
    assert c_heavy["normal_stiffness_n_per_m"] > 10 * c_light["normal_stiffness_n_per_m"]
    f_l, f_h = np.array(light["frequencies_hz"]), np.array(heavy["frequencies_hz"])
    assert np.all(f_h > f_l) and f_h[2] / f_l[2] > 1.5  # 5470 -> 9820 Hz
    rigid = [_modes(capsys, str(MODELS / "triboair_coarse.yaml"), "-n", "3", "--load", q)["frequencies_hz"]
             for q in ("0.5 N", "20 N")]
    assert rigid[0] == pytest.approx(rigid[1], rel=1e-9)


def test_ring_preload_gives_seed_002s_contact_pressure(capsys):
    """ring.yaml's cylinder expands until the mean contact pressure is seed 002's 40 MPa (solved to 1e-9)."""
    j = _modes(capsys, str(MODELS / "ring.yaml"), "-n", "4", "--contact")
    (c,) = j["contact"]
    assert c["mean_pressure_pa"] == pytest.approx(40e6, rel=1e-8)
    assert c["closed_nodes"] == 180 and c["contact_length_m"] == pytest.approx(2 * np.pi * 0.065, rel=1e-4)
    assert main(["modes", str(MODELS / "ring.yaml"), "-n", "4"]) == 0  # and without the contact: a held ring
    first = capsys.readouterr().out.splitlines()[-4]  # its outer edge is clamped (the fixed frame): no rigid-body mode
    assert float(first.split()[1]) > 100.0
    assert main(["cea", str(MODELS / "triboair_rough.yaml"), "--mu", "0", "1", "3"]) == 2  # needs --load
    assert "--load" in capsys.readouterr().err


@pytest.mark.slow
def test_ring_cea_and_transient_run(capsys, tmp_path):
    """CEA about the expansion preload finds friction-induced instabilities of split doublets (seed 002's
    mechanism), and the transient runs with the energy balance closed (slow: 40 s + 15 s)."""
    assert main(["cea", str(MODELS / "ring.yaml"), "--mu", "0", "1", "6", "-n", "10", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["unstable"] and any(u["partner"] is not None for u in j["unstable"])
    out = tmp_path / "ring.nc"
    assert main(["simulate", str(MODELS / "ring.yaml"), "--duration", "1 ms", "--sample-rate", "100 kHz", "-o",
                 str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert abs(s["max_energy_balance_error_j"]) < 1e-9
