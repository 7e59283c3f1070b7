"""The load guard every benchmark shares: figures taken on a busy machine measure the other jobs.

A benchmark parses its arguments with :func:`parse_guarded` (which adds ``--force``), then puts the returned
1-minute load average into its JSON line as ``load_average_1min``::

    args, load = parse_guarded(parser, argv)
    ...
    out["load_average_1min"] = load

When the 1-minute load average at the start exceeds the number of cores the benchmark refuses to run: it
prints why on stderr and exits with status 3, unless ``--force`` is given (a smoke run, or a deliberate
measurement of ratios on a loaded machine -- the load is then in the JSON line to judge the figures by).
"""

from __future__ import annotations

import argparse
import os
import sys

__all__ = ["LOADED_EXIT_STATUS", "check_load", "parse_guarded"]

#: exit status of a benchmark that refused to run on a loaded machine
LOADED_EXIT_STATUS = 3


def check_load(force: bool, *, load: float | None = None, cores: int | None = None) -> float:
    """The 1-minute load average [runnable processes]; exit with :data:`LOADED_EXIT_STATUS` and a message when it
    exceeds ``cores`` (default: ``os.cpu_count()``) and ``force`` is false. ``load`` defaults to
    ``os.getloadavg()[0]``."""
    load = os.getloadavg()[0] if load is None else float(load)
    cores = (os.cpu_count() or 1) if cores is None else int(cores)
    if load > cores and not force:
        print(f"{os.path.basename(sys.argv[0]) or 'benchmark'}: the 1-minute load average is {load:.2f}, above the "
              f"{cores} cores of this machine: timings taken now would measure the other jobs. Run it again when "
              f"the machine is idle (see `uptime`), or pass --force to run anyway (the load is recorded in the "
              f"JSON line as load_average_1min).", file=sys.stderr)
        raise SystemExit(LOADED_EXIT_STATUS)
    return round(load, 2)


def parse_guarded(parser: argparse.ArgumentParser, argv=None) -> tuple[argparse.Namespace, float]:
    """Add ``--force`` to ``parser``, parse ``argv`` and check the load (:func:`check_load`); returns
    ``(arguments, 1-minute load average at the start)``."""
    parser.add_argument("--force", action="store_true",
                        help="run even when the 1-minute load average exceeds the number of cores (the figures "
                             "are then unreliable; the load is printed in the JSON line)")
    args = parser.parse_args(argv)
    return args, check_load(args.force)
