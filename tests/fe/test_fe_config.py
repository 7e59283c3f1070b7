"""Model config -> Model: the shipped configs build, and every kind of bad input is a ConfigError naming the key path."""

import copy
from pathlib import Path

import numpy as np
import pytest

from fivid.errors import ConfigError
from fivid.fe import load_model
from tests.helpers.config_errors import assert_config_error

ROOT = Path(__file__).resolve().parents[2]
COARSE = ROOT / "configs" / "models" / "triboair_coarse.yaml"


def _beam(**body):
    """A one-body cantilever mapping (100 x 10 mm steel), with body keys overridden."""
    b = {"corners": [[0, 0], ["100 mm", 0], ["100 mm", "10 mm"], [0, "10 mm"]], "divisions": [10, 2],
         "material": {"E": "210 GPa", "nu": 0.3, "rho": "7850 kg/m^3"}, "thickness": "10 mm", "clamp": ["left"]}
    b.update(body)
    return {"bodies": {"beam": b}}


def test_default_rig_builds_with_design_values():
    m = load_model(ROOT / "configs" / "models" / "triboair.yaml")
    lower, upper = m.block("lower"), m.block("upper")
    assert (lower.nx, lower.ny, upper.nx, upper.ny) == (200, 20, 120, 20)  # 0.5 mm mesh (DESIGN §8)
    assert m.n_nodes == 201 * 21 + 121 * 21 and m.n_dofs == 2 * m.n_nodes
    assert lower.material.E == pytest.approx(210e9) and lower.material.rho == pytest.approx(7850.0)
    assert upper.thickness == pytest.approx(0.01)
    # DESIGN §8's 0.5 % at 1 kHz and 1 % at 10 kHz (classic Rayleigh: alpha ~ 50.8, beta ~ 3.05e-7), held exactly
    # by the band-limited scheme the default rig uses (cut-off 60 kHz)
    from fivid.fe.damping import damping_ratio

    assert m.damping_cutoff == pytest.approx(6e4)
    np.testing.assert_allclose(damping_ratio([1e3, 1e4], m.rayleigh_alpha, m.rayleigh_beta, m.damping_cutoff),
                               [0.005, 0.01], rtol=1e-10)
    c = m.contacts[0]
    xs = m.coords[c.slave_nodes, 0]
    assert xs.min() == pytest.approx(0.09) and xs.max() == pytest.approx(0.10)  # last 10 mm: 21 nodes at 0.5 mm
    assert c.slave_nodes.size == 21 and c.master_nodes.size == 201
    assert np.allclose(m.coords[c.slave_nodes, 1], 0.01) and np.allclose(m.coords[c.master_nodes, 1], 0.01)
    assert m.motion("base").component == 0 and m.motion("base").amplitude == pytest.approx(0.01)
    assert m.motion("load").component == 1 and m.motion("load").kind == "displacement"
    s = m.sensors[0]
    assert np.allclose(m.coords[s.node], [0.12, 0.02]) and np.allclose(s.direction, [0, 1])
    assert set(m.reactions[0].nodes) == set(upper.edge_nodes("right"))
    assert "sha256:" in m.source and len(m.sha256) == 64


def test_numbering_and_edges_follow_the_documented_convention():
    m = load_model(_beam(divisions=[3, 2]))
    b = m.blocks[0]
    assert b.node(1, 2) == 2 * 4 + 1
    assert list(b.edge_nodes("bottom")) == [0, 1, 2, 3]
    assert list(b.edge_nodes("right")) == [3, 7, 11]
    assert list(b.edge_nodes("top")) == [11, 10, 9, 8]
    assert list(b.edge_nodes("left")) == [8, 4, 0]
    assert np.allclose(m.coords[11], [0.1, 0.01])
    assert list(m.fixed_dofs) == [0, 1, 8, 9, 16, 17]
    assert b.is_rectangular_grid()
    assert np.array_equal(b.element_dofs()[..., 0::2] // 2, b.element_nodes())
    assert np.array_equal(b.element_dofs()[..., 1::2], 2 * b.element_nodes() + 1)
    trapezoid = load_model(_beam(corners=[[0, 0], [0.1, 0], [0.08, 0.01], [0, 0.01]])).blocks[0]
    assert not trapezoid.is_rectangular_grid()


def test_quantities_with_units_equal_si_numbers():
    a = load_model(_beam())
    b = load_model(_beam(corners=[[0, 0], [0.1, 0], [0.1, 0.01], [0, 0.01]], thickness=0.01,
                         material={"E": 210e9, "nu": 0.3, "rho": 7850}))
    assert np.array_equal(a.coords, b.coords) and a.blocks[0].material == b.blocks[0].material


def test_error_in_a_file_names_file_line_and_key(tmp_path):
    text = COARSE.read_text().replace("nu: 0.3", "nu: 0.5")
    p = tmp_path / "bad.yaml"
    p.write_text(text)
    with pytest.raises(ConfigError) as e:
        load_model(p)
    err = e.value
    assert err.key == "materials.steel.nu" and err.file == str(p)
    assert err.line == 1 + text.splitlines().index(next(ln for ln in text.splitlines() if "nu: 0.5" in ln))
    assert "0.5" in str(err) and "nu < 0.5" in str(err)


BAD = [
    # (description, mutation of the beam mapping, expected key path, words the message must contain)
    ("unknown top key", lambda c: c.update(bodys={}), "bodys", ["unknown key", "bodies"]),
    ("unknown body key", lambda c: c["bodies"]["beam"].update(thicknes=0.01), "bodies.beam.thicknes", ["allowed"]),
    ("clockwise corners", lambda c: c["bodies"]["beam"].update(corners=[[0, 0], [0, 0.01], [0.1, 0.01], [0.1, 0]]),
     "bodies.beam.corners", ["clockwise"]),
    ("non-convex corners", lambda c: c["bodies"]["beam"].update(corners=[[0, 0], [0.1, 0], [0.02, 0.002], [0, 0.01]]),
     "bodies.beam.corners", ["not convex"]),
    ("zero divisions", lambda c: c["bodies"]["beam"].update(divisions=[10, 0]), "bodies.beam.divisions[1]", [">= 1"]),
    ("nu = 0.5", lambda c: c["bodies"]["beam"]["material"].update(nu=0.5), "bodies.beam.material.nu", ["nu < 0.5"]),
    ("nu > 0.5", lambda c: c["bodies"]["beam"]["material"].update(nu=0.7), "bodies.beam.material.nu", ["nu < 0.5"]),
    ("missing material", lambda c: c["bodies"]["beam"].pop("material"), "bodies.beam.material", ["required"]),
    ("material without rho", lambda c: c["bodies"]["beam"]["material"].pop("rho"), "bodies.beam.material.rho",
     ["required"]),
    ("undefined named material", lambda c: c["bodies"]["beam"].update(material="steel"), "bodies.beam.material",
     ["not defined"]),
    ("wrong unit", lambda c: c["bodies"]["beam"].update(thickness="10 kg"), "bodies.beam.thickness", ["m"]),
    ("unknown clamp edge", lambda c: c["bodies"]["beam"].update(clamp=["front"]), "bodies.beam.clamp[0]",
     ["bottom", "left"]),
    ("contact edge does not exist", lambda c: c.update(contacts=[{"name": "c", "slave": {"body": "beam", "edge": "side"},
                                                                   "master": {"body": "base", "edge": "top"}, "mu": 0.3}]),
     "contacts[0].slave.edge", ["right", "top"]),
    ("contact body does not exist", lambda c: c.update(contacts=[{"name": "c", "slave": {"body": "beam", "edge": "top"},
                                                                   "master": {"body": "nope", "edge": "top"}, "mu": 0.3}]),
     "contacts[0].master.body", ["beam"]),
    ("contact range selects nothing", lambda c: c.update(contacts=[{"name": "c", "slave": {"body": "beam", "edge": "top", "x": [1, 2]},
                                                                     "master": {"body": "beam", "edge": "bottom"}, "mu": 0.3}]),
     "contacts[0].slave.x", ["no node"]),
    ("sensor off the body", lambda c: c.update(sensors=[{"name": "a", "body": "beam", "at": [0.5, 0.0], "direction": "y"}]),
     "sensors[0].at", ["not on body"]),
    ("reaction on free nodes", lambda c: c.update(reactions=[{"name": "r", "body": "beam", "edge": "right",
                                                              "tangential": "x", "normal": "y"}]),
     "reactions[0]", ["constrained"]),
    ("bad plane", lambda c: c.update(plane="stres"), "plane", ["stress", "strain"]),
    ("damping both ways", lambda c: c.update(damping={"alpha": 1, "ratios": []}), "damping", ["either"]),
    ("motion kind", lambda c: c.update(motions=[{"name": "m", "body": "beam", "edge": "left", "component": "x",
                                                 "kind": "force", "amplitude": 1}]), "motions[0].kind", ["velocity"]),
]


def test_missing_file_and_bad_yaml(tmp_path):
    with pytest.raises(ConfigError, match="does not exist"):
        load_model(tmp_path / "absent.yaml")
    p = tmp_path / "broken.yaml"
    p.write_text("bodies:\n  a: [1, 2\n")
    with pytest.raises(ConfigError) as e:
        load_model(p)
    assert e.value.line is not None and "YAML" in str(e.value)


INNER = [
    # the inner sections are typed by the one schema: the same format as the top level, at the inner key
    ("material as a number", lambda c: c["bodies"]["beam"].update(material=3), "bodies.beam.material",
     ["expected a mapping", "3"]),
    ("sensor direction", lambda c: c.update(sensors=[{"name": "a", "body": "beam", "at": [0.1, 0.01],
                                                      "direction": "z"}]), "sensors[0].direction", ["'x'", "'-y'"]),
    ("motion amplitude unit follows its kind",
     lambda c: c.update(motions=[{"name": "m", "body": "beam", "edge": "left", "component": "x", "kind": "velocity",
                                  "amplitude": "1 mm"}]), "motions[0].amplitude", ["m s-1", "1 mm"]),
    ("power-law coefficient unit follows its exponent",
     lambda c: c["bodies"].update(base=copy.deepcopy(c["bodies"]["beam"])) or c.update(contacts=[
         {"name": "c", "slave": {"body": "beam", "edge": "top"}, "master": {"body": "base", "edge": "bottom"},
          "mu": 0.3, "normal": {"law": "power", "coefficient": "1 Pa", "exponent": 1.5}}]),
     "contacts[0].normal.coefficient", ["Pa / m**1.5", "1 Pa"]),
    ("a parameter of another law", lambda c: c["bodies"].update(base=copy.deepcopy(c["bodies"]["beam"])) or c.update(
        contacts=[{"name": "c", "slave": {"body": "beam", "edge": "top"}, "master": {"body": "base", "edge": "bottom"},
                   "mu": 0.3, "normal": {"law": "linear", "stiffness": 1e12, "exponent": 2}}]),
     "contacts[0].normal.exponent", ["not a parameter of the linear law", "stiffness"]),
    ("duplicate sensor names", lambda c: c.update(sensors=[{"name": "a", "body": "beam", "at": [0.1, 0.01],
                                                            "direction": "y"}] * 2), "sensors", ["duplicate", "'a'"]),
    ("divisions as a tuple of a bool", lambda c: c["bodies"]["beam"].update(divisions=(True, 2)),
     "bodies.beam.divisions[0]", ["integer", "True"]),
]


@pytest.mark.parametrize("what, mutate, key, words", BAD + INNER, ids=[b[0] for b in BAD + INNER])
def test_bad_input_names_key_path_and_what_is_allowed(what, mutate, key, words):
    """Top-level and inner sections (typed by the one schema) give the same error format: the key path, the
    value given and what is allowed."""
    cfg = copy.deepcopy(_beam())
    mutate(cfg)
    assert_config_error(cfg, key, words)


def test_inner_key_errors_in_a_file_name_their_line(tmp_path):
    """An unknown key inside a contact item: the file's line of that key, and the keys a contact takes."""
    text = COARSE.read_text()
    lines = text.splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.strip().startswith("mu:"))
    indent = lines[i][:len(lines[i]) - len(lines[i].lstrip())]
    lines.insert(i + 1, f"{indent}mu_kinetic: 0.2")
    p = tmp_path / "typo.yaml"
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(ConfigError) as e:
        load_model(p)
    assert e.value.key.endswith(".mu_kinetic") and e.value.line == i + 2 and e.value.file == str(p)
    assert "mu_static" in str(e.value) and "stribeck_velocity" in str(e.value)
