"""Bad configuration raises ConfigError naming the key, in the FE model's API too (issue 20 item 5); the
per-node friction coefficient has one builder (item 6)."""

from pathlib import Path

import numpy as np
import pytest

from fivid.errors import ConfigError
from fivid.fe import load_model

COARSE = Path(__file__).resolve().parents[2] / "configs" / "models" / "triboair_coarse.yaml"


@pytest.fixture(scope="module")
def model():
    return load_model(COARSE)


@pytest.mark.parametrize("call, key", [
    (lambda m: __import__("fivid.fe.modal", fromlist=["x"]).modal_analysis(m, 3, mass="diagonal"), "mass"),
    (lambda m: __import__("fivid.fe.modal", fromlist=["x"]).modal_analysis(m, 0), "n_modes"),
    (lambda m: __import__("fivid.fe.assembly", fromlist=["x"]).damping_matrix(m, mass="diagonal"), "mass"),
    (lambda m: m.blocks[0].edge_nodes("middle"), "bodies.lower.edge"),
    (lambda m: __import__("fivid.fe.cea", fromlist=["x"]).complex_eigenvalue_analysis(
        m, [0.1, 0.2], normal_load=5.0, n_modes=4, n_basis=2), "n_basis"),
])
def test_fe_api_config_errors_name_the_key(model, call, key):
    with pytest.raises(ConfigError) as exc:
        call(model)
    assert exc.value.key == key and f"key '{key}'" in str(exc.value)


@pytest.mark.parametrize("edit, key", [
    (lambda c: c.update(plane="3d"), "plane"),
    (lambda c: c["bodies"]["lower"].update(thickness="10 s"), "bodies.lower.thickness"),
    (lambda c: c["contacts"][0].update(mu_k=0.3), "contacts[0]"),
])
def test_model_config_wrong_key_or_unit_names_the_key(edit, key):
    from fivid.fe.config import read_config

    cfg = read_config(COARSE)[0]
    edit(cfg)
    with pytest.raises(ConfigError) as exc:
        load_model(cfg)
    assert key in str(exc.value)


def test_one_per_node_friction_builder(model):
    """The solver's constant-friction table and the preload use the same per-node coefficients."""
    from fivid.friction import FrictionInput, OperatingCondition
    from fivid.friction.curve import slave_coefficients
    from fivid.friction.injection import friction_table

    pair = np.concatenate([[p] * len(c.slave_nodes) for p, c in enumerate(model.contacts)])
    table = friction_table(model, pair, np.zeros(pair.size), FrictionInput(), OperatingCondition(sliding_velocity=0.01),
                           total_time=1e-3, dt=1e-6, sample_rate=1e4)
    np.testing.assert_array_equal(table.mu[0], slave_coefficients(model))
