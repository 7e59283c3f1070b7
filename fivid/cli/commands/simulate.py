"""``fivid simulate MODEL.yaml [--law LAW.nc | --mu MU] ... -o SIM.nc``: explicit contact simulation of a rig."""

from __future__ import annotations

import sys

from fivid.cli import quantity

__all__ = ["register"]


def register(subparsers) -> None:
    """Add the ``simulate`` sub-command."""
    p = subparsers.add_parser(
        "simulate",
        help="explicit FE simulation of the rig with frictional contact -> a RunDataset (netCDF)",
        description="Simulate a rig model (configs/models/*.yaml) with the jitted explicit solver: preload by the "
        "loading clamp to --load, settling, ramp of the base to --velocity, then --duration of steady sliding. "
        "Friction is Coulomb (--mu, or each contact pair's mu) or an identified law (--law, mu0 + mu_p(t)). "
        "The output has the variable names of a measured run (acceleration, friction_force, normal_force), so "
        "'fivid score' compares them directly, plus contact diagnostics and the energy balance. "
        "Quantities take units, e.g. --velocity '10 mm/s' --load '5 N' --duration '0.1 s'; a bare number is in "
        "SI units (m/s, N, m, s, Hz).",
    )
    p.add_argument("model", metavar="MODEL.yaml",
                   help="model config (see docs/model-config.md), or the name of a built-in model such as "
                        "triboair_coarse (configs/models/, shipped with fivid)")
    fr = p.add_mutually_exclusive_group()
    fr.add_argument("--law", metavar="LAW.nc", help="friction-law file written by 'fivid identify'")
    fr.add_argument("--mu", type=float, metavar="MU", help="constant Coulomb friction coefficient for every pair")
    p.add_argument("--velocity", metavar="Q", type=quantity("m s-1", positive=True),
                   help="sliding velocity of the base, e.g. '10 mm/s'; bare number in m/s (default: config)")
    p.add_argument("--load", metavar="Q", type=quantity("N", positive=True),
                   help="normal load at the force transducer, e.g. '5 N'; bare number in N (default: the configured "
                        "clamp displacement)")
    p.add_argument("--roughness", metavar="Q", type=quantity("m", nonnegative=True),
                   help="roughness Ra, e.g. '0.8 um'; bare number in m (passed to the law, recorded)")
    p.add_argument("--duration", metavar="Q", default="0.1 s", type=quantity("s", positive=True),
                   help="steady-sliding time after the transient; bare number in s (default '0.1 s')")
    p.add_argument("--sample-rate", metavar="Q", default="51.2 kHz", type=quantity("Hz", positive=True),
                   help="output sample rate; bare number in Hz (default '51.2 kHz')")
    p.add_argument("--seed", type=int, default=0, metavar="N", help="seed of the friction-law synthesis (default 0)")
    p.add_argument("--time-step", metavar="Q", type=quantity("s", positive=True),
                   help="solver step, e.g. '50 ns'; bare number in s (default 0.9 x critical; refused above critical)")
    p.add_argument("--reduced", nargs="?", const=True, default=None, type=int, metavar="N",
                   help="run a Craig-Bampton reduced system (physical contact and sensor nodes, fixed-interface "
                   "modes up to 3 x sample-rate/2, or N modes); the truncation is recorded in the output")
    p.add_argument("--run-id", metavar="ID", help="run identifier recorded in the output")
    p.add_argument("-o", "--output", metavar="SIM.nc", required=True, help="output RunDataset (netCDF)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument("--json", action="store_true", help="print a JSON summary on stdout")
    p.add_argument("--dry-run", action="store_true",
                   help="check the settings, print the solver steps and the memory estimate; simulate nothing")
    p.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``fivid simulate``."""
    import numpy as np

    from fivid.errors import FividError
    from fivid.io import write_run
    from fivid.pipeline.resources import check_simulation_memory, simulation_memory
    from fivid.solver import simulate
    from fivid.storage import check_writable, dumps_json

    def si(value):  # a parsed Quantity -> plain float (None stays None)
        return None if value is None else float(value)

    if not args.dry_run:
        check_writable(args.output, overwrite=args.overwrite)
    law = None
    if args.law:
        try:
            from fivid.friction import load_law
        except ImportError:
            raise FividError("--law needs fivid.friction (friction laws), which this installation lacks") from None
        law = load_law(args.law)
    model = _load_model(args.model)
    duration, sample_rate, time_step = si(args.duration), si(args.sample_rate), si(args.time_step)
    size = simulation_memory(model, duration=duration, sample_rate=sample_rate, time_step=time_step, law=law)
    check_simulation_memory(size)  # before any allocation: a year of records fails here, not in the kernel
    if args.dry_run:
        print(f"{model.describe()}: {size.describe()}")
        return 0
    ds = simulate(
        model,
        law=law,
        mu=args.mu,
        sliding_velocity=si(args.velocity),
        normal_load=si(args.load),
        roughness_ra=si(args.roughness),
        duration=duration,
        sample_rate=sample_rate,
        seed=args.seed,
        time_step=time_step,
        run_id=args.run_id,
        reduced=args.reduced,
    )
    from fivid.schema import append_history

    append_history(ds, _command_line(args))
    write_run(ds, args.output, overwrite=args.overwrite)
    steady = ds.time >= ds.attrs["transient_end"]
    summary = {
        "output": str(args.output),
        "samples": int(ds.sizes["time"]),
        "time_step_s": ds.attrs["time_step"],
        "critical_time_step_s": ds.attrs["critical_time_step"],
        "transient_end_s": ds.attrs["transient_end"],
        "mean_normal_force_n": float(ds.normal_force.where(steady).mean()),
        "mean_friction_force_n": float(ds.friction_force.where(steady).mean()),
        "max_energy_balance_error_j": float(np.abs(ds.energy_balance_error).max()),
        "friction": ds.attrs["friction"],
    }
    summary.update({k: ds.attrs[k] for k in ("reduced_size", "reduced_modes", "reduced_cutoff",
                                             "reduced_first_truncated_frequency", "reduced_static_residual")
                    if k in ds.attrs})
    if args.json:
        print(dumps_json(summary))
    else:
        print(f"{model.describe()}; dt {summary['time_step_s']:.4g} s (critical {summary['critical_time_step_s']:.4g} s)")
        print(f"steady sliding from {summary['transient_end_s']:.4g} s: mean normal force "
              f"{summary['mean_normal_force_n']:.4g} N, friction force {summary['mean_friction_force_n']:.4g} N")
        print(f"written {args.output} ({summary['samples']} samples)", file=sys.stderr)
    return 0


def _load_model(path):
    """The model of ``path``; a mesh too large for this machine is a ConfigError naming the file."""
    from fivid.errors import ConfigError
    from fivid.fe import load_model
    from fivid.pipeline.resources import available_memory, format_bytes

    try:
        return load_model(path)
    except MemoryError as exc:
        free = available_memory()
        have = "" if free is None else f"; {format_bytes(free[0])} available ({free[1]})"
        raise ConfigError(f"not enough memory to build the mesh ({exc}){have}; lower the bodies' divisions",
                          file=path) from None


# option -> attribute of the parsed arguments, in the order of the help (for the history line)
_OPTIONS = (("--law", "law"), ("--mu", "mu"), ("--velocity", "velocity"), ("--load", "load"),
            ("--roughness", "roughness"), ("--duration", "duration"), ("--sample-rate", "sample_rate"),
            ("--seed", "seed"), ("--time-step", "time_step"), ("--reduced", "reduced"), ("--run-id", "run_id"),
            ("-o", "output"))


def _command_line(args) -> str:
    """The command as parsed, defaults included, shell-quoted so that it can be run again.

    Built from ``args``, not ``sys.argv``: :func:`fivid.cli.main` may be called in-process with its own argv.
    """
    import shlex

    words = ["fivid", "simulate", str(args.model)]
    for option, dest in _OPTIONS:
        value = getattr(args, dest)
        if value is True:  # a flag with an optional value given bare (--reduced)
            words.append(option)
        elif value is not None:
            words += [option, str(getattr(value, "text", value))]  # a quantity as it was written
    return shlex.join(words + (["--overwrite"] if args.overwrite else []))
