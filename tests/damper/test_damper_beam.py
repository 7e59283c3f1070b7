"""Euler-Bernoulli cantilever: closed-form frequencies, observed convergence order, config errors."""

from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import eigh

from fivid.damper.model import damper_model_from_dict, load_damper_model
from fivid.errors import ConfigError
from fivid.fe.beam import cantilever_beam
from tests.helpers.convergence import assert_order

CONFIGS = Path(__file__).resolve().parents[2] / "configs" / "dampers"
BETA_L = np.array([1.8751040687, 4.6940911330, 7.8547574382])  # roots of 1 + cos(bL) cosh(bL) = 0


def _exact(length=0.5, width=0.04, thickness=0.008, e=210e9, rho=7850):
    ei = e * width * thickness**3 / 12
    return BETA_L**2 / (2 * np.pi) * np.sqrt(ei / (rho * width * thickness * length**4))


def _fe(n, **kw):
    b = cantilever_beam(0.5, 0.04, 0.008, 210e9, 7850, n_elements=n, **kw)
    return np.sqrt(eigh(b.stiffness, b.mass, eigvals_only=True)) / (2 * np.pi)


def test_cantilever_frequencies_and_convergence_order():
    exact = _exact()
    assert exact[0] == pytest.approx(26.74, abs=0.01)  # seed 004 beam without the device mass
    ns = np.array([4, 8, 16])
    err = np.array([_fe(n)[:3] / exact - 1 for n in ns])
    assert np.all(err > 0)  # consistent mass, conforming elements: upper bounds (Rayleigh-Ritz)
    # cubic Hermite elements: eigenvalue error O(h^(2(p+1-m))) = O(h^4), frequency error alike
    for mode in (1, 2):  # the order fitted on the three meshes, within the fit's own 95 % interval
        assert_order(1.0 / ns, err[:, mode], 4.0)
    assert abs(err[-1, 0]) < 1e-6


def test_tip_mass_and_compliant_clamp():
    # a tip mass lowers the first frequency; Rayleigh with the static deflection shape gives an upper
    # bound f = (1/2pi) sqrt(3EI/L^3 / (m_t + 33/140 m_beam)) (within 1 % for these masses)
    ei = 210e9 * 0.04 * 0.008**3 / 12
    m_beam = 7850 * 0.04 * 0.008 * 0.5
    for m_t in (0.0725, 1.0):
        f = _fe(20, tip_mass=m_t)[0]
        rayleigh = np.sqrt(3 * ei / 0.5**3 / (m_t + 33 / 140 * m_beam)) / (2 * np.pi)
        assert f <= rayleigh * (1 + 1e-9) and f > 0.99 * rayleigh
    # a stiff rotational clamp tends to the rigid one: the clamp rotation adds a compliance of relative
    # size ~ EI / (k_r L) to the beam's (a few times that on the frequencies; 10x as the bound)
    k_r = 1e10
    assert np.allclose(_fe(20, clamp_rotational_stiffness=k_r)[:3], _fe(20)[:3], rtol=10 * ei / (k_r * 0.5))
    assert _fe(20, clamp_rotational_stiffness=1e3)[0] < _fe(20)[0]


def test_tip_mass_against_the_exact_frequency_equation():
    """First frequency of a cantilever with a tip point mass: the exact Euler-Bernoulli root.

    With ``r = m_t / m_beam`` the frequency equation is
    ``1 + cos(bL) cosh(bL) + r bL (cos(bL) sinh(bL) - sin(bL) cosh(bL)) = 0`` (e.g. Blevins, Formulas for
    natural frequency and mode shape, table 8-8); its first root lies below the bare beam's 1.8751.
    """
    from scipy.optimize import brentq

    ei = 210e9 * 0.04 * 0.008**3 / 12
    m_beam = 7850 * 0.04 * 0.008 * 0.5
    for m_t in (0.0725, 1.0):  # 0.0725 kg: the seed 004 configs (their free beam at 24.09 Hz)
        r = m_t / m_beam

        def g(b, r=r):
            return 1 + np.cos(b) * np.cosh(b) + r * b * (np.cos(b) * np.sinh(b) - np.sin(b) * np.cosh(b))

        bl = brentq(g, 0.5, BETA_L[0], xtol=1e-14)
        exact = bl**2 / (2 * np.pi) * np.sqrt(ei / (m_beam / 0.5 * 0.5**4))
        # 20 Hermite elements: the bare beam's error is < 1e-6 at 16 (previous test) and falls as h^4;
        # the point mass adds no discretisation error (it sits on a node)
        assert _fe(20, tip_mass=m_t)[0] == pytest.approx(exact, rel=1e-6)


def test_points_become_nodes():
    b = cantilever_beam(0.5, 0.04, 0.008, 210e9, 7850, n_elements=20, points=(0.35, 0.3333))
    assert 0.3333 in b.node_x and 0.35 in b.node_x
    with pytest.raises(ConfigError, match="no free beam node"):
        b.transverse_dof(0.123)


def test_seed_configs_load():
    m1 = load_damper_model(CONFIGS / "seed004_model1.yaml")
    m2 = load_damper_model(CONFIGS / "seed004_model2.yaml")
    assert (m1.friction_coefficient, m1.contact_stiffness) == (0.45, 3.9e5)
    assert (m2.friction_coefficient, m2.contact_stiffness) == (0.66, 3e7)
    assert m1.modal.natural_frequencies[0] / (2 * np.pi) == pytest.approx(24.0, abs=0.1)


def _cfg():
    import yaml

    return yaml.safe_load((CONFIGS / "seed004_model1.yaml").read_text())


@pytest.mark.parametrize("path, value, match", [
    (("contact", "position"), "0.7 m", "not on the beam"),
    (("beam", "length"), "0.5 kg", "kg"),
    (("contact", "stiffness"), "3.9e5", "no unit"),
    (("harmonic_balance", "harmonics"), [1, 2], "odd"),
    (("beam", "n_elements"), 1, "n_elements"),
])
def test_config_errors_name_the_key(path, value, match):
    cfg = _cfg()
    cfg[path[0]][path[1]] = value
    with pytest.raises(ConfigError, match=match) as err:
        damper_model_from_dict(cfg)
    assert ".".join(path) in str(err.value)


@pytest.mark.parametrize("path", [("beam", "tip_mas"), ("contact", "stifness"), ("harmonic_balance", "harmonic"),
                                  ("frequency_rang",)])
def test_config_unknown_keys_are_errors(path):
    # a misspelt optional key (beam.tip_mas) would otherwise silently fall back to its default
    cfg = _cfg()
    node = cfg
    for k in path[:-1]:
        node = node[k]
    node[path[-1]] = "1 kg"
    with pytest.raises(ConfigError, match="unknown key; allowed") as err:
        damper_model_from_dict(cfg)
    assert ".".join(path) in str(err.value)


def test_config_file_errors(tmp_path):
    p = tmp_path / "m.yaml"
    p.write_text("beam: [1, 2\n")
    with pytest.raises(ConfigError, match="not valid YAML") as err:
        load_damper_model(p)
    assert str(p) in str(err.value)
    p.write_bytes(b"name: \xff\n")
    with pytest.raises(ConfigError, match="not UTF-8 text"):
        load_damper_model(p)
