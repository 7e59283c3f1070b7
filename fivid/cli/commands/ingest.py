"""``fivid ingest PATH... -o OUTDIR [--rig PROFILE] [--overwrite]``: rig CSVs to RunDataset netCDF files."""

from __future__ import annotations

import argparse
import sys

from fivid.cli import quiet

__all__ = ["register", "run"]

_DESCRIPTION = """\
Convert test-rig CSV files into RunDataset netCDF files OUTDIR/<run_id>.nc (SI units, CF attributes,
provenance: file name and sha256). A file is either a 'fivid-rig-csv: 1' file (metadata lines
'# key: value' with units, header 'name [unit]') or a DAQ export described by a rig profile
(configs/rigs/<name>.yaml: delimiter, decimal comma, column names, units, sensor sensitivity,
metadata from the file, its name or the profile). NI TDMS (.tdms), UFF58 (.uff, .unv), MATLAB (.mat),
LabVIEW LVM (.lvm) and ASAM MDF4 (.mf4) files are read by suffix through the same profile
(pip install 'fivid[daq]'). See docs/ingest.md, section 9.

Valid files are written even when others are bad; each rejected file gets one line on stderr
naming the file, the line and the column or key. Outputs are written atomically: an interrupted
ingest leaves no partial .nc file."""

_EPILOG = """\
examples:
  fivid ingest sample_data/R001_v10_ra08.csv -o out/
  fivid ingest exports/*.csv -o runs/ --rig labdaq
  fivid ingest R002_v20_ra16.tdms -o runs/ --rig labdaq
  fivid ingest exports/ -o runs/ --rig configs/rigs/labdaq.yaml --overwrite

exit status: 0 all files written; 2 a file was rejected or the options are wrong; 1 unexpected failure."""


def register(subparsers) -> None:
    """Add the ``ingest`` sub-command."""
    parser = subparsers.add_parser(
        "ingest",
        help="convert rig CSV and DAQ files to RunDataset netCDF files",
        description=_DESCRIPTION,
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("paths", nargs="+", metavar="PATH", help="rig CSV or DAQ files (.tdms .uff .mat .lvm .mf4), or folders of them")
    parser.add_argument("-o", "--outdir", required=True, metavar="OUTDIR",
                        help="output folder (created if missing); one OUTDIR/<run_id>.nc per input file")
    parser.add_argument("--rig", metavar="PROFILE", default=None,
                        help="rig profile: the name of a built-in profile (triboair, labdaq: shipped with fivid, "
                             "configs/rigs/ in a checkout) or a YAML path; default: the fivid-rig-csv format")
    parser.add_argument("--overwrite", action="store_true", help="replace existing output files")
    parser.add_argument("--json", action="store_true",
                        help='print {"written": [{"input", "output", "run_id", "samples", "sample_rate_hz"}, ...], '
                             '"rejected": [{"input", "error"}, ...]} on stdout instead of one line per file')
    parser.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``fivid ingest``; returns 0 when every file was written, 2 when one was rejected."""
    from tqdm import tqdm

    from fivid.io import ingest_files
    from fivid.io.ingest import expand_inputs
    from fivid.storage import dumps_json

    n_files = len(expand_inputs(args.paths))
    bar = tqdm(total=n_files, unit="file", desc="ingest", disable=n_files < 2 or not sys.stderr.isatty())

    records = []

    def written(path, target, ds):
        record = {"input": str(path), "output": str(target), "run_id": str(ds.attrs["run_id"]),
                  "samples": int(ds.sizes["time"]), "sample_rate_hz": float(ds.attrs["sample_rate"])}
        records.append(record)
        if not (args.json or quiet(args)):  # -q: only rejections and the final count
            bar.write(f"{path} -> {target} (run {record['run_id']}: {record['samples']} samples at "
                      f"{record['sample_rate_hz']:.6g} Hz)", file=sys.stdout)

    with bar:
        result = ingest_files(args.paths, args.outdir, profile=args.rig, overwrite=args.overwrite,
                              on_written=written, on_file_done=lambda path: bar.update())
    if args.json:
        print(dumps_json({"written": records, "rejected": [{"input": str(r.path), "error": str(r)}
                                                            for r in result.rejected]}))
    for rejection in result.rejected:
        print(f"fivid ingest: rejected: {rejection}", file=sys.stderr)
    if result.rejected:
        print(f"fivid ingest: {len(result.written)} file(s) written, {len(result.rejected)} rejected",
              file=sys.stderr)
        return 2
    return 0
