"""The ``fivid`` command line.

Each sub-command lives in its own module in :mod:`fivid.cli.commands` and defines
``register(subparsers)``, which adds its parser and sets ``func`` (a callable taking the parsed
arguments and returning an exit status). Modules are discovered, so adding a command touches no
other file. Command modules import heavy libraries inside their ``func``, so ``fivid --help`` is fast.

Exit codes, for schedulers: 0 success; 2 bad input or configuration (one clear line per problem on
stderr, no traceback); 3 the pipeline ran but scores are below their thresholds; 1 an unexpected
failure (traceback on stderr); 130 interrupted by SIGINT (Ctrl-C), 143 by SIGTERM (what schedulers send to
stop a job): 128 + the signal number, as a shell reports it. A signal that comes after the command has
finished (``fivid run``: after summary.json is written, e.g. during dask's shutdown at exit) does not change
the status: the process ends at once with the command's own (:class:`_SignalPolicy`).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import pkgutil
import sys

from fivid import __version__
from fivid.cli import commands
from fivid.cli.types import QuantityArgument, in_si, integer_at_least, quantity
from fivid.errors import FividError, Interrupted, exit_status

__all__ = ["main", "build_parser", "integer_at_least", "quantity", "QuantityArgument", "in_si", "quiet",
           "EXIT_OK", "EXIT_FAILURE", "EXIT_BAD_INPUT", "EXIT_BELOW_THRESHOLD", "exit_status_of_signal"]

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2
EXIT_BELOW_THRESHOLD = 3

# optional dependencies (pyproject extras) -> the extra that installs them
_OPTIONAL = {"dask": "sweep", "distributed": "sweep", "matplotlib": "report"}

_EPILOG = """\
exit status: 0 ok, 2 bad input or configuration, 3 scores below thresholds (fivid run),
1 unexpected failure, 130 interrupted (Ctrl-C), 143 terminated (SIGTERM).
Run 'fivid COMMAND --help' for a command's options."""


class _Parser(argparse.ArgumentParser):
    """argparse with the error contract of fivid: one line on stderr naming the command, exit status 2.

    Sub-command parsers are of this class too (``add_subparsers`` uses the parent's class).
    """

    def error(self, message: str):
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every sub-command found in :mod:`fivid.cli.commands`."""
    parser = _Parser(
        prog="fivid",
        description="fivid: friction-induced vibration identification. From friction test-rig "
        "measurements to an identified friction law, a finite-element contact simulation and "
        "PSD scores of simulated against measured vibration.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"fivid {__version__}")
    _add_verbosity(parser, 0)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"fivid.cli.commands.{info.name}")
        module.register(sub)
    for command_parser in _subparsers(parser):
        _add_verbosity(command_parser, argparse.SUPPRESS)
    return parser


def _add_verbosity(parser: argparse.ArgumentParser, default) -> None:
    """``-v``/``-q`` on ``parser``. On a sub-command they count into their own attributes (``default``
    SUPPRESS: absent unless given), added to the top-level counts by :func:`_verbosity`, so that
    ``fivid -v psd X.nc`` and ``fivid psd X.nc -v`` mean the same."""
    suffix = "" if default == 0 else "_after_command"
    parser.add_argument("-v", "--verbose", action="count", default=default, dest="verbose" + suffix,
                        help="more log output (-vv for debug); also accepted after the command")
    parser.add_argument("-q", "--quiet", action="count", default=default, dest="quiet" + suffix,
                        help="less log output: errors only; also accepted after the command")


def _subparsers(parser: argparse.ArgumentParser):
    """Every sub-command parser below ``parser``, nested ones (``fivid damper fit``) included."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in dict.fromkeys(action.choices.values()):  # aliases map to the same parser
                yield child
                yield from _subparsers(child)


def quiet(args: argparse.Namespace) -> bool:
    """True when ``-q`` outweighs ``-v`` (before and after the sub-command): print results, no per-item chatter."""
    return _verbosity(args) < 0


def _verbosity(args: argparse.Namespace) -> int:
    """-v count minus -q count, before and after the sub-command."""
    counts = [getattr(args, name, 0) for name in ("verbose", "verbose_after_command", "quiet", "quiet_after_command")]
    return counts[0] + counts[1] - counts[2] - counts[3]


@contextlib.contextmanager
def _logging_to_stderr(verbosity: int):
    """Route the ``fivid`` logger to stderr for one command; restore its previous state afterwards.

    Restoring matters when ``main`` is called in-process (tests, notebooks): the logger must not keep a
    handler on a stream that is closed later, nor stop propagating to the caller's handlers.
    """
    levels = {-1: logging.ERROR, 0: logging.WARNING, 1: logging.INFO}
    level = levels.get(verbosity, logging.ERROR if verbosity < 0 else logging.DEBUG)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("fivid: %(levelname)s: %(message)s"))
    log = logging.getLogger("fivid")
    saved = (list(log.handlers), log.level, log.propagate)
    log.handlers[:] = [handler]
    log.setLevel(level)
    log.propagate = False
    try:
        yield
    finally:
        log.handlers[:], level0, log.propagate = saved[0], saved[1], saved[2]
        log.setLevel(level0)


def exit_status_of_signal(signum: int) -> int:
    """The exit status of a command stopped by signal ``signum``: 128 + its number (130 SIGINT, 143 SIGTERM)."""
    return exit_status(Interrupted(signum))


class _SignalPolicy:
    """SIGINT and SIGTERM over a command's whole life, from parsing to the process's exit.

    While the command works, a signal raises :class:`~fivid.errors.Interrupted` (a KeyboardInterrupt): the
    default SIGTERM action kills the process on the spot (no summary, lock file left, exit -15); as an
    exception, the command cleans up like on Ctrl-C and exits 128 + the signal (130, 143). The signal is also
    recorded in ``Interrupted.received`` so that a pipeline notices it at its next task even if a library
    swallowed the exception.

    Once the outcome is settled (:meth:`~fivid.errors.Interrupted.settle`: ``fivid run`` wrote summary.json;
    any command when its function returns) a signal no longer interrupts: every output is complete and the
    exit status decided, so it is kept. Before :meth:`finish` the signal is only noted (the command ends its
    last lines of output); after it, stdout and stderr are flushed and the process exits at once with that
    status (``os._exit``: nothing is left to write, and a scheduler's SIGTERM asks for a prompt end).

    In a process (``process`` true) the handler stays installed after :func:`main` returns, through the
    threads' joins and the atexit clean-up (dask.distributed's among them). The interpreter's finalization
    after atexit resets SIGINT/SIGTERM to their defaults before it collects the modules and runs the C
    libraries' exit handlers -- ~1.5 s after a dask run, in which a scheduler's SIGTERM killed a passed run
    with -15. So the process ends with ``os._exit(status)`` at the end of the atexit clean-up (a handler
    registered when the command starts: it runs after those registered by what the command imported),
    skipping that last part, which has nothing of fivid's left to do. In-process (``process`` false: tests,
    notebooks) the previous handlers are restored on exit. Only the main thread can install handlers;
    elsewhere nothing changes.
    """

    def __init__(self, process: bool):
        self.process = process
        self.status: int | None = None
        self.late: int | None = None
        self.previous: dict = {}

    def __enter__(self):
        import atexit
        import signal
        import threading

        Interrupted.received = None
        Interrupted.settled = False
        if threading.current_thread() is threading.main_thread():
            self.previous = {s: signal.signal(s, self._handler) for s in (signal.SIGINT, signal.SIGTERM)}
            if self.process:
                atexit.register(self._end_process)
        return self

    def _end_process(self):
        """Last atexit step of a finished command: end the process before the finalization that cannot handle
        signals (see the class)."""
        if self.status is not None and self.previous:
            _exit_now(self.status, None)

    def _handler(self, signum, frame):
        if not Interrupted.settled:
            Interrupted.received = signum
            raise Interrupted(signum)
        self.late = signum
        if self.status is not None and self.process:
            _exit_now(self.status, signum)

    def finish(self, status: int) -> int:
        """The command's exit status is final; in a process, a signal noted since the outcome was settled ends it
        now (see the class). Returns ``status``."""
        Interrupted.settle()
        self.status = status
        if self.late is not None and self.process:
            _exit_now(status, self.late)
        return status

    def __exit__(self, *exc):
        import signal

        if self.process and self.status is not None:
            return False  # the handler covers the interpreter's shutdown too
        for s, h in self.previous.items():
            signal.signal(s, h)
        Interrupted.received = None
        Interrupted.settled = False
        return False


def _exit_now(status: int, signum: int | None) -> None:
    """End the process with ``status`` once the command has finished (see :class:`_SignalPolicy`): stdio
    flushed, no interpreter finalization; after a signal ``signum``, one line on stderr saying so."""
    import signal

    if signum is not None:
        try:
            print(f"fivid: {signal.Signals(signum).name} after the command had finished (outputs complete); "
                  f"exit status {status}", file=sys.stderr)
        except BaseException:  # noqa: BLE001 -- a reentrant print from a handler: the status matters, not the line
            pass
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except BaseException:  # noqa: BLE001 -- a closed pipe: nothing more to deliver
            pass
    os._exit(status)


def _missing_optional(exc: BaseException) -> str | None:
    """The optional package whose absence raised ``exc``, or None."""
    if isinstance(exc, ModuleNotFoundError):
        root = (exc.name or "").split(".")[0]
        if root in _OPTIONAL:
            return root
    return None


#: exit status when the reader of stdout closed the pipe (128 + SIGPIPE, as a shell reports a tool SIGPIPE ended)
EXIT_BROKEN_PIPE = 141


def main(argv: list[str] | None = None) -> int:
    """Run the ``fivid`` command; returns the exit status.

    ``argv`` None (the ``fivid`` console script, ``python -m fivid``): the command line of the process, which
    this call then ends: SIGINT/SIGTERM stay handled until the process exits (see :class:`_SignalPolicy`). A
    list: an in-process call (tests, notebooks); the signal handlers are restored when it returns.
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse refused the command line (message on stderr): return its status;
        if exc.code in (0, None):  # --help and --version still exit as argparse does
            raise
        return int(exc.code) if isinstance(exc.code, int) else EXIT_BAD_INPUT
    if args.command is None:
        parser.print_help(sys.stderr)
        return EXIT_BAD_INPUT
    with _logging_to_stderr(_verbosity(args)), _SignalPolicy(process=argv is None) as signals:
        return signals.finish(_run_command(args))


def _run_command(args) -> int:
    """Run the parsed command; its exit status, every failure mapped to its status and message."""
    try:
        status = args.func(args)
        Interrupted.settle()  # the command returned: its outputs are written
    except FividError as exc:
        print(f"fivid {args.command}: error: {exc}", file=sys.stderr)
        return exit_status(exc)
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM as Interrupted; no traceback
        print(f"fivid {args.command}: {exc if isinstance(exc, Interrupted) else 'interrupted by SIGINT'}",
              file=sys.stderr)
        return exit_status(exc)
    except MemoryError as exc:  # a problem too large for this machine: its size is the input to change
        print(f"fivid {args.command}: error: out of memory ({exc or 'MemoryError'}); make the problem smaller "
              "(mesh divisions, duration, sample rate, number of runs)", file=sys.stderr)
        return exit_status(exc)
    except BrokenPipeError:  # the reader closed our output early (`fivid ... | head`): not a failure of the command
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())  # so the interpreter's final flush does not raise again
        return EXIT_BROKEN_PIPE
    except Exception as exc:
        missing = _missing_optional(exc)
        if missing is not None:
            print(f"fivid {args.command}: error: this command needs the optional package {missing!r}, which is not "
                  f"installed; install it with: python -m pip install 'fivid[{_OPTIONAL[missing]}]'", file=sys.stderr)
            return EXIT_FAILURE
        import traceback

        traceback.print_exc()
        print(f"fivid {args.command}: unexpected failure (a bug: please report it with the traceback above)", file=sys.stderr)
        return EXIT_FAILURE
    return EXIT_OK if status is None else int(status)
