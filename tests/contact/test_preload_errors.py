"""The static preload's singular systems as errors a person can act on (issue 26 item 2).

``rough_pair_short.yaml``'s 5 x 1 mm cut (the roughness tests' base; the shipped file too) keeps the upper body's whole
bottom edge as the slave range: its left end node is driven along x (the carriage) and faces the lower body's
clamped corner, so with friction its tangential constraint ties prescribed dofs only and the preload's bordered
system is singular. That used to escape as numpy's LinAlgError with a traceback; it is a ConfigError naming the
file, the node and the fix, and following the fix makes the same command run.
"""

import copy
from pathlib import Path

import pytest
import yaml

from fivid.errors import ConfigError
from fivid.fe import load_model
from fivid.fe.config import read_config
from fivid.fe.static import preload_state
from tests.helpers.cli import fails

ROOT = Path(__file__).resolve().parents[2]
SHORT = ROOT / "configs" / "models" / "rough_pair_short.yaml"


def _cut(tmp_path, slave_x=None):
    """The 5 x 1 mm cut of rough_pair_short.yaml (20 x 2 elements per body, the sensor moved onto it) as a file."""
    data = copy.deepcopy(read_config(SHORT)[0])
    data["bodies"]["lower"].update(corners=[["0 mm", "0 mm"], ["5 mm", "0 mm"], ["5 mm", "1 mm"], ["0 mm", "1 mm"]],
                                   divisions=[20, 2])
    data["bodies"]["upper"].update(corners=[["0 mm", "1 mm"], ["5 mm", "1 mm"], ["5 mm", "2 mm"], ["0 mm", "2 mm"]],
                                   divisions=[20, 2])
    data["sensors"][0]["at"] = ["2.5 mm", "0 mm"]
    if slave_x:
        data["contacts"][0]["slave"]["x"] = slave_x
    path = tmp_path / "cut.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    return path


def test_singular_preload_names_the_file_the_node_and_the_fix(tmp_path):
    path = _cut(tmp_path)
    with pytest.raises(ConfigError) as info:
        preload_state(load_model(path), None)
    msg = str(info.value)
    assert info.value.file == str(path) and info.value.key == "contacts.interface.slave"
    assert "slave node" in msg and "[0.0, 0.001] m" in msg and "prescribed" in msg and "slave range" in msg


def test_cli_exits_2_without_traceback_and_the_fix_runs(tmp_path, capsys):
    err = fails(capsys, ["modes", str(_cut(tmp_path)), "--contact", "-n", "3"])
    assert "cut.yaml" in err and "contacts.interface.slave" in err
    fixed = _cut(tmp_path, slave_x=["0.125 mm", "4.875 mm"])  # half an element inside both ends, as suggested
    state = preload_state(load_model(fixed), None)
    assert state.normal_load == pytest.approx(0.25, rel=1e-6)  # the 5 kPa dead load on 5 mm x 10 mm, all carried

