"""``fivid score MEASURED.nc SIMULATED.nc [--variable V] [--band F_LO F_HI] [--nperseg N] [-o SCORES.nc] [--json]``."""

from __future__ import annotations

import argparse

from fivid.cli import integer_at_least, quantity

__all__ = ["register", "run"]

_DESCRIPTION = """\
PSD scores of a simulated run against a measured one over a frequency band (DESIGN §6): log-spectral
distance lsd_db, band level difference level_diff_db, 1/3-octave band level errors and their RMS,
matched peaks (relative frequency error, level difference) and the shape correlation of the
log-PSDs. Each score is flagged 'significant' when it exceeds what two Welch estimates of one
spectrum reach with probability --confidence. Runs at different sample rates are resampled
(polyphase) to the lower rate. With --envelope ENV.nc (from 'fivid simulate --law LAW.nc --samples N'),
each 1/3-octave band also says whether the measured band level lies inside the 5-95 % Monte-Carlo
envelope, and the coverage (% of bands inside) is reported. See docs/spectra.md, docs/uncertainty.md."""

_EPILOG = """\
examples:
  fivid score runs/R012.nc sim/R012_sim.nc --band 100 20000 --json
  fivid score runs/R012.nc sim/R012_sim.nc --nperseg 16384 -o R012_scores.nc
  fivid score runs/R012.nc sim/R012_sim.nc --envelope sim/R012_env.nc --json

exit status: 0 scored; 2 bad input (the message names the run and the value); 1 unexpected failure."""


def register(subparsers) -> None:
    """Add the ``score`` sub-command."""
    parser = subparsers.add_parser("score", help="PSD scores of a simulated run against a measured run",
                                   description=_DESCRIPTION, epilog=_EPILOG,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("measured", metavar="MEASURED.nc", help="measured RunDataset (netCDF)")
    parser.add_argument("simulated", metavar="SIMULATED.nc", help="simulated RunDataset (netCDF)")
    parser.add_argument("--variable", default="acceleration", help="variable to compare (default: acceleration)")
    parser.add_argument("--band", nargs=2, type=quantity("Hz", nonnegative=True), default=None,
                        metavar=("F_LO", "F_HI"),
                        help="frequency band, e.g. '800 Hz' '5 kHz'; a bare number is in Hz (default: 4 PSD bins "
                             "to 80%% of the lower Nyquist frequency)")
    parser.add_argument("--nperseg", type=integer_at_least(2), default=None, metavar="N",
                        help="Welch segment length [samples] (default: the largest power of two <= n/16 with bins "
                             ">= 2 Hz, at least 256; n: samples of the shorter run at the common rate)")
    parser.add_argument("--sensor", default=None, help="sensor name when the variable has several")
    parser.add_argument("--steady", action="store_true", help="score only each run's steady-sliding window")
    parser.add_argument("--confidence", type=float, default=0.95,
                        help="confidence of the significance judgement (default 0.95)")
    parser.add_argument("--envelope", default=None, metavar="ENV.nc",
                        help="Monte-Carlo PSD envelope ('fivid simulate --samples'): per band, is the measured level "
                             "inside its 5-95 %% band levels; coverage in %%")
    parser.add_argument("-o", "--output", default=None, metavar="SCORES.nc", help="write the scores to netCDF")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    parser.add_argument("--json", action="store_true", help="print the scores as JSON on stdout")
    parser.set_defaults(func=run)


def _summary(j: dict) -> str:
    nperseg = j.get("settings", {}).get("nperseg")
    lines = [f"scores of {j['simulated']} against {j['measured']} ({j['variable']}, "
             f"{j['band_hz'][0]:.6g}-{j['band_hz'][1]:.6g} Hz"
             + ("" if nperseg is None else f", Welch nperseg {nperseg}") + "):"]
    for key in ("lsd_db", "level_diff_db", "band_level_rms_error_db", "shape_correlation"):
        value, thr = j[key], j["thresholds"][key]
        if thr is None:  # e.g. shape_correlation of log-PSDs with no spread above their noise
            mark = "not judged"
        else:
            mark = "significant" if j["significant"][key] else "within uncertainty"
        fmt = (lambda v: "n/a" if v is None else f"{v:.4g}")
        lines.append(f"  {key:26s} {fmt(value):>10s}  (threshold {fmt(thr)}: {mark})")
    env = j.get("envelope")
    if env is not None:
        lines.append(f"  envelope coverage: {env['inside_count']} of {len(env['bands'])} 1/3-octave bands inside the "
                     f"5-95 % Monte-Carlo envelope ({env['n_samples']} samples): "
                     + ("n/a" if env["coverage_percent"] is None else f"{env['coverage_percent']:.0f} %"))
        out = [f"{b['centre_hz']:.4g} Hz" for b in env["bands"] if not b["inside"]]
        if out:
            lines.append(f"    outside: {', '.join(out)}")
    for p in j["peaks"]:
        fs = "unmatched" if p["frequency_simulated_hz"] is None else f"{p['frequency_simulated_hz']:.6g} Hz"
        lines.append(f"  peak {p['frequency_measured_hz']:.6g} Hz -> {fs}")
    return "\n".join(lines)


def run(args) -> int:
    """Handler of ``fivid score``."""
    from fivid.io import read_run
    from fivid.score import score_runs, scores_to_json
    from fivid.storage import check_writable, dumps_json, write_netcdf

    if args.output is not None:
        check_writable(args.output, overwrite=args.overwrite)
    envelope = None
    if args.envelope is not None:
        from fivid.score.envelope import read_envelope

        envelope = read_envelope(args.envelope)  # before the work: a wrong file fails fast
    measured = read_run(args.measured)
    simulated = read_run(args.simulated)
    scores = score_runs(measured, simulated, variable=args.variable, band=args.band, nperseg=args.nperseg,
                        sensor=args.sensor, steady=args.steady, confidence=args.confidence)
    scores.attrs["measured_file"] = str(args.measured)
    scores.attrs["simulated_file"] = str(args.simulated)
    if envelope is not None:
        from fivid.score.envelope import add_envelope_coverage

        scores = add_envelope_coverage(scores, envelope, envelope_file=str(args.envelope))
    if args.output is not None:
        write_netcdf(scores, args.output, overwrite=args.overwrite)
    result = scores_to_json(scores)
    print(dumps_json(result) if args.json else _summary(result))
    return 0
