"""``fivid study STUDY.yaml -o DIR``: a parametric study (sweep -> per-point analyses -> regimes, fits, report)."""

from __future__ import annotations

__all__ = ["register"]

_DESCRIPTION = """\
Run a parametric study (configs/studies/*.yaml; keys in docs/studies.md): a sweep over conditions with
units (normal load, velocity, roughness, mu, seed), at each point the analyses the study asks for (preloaded
modes, transient with a law or mu, PSD, regime classification), and once for the study a CEA over mu.
Points run on a dask LocalCluster (or --scheduler), each written to DIR/points/ as it finishes: a re-run skips
finished points, so a killed study resumes. Writes DIR/study.nc (a 'point' dimension with the swept conditions
as coordinates), DIR/summary.json and DIR/report.html.

exit status: 0 all points done, 2 bad input or configuration, 1 a point failed (the others are kept)
or an unexpected failure."""


def register(subparsers) -> None:
    """Add the ``study`` sub-command."""
    import argparse

    p = subparsers.add_parser("study", help="run a parametric study (sweep, per-point analyses, regimes, report)",
                              description=_DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("study", metavar="STUDY.yaml", help="study config, e.g. configs/studies/hoffmann_mu_sweep.yaml")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="output folder (created; resumable)")
    p.add_argument("--quick", action="store_true", help="the study's coarse variant (its 'quick' overrides)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="dask scheduler tcp://host:port (default: a local cluster, nothing to start)")
    p.add_argument("--workers", type=int, default=2, metavar="N",
                   help="worker processes of the local dask cluster (default 2; 0: in this process, no dask)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_run)


def _run(args) -> int:
    import sys

    from fivid.errors import ConfigError
    from fivid.storage import dumps_json
    from fivid.study import AXES, load_study, run_study

    if args.workers < 0:
        raise ConfigError(f"--workers must be >= 0, got {args.workers}", key="--workers")
    study = load_study(args.study, quick=args.quick)
    summary = run_study(study, args.output, workers=args.workers, scheduler=args.scheduler,
                        progress=False if args.no_progress else None)
    if args.json:
        print(dumps_json(summary))
    else:
        print(f"study {summary['study']}: {summary['n_done']}/{summary['n_points']} points done in "
              f"{summary['timing']['wall_s']:.1f} s; see {args.output}/summary.json and report.html")
        if "critical_mu" in summary:
            c = summary["critical_mu"]
            print("  CEA: stable over the mu range" if c is None else
                  f"  CEA: critical mu {c['value']:.4g} at {c['frequency']:.4g} Hz")
        for line in _transition_lines(summary):
            print(line)
        for p in summary["points"]:
            cond = ", ".join(_with_units(k, v) for k, v in p.items() if k in AXES)
            print(f"  {cond}: {p.get('regime', p['status'])}")
    for f in summary["failed"]:
        print(f"  point {f['point']} failed: {f['error']}", file=sys.stderr)
    return 1 if summary["failed"] else 0


def _with_units(name: str, value) -> str:
    """``normal_load 5 N``: a swept quantity with its units (fivid.study.config.AXES; none for a pure number)."""
    from fivid.study.config import AXES  # here, not at module top: every command's parser imports this module

    units = AXES[name][0]
    return f"{name} {value:g}" + ("" if units == "1" else f" {units}")


def _transition_lines(summary: dict) -> list[str]:
    """The weak/strong transition load of a load sweep (summary ``transition_load``, ``transition_loads``)."""
    from fivid.study.config import AXES

    def one(t) -> str:
        if t.get("value") is None:
            return t.get("note", "no transition in the swept loads")
        lo, hi = t["bracket"]
        return (f"at normal_load {t['value']:.3g} N (between the swept {lo:g} and {hi:g} N; "
                f"{t.get('criterion_label', 'coupling indicator kappa').replace('κ', 'kappa')} = {t['threshold']:g})")

    t = summary.get("transition_load")
    if not t:
        return []
    lines = [f"  weak/strong contact transition: {one(t)}"]
    for group in summary.get("transition_loads", []):
        cond = ", ".join(_with_units(k, v) for k, v in group.items() if k in AXES)
        lines.append(f"    {cond}: {one(group)}")
    return lines
