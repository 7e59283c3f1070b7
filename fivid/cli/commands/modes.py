"""``fivid modes MODEL.yaml [-n N] [--load Q] [--json] [-o MODES.nc]``: natural frequencies and mode shapes of a model."""

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
        "With --load the bodies are coupled at the contact nodes closed under that normal load (static preload "
        "solve): the linearisation about the sliding equilibrium. Mode shapes can be written to netCDF.",
    )
    p.add_argument("model", metavar="MODEL.yaml", help="model config (see docs/model-config.md)")
    p.add_argument("-n", "--n-modes", type=int, default=30, metavar="N", help="number of modes (default 30)")
    p.add_argument("--json", action="store_true", help='print {"frequencies_hz": [...], ...} as JSON')
    p.add_argument("-o", "--output", metavar="MODES.nc", help="write frequencies and mode shapes to netCDF")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument("--mass", choices=("consistent", "lumped"), default="consistent",
                   help="mass matrix (default consistent; lumped is what the explicit solver uses)")
    p.add_argument("--load", metavar="Q",
                   help="normal load with unit, e.g. '5 N': couple the bodies by normal penalty springs at the slave "
                        "nodes closed under it (static preload solve; no friction)")
    p.add_argument("--contact", action="store_true", help="same as --load (which it needs): kept for clarity")
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
    from fivid.units import parse_quantity

    if args.contact and args.load is None:
        raise ConfigError("--contact needs --load Q (e.g. --load '5 N'): the contact is linearised about the "
                          "nodes closed under that normal load")
    load = None if args.load is None else _positive_load(args.load, parse_quantity)
    model = load_model(args.model)
    ds = modal_analysis(model, args.n_modes, mass=args.mass, include_contact=load is not None, normal_load=load)
    if args.output:
        write_modes(ds, args.output, overwrite=args.overwrite)
    summary = modes_to_json(ds)
    if args.output:
        summary["output"] = str(args.output)
    if args.json:
        print(dumps_json(summary))
    else:
        print(f"{model.describe()}; {ds.attrs['n_free_dofs']} free dofs; {args.mass} mass")
        if load is not None:
            print(f"contact closed under {load:g} N at slave node(s) {summary['closed_slave_nodes']}")
        print(" mode   frequency [Hz]")
        for i, f in enumerate(summary["frequencies_hz"], 1):
            print(f"{i:5d}   {f:14.2f}")
        if args.output:
            print(f"mode shapes written to {args.output}", file=sys.stderr)
    return 0


def _positive_load(text, parse_quantity) -> float:
    """``--load`` in newtons, > 0 (ConfigError naming the option otherwise)."""
    from fivid.errors import ConfigError, FividError

    try:
        load = parse_quantity(text, "N")
    except FividError as exc:  # name the option: the bare message does not say which argument it was
        raise type(exc)(f"--load: {exc.message}") from None
    if not load > 0:
        raise ConfigError(f"--load must be a positive force, got {text!r}")
    return float(load)
