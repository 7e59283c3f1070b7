"""``fivid modes MODEL.yaml [-n N] [--json] [-o MODES.nc]``: natural frequencies and mode shapes of a model."""

from __future__ import annotations

import sys

__all__ = ["register"]


def register(subparsers) -> None:
    """Add the ``modes`` sub-command."""
    p = subparsers.add_parser(
        "modes",
        help="natural frequencies and mode shapes of a model config (sparse shift-invert)",
        description="Modal analysis of a finite-element model config (configs/models/*.yaml): the lowest N "
        "natural frequencies with clamps and imposed motions eliminated, by shift-invert Lanczos. "
        "Mode shapes can be written to netCDF.",
    )
    p.add_argument("model", metavar="MODEL.yaml", help="model config (see docs/model-config.md)")
    p.add_argument("-n", "--n-modes", type=int, default=30, metavar="N", help="number of modes (default 30)")
    p.add_argument("--json", action="store_true", help='print {"frequencies_hz": [...], ...} as JSON')
    p.add_argument("-o", "--output", metavar="MODES.nc", help="write frequencies and mode shapes to netCDF")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument("--mass", choices=("consistent", "lumped"), default="consistent",
                   help="mass matrix (default consistent; lumped is what the explicit solver uses)")
    p.add_argument("--contact", action="store_true",
                   help="couple the bodies by the contact pairs' normal penalty springs (no friction)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``fivid modes``."""
    from fivid.errors import ConfigError
    from fivid.fe import load_model
    from fivid.fe.modal import modal_analysis, modes_to_json, write_modes
    from fivid.storage import check_writable, dumps_json

    if args.n_modes < 1:
        raise ConfigError(f"-n must be >= 1, got {args.n_modes}")
    if args.output:
        check_writable(args.output, overwrite=args.overwrite)
    model = load_model(args.model)
    ds = modal_analysis(model, args.n_modes, mass=args.mass, include_contact=args.contact)
    if args.output:
        write_modes(ds, args.output, overwrite=args.overwrite)
    summary = modes_to_json(ds)
    if args.output:
        summary["output"] = str(args.output)
    if args.json:
        print(dumps_json(summary))
    else:
        print(f"{model.describe()}; {ds.attrs['n_free_dofs']} free dofs; {args.mass} mass")
        print(" mode   frequency [Hz]")
        for i, f in enumerate(summary["frequencies_hz"], 1):
            print(f"{i:5d}   {f:14.2f}")
        if args.output:
            print(f"mode shapes written to {args.output}", file=sys.stderr)
    return 0
