"""Errors a person can act on.

Every domain error subclasses :class:`ValueError` through :class:`FividError`. A message says what
was wrong, where (file, line, column or config key), the value given, and what is allowed. The CLI
prints ``str(error)`` on one line without a traceback and exits with status 2.
"""

from __future__ import annotations

from os import PathLike

__all__ = [
    "FividError",
    "SchemaError",
    "ConfigError",
    "DataQualityError",
    "UnitError",
    "OutputExistsError",
    "SimulationDiverged",
    "Interrupted",
    "exit_status",
]


class FividError(ValueError):
    """Base class of fivid's input errors (bad data, bad configuration, bad units).

    Parameters
    ----------
    message : str
        What is wrong, the value given and what is allowed.
    file : str or path-like, optional
        The file the problem is in.
    line : int, optional
        1-based line number in ``file``.
    column : str, optional
        Column name (CSV) where the problem is.
    key : str, optional
        Config key path such as ``bodies[0].material.E``.
    """

    def __init__(
        self,
        message: str,
        *,
        file: str | PathLike | None = None,
        line: int | None = None,
        column: str | None = None,
        key: str | None = None,
    ):
        self.message = message
        self.file = None if file is None else str(file)
        self.line = line
        self.column = column
        self.key = key
        super().__init__(str(self))

    def where(self) -> str:
        """The location part of the message: ``file:line: column 'c': key 'k'`` (may be empty)."""
        parts = []
        if self.file is not None:
            parts.append(self.file + (f":{self.line}" if self.line is not None else ""))
        elif self.line is not None:
            parts.append(f"line {self.line}")
        if self.column is not None:
            parts.append(f"column {self.column!r}")
        if self.key is not None:
            parts.append(f"key {self.key!r}")
        return ": ".join(parts)

    def __str__(self) -> str:
        where = self.where()
        return f"{where}: {self.message}" if where else self.message

    def located(self, **where) -> "FividError":
        """A copy of this error with location fields filled in where they are still empty."""
        fields = {k: getattr(self, k) for k in ("file", "line", "column", "key")}
        for k, v in where.items():
            if fields.get(k) is None:
                fields[k] = v
        return type(self)(self.message, **fields)


class SchemaError(FividError):
    """A dataset or file does not follow fivid's schema (missing variable, wrong dims or units)."""


class ConfigError(FividError):
    """A configuration (YAML) is invalid; ``key`` names the key path."""


class DataQualityError(FividError):
    """Data are well-formed but unusable (NaN, non-uniform sampling, too short, no steady sliding)."""


class UnitError(FividError):
    """A unit is unknown, or not compatible with the quantity it is given for."""


class OutputExistsError(FividError):
    """An output file exists and overwriting was not asked for."""


class SimulationDiverged(FividError):
    """The explicit run produced NaN or a runaway energy; the message names the step, time and node."""


class Interrupted(KeyboardInterrupt):
    """A run stopped by a signal (SIGINT: Ctrl-C; SIGTERM: what schedulers send); the CLI exits 128 + ``signum``.

    A :class:`KeyboardInterrupt`, so code that already cleans up on Ctrl-C cleans up on SIGTERM too.
    """

    received: int | None = None  # set by the CLI's handler: a signal seen even if a library swallowed the exception
    #: True once the command's outcome is final and its outputs are complete (``fivid run``: summary.json written,
    #: :meth:`settle`); the CLI's handler then no longer raises: a later SIGINT/SIGTERM keeps the command's own
    #: exit status (see :func:`fivid.cli.main`)
    settled: bool = False

    @classmethod
    def raise_if_received(cls) -> None:
        """Raise at a safe point if a signal arrived whose exception was swallowed (a bare ``except:``)."""
        if cls.received is not None:
            raise cls(cls.received)

    @classmethod
    def settle(cls) -> None:
        """Mark the running command's outcome as final: every output is written and its exit status decided.

        Called by :func:`fivid.pipeline.run_pipeline` once ``summary.json`` is written (and by the CLI when a
        command returns). A signal after this point cannot make the run "interrupted" any more: its outputs and
        summary are complete, so the process keeps the run's exit status instead of 128 + the signal.
        """
        cls.settled = True

    def __init__(self, signum: int, detail: str = ""):
        import signal

        self.signum = int(signum)
        self.signame = signal.Signals(self.signum).name
        super().__init__(f"interrupted by {self.signame}" + (f" {detail}" if detail else ""))


def exit_status(exc: BaseException) -> int:
    """The exit status a command ends with when ``exc`` stops it: the one rule the CLI and summaries share.

    2 for bad input (:class:`FividError`) and for :class:`MemoryError` (the problem's size is the input
    to change), 128 + the signal number for an interrupt (130 Ctrl-C, 143 SIGTERM), 1 for anything else
    (a bug). ``fivid run`` writes it as ``exit_code`` in summary.json, so the file and the process agree.
    """
    if isinstance(exc, (FividError, MemoryError)):
        return 2
    if isinstance(exc, KeyboardInterrupt):
        import signal

        return 128 + int(getattr(exc, "signum", signal.SIGINT))
    return 1
