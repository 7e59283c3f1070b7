"""``fivid verify [--quick] [--case NAME ...] [-o DIR] [--json]``: the verification manual of this installation."""

from __future__ import annotations

__all__ = ["register", "run", "format_table"]

_DESCRIPTION = """\
Run fivid's verification cases on this installation and write the manual: each case compares a quantity fivid
computes with a reference nobody here wrote (a closed form, a published benchmark, a standard, a measurement by
others), with its citation and a tolerance derived from the method. Prints the table (case, quantity, reference,
fivid, error, tolerance, pass) and writes DIR/verification.json and DIR/verification.html (one section per case
with its figure, and the environment: fivid version and git revision, numpy/scipy/numba versions, CPU, date).
Cases run on a dask LocalCluster (or --scheduler), like a study. Cases that need measured data not found are
skipped and say so (--real-data DIR). See docs/verification.md."""

_EPILOG = """\
examples:
  fivid verify --quick
  fivid verify --case hertz_half_width --case welch_vs_scipy -o verification --json
  fivid verify --list

exit status: 0 every case within its tolerance (skipped cases allowed), 3 a case outside its tolerance (or its
computation failed), 2 bad input (unknown case, bad folder), 1 unexpected failure."""


def register(subparsers) -> None:
    """Add the ``verify`` sub-command."""
    import argparse

    p = subparsers.add_parser("verify", help="run the verification cases and write the verification manual",
                              description=_DESCRIPTION, epilog=_EPILOG,
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true",
                   help="every case at reduced resolution (minutes, not tens of minutes)")
    p.add_argument("--case", action="append", metavar="NAME", dest="cases",
                   help="run this case only (repeatable; default: all; names: --list)")
    p.add_argument("-o", "--output", default="fivid-verification", metavar="DIR",
                   help="folder for verification.json and verification.html (default ./fivid-verification)")
    p.add_argument("--json", action="store_true", help="print the results as JSON (cases, passed, environment)")
    p.add_argument("--list", action="store_true", help="list the catalogue (name, quantity, source) and exit")
    p.add_argument("--real-data", metavar="DIR",
                   help="folder of the measured data the data cases need (default: the data shipped in fivid, then "
                        "../shared/real_data beside a checkout)")
    p.add_argument("--workers", type=int, default=2, metavar="N",
                   help="worker processes of the local dask cluster (default 2; 0: in this process, no dask)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="dask scheduler tcp://host:port (default: a local cluster, nothing to start)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def format_table(header: list[str], rows: list[list]) -> str:
    """A plain-text table: floats to 4 significant digits, booleans as pass/FAIL, None as a dash."""
    def cell(v):
        if isinstance(v, bool):
            return "pass" if v else "FAIL"
        if isinstance(v, float):
            return "-" if v != v else f"{v:.4g}"
        return "-" if v is None else str(v)

    text = [[cell(v) for v in row] for row in rows]
    widths = [max(len(h), *(len(r[i]) for r in text)) if text else len(h) for i, h in enumerate(header)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths))]
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths)) for r in text]
    return "\n".join(lines)


def run(args) -> int:
    """Handler of ``fivid verify``."""
    from pathlib import Path

    from fivid.errors import ConfigError
    from fivid.storage import dumps_json, write_json
    from fivid.verify import environment, render_manual, run_cases, select_cases
    from fivid.verify.manual import SUMMARY_HEADER, summary_rows

    if args.workers < 0:
        raise ConfigError(f"--workers must be >= 0, got {args.workers}", key="--workers")
    cases = select_cases(args.cases)
    if args.list:
        print(format_table(["case", "quantity", "source"], [[c.name, c.quantity, c.source[:90]] for c in cases]))
        return 0
    out = Path(args.output)
    if out.exists() and not out.is_dir():
        raise ConfigError(f"-o {args.output!r} is a file; give a folder (created if absent)", key="--output")
    if args.real_data is not None and not Path(args.real_data).is_dir():
        raise ConfigError(f"--real-data {args.real_data!r} is not a folder; give the folder holding profiles/ and "
                          "friction_damper/ (../shared/real_data of a checkout)", key="--real-data")
    env = environment()
    results = run_cases(cases, quick=args.quick, workers=args.workers, scheduler=args.scheduler,
                        real_data=args.real_data, progress=False if args.no_progress else None)
    passed = all(r.status != "failed" for r in results)
    doc = {"passed": passed, "quick": bool(args.quick), "n_cases": len(results),
           "n_passed": sum(r.status == "passed" for r in results),
           "n_failed": sum(r.status == "failed" for r in results),
           "n_skipped": sum(r.status == "skipped" for r in results),
           "cases": [r.as_json() for r in results], "environment": env,
           "manual": str(out / "verification.html")}
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "verification.json", doc)
    render_manual(out / "verification.html", results, env, quick=args.quick)
    if args.json:
        print(dumps_json(doc))
    else:
        print(format_table(SUMMARY_HEADER, summary_rows(results)))
        print(f"{'PASSED' if passed else 'FAILED'}: {doc['n_passed']} passed, {doc['n_failed']} failed, "
              f"{doc['n_skipped']} skipped; manual {out / 'verification.html'}")
        for r in results:
            if r.status != "passed":
                print(f"  {r.case.name}: {r.status}: {r.reason}")
    return 0 if passed else 3
