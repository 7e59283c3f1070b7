"""``fivid identify``: the friction law (and optionally Rayleigh damping) from measured runs."""

from __future__ import annotations

from fivid.cli import integer_at_least

__all__ = ["register"]

_DESCRIPTION = """\
Identify the friction law of DESIGN §3 from RunDatasets (files written by 'fivid ingest'):
mu0 with its confidence interval, the normalised spectrum of the friction perturbation in the
valid band, the per-run RMS amplitudes and the amplitude law A(V, Ra, Fn) fitted in every candidate
form continuous in V, Ra and Fn (power law, (a + bV) Ra^n, log-linear; Fn wherever the runs differ in
load), with AICc, Akaike weights, leave-one-condition-out cross-validation error and the chosen form,
the identified domain, Cook's distance of every run, and a test of whether the spectrum's shape
depends on the condition. 'fivid law show LAW.nc' and 'fivid law eval' read the result. Runs not in steady sliding or with a normal force near zero are
excluded with the reason. Writes the law file (netCDF) read by 'fivid simulate --law'.
With --damping, modal damping ratios are identified from the acceleration PSD peaks and a Rayleigh
(alpha, beta) fit is written as a model-config fragment (YAML)."""


def register(subparsers) -> None:
    """Add the ``identify`` sub-command."""
    from fivid.cli import quantity

    p = subparsers.add_parser("identify", help="identify the friction law (and damping) from measured runs",
                              description=_DESCRIPTION)
    p.add_argument("runs", nargs="+", metavar="RUN.nc", help="RunDataset netCDF files")
    p.add_argument("-o", "--output", required=True, metavar="LAW.nc", help="law file to write")
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    p.add_argument("--band", nargs=2, type=quantity("Hz", nonnegative=True), metavar=("F_LO", "F_HI"),
                   help="valid band [Hz] (default 20 Hz to min(2 kHz, 0.4 fs): where the force chain is trustworthy)")
    p.add_argument("--json", action="store_true", help="print the JSON report on stdout")
    p.add_argument("--report", metavar="REPORT.json", help="also write the JSON report to this file")
    p.add_argument("--nperseg", type=integer_at_least(2), help="Welch segment length [samples] (default per run: bins <= mains/4, e.g. 12.5 Hz at 50 Hz, so that "
                   "mains-line removal takes only the lines, with >= 7 segments; see docs/identification.md)")
    p.add_argument("--tolerance", type=float, default=0.05,
                   help="relative velocity tolerance of the steady-sliding window (default 0.05)")
    p.add_argument("--min-normal-force", type=quantity("N", nonnegative=True), default=0.1,
                   help="exclude runs whose mean normal force is below this [N] (default 0.1)")
    p.add_argument("--tare", nargs=2, type=quantity("s", nonnegative=True), metavar=("T0", "T1"),
                   help="unloaded interval [s]: its mean forces are subtracted (sensor offsets) and its noise PSD "
                   "is removed from the perturbation PSD")
    p.add_argument("--window", nargs=2, type=quantity("s", nonnegative=True), metavar=("T0", "T1"),
                   help="steady-sliding window [s] of every run, e.g. --window '50 ms' '0.4 s' (default: where the "
                   "encoder velocity is on its plateau; without velocity or position columns, where the normal "
                   "force is loaded and Ft/Fn on its plateau)")
    p.add_argument("--mains-frequency", type=quantity("Hz", nonnegative=True), default=50.0,
                   help="mains frequency [Hz] whose harmonics are removed when they stand out (0 disables; default 50)")
    p.add_argument("--shape", choices=("smoothed", "rolloff"), default="smoothed",
                   help="spectral shape written into the law (default smoothed)")
    p.add_argument("--injection", choices=("uniform", "per_node", "convected"), default="uniform",
                   help="injection mode of the law (default uniform)")
    p.add_argument("--interaction", action="store_true",
                   help="also fit the power law with an Ra x V interaction term")
    p.add_argument("--categorical", action="store_true",
                   help="also fit the categorical forms (one line in V per roughness level; they cannot be "
                   "evaluated at an Ra between the identified levels)")
    p.add_argument("--weighting", choices=("estimator", "none"), default="estimator",
                   help="amplitude-law fit: WLS with the per-run estimator variances (default) or OLS")
    p.add_argument("--damping", metavar="DAMPING.yaml",
                   help="also identify modal damping from the acceleration and write a Rayleigh fragment here")
    p.add_argument("--damping-band", nargs=2, type=quantity("Hz", nonnegative=True), metavar=("F_LO", "F_HI"),
                   help="band [Hz] searched for resonance peaks (default: the friction band)")
    p.add_argument("--allow-implausible", action="store_true",
                   help="identify from runs whose mean Ft/Fn is beyond +-2 (refused otherwise: a swapped column, a "
                        "unit, and a sign that would be lost); recorded in the law file")
    p.add_argument("--damping-peaks", type=int, default=4, help="number of resonance peaks to use (default 4)")
    p.add_argument("--inverse", metavar="MODEL.yaml",
                   help="also run the inverse route of seed 001 with this FE model: scale the amplitude until the "
                   "simulated acceleration level matches the measured one (reported beside the forward estimate)")
    p.add_argument("--inverse-band", nargs=2, type=quantity("Hz", nonnegative=True), metavar=("F_LO", "F_HI"),
                   help="band [Hz] of the level match (default: the friction band)")
    p.add_argument("--inverse-run", action="append", metavar="RUN_ID",
                   help="run(s) to match (repeatable; default: the first used run)")
    p.add_argument("--inverse-duration", type=quantity("s", positive=True), default=0.1,
                   help="steady-sliding time simulated per iteration [s] (default 0.1)")
    p.add_argument("--inverse-iterations", type=int, default=4, help="maximum iterations (default 4)")
    p.set_defaults(func=_run)


def _run(args) -> int:
    import logging

    from fivid.identify import AmplitudeSettings, RunAnalysisSettings, ShapeSettings, identify_friction_law
    from fivid.identify.friction import load_runs
    from fivid.storage import check_writable, dumps_json, write_text

    log = logging.getLogger("fivid")
    check_writable(args.output, overwrite=args.overwrite)
    if args.report:
        check_writable(args.report, overwrite=args.overwrite)
    if args.damping:
        check_writable(args.damping, overwrite=args.overwrite)
    model = None
    if args.inverse:  # a bad model file fails here, before the identification
        from fivid.fe import load_model

        model = load_model(args.inverse)
    datasets = load_runs(args.runs)  # read once; the damping and inverse routes reuse them
    result = identify_friction_law(
        datasets,
        band=args.band,
        analysis=RunAnalysisSettings(nperseg=args.nperseg, tolerance=args.tolerance,
                                     min_normal_force=args.min_normal_force, tare=args.tare, window=args.window,
                                     mains_frequency=args.mains_frequency or None,
                                     allow_implausible=args.allow_implausible),
        shape=ShapeSettings(method=args.shape),
        amplitude=AmplitudeSettings(weighting=args.weighting, interaction=args.interaction,
                                    categorical=args.categorical),
        injection=args.injection,
    )
    report = result.to_json()
    damping = None
    if args.damping:
        from fivid.identify import identify_damping

        band = tuple(args.damping_band) if args.damping_band else result.band
        damping = identify_damping(datasets, band=band, n_peaks=args.damping_peaks)
        report["damping"] = damping.to_json()
    if args.inverse:
        report["inverse"] = _inverse(args, result, model, datasets)
    text = dumps_json(report)
    if args.json:  # everything printed is built before anything is written: no output of a failed command
        printed = [text]
    else:
        printed = [result.summary()] + ([damping.summary()] if damping is not None else [])
        printed += [f"inverse route, run {inv['run_id']}: amplitude forward {inv['forward_amplitude']:.4g}, inverse "
                    f"{inv['inverse_amplitude']:.4g} (scale {inv['scale']:.3g}; {inv['reason']})"
                    for inv in report.get("inverse", [])]
        printed.append(f"wrote {args.output}")
    result.write(args.output, overwrite=args.overwrite)
    log.info("wrote %s", args.output)
    if damping is not None:
        write_text(args.damping, damping.to_yaml(), overwrite=args.overwrite)
        log.info("wrote %s", args.damping)
    if args.report:
        write_text(args.report, text + "\n", overwrite=args.overwrite)
    print("\n".join(printed))
    return 0


def _inverse(args, result, model, runs) -> list:
    from fivid.errors import FividError
    from fivid.identify import inverse_amplitude_scale

    datasets = {str(ds.attrs.get("run_id")): ds for ds in runs}
    used = [r.run_id for r in result.runs if r.used]
    wanted = args.inverse_run or used[:1]
    unknown = [r for r in wanted if r not in datasets]
    if unknown:
        raise FividError(f"--inverse-run {', '.join(unknown)}: no such run; runs: {', '.join(datasets)}")
    band = tuple(args.inverse_band) if args.inverse_band else result.band
    out = []
    for run_id in wanted:
        res = inverse_amplitude_scale(result.law, datasets[run_id], model, band=band, duration=args.inverse_duration,
                                      max_iterations=args.inverse_iterations)
        out.append(res.to_json())
    return out
