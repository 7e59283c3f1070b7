"""One config layer (issue 19 "one config layer", issue 20 item 3): one YAML loader with line numbers, pydantic
models with pint quantities, one error format (file:line: key 'path': expected ..., found ...), and JSON Schemas
published in docs/schema/ that cannot drift from the models."""

import json
import math
import textwrap
from pathlib import Path

import pytest

from fivid.config_layer import ConfigModel, Quantity, from_mapping, read_yaml, validate
from fivid.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]
SCHEMA_DIR = ROOT / "docs" / "schema"


def _write(path, text):
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


# ---- the loader -------------------------------------------------------------------------------------------


def test_the_loader_keeps_the_line_of_every_key_path(tmp_path):
    path = _write(tmp_path / "c.yaml", """\
        # a comment
        a:
          b: 1
          c: [x,
              y]
        d:
          - {e: 2}
          - f: 3
        """)
    src = read_yaml(path)
    assert src.data == {"a": {"b": 1, "c": ["x", "y"]}, "d": [{"e": 2}, {"f": 3}]}
    assert {k: src.lines[k] for k in ("a", "a.b", "a.c", "a.c[1]", "d", "d[0].e", "d[1].f")} == {
        "a": 2, "a.b": 3, "a.c": 4, "a.c[1]": 5, "d": 6, "d[0].e": 7, "d[1].f": 8}
    # a key that is not in the file (a required one left out) is reported at its nearest parent
    assert src.line("d[1].g") == 8 and src.line("a.missing.deeper") == 2


@pytest.mark.parametrize("content, words", [
    (b"a: [1, 2\nb: 3\n", "not valid YAML"),
    (b"a: 1\nb: \xff\n", "not UTF-8 text (byte 0xff at offset 8)"),
    (b"", "is empty"),
    (b"- 1\n- 2\n", "must be a YAML mapping"),
])
def test_unreadable_files_are_one_line_config_errors(tmp_path, content, words):
    path = tmp_path / "bad.yaml"
    path.write_bytes(content)
    with pytest.raises(ConfigError) as info:
        read_yaml(path, "config")
    assert words in str(info.value) and "\n" not in str(info.value) and info.value.file == str(path)
    if words != "is empty":
        assert info.value.line is not None


# ---- quantities and models --------------------------------------------------------------------------------


class _Demo(ConfigModel):
    velocity: Quantity("m s-1", positive=True)
    length: Quantity("m", bare_is_si=True) = 1.0
    ratio: Quantity("1") = 0.5
    count: int = 3


@pytest.mark.parametrize("given, field, expected", [
    ({"velocity": "10 mm/s"}, "velocity", 0.01),
    ({"velocity": "36 km/h"}, "velocity", 10.0),
    ({"velocity": "1 m/s", "length": 0.25}, "length", 0.25),  # a bare number is SI where the model says so
    ({"velocity": "1 m/s", "length": "25 cm"}, "length", 0.25),
    ({"velocity": "1 m/s", "ratio": 0.3}, "ratio", 0.3),  # dimensionless: a bare number is its value
    ({"velocity": "1 m/s"}, "count", 3),
])
def test_quantities_are_si_floats(given, field, expected):
    assert getattr(validate(_Demo, from_mapping(given)), field) == pytest.approx(expected, rel=1e-15)


@pytest.mark.parametrize("given, key, words", [
    ({"velocity": "10 N"}, "velocity", ["expected a positive quantity in 'm s-1'", "found '10 N'", "not compatible"]),
    ({"velocity": 10}, "velocity", ["found 10", "has no unit"]),  # ambiguous: 10 m/s or 10 mm/s?
    ({"velocity": "-1 m/s"}, "velocity", ["(> 0)", "found '-1 m/s'"]),
    ({"velocity": "1 m/s", "count": "3"}, "count", ["expected an integer", "found str '3'"]),  # no coercion
    ({"velocity": "1 m/s", "count": True}, "count", ["expected an integer", "found bool True"]),
    ({"velocity": "1 m/s", "lenght": 1}, "lenght", ["unknown key; allowed: count, length, ratio, velocity",
                                                    "did you mean 'length'?"]),
    ({}, "velocity", ["is required (missing)"]),
])
def test_model_errors_name_the_key_what_is_expected_and_what_was_found(given, key, words):
    with pytest.raises(ConfigError) as info:
        validate(_Demo, from_mapping(given))
    assert info.value.key == key, str(info.value)
    for w in words:
        assert w in info.value.message, str(info.value)


def test_every_problem_is_listed_the_first_leads(tmp_path):
    path = _write(tmp_path / "c.yaml", "velocity: 2 kg\nlength: 3 s\ncount: x\n")
    with pytest.raises(ConfigError) as info:
        validate(_Demo, read_yaml(path))
    text = str(info.value)
    assert text.startswith(f"{path}:1: key 'velocity': expected a positive quantity")
    assert "(and 2 more: key 'length' (line 2): expected a quantity in 'm'" in text
    assert "key 'count' (line 3): expected an integer, found str 'x')" in text


# ---- every kind of config: one error format ---------------------------------------------------------------

_FORMAT_CASES = [
    # (kind, loader, file text with one bad value, key, line, words of "expected ..." / found)
    ("pipeline", "fivid.pipeline.config:load_recipe", "fivid-pipeline: 1\nstages:\n  - ingest\n  - identfy\n",
     "stages[1]", 4, ["expected one of ingest, identify", "'identfy'"]),
    ("damper", "fivid.damper.model:load_damper_model",
     (ROOT / "configs/dampers/seed004_model1.yaml").read_text().replace("stiffness: 3.9e5 N/m", "stiffness: 3.9e5 N"),
     "contact.stiffness", None, ["expected a positive quantity in 'N m-1'", "found '3.9e5 N'"]),
    ("rig", "fivid.io.rig_profile:load_rig_profile",
     (ROOT / "configs/rigs/labdaq.yaml").read_text().replace('decimal: ","', 'decimal: ":"'),
     "csv.decimal", None, ["expected one of '.' or ','", "found str ':'"]),
    ("model", "fivid.fe:load_model",
     (ROOT / "configs/models/triboair_coarse.yaml").read_text().replace("plane: stress", "plane: stres"),
     "plane", None, ["expected one of 'stress' or 'strain'", "found str 'stres'"]),
    ("study", "fivid.study:load_study",
     (ROOT / "configs/studies/hoffmann_mu_sweep.yaml").read_text().replace("nperseg: 2048", "nperseg: 8"),
     "points.psd.nperseg", None, ["expected a value >= 16", "found int 8"]),
]


@pytest.mark.parametrize("kind, loader, text, key, line, words", _FORMAT_CASES, ids=[c[0] for c in _FORMAT_CASES])
def test_every_kind_of_config_reports_file_line_key_expected_found(tmp_path, kind, loader, text, key, line, words):
    import importlib

    module, name = loader.split(":")
    path = tmp_path / f"{kind}.yaml"
    path.write_text(text, encoding="utf-8")
    if line is None:  # the line of the key in the file as written
        leaf = key.rsplit(".", 1)[-1]
        line = 1 + next(i for i, ln in enumerate(text.splitlines()) if ln.strip().startswith(f"{leaf}:")
                        or f" {leaf}:" in ln or f"{{{leaf}:" in ln)
    with pytest.raises(ConfigError) as info:
        getattr(importlib.import_module(module), name)(path)
    err = info.value
    assert (err.file, err.line, err.key) == (str(path), line, key), str(err)
    assert str(err).startswith(f"{path}:{line}: key '{key}': ")
    for w in words:
        assert w in err.message, str(err)


# ---- published JSON Schemas and the shipped configs -------------------------------------------------------


def _kinds():
    from fivid.cli.commands.schema import KINDS

    return list(KINDS)


@pytest.mark.parametrize("kind", _kinds())
def test_published_schema_is_what_the_models_generate(kind):
    """docs/schema/*.json are generated (fivid schema --write docs/schema): they cannot drift from the models."""
    from fivid.cli.commands.schema import schema_text

    published = SCHEMA_DIR / f"{kind}.schema.json"
    assert published.is_file(), f"run: python -m fivid schema --write docs/schema"
    assert published.read_text(encoding="utf-8") == schema_text(kind), "regenerate: fivid schema --write docs/schema"


def _shipped():
    out = [("pipeline", p) for p in sorted((ROOT / "pipelines").glob("*.yaml"))]
    for kind, folder in (("run", "runs"), ("rig", "rigs"), ("model", "models"), ("damper", "dampers"),
                         ("study", "studies")):
        out += [(kind, p) for p in sorted((ROOT / "configs" / folder).glob("*.yaml"))]
    return out


SHIPPED = _shipped()


def test_every_config_folder_is_covered():
    folders = {p.parent.name for _, p in SHIPPED}
    assert folders == {"pipelines"} | {d.name for d in (ROOT / "configs").iterdir()
                                       if d.is_dir() and any(d.glob("*.yaml"))}


@pytest.mark.parametrize("kind, path", SHIPPED, ids=[f"{k}:{p.name}" for k, p in SHIPPED])
def test_every_shipped_config_validates_and_matches_its_published_schema(kind, path):
    """Through its loader (the models) and, independently, against the published JSON Schema (jsonschema)."""
    jsonschema = pytest.importorskip("jsonschema")
    from fivid.cli.commands.schema import KINDS

    module, model, _ = KINDS[kind]
    import importlib

    source = read_yaml(path)
    validate(getattr(importlib.import_module(module), model), source)
    schema = json.loads((SCHEMA_DIR / f"{kind}.schema.json").read_text(encoding="utf-8"))
    jsonschema.validate(source.data, schema, cls=jsonschema.Draft202012Validator)


def test_the_schema_rejects_what_the_models_reject():
    """Two independent checkers agree on a typo and a wrong type (the schema is not vacuous)."""
    jsonschema = pytest.importorskip("jsonschema")
    schema = json.loads((SCHEMA_DIR / "damper.schema.json").read_text(encoding="utf-8"))
    good = read_yaml(ROOT / "configs/dampers/seed004_model1.yaml").data
    v = jsonschema.Draft202012Validator(schema)
    assert v.is_valid(good)
    for bad in ({**good, "frequency_rang": ["1 Hz", "2 Hz"]},
                {**good, "beam": {**good["beam"], "n_elements": "20"}},
                {**good, "harmonic_balance": {"harmonics": []}}):
        assert not v.is_valid(bad)
        with pytest.raises(ConfigError):
            validate(__import__("fivid.damper.model", fromlist=["x"]).DamperConfig, from_mapping(bad))


def test_schema_cli(capsys, tmp_path):
    from fivid.cli import main
    from fivid.cli.commands.schema import schema_of

    assert main(["schema", "run"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed == schema_of("run") and printed["properties"]["simulate"]
    assert main(["schema"]) == 2
    assert "KIND" in capsys.readouterr().err
    assert main(["schema", "--write", str(tmp_path)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(f"{k}.schema.json" for k in _kinds())


def test_infinite_defaults_are_written_as_inf():
    """JSON has no Infinity: an infinite default (a clamped root) is written in the config's spelling."""
    from fivid.cli.commands.schema import schema_text

    text = schema_text("damper")
    assert "Infinity" not in text and '"default": "inf"' in text
    from fivid.damper.model import DamperConfig

    cfg = validate(DamperConfig, read_yaml(ROOT / "configs/dampers/seed004_model1.yaml"))
    assert cfg.beam.clamp_rotational_stiffness == math.inf


@pytest.mark.parametrize("edit", [
    lambda c: c["bodies"]["upper"].update(thicknes="10 mm"),
    lambda c: c["contacts"][0].update(mu_k=0.3),
    lambda c: c["motions"][0].pop("kind"),
    lambda c: c["sensors"][0].update(body_name="upper"),
])
def test_the_model_schema_describes_the_item_sections(edit):
    """The FE model's inner sections are checked by build_model; their schema (for editors) agrees on keys."""
    import copy

    jsonschema = pytest.importorskip("jsonschema")
    from fivid.fe import load_model

    schema = json.loads((SCHEMA_DIR / "model.schema.json").read_text(encoding="utf-8"))
    cfg = copy.deepcopy(read_yaml(ROOT / "configs/models/triboair_coarse.yaml").data)
    assert jsonschema.Draft202012Validator(schema).is_valid(cfg)
    edit(cfg)
    assert not jsonschema.Draft202012Validator(schema).is_valid(cfg)
    with pytest.raises(ConfigError):
        load_model(cfg)


def test_quantity_at_checks_like_a_quantity_field_and_names_the_key(tmp_path):
    """The public form of a field check, for a value read outside a model (same message as the field)."""
    from fivid.config_layer import quantity_at

    p = tmp_path / "m.yaml"
    p.write_text("bodies:\n  a:\n    thickness: 10 kg\n")
    src = read_yaml(p)
    assert quantity_at(src, "10 mm", "bodies.a.thickness", "m") == pytest.approx(0.01, rel=1e-15)
    assert quantity_at(src, 2, "x", "m") == 2.0  # a bare number is in the units
    with pytest.raises(ConfigError) as e:
        quantity_at(src, src.data["bodies"]["a"]["thickness"], "bodies.a.thickness", "m", positive=True)
    assert e.value.line == 3 and e.value.key == "bodies.a.thickness" and "10 kg" in str(e.value)
