"""``fivid simulate MODEL.yaml [--law LAW.nc [--samples N] | --mu MU] ... -o SIM.nc``: explicit contact simulation.

With ``--samples N`` the output is a Monte-Carlo PSD envelope instead of one run (issue 16 item 3).
"""

from __future__ import annotations

import argparse
import sys

from fivid.cli import in_si, integer_at_least, quantity

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
        "SI units (m/s, N, m, s, Hz). "
        "With --law, the condition is checked against the law's identified domain: outside it a warning names the "
        "variable and the identified range (--strict: refused, exit 2). "
        "--samples N: a Monte-Carlo over the law's uncertainty (amplitude-law coefficients drawn from their "
        "covariance, an independent seed per sample; mu0 and the spectral shape kept), run on dask; -o is then the "
        "PSD envelope (netCDF: psd_median, psd_p05, psd_p95, every sample's PSD and 1/3-octave band levels) for "
        "'fivid score --envelope'. See docs/uncertainty.md.",
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
    path = p.add_mutually_exclusive_group()
    path.add_argument("--reduced", nargs="?", const="reduced", default=None, type=_mode_count, metavar="N",
                      help="force the Craig-Bampton reduced system (physical contact and sensor nodes; fixed-interface "
                      "modes and mass scaling at 18 x sample-rate/2, basis from the cache), or with N: N modes, no "
                      "mass scaling. Default: chosen automatically, reduced when its estimated in-band error is "
                      "within --reduced-tolerance (docs/solver.md)")
    path.add_argument("--full", dest="reduced", action="store_const", const="full",
                      help="force the full model (no reduction, no estimate)")
    p.add_argument("--reduced-tolerance", metavar="DB", type=float, default=0.5,
                   help="largest estimated in-band log-spectral distance [dB] of the reduced path for the automatic "
                   "choice (default 0.5)")
    p.add_argument("--reduced-check", action="store_true",
                   help="after a reduced run, check it against a second reduced run at half its step (a Richardson "
                   "pair: about twice the reduced run's time loop) and record reduced_error_check_db; with the "
                   "automatic choice, run the full model instead when that figure exceeds --reduced-tolerance "
                   "(docs/solver.md)")
    p.add_argument("--error-band", nargs=2, metavar=("LOW", "HIGH"), type=quantity("Hz", nonnegative=True),
                   help="band of that estimate, e.g. '800 Hz' '8 kHz' (default 200 Hz to 10 kHz or sample-rate/2)")
    p.add_argument("--reduced-mass-scaling", metavar="Q", type=quantity("Hz", positive=True),
                   help="with --reduced: keep the modes up to Q and mass-scale the reduced system's modes above Q "
                   "down to Q (longer stable step; the default reduced path uses 18 x the band top, 460.8 kHz for "
                   "51.2 kHz records, docs/solver.md); bare number in Hz")
    p.add_argument("--cache-dir", metavar="DIR",
                   help="reduced-basis cache folder (default $FIVID_CACHE_DIR, else the user cache folder; "
                        "'fivid cache info')")
    p.add_argument("--run-id", metavar="ID", help="run identifier recorded in the output")
    p.add_argument("--strict", action="store_true",
                   help="refuse a condition outside the law's identified domain (exit 2) instead of warning")
    mc = p.add_argument_group("Monte-Carlo envelope (--law with --samples)")
    mc.add_argument("--samples", type=integer_at_least(2), metavar="N",
                    help="simulate N draws of the law's uncertainty (seeds derived from --seed) and write their PSD "
                         "envelope to -o instead of one run")
    mc.add_argument("--nperseg", type=integer_at_least(2), default=8192, metavar="N",
                    help="Welch segment length of the samples' PSDs (default 8192, as 'fivid score'); the steady "
                         "record (--duration x --sample-rate) must hold one")
    mc.add_argument("--variable", default="acceleration", help="variable whose PSD is taken (default acceleration)")
    mc.add_argument("--sensor", default=None, help="sensor name when the variable has several")
    mc.add_argument("--workers", type=integer_at_least(0), default=2, metavar="N",
                    help="dask worker processes (default 2; 0 runs the samples in this process)")
    mc.add_argument("--scheduler", metavar="ADDRESS", help="tcp://host:port of a running dask scheduler")
    mc.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                    help="progress bar over the samples (default: when stderr is a terminal)")
    p.add_argument("-o", "--output", metavar="SIM.nc", required=True,
                   help="output RunDataset (netCDF); with --samples the PSD envelope (netCDF)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing output file")
    p.add_argument("--json", action="store_true", help="print a JSON summary on stdout")
    p.add_argument("--dry-run", action="store_true",
                   help="check the settings, choose the solver path, print the solver steps, the memory estimate and "
                        "the estimated run time (from a short timed probe of the time loop; builds the reduced basis "
                        "if it is not cached); write nothing else")
    p.set_defaults(func=run)


def run(args) -> int:
    """Handler of ``fivid simulate``."""
    import numpy as np

    from fivid.errors import FividError
    from fivid.io import write_run
    from fivid.solver import simulate
    from fivid.storage import check_writable, dumps_json

    if args.samples is not None and not args.law:
        raise FividError("--samples needs --law LAW.nc: the Monte-Carlo samples the law's uncertainty")
    if not args.dry_run:
        check_writable(args.output, overwrite=args.overwrite)
    law = law_file = None
    model = _load_model(args.model)
    if args.law:
        law, law_file = _law_checked(args, model)
        args.law_domain = law_file.pop("domain")
    inputs = _simulation_inputs(args, law)
    size = _checked_size(args, model, inputs, law)  # before any allocation: a year of records fails here
    if args.dry_run:
        return _dry_run(args, model, size, inputs)
    if args.samples is not None:
        return _run_samples(args, model, inputs, law_file)
    ds = simulate(model, inputs.condition, inputs.friction, schedule=inputs.schedule,
                  integration=inputs.integration, output=inputs.output)
    from fivid.schema import append_history

    append_history(ds, _command_line(args))
    write_run(ds, args.output, overwrite=args.overwrite)
    from fivid.signal.steady import steady_part

    steady = steady_part(ds)  # from the run's transient_end
    summary = {
        "output": str(args.output),
        "samples": int(ds.sizes["time"]),
        "time_step_s": ds.attrs["time_step"],
        "critical_time_step_s": ds.attrs["critical_time_step"],
        "transient_end_s": ds.attrs["transient_end"],
        "mean_normal_force_n": float(steady.normal_force.mean()),
        "mean_friction_force_n": float(steady.friction_force.mean()),
        "max_energy_balance_error_j": float(np.abs(ds.energy_balance_error).max()),
        "friction": ds.attrs["friction"],
    }
    if getattr(args, "law_domain", None) is not None:
        summary["law_domain"] = args.law_domain
    summary.update({k: ds.attrs[k] for k in ("solver_path", "solver_choice", "solver_choice_reason",
                                             "reduced_error_estimate_db", "reduced_error_tolerance_db",
                                             "reduced_error_band", "reduced_basis_source", "reduced_setup_time",
                                             "reduced_size", "reduced_modes", "reduced_cutoff",
                                             "reduced_first_truncated_frequency", "reduced_static_residual",
                                             "reduced_mass_scaling", "reduced_added_mass_fraction",
                                             "reduced_error_check_db", "reduced_error_check_step_ratio")
                    if k in ds.attrs})
    if args.json:
        print(dumps_json(summary))
    else:
        print(f"{model.describe()}; dt {summary['time_step_s']:.4g} s (critical {summary['critical_time_step_s']:.4g} s)")
        print(f"solver path: {summary.get('solver_path', 'full')} ({summary.get('solver_choice_reason', '')})")
        print(f"steady sliding from {summary['transient_end_s']:.4g} s: mean normal force "
              f"{summary['mean_normal_force_n']:.4g} N, friction force {summary['mean_friction_force_n']:.4g} N")
        print(f"written {args.output} ({summary['samples']} samples)", file=sys.stderr)
    return 0


def _checked_size(args, model, inputs, law):
    """The run's memory and work estimate (:func:`fivid.execution.resources.simulation_memory`), refused with a
    ConfigError when too large -- for ``--samples`` the N runs' too.

    Without ``--time-step`` the estimate needs the stable step. Unless ``--dry-run`` prints the estimate, a lower
    bound of the full model's step (:func:`fivid.solver.timestep.stable_step_bound`, no eigenvalue solve: more
    steps, hence more work and memory, than the run takes) is tried first; the full model's exact step, whose
    eigenvalue solve the reduced path does not otherwise need, is computed only when the bound does not pass.
    """
    from fivid.errors import ConfigError
    from fivid.execution.resources import check_monte_carlo_size, check_simulation_memory, simulation_memory
    from fivid.solver.timestep import stable_step_bound

    def checked(time_step):
        size = simulation_memory(model, duration=inputs.schedule.duration, sample_rate=inputs.schedule.sample_rate,
                                 time_step=time_step, law=law)
        check_simulation_memory(size, n_dofs=2 * model.n_nodes)
        if args.samples is not None:  # N runs' work and the envelope's PSDs (fivid.execution.resources)
            check_monte_carlo_size(size, samples=args.samples, nperseg=args.nperseg, n_dofs=2 * model.n_nodes,
                                   workers=args.workers)
        return size

    if inputs.integration.time_step is None and not args.dry_run:
        try:
            return checked(float(inputs.integration.safety) * stable_step_bound(model).critical_time_step)
        except ConfigError:
            pass  # the bound may be too pessimistic: judge by the exact step
    return checked(inputs.integration.time_step)


def _mode_count(text):
    """``--reduced N``: a number of modes >= 1 (argparse also passes the bare flag's constant through here)."""
    if text == "reduced":
        return text
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected a number of modes >= 1, got {text!r}")
    return n


def _simulation_inputs(args, law):
    """The grouped inputs of :func:`fivid.solver.simulate` from the parsed arguments (SI floats)."""
    from fivid.solver import (
        FrictionInput,
        IntegrationOptions,
        OperatingCondition,
        OutputOptions,
        RunSchedule,
        SimulationInputs,
    )

    return SimulationInputs(
        OperatingCondition(in_si(args.velocity), in_si(args.load), in_si(args.roughness)),
        FrictionInput(law=law, mu=args.mu, seed=args.seed),
        RunSchedule(duration=in_si(args.duration), sample_rate=in_si(args.sample_rate)),
        IntegrationOptions(time_step=in_si(args.time_step), **_path_options(args)),
        OutputOptions(run_id=args.run_id))


def _path_options(args) -> dict:
    """The solver-path arguments of :func:`fivid.solver.simulate` from ``--full``/``--reduced [N]`` (default auto),
    ``--reduced-tolerance``, ``--reduced-check``, ``--error-band``, ``--reduced-mass-scaling`` and ``--cache-dir``."""
    from fivid.errors import ConfigError

    reduced = {None: "auto", "full": None}.get(args.reduced, args.reduced)
    scaling = None if args.reduced_mass_scaling is None else float(args.reduced_mass_scaling)
    if scaling is not None and reduced != "reduced" and not isinstance(reduced, int):
        raise ConfigError("--reduced-mass-scaling needs --reduced (it sets the forced reduced path's scaling)",
                          key="--reduced-mass-scaling")
    if scaling is not None and isinstance(reduced, int) and not isinstance(reduced, bool):
        raise ConfigError(f"give --reduced without N with --reduced-mass-scaling (its frequency sets the modes kept), "
                          f"not {reduced} modes", key="--reduced-mass-scaling")
    if not (args.reduced_tolerance >= 0.0):
        raise ConfigError(f"--reduced-tolerance must be a number of dB >= 0, got {args.reduced_tolerance!r}",
                          key="--reduced-tolerance")
    band = None if args.error_band is None else tuple(float(b) for b in args.error_band)
    if band is not None and not band[0] < band[1]:
        raise ConfigError(f"--error-band LOW HIGH needs LOW < HIGH, got {band[0]:g} Hz and {band[1]:g} Hz",
                          key="--error-band")
    if args.reduced_check and reduced is None:
        raise ConfigError("--reduced-check checks a reduced run; it has nothing to check with --full",
                          key="--reduced-check")
    return dict(reduced=reduced, reduced_mass_scaling=scaling, reduced_tolerance=float(args.reduced_tolerance),
                error_band=band, cache_dir=args.cache_dir, reduced_check=bool(args.reduced_check))


def _dry_run(args, model, size, inputs) -> int:
    """``--dry-run``: the memory estimate, the solver path and the run time estimated from a short timed probe."""
    import time

    from fivid.solver.driver import choice_attrs, prepare_run
    from fivid.solver.runtime import estimate_run_time
    from fivid.storage import dumps_json

    t0 = time.perf_counter()
    prep = prepare_run(model, inputs.condition, inputs.friction, schedule=inputs.schedule,
                       integration=inputs.integration, output=inputs.output)
    timing = estimate_run_time(prep, setup_seconds=time.perf_counter() - t0)
    path = choice_attrs(prep.choice)
    if args.samples is not None:  # every sample runs the same steps; the workers share the cached basis
        per_sample = timing["loop_seconds"] + timing["setup_seconds"]
        timing["estimated_seconds"] = timing["setup_seconds"] + per_sample * args.samples / max(1, args.workers)
    if args.json:
        print(dumps_json({"dry_run": True, "model": model.describe(), "output_samples": size.output_samples,
                          "memory_bytes": size.bytes, "memory_parts_bytes": size.parts,
                          "solver_path": path.get("solver_path"), "solver_choice_reason": path.get("solver_choice_reason"),
                          "reduced_error_estimate_db": path.get("reduced_error_estimate_db"),
                          "time_step_s": prep.settings.time_step, "solver_steps": timing["steps"],
                          "estimated_run_time_s": timing["estimated_seconds"], "run_time_estimate": timing}))
    else:
        print(f"{model.describe()}: {size.describe()}")
        print(f"solver path: {path.get('solver_path')} ({path.get('solver_choice_reason')}); "
              f"{timing['steps']:,} solver steps of {prep.settings.time_step:.3g} s on that path")
        print(f"estimated run time: about {timing['estimated_seconds']:.3g} s on this machine now (set-up "
              f"{timing['setup_seconds']:.3g} s + time loop {timing['loop_seconds']:.3g} s, from a timed probe of "
              f"{timing['probe_intervals'][1]} of {timing['n_intervals']} intervals)")
    return 0


def _law_checked(args, model):
    """The law of ``--law`` and its file record, the condition checked against its identified domain."""
    import hashlib
    from pathlib import Path

    from fivid.cli.law_domain import check_law_condition, open_law_file
    from fivid.friction import PerturbedCoulombLaw

    _, law, domain = open_law_file(args.law)
    record = {"law_file": str(args.law), "law_file_sha256": hashlib.sha256(Path(args.law).read_bytes()).hexdigest(),
              "domain": None}
    if isinstance(law, PerturbedCoulombLaw):  # a Coulomb law has no amplitude, hence no domain to leave
        base = model.motion("base")
        velocity = float(args.velocity) if args.velocity is not None else abs(base.amplitude) if base else None
        pred = check_law_condition(law, domain, velocity, in_si(args.roughness), in_si(args.load), strict=args.strict,
                                   command="simulate")
        record["domain"] = {"checked": domain is not None, "inside": bool(pred.inside[0]), "warnings": pred.messages}
    return law, record


def _run_samples(args, model, inputs, law_file) -> int:
    """``--samples N``: the Monte-Carlo envelope of the law at the condition, written to ``-o``."""
    from fivid.identify.montecarlo import EnvelopeSpectrum
    from fivid.pipeline.montecarlo import SampleExecution, run_monte_carlo
    from fivid.schema import new_history
    from fivid.storage import dumps_json, write_netcdf

    env = run_monte_carlo(
        model, inputs.friction.law, inputs.condition, inputs.schedule, samples=args.samples, seed=args.seed,
        integration=inputs.integration,
        spectrum=EnvelopeSpectrum(variable=args.variable, sensor=args.sensor, nperseg=args.nperseg),
        execution=SampleExecution(workers=args.workers, scheduler=args.scheduler, progress=args.progress),
        attrs={**law_file, "law_domain_check": _domain_text(args.law_domain), "model": str(args.model),
               "model_description": model.describe(),
               "history": new_history(_command_line(args))},
    )
    write_netcdf(env, args.output, overwrite=args.overwrite)
    summary = {"output": str(args.output), "samples": int(env.sizes["sample"]), "seed": int(args.seed),
               "law_domain": args.law_domain,
               "seeds": env["sample_seed"].values.tolist(), "law_file_sha256": law_file["law_file_sha256"],
               "coefficient_covariance_sampled": bool(env.attrs["coefficient_covariance_sampled"]),
               "amplitude": {"median": float(env["sample_amplitude"].median()),
                             "min": float(env["sample_amplitude"].min()), "max": float(env["sample_amplitude"].max())},
               "frequency_resolution_hz": env.attrs["frequency_resolution"],
               "bands": [{"centre_hz": float(c), "p05_db": float(a), "median_db": float(b), "p95_db": float(d)}
                         for c, a, b, d in zip(env["band_centre"].values, env["band_level_p05"].values,
                                               env["band_level_median"].values, env["band_level_p95"].values)]}
    if args.json:
        print(dumps_json(summary))
    else:
        widths = [b["p95_db"] - b["p05_db"] for b in summary["bands"]]
        print(f"{model.describe()}; {summary['samples']} Monte-Carlo samples, amplitude A from "
              f"{summary['amplitude']['min']:.4g} to {summary['amplitude']['max']:.4g} (median "
              f"{summary['amplitude']['median']:.4g})")
        if widths:
            print(f"5-95 % envelope width over {len(widths)} 1/3-octave bands: {min(widths):.3g} to "
                  f"{max(widths):.3g} dB")
        print(f"written {args.output}", file=sys.stderr)
    return 0


def _domain_text(domain) -> str:
    """One line for the envelope file: whether the condition was inside the law's identified domain."""
    if domain is None or not domain["checked"]:
        return "not checked (the law file records no domain)"
    return "inside the identified domain" if domain["inside"] else "outside: " + " | ".join(domain["warnings"])


def _load_model(path):
    """The model of ``path``; a mesh too large for this machine is a ConfigError naming the file."""
    from fivid.errors import ConfigError
    from fivid.fe import load_model
    from fivid.execution.resources import available_memory, format_bytes

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
            ("--seed", "seed"), ("--time-step", "time_step"), ("--reduced", "reduced"), ("--reduced-tolerance", "reduced_tolerance"),
            ("--reduced-check", "reduced_check"), ("--error-band", "error_band"), ("--reduced-mass-scaling", "reduced_mass_scaling"), ("--run-id", "run_id"),
            ("--samples", "samples"), ("-o", "output"))


def _command_line(args) -> str:
    """The command as parsed, defaults included, shell-quoted so that it can be run again.

    Built from ``args``, not ``sys.argv``: :func:`fivid.cli.main` may be called in-process with its own argv.
    """
    import shlex

    words = ["fivid", "simulate", str(args.model)]
    for option, dest in _OPTIONS:
        value = getattr(args, dest, None)
        if dest == "reduced":  # the solver path: auto (nothing), --full, --reduced or --reduced N
            words += {None: [], "full": ["--full"], "reduced": ["--reduced"]}.get(value, ["--reduced", str(value)])
        elif isinstance(value, bool):  # a flag: named when set
            words += [option] if value else []
        elif isinstance(value, (list, tuple)):
            words += [option, *(str(getattr(v, "text", v)) for v in value)]
        elif value is not None:
            words += [option, str(getattr(value, "text", value))]  # a quantity as it was written
    if getattr(args, "samples", None) is not None:
        words += ["--nperseg", str(args.nperseg), "--variable", args.variable]
        words += ["--sensor", args.sensor] if args.sensor is not None else []
    words += ["--strict"] if getattr(args, "strict", False) else []
    return shlex.join(words + (["--overwrite"] if args.overwrite else []))
