"""``fivid damper``: identify a Jenkins element from a hysteresis loop; FRFs of a friction-damped beam."""

from __future__ import annotations

import argparse
import sys

from fivid.cli import quantity

__all__ = ["register"]


def register(subparsers) -> None:
    """Add ``fivid damper fit`` and ``fivid damper frf``."""
    p = subparsers.add_parser(
        "damper",
        help="friction dampers: fit a Jenkins element to a loop, FRFs by harmonic balance",
        description="Friction dampers (Jenkins/Masing contact). 'fit' identifies slip force and stiffness from a "
        "force-displacement recording; 'frf' computes forced responses of a beam with a rubbing contact.",
    )
    sub = p.add_subparsers(dest="damper_command", metavar="ACTION")
    fit = sub.add_parser("fit", help="fit a Jenkins element to a hysteresis recording",
                         description="Read a hysteresis file (.json ARTS layout or .csv with units) and fit slip "
                         "force and stiffness; report energy per cycle measured vs model (SI units).")
    fit.add_argument("file", help="hysteresis recording (.json or .csv)")
    fit.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    fit.set_defaults(func=_fit)
    frf = sub.add_parser("frf", help="FRF of a damper model by harmonic balance",
                         description="Harmonic-balance FRF (first-harmonic displacement and receptance at the sensor) of "
                         "a damper model YAML at one or more normal loads, over the model's frequency range. Units: "
                         "Hz, m, m/N, N.")
    frf.add_argument("model", help="damper model YAML (see configs/dampers/)")
    frf.add_argument("--normal-load", type=quantity("N", positive=True), nargs="+", required=True, metavar="F",
                     help="normal load(s), e.g. '5 N' '500 mN'; a bare number is in N")
    frf.add_argument("--points", type=int, default=200, help="frequencies in the range (default 200)")
    frf.add_argument("--arclength", action="store_true",
                     help="follow the branch by arclength continuation (adaptive points, Floquet stability) "
                     "instead of the fixed frequency grid")
    frf.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    frf.set_defaults(func=_frf)
    p.set_defaults(func=lambda args: _usage(p))


def _usage(parser) -> int:
    parser.print_help(sys.stderr)
    return 2


def _fit(args: argparse.Namespace) -> int:
    from fivid.damper.loop_fit import fit_jenkins_loop
    from fivid.io.hysteresis import read_hysteresis
    from fivid.storage import dumps_json

    rec = read_hysteresis(args.file)
    result = fit_jenkins_loop(rec.displacement, rec.force, file=args.file)
    out = dict(result.summary(), file=args.file, source=rec.metadata.get("source"))
    if args.json:
        print(dumps_json(out))
    else:
        print(f"{args.file}: {out['n_cycles']} cycles")
        print(f"  slip_force  {out['slip_force']:.6g} +- {out['slip_force_stderr']:.2g} N")
        print(f"  stiffness   {out['stiffness']:.6g} +- {out['stiffness_stderr']:.2g} N/m")
        print(f"  energy_per_cycle_measured {out['energy_per_cycle_measured']:.6g} J, "
              f"model {out['energy_per_cycle_model']:.6g} J ({out['energy_relative_error']:+.1%})")
        print(f"  force fit: R^2 {out['r_squared']:.4f}, rms residual {out['rms_residual']:.4g} N")
    return 0


def _frf(args: argparse.Namespace) -> int:
    import numpy as np

    from fivid.damper.continuation import continue_frequency_response
    from fivid.damper.hbm import HarmonicBalance
    from fivid.damper.model import load_damper_model
    from fivid.errors import FividError
    from fivid.storage import dumps_json

    if args.points < 2:
        raise FividError(f"--points must be >= 2, got {args.points}", key="--points")
    model = load_damper_model(args.model)
    freqs = np.linspace(*model.frequency_range, args.points)
    curves = []
    for fn in args.normal_load:
        hb = HarmonicBalance.from_model(model, fn)
        extra = {}
        if args.arclength:
            curve = continue_frequency_response(hb, *model.frequency_range)
            f_c, amp = curve.frequency, curve.amplitude
            extra = {"frequency": f_c, "stable": curve.stable, "max_floquet_multiplier": curve.max_multiplier}
        else:
            f_c = freqs
            amp = np.array([abs(s.measurement[0]) for s in hb.sweep(freqs)])
        i = int(np.argmax(amp))
        curves.append({"normal_load": float(fn), "slip_force": model.slip_force(fn), "peak_frequency": float(f_c[i]),
                       "peak_amplitude": float(amp[i]), "amplitude": amp,
                       "receptance": amp / model.excitation_amplitude, **extra})
    if args.json:
        import hashlib
        from pathlib import Path

        source = Path(model.source)  # the file the name resolved to (a built-in name is no path)
        sha = hashlib.sha256(source.read_bytes()).hexdigest()
        print(dumps_json({"model": model.name, "model_source": f"{source.name} sha256:{sha}",
                          "harmonics": list(model.harmonics), "samples_per_period": model.samples_per_period,
                          "frequency": None if args.arclength else freqs, "curves": curves,
                          "units": {"frequency": "Hz", "amplitude": "m", "receptance": "m N-1",
                                    "normal_load": "N", "slip_force": "N"}}))
    else:
        grid = "arclength continuation" if args.arclength else f"{args.points} frequencies"
        print(f"{model.name}: {grid} {freqs[0]:g}-{freqs[-1]:g} Hz, first-harmonic displacement at the sensor")
        for c in curves:
            line = f"  Fn {c['normal_load']:g} N: peak {c['peak_amplitude']:.4g} m at {c['peak_frequency']:.4g} Hz"
            if args.arclength:
                line += f", {len(c['amplitude'])} points, {int(np.sum(~c['stable']))} unstable"
            print(line)
    return 0
