"""``fivid update MODEL.yaml --targets TARGETS.yaml -o UPDATED.yaml [--json]``: least-squares model updating."""

from __future__ import annotations

import sys

__all__ = ["register"]


def register(subparsers) -> None:
    """Add the ``update`` sub-command."""
    p = subparsers.add_parser(
        "update",
        help="model updating: fit named model parameters to target modes (or damper FRF peaks)",
        description="Least-squares updating (scipy least_squares, bounds respected) of the model parameters named "
        "in TARGETS.yaml (dotted key paths, bounds with units) against target modes (frequency and tolerance; "
        "MAC pairing with a MODES.nc from 'fivid ema'; count_below checks) or, for a damper model, against FRF "
        "peak frequencies per normal load. Reports estimates with 95 %% intervals, the correlation matrix and "
        "parameter pairs the targets cannot tell apart; writes the model with the new values and a provenance "
        "comment (docs/ema.md).",
    )
    p.add_argument("model", metavar="MODEL.yaml", help="FE model config (configs/models) or damper model config "
                                                       "(configs/dampers), or the name of a built-in one")
    p.add_argument("--targets", required=True, metavar="TARGETS.yaml", help="parameters, bounds and target modes")
    p.add_argument("-o", "--output", required=True, metavar="UPDATED.yaml", help="the updated model config")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument("--json", action="store_true", help="print parameters, residuals, cost, iterations as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``fivid update``."""
    from fivid.storage import check_writable, dumps_json, write_text
    from fivid.updating import load_targets, update_model

    check_writable(args.output, overwrite=args.overwrite)
    targets = load_targets(args.targets)
    result, text = update_model(args.model, targets)
    write_text(args.output, text, overwrite=args.overwrite)
    summary = result.to_json()
    summary["output"] = str(args.output)
    if args.json:
        print(dumps_json(summary))
    else:
        print(f"{'parameter':32s} {'initial':>14s} {'updated':>14s} {'95 % interval':>14s}")
        for p in summary["parameters"]:
            ci = "not identified" if p["ci95"] is None else f"+- {p['ci95']:.3g}"
            print(f"{p['path']:32s} {p['initial']:14.6g} {p['value']:14.6g} {ci:>14s} {p['unit']}")
        for r in summary["residuals"]:
            print(f"  {r['name']}: target {r['target']:.5g} Hz, model {r['model']:.5g} Hz "
                  f"({r['error_pct']:+.3f} %)")
        print(f"cost {summary['cost']:.4g}, {summary['evaluations']} model evaluations, converged: "
              f"{summary['converged']}")
        print(f"updated model written to {args.output}", file=sys.stderr)
    for w in result.warnings:
        print(f"fivid: warning: {w}", file=sys.stderr)
    return 0
