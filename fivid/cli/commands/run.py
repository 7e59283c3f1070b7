"""``fivid run``: the calibration pipeline (ingest → identify → simulate → score → report)."""

from __future__ import annotations

__all__ = ["register"]

_DESCRIPTION = """\
Run a pipeline recipe (pipelines/*.yaml: which stages, in which order) with a run configuration
(configs/runs/*.yaml: input folder, rig profile, model, band, seeds, thresholds, output folder).
The whole plan is validated before anything is computed. Each task's outputs are cached under a hash
of its inputs and parameters: a re-run with nothing new does no work, a new CSV re-runs only what
depends on it. One run at a time per output folder (lock). Writes <output>/summary.json,
<output>/report.html and <output>/fivid-run.log, and marks the folder with <output>/.fivid-output.json:
an existing folder holding other files is refused unless --force. Ctrl-C or SIGTERM stop the run
cleanly: summary.json says 'interrupted' with the stage, finished tasks are kept for the next run.

exit status: 0 pass, 3 scores below the configured thresholds, 2 bad input or configuration,
1 unexpected failure, 130 interrupted (Ctrl-C), 143 terminated (SIGTERM)."""


def register(subparsers) -> None:
    """Add the ``run`` sub-command."""
    import argparse

    p = subparsers.add_parser("run", help="run the calibration pipeline (cached, locked, on dask)",
                              description=_DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("pipeline", help="recipe file, e.g. pipelines/calibration.yaml")
    p.add_argument("--config", "-c", help="run configuration, e.g. configs/runs/sample.yaml")
    p.add_argument("--output", "-o", help="output folder (overrides the config's 'output')")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="dask scheduler tcp://host:port (default: a local cluster, nothing to start)")
    p.add_argument("--workers", type=int, default=2, metavar="N",
                   help="worker processes of the local dask cluster (default 2)")
    p.add_argument("--dry-run", action="store_true", help="validate and print what would run; compute nothing")
    p.add_argument("--force", action="store_true", help="re-run every task, ignoring the cache; also write into an existing folder "
                                                            "that is not a fivid output")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--json", action="store_true",
                   help="print <output>/summary.json on stdout (with --dry-run: the planned lines as "
                        '{"dry_run": true, "plan": [...]}); progress lines go to stderr')
    p.set_defaults(func=_run)


def _run(args) -> int:
    import sys

    from fivid.errors import ConfigError
    from fivid.pipeline import load_plan, run_pipeline
    from fivid.storage import dumps_json

    if args.workers < 1:
        raise ConfigError(f"--workers must be at least 1, got {args.workers}", key="--workers")
    plan = load_plan(args.pipeline, args.config, output=args.output)
    planned = []
    echo = planned.append if args.json and args.dry_run else (
        lambda line: print(line, file=sys.stderr if args.json else sys.stdout))
    status, summary = run_pipeline(plan, workers=args.workers, scheduler=args.scheduler, dry_run=args.dry_run,
                                   force=args.force, progress=False if args.no_progress else None, echo=echo,
                                   notify=lambda line: print(line, file=sys.stderr, flush=True))
    if args.json:
        print(dumps_json({"dry_run": True, "plan": planned} if args.dry_run else summary))
    if not args.dry_run:
        c = summary["cache"]
        print(f"fivid run: {summary['status']} (exit {status}) in {summary['seconds']:.1f} s; "
              f"{c['ran']} task(s) run, {c['cached']} cached; see {plan.config.output / 'summary.json'}",
              file=sys.stderr)
        for check in summary["checks"]:
            if not check["pass"]:
                print(f"  below threshold: {check['condition']}: {check['score']} = {check['value']} "
                      f"(need {check['threshold']})", file=sys.stderr)
        report = plan.config.output / "report.html"
        if report.is_file() and "report" in plan.stages:
            print(f"open the report: {report}", file=sys.stderr)
    return status
