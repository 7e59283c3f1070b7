"""``fivid ema FRF_FILE... [--band LO HI] [--modes N] -o MODES.nc [--json]``: experimental modal analysis."""

from __future__ import annotations

import sys

from fivid.cli import quantity

__all__ = ["register"]


def register(subparsers) -> None:
    """Add the ``ema`` sub-command."""
    p = subparsers.add_parser(
        "ema",
        help="experimental modal analysis: frequencies, damping ratios, mode shapes from measured FRFs",
        description="Modal parameters from measured FRFs of one reference: LSCF poles over model orders (sdypy-EMA), "
        "an automatic stabilisation diagram, LSFD mode shapes. Inputs: UFF58 FRF records (.uff/.unv), an FRF netCDF "
        "(complex or NAME_real/NAME_imag along frequency) or a run dataset (H1 of response channels to a force "
        "channel, with coherence). Writes MODES.nc (docs/ema.md); Rayleigh alpha, beta are fitted to the identified "
        "damping ratios.",
    )
    p.add_argument("files", nargs="+", metavar="FRF_FILE", help="UFF58 files, FRF netCDF files or run datasets")
    p.add_argument("--band", nargs=2, type=quantity("Hz", positive=True), metavar=("LO", "HI"),
                   help="frequency band, e.g. '20 Hz' '180 Hz' (bare numbers in Hz; default: all lines)")
    p.add_argument("--modes", type=int, metavar="N", help="keep the N best-stabilised modes (default: every mode "
                                                          "stable at 30 %% of the orders)")
    p.add_argument("--max-order", type=int, default=40, metavar="N",
                   help="highest LSCF polynomial order / 2 (default 40)")
    p.add_argument("--form", choices=("receptance", "mobility", "accelerance"),
                   help="what the FRFs are (default: from the files' units or UFF data types)")
    p.add_argument("--force", default="friction_force", metavar="VAR",
                   help="run datasets: the force variable (default friction_force)")
    p.add_argument("--response", default="acceleration", metavar="VAR",
                   help="run datasets: the response variable, one FRF per sensor (default acceleration)")
    p.add_argument("--nperseg", type=int, metavar="N", help="run datasets: Welch segment length")
    p.add_argument("-o", "--output", metavar="MODES.nc", required=True, help="write the modes to netCDF")
    p.add_argument("--figure", metavar="PNG", help="write the stabilisation diagram to this PNG")
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    p.add_argument("--json", action="store_true", help="print modes, shapes and settings as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``fivid ema``."""
    from fivid.ema import experimental_modal_analysis, modes_json
    from fivid.ema.modes_file import stabilisation_figure, write_modes_file
    from fivid.errors import ConfigError
    from fivid.storage import check_writable, dumps_json

    if args.modes is not None and args.modes < 1:
        raise ConfigError(f"--modes must be >= 1, got {args.modes}", key="--modes")
    if args.max_order < 2:
        raise ConfigError(f"--max-order must be >= 2, got {args.max_order}", key="--max-order")
    if args.band is not None and not args.band[0] < args.band[1]:
        raise ConfigError(f"--band needs LO < HI, got {args.band[0]:g} {args.band[1]:g} Hz", key="--band")
    check_writable(args.output, overwrite=args.overwrite)
    if args.figure:
        check_writable(args.figure, overwrite=args.overwrite)
    band = None if args.band is None else (float(args.band[0]), float(args.band[1]))
    ds, frfs = experimental_modal_analysis(args.files, band=band, n_modes=args.modes, max_order=args.max_order,
                                           form=args.form, force=args.force, response=args.response,
                                           nperseg=args.nperseg)
    write_modes_file(ds, args.output, overwrite=args.overwrite)
    if args.figure:
        stabilisation_figure(ds, args.figure, frfs)
    summary = modes_json(ds)
    summary["output"] = str(args.output)
    if args.figure:
        summary["figure"] = str(args.figure)
    if args.json:
        print(dumps_json(summary))
        return 0
    print(f"{len(frfs.name)} FRFs ({frfs.form}) from {', '.join(frfs.sources)}; band "
          f"{summary['settings']['band_hz'][0]:g}..{summary['settings']['band_hz'][1]:g} Hz")
    print(" mode   frequency [Hz]   damping ratio   stable orders")
    for k, m in enumerate(summary["modes"], 1):
        print(f"{k:5d}   {m['frequency_hz']:14.4f}   {m['damping_ratio']:13.5f}   {m['stable_orders']:13d}")
    if "rayleigh" in summary:
        r = summary["rayleigh"]
        print(f"Rayleigh fit: alpha {r['alpha']:.4g} 1/s, beta {r['beta']:.4g} s")
    print(f"FRF reconstruction error {summary['reconstruction_error']:.3g}; modes written to {args.output}",
          file=sys.stderr)
    return 0
