"""``fivid psd RUN.nc [--variable acceleration] [--nperseg N] -o PSD.nc``: Welch PSD of a run to netCDF."""

from __future__ import annotations

import argparse

from fivid.cli import integer_at_least

__all__ = ["register", "run"]

_DESCRIPTION = """\
Welch power spectral density (one-sided, unit²/Hz) of one variable of a RunDataset, with χ² confidence
bounds from the equivalent number of averages. Every setting (window, nperseg, noverlap, detrend,
scaling, FFT backend) is written to the attributes of the output file. See docs/spectra.md."""

_EPILOG = """\
examples:
  fivid psd runs/R012.nc -o R012_psd.nc
  fivid psd runs/R012.nc --variable friction_force --nperseg 16384 --steady -o R012_ft_psd.nc

exit status: 0 written; 2 bad input (the message names the file, the variable and the value); 1 unexpected."""


def register(subparsers) -> None:
    """Add the ``psd`` sub-command."""
    parser = subparsers.add_parser("psd", help="Welch PSD of a run's variable, written to netCDF",
                                   description=_DESCRIPTION, epilog=_EPILOG,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run_path", metavar="RUN.nc", help="a RunDataset netCDF file (fivid ingest / simulate)")
    parser.add_argument("--variable", default="acceleration", help="variable to analyse (default: acceleration)")
    parser.add_argument("--nperseg", type=integer_at_least(2), default=None, metavar="N",
                        help="segment length [samples]; resolution = sample rate / N (default: the largest power of "
                             "two <= n/16 with bins >= 2 Hz, at least 256; n: samples analysed)")
    parser.add_argument("--noverlap", type=int, default=None, metavar="N",
                        help="segment overlap [samples] (default N/2)")
    parser.add_argument("--window", default="hann", help="taper, a scipy.signal.get_window name (default hann)")
    parser.add_argument("--detrend", default="constant", choices=("constant", "linear", "none"),
                        help="per-segment detrending (default constant)")
    parser.add_argument("--confidence", type=float, default=0.95, help="level of the χ² bounds (default 0.95)")
    parser.add_argument("--steady", action="store_true",
                        help="analyse only the steady part: a simulated run from its transient_end, a measured run's "
                             "steady-sliding window (from velocity or position, else from the forces)")
    parser.add_argument("-o", "--output", required=True, metavar="PSD.nc", help="output netCDF file")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    parser.add_argument("--json", action="store_true",
                        help="print a JSON summary on stdout (output, run, variable, units, resolution, segments, "
                             "degrees of freedom, peak, settings; see docs/cli.md)")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``fivid psd``."""
    import xarray as xr

    from fivid.errors import SchemaError
    from fivid.io import read_run
    from fivid.schema import new_history
    from fivid.signal import steady_part, welch_psd
    from fivid.signal.sampling import run_label
    from fivid.storage import check_writable, dumps_json, write_netcdf

    check_writable(args.output, overwrite=args.overwrite)
    ds = read_run(args.run_path)
    label = run_label(ds)
    if args.variable not in ds.data_vars:
        raise SchemaError(f"{label} has no variable {args.variable!r}; it has: "
                          f"{', '.join(sorted(map(str, ds.data_vars)))}")
    window, steady = "", None
    if args.steady:
        ds = steady_part(ds, label=label)  # a simulated run from its transient_end, a measured one by its encoder
        t0, t1 = float(ds["time"][0]), float(ds["time"][-1])
        window, steady = f", steady window [{t0:.6g}, {t1:.6g}] s", [float(t0), float(t1)]
    psd = welch_psd(ds[args.variable], nperseg=args.nperseg, noverlap=args.noverlap, window=args.window,
                    detrend=args.detrend, confidence=args.confidence, label=label,
                    fs=ds.attrs.get("sample_rate"))
    out = xr.Dataset({psd.name: psd})
    out.attrs = {
        "title": f"Welch PSD of {args.variable} of run {ds.attrs.get('run_id', '')}",
        "run_id": str(ds.attrs.get("run_id", "")),
        "source_file": str(args.run_path),
        "source": str(ds.attrs.get("source", "")),
        "steady_only": int(args.steady),
        "Conventions": "CF-1.8",
        "history": new_history(f"fivid psd {args.run_path} --variable {args.variable} --nperseg {psd.attrs['nperseg']}"
                               f"{window}"),
    }
    write_netcdf(out, args.output, overwrite=args.overwrite)
    if args.json:
        print(dumps_json(_summary(args, out.attrs["run_id"], psd, steady)))
        return 0
    print(f"{args.output}: PSD of {args.variable} ({psd.attrs['units']}), {psd.sizes['frequency']} bins of "
          f"{psd.attrs['frequency_resolution']:.6g} Hz, {psd.attrs['n_segments']} segments of "
          f"nperseg {psd.attrs['nperseg']} samples, "
          f"{psd.attrs['equivalent_degrees_of_freedom']:.4g} degrees of freedom")
    return 0


def _summary(args, run_id: str, psd, steady) -> dict:
    """The ``--json`` record of ``fivid psd`` (shape in docs/cli.md)."""
    import numpy as np

    a = psd.attrs
    values = np.asarray(psd.values, dtype=float).reshape(psd.sizes["frequency"], -1).max(axis=1)
    peak = int(np.nanargmax(values)) if np.isfinite(values).any() else None
    return {
        "output": str(args.output), "run_id": run_id, "variable": args.variable, "units": a["units"],
        "n_frequencies": int(psd.sizes["frequency"]), "frequency_resolution_hz": float(a["frequency_resolution"]),
        "n_segments": int(a["n_segments"]), "equivalent_degrees_of_freedom": float(a["equivalent_degrees_of_freedom"]),
        "peak_frequency_hz": None if peak is None else float(psd.frequency[peak]),
        "steady_window_s": steady,
        "settings": {"nperseg": int(a["nperseg"]), "nperseg_rule": a["nperseg_rule"], "noverlap": args.noverlap, "window": args.window,
                     "detrend": args.detrend, "confidence": args.confidence},
    }
