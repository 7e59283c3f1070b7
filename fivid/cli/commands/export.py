"""``fivid export RUN.nc|PSD.nc --format uff58|csv -o OUT``: results for modal and test software."""

from __future__ import annotations

import argparse

__all__ = ["register", "run"]

_DESCRIPTION = """\
Write a run (ingested or simulated, RUN.nc), a PSD (fivid psd, PSD.nc) or an FRF dataset as
Universal File Format dataset 58 (one time response, auto spectrum or FRF per channel, pyuff:
pip install 'fivid[daq]') or as CSV with units in the header ('name [unit]'; a run is written in
the fivid-rig-csv format, which fivid ingest reads back). Units are the files' CF units (SI).
See docs/export.md."""


def register(subparsers) -> None:
    """Add the ``export`` sub-command."""
    parser = subparsers.add_parser("export", help="write a run, PSD or FRF as UFF58 or CSV with units",
                                   description=_DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("path", metavar="RUN.nc|PSD.nc", help="a RunDataset, PSD or FRF netCDF file")
    parser.add_argument("--format", required=True, choices=("uff58", "csv"), dest="file_format",
                        help="uff58: Universal File Format dataset 58; csv: CSV with units in the header")
    parser.add_argument("-o", "--output", required=True, metavar="OUT", help="output file (.uff / .csv)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``fivid export``."""
    import xarray as xr

    from fivid.errors import FividError
    from fivid.io.export import export_dataset
    from fivid.storage import atomic_path, check_writable

    check_writable(args.output, overwrite=args.overwrite)
    try:
        with xr.open_dataset(args.path) as ds:
            ds = ds.load()
    except (OSError, ValueError) as exc:
        raise FividError(f"cannot read {args.path!r} as a netCDF dataset: {exc}") from None
    try:
        with atomic_path(args.output) as tmp:
            n = export_dataset(ds, tmp, args.file_format)
    except FividError as exc:
        raise exc.located(file=args.path) from None
    print(f"{args.path} -> {args.output} ({args.file_format}, {n} channel(s))")
    return 0
