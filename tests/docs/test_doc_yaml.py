"""Every YAML example in README.md and docs/*.md loads through the config loader of its kind.

Fenced blocks tagged ``yaml``/``yml`` (found by tests/docs/test_doc_commands.py's parser). A block with alternatives
separated by a line starting ``# or`` is checked per alternative. The kind is found by the keys:

- ``fivid-rig-profile`` -> ``fivid.io.rig_profile.rig_profile_from_mapping``;
- ``fivid-study`` -> ``fivid.study.config.load_study``;
- ``fivid-run`` -> ``fivid.pipeline.config.load_run_config`` (from a file in a directory with the repository's
  ``configs/``, ``pipelines/``, ``sample_data/``);
- top-level keys of a model config (``bodies``, ``damping``, ``contacts``, ``motions``, ...): a fragment of a
  model. It is merged into a shipped model (``FRAGMENTS`` names which, per fragment; default
  ``configs/models/triboair_coarse.yaml``): ``bodies`` and ``materials`` entry by entry, any other key
  replaced; the model is then built by ``fivid.fe.build.build_model`` from a file in a directory whose
  ``profiles/`` is ``configs/models/profiles/`` (so relative profile paths resolve as in ``configs/models``);
- a fragment of a smaller part (an edge selector, a body's ``grading``, a contact's ``rigid`` master): placed
  into the base at the path ``FRAGMENTS`` names;
- ``parameters`` and ``modes``: a targets file of ``fivid update`` -> ``fivid.updating.load_targets``.

A block of no known kind fails the test: add its loader here.
"""

from __future__ import annotations

import copy
import re
from pathlib import Path

import pytest
import yaml
from tests.docs.test_doc_commands import ROOT, all_blocks

YAML_LANGS = {"yaml", "yml"}
COARSE = "configs/models/triboair_coarse.yaml"
RING = "configs/models/ring.yaml"

#: fragment, by its signature (its first two lines, comments dropped, joined by " / "; a key matches the
#: signatures it starts) -> (base configs merged in order, keys dropped from the base, where the fragment goes:
#: None for a top-level fragment, else a path of keys/indices). A base under configs/rigs/ is a rig profile.
FRAGMENTS: dict[str, tuple[tuple[str, ...], tuple[str, ...], tuple | None]] = {
    # a quarter ring: the base's supports are off it, and nothing holds it on the expanding cylinder
    "bodies: / ring:": ((RING,), ("springs", "sensors", "contacts"), None),
    "bodies: / lower:": (("configs/models/triboair_rough.yaml",), (), None),
    "grading: {edge: top, ratio: 1.2}": ((COARSE,), (), ("bodies", "lower")),
    "{body: upper, edge: bottom, x: [90 mm, 100 mm]}": ((COARSE,), (), ("contacts", 0, "slave")),
    "loads: / - {name: expansion, body: ring": ((COARSE, RING), ("springs", "sensors", "contacts"), None),
    "rigid:": ((RING,), (), ("contacts", 0)),
    "acceleration: / - {name:": (("configs/rigs/labdaq.yaml",), (), ("columns",)),
}
MODEL_KEYS = {"name", "description", "plane", "materials", "bodies", "damping", "contacts", "motions",
              "point_masses", "springs", "sensors", "reactions", "loads", "prestress"}


def yaml_examples() -> list[tuple[str, str]]:
    """``(doc:line, text)`` per alternative of every YAML block."""
    out = []
    for block in all_blocks():
        if block.lang not in YAML_LANGS:
            continue
        parts = re.split(r"(?m)^\s*# or\b.*\n", block.text)
        for k, part in enumerate(parts):
            out.append((f"{block.doc}:{block.line}" + (f" (alternative {k + 1})" if len(parts) > 1 else ""), part))
    return out


def _signature(text: str) -> str:
    lines = [re.sub(r"\s+#.*$", "", line).strip() for line in text.splitlines()]
    return " / ".join([line for line in lines if line and not line.startswith("#")][:2])


def _fragment(text: str):
    """``(bases, drop, place)`` of a fragment listed in FRAGMENTS, else None."""
    signature = _signature(text)
    return next((v for k, v in FRAGMENTS.items() if signature.startswith(k)), None)


def _merge(base: dict, fragment: dict) -> dict:
    out = copy.deepcopy(base)
    for key, value in fragment.items():
        if key in ("bodies", "materials") and isinstance(value, dict):  # entry by entry, key by key
            for name, entry in value.items():
                if isinstance(entry, dict) and isinstance(out.get(key, {}).get(name), dict):
                    out[key][name].update(copy.deepcopy(entry))
                else:
                    out.setdefault(key, {})[name] = copy.deepcopy(entry)
        else:
            out[key] = copy.deepcopy(value)
    return out


def _place(model: dict, path: tuple, fragment) -> None:
    node = model
    for step in path[:-1]:
        node = node[step]
    last = path[-1]
    if isinstance(fragment, dict) and isinstance(node[last], dict) and last != "slave":  # keys into an entry
        if "rigid" in fragment:
            node[last].pop("master", None)
        node[last].update(fragment)
    else:
        node[last] = fragment


def _model(where: str, text: str, tmp_path: Path):
    from fivid.fe.build import build_model

    bases, drop, place = _fragment(text) or ((COARSE,), (), None)
    model: dict = {}
    for base in bases:
        model = _merge(model, yaml.safe_load((ROOT / base).read_text(encoding="utf-8")))
    for key in drop:
        model.pop(key, None)
    fragment = yaml.safe_load(text)
    if place is None:
        model = _merge(model, fragment)
    else:
        _place(model, place, fragment)
    (tmp_path / "profiles").symlink_to(ROOT / "configs" / "models" / "profiles", target_is_directory=True)
    path = tmp_path / "model.yaml"
    path.write_text(yaml.safe_dump(model, sort_keys=False), encoding="utf-8")
    return build_model(path)


def load_example(where: str, text: str, tmp_path: Path):
    """Load one YAML example with its kind's loader; return what the loader returns."""
    data = yaml.safe_load(text)
    if isinstance(data, dict) and "fivid-rig-profile" in data:
        from fivid.io.rig_profile import rig_profile_from_mapping

        return rig_profile_from_mapping(data, path=where)
    if isinstance(data, dict) and "fivid-study" in data:
        from fivid.study.config import load_study

        return load_study(data)
    if isinstance(data, dict) and "fivid-run" in data:
        from fivid.pipeline.config import load_run_config

        for name in ("configs", "pipelines", "sample_data"):
            (tmp_path / name).symlink_to(ROOT / name, target_is_directory=True)
        path = tmp_path / "run.yaml"  # paths in a run config are relative to the config file
        path.write_text(text, encoding="utf-8")
        return load_run_config(path)
    if isinstance(data, dict) and {"parameters", "modes"} <= set(data):  # a targets file of fivid update
        from fivid.updating import load_targets

        path = tmp_path / "targets.yaml"
        path.write_text(text, encoding="utf-8")
        return load_targets(path)
    fragment = _fragment(text)
    if fragment and fragment[0][0].startswith("configs/rigs/"):
        from fivid.io.rig_profile import rig_profile_from_mapping

        profile = yaml.safe_load((ROOT / fragment[0][0]).read_text(encoding="utf-8"))
        _place(profile, fragment[2], data)
        return rig_profile_from_mapping(profile, path=where)
    if (isinstance(data, dict) and set(data) <= MODEL_KEYS) or fragment:
        return _model(where, text, tmp_path)
    raise AssertionError(f"{where}: a YAML example of no known kind (keys {sorted(data) if isinstance(data, dict) else data!r})"
                         "; add its loader to tests/docs/test_doc_yaml.py")


EXAMPLES = yaml_examples()


def test_the_docs_have_yaml_examples():
    assert len(EXAMPLES) >= 15, [w for w, _ in EXAMPLES]


@pytest.mark.parametrize("where,text", EXAMPLES, ids=[w for w, _ in EXAMPLES])
def test_yaml_example_loads(where, text, tmp_path):
    assert load_example(where, text, tmp_path) is not None


def test_a_wrong_example_is_caught(tmp_path):
    """The check can fail: a model fragment with a key the loader refuses, an example of no known kind."""
    from fivid.errors import ConfigError

    with pytest.raises(ConfigError):
        load_example("x.md:1", "bodies:\n  upper:\n    divisions: [120, 20]\n    colour: red\n", tmp_path)
    with pytest.raises(AssertionError, match="no known kind"):
        load_example("x.md:1", "whatever: 1\n", tmp_path)
