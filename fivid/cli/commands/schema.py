"""``fivid schema KIND | --write DIR``: the JSON Schema of a config kind (pipeline, run, rig, model, damper, study)."""

from __future__ import annotations

import sys

__all__ = ["register", "KINDS", "schema_of"]

#: config kind -> (module, pydantic model, what a file of that kind is and where they live)
KINDS = {
    "pipeline": ("fivid.pipeline.config", "RecipeConfig", "pipeline recipe, pipelines/*.yaml"),
    "run": ("fivid.pipeline.config", "RunConfigModel", "run configuration, configs/runs/*.yaml"),
    "rig": ("fivid.io.rig_profile", "RigProfileConfig", "rig profile, configs/rigs/*.yaml"),
    "model": ("fivid.fe.config", "ModelConfig", "FE model config, configs/models/*.yaml"),
    "damper": ("fivid.damper.model", "DamperConfig", "friction-damper model, configs/dampers/*.yaml"),
    "study": ("fivid.study.config", "StudyConfig", "parametric study, configs/studies/*.yaml"),
}

_DESCRIPTION = """\
Print the JSON Schema (draft 2020-12) of a kind of fivid config. Every YAML config fivid reads is
checked by one typed layer (fivid.config_layer); these schemas are generated from it and published
in docs/schema/<kind>.schema.json, so an editor (e.g. VS Code with the YAML extension) completes and
checks configs as they are typed. Quantities are strings with units ('10 mm/s'); the unit a
quantity is converted to is given in 'x-fivid-units'.

kinds:
""" + "\n".join(f"  {k:<9} {v[2]}" for k, v in KINDS.items())

_EPILOG = """\
example:
  fivid schema run > run.schema.json
  fivid schema --write docs/schema        # every kind, as published
  # in a config, for editors:  # yaml-language-server: $schema=../../docs/schema/run.schema.json"""


def schema_of(kind: str) -> dict:
    """The JSON Schema of config ``kind`` (a key of :data:`KINDS`)."""
    import importlib

    from fivid.config_layer import json_schema

    module, model, what = KINDS[kind]
    return json_schema(getattr(importlib.import_module(module), model), title=f"fivid {what.split(',')[0]}")


def schema_text(kind: str) -> str:
    """The schema as published: JSON, 2-space indent, a final newline."""
    import json

    return json.dumps(schema_of(kind), indent=2, ensure_ascii=False, allow_nan=False) + "\n"


def register(subparsers) -> None:
    """Add the ``schema`` sub-command."""
    import argparse

    p = subparsers.add_parser("schema", help="JSON Schema of a config kind (for editors and checks)",
                              description=_DESCRIPTION, epilog=_EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("kind", nargs="?", choices=list(KINDS), metavar="KIND",
                   help=f"config kind: {', '.join(KINDS)}")
    p.add_argument("--write", metavar="DIR", help="write DIR/<kind>.schema.json for every kind (overwrites)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``fivid schema``."""
    from pathlib import Path

    from fivid.errors import FividError
    from fivid.storage import write_text

    if (args.kind is None) == (args.write is None):
        raise FividError("give a KIND to print, or --write DIR for every kind (not both)", key="KIND")
    if args.kind is not None:
        sys.stdout.write(schema_text(args.kind))
        return 0
    folder = Path(args.write)
    folder.mkdir(parents=True, exist_ok=True)
    for kind in KINDS:
        write_text(folder / f"{kind}.schema.json", schema_text(kind), overwrite=True)
        print(folder / f"{kind}.schema.json")
    return 0
