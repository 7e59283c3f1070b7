"""The verification case protocol: what a case declares, what it computes, what the runner makes of it.

A case is data plus one function. The data say what is checked (``quantity``), against what (``reference``:
a closed form, a benchmark, a paper or a measurement, with its citation in ``source``), how fivid computes it
(``method``) and where the tolerance comes from (``tolerance_basis``). The function ``compute(quick, data)``
returns an :class:`Outcome`: fivid's value, the reference value, the tolerance (which may depend on the
resolution the case ran at) and a :class:`Plot` for the manual. The runner turns it into a :class:`Result`
(error, pass/fail); no runner or report knows a case by name (STYLE rule 9).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

__all__ = ["Case", "Outcome", "Plot", "Curve", "Result", "ERROR_KINDS"]

#: how a case's error is measured: ``relative`` |value - reference| / |reference|, ``absolute`` |value - reference|
ERROR_KINDS = ("relative", "absolute")


@dataclass(frozen=True)
class Curve:
    """One line or set of markers of a :class:`Plot`.

    Parameters
    ----------
    x, y : array-like
        Coordinates, in the units of the plot's axis labels.
    label : str
        Legend text.
    style : str
        ``line``, ``dashed`` (a reference curve) or ``points`` (markers).
    """

    x: np.ndarray
    y: np.ndarray
    label: str
    style: str = "line"


@dataclass(frozen=True)
class Plot:
    """A case's figure as data (no matplotlib on the workers): axes, scales and curves.

    Parameters
    ----------
    xlabel, ylabel : str
        Axis labels with units.
    curves : tuple of Curve
        What is drawn.
    xscale, yscale : str
        ``linear`` or ``log``.
    """

    xlabel: str
    ylabel: str
    curves: tuple[Curve, ...]
    xscale: str = "linear"
    yscale: str = "linear"


@dataclass(frozen=True)
class Outcome:
    """What a case's ``compute`` returns.

    Parameters
    ----------
    value : float
        fivid's value of the case's quantity [the case's ``unit``].
    reference : float
        The reference value [same unit].
    tolerance : float
        Largest error that passes (relative or absolute, as the case's ``error``).
    plot : Plot, optional
        The manual's figure of the case.
    details : dict
        Further numbers the manual lists (name -> value), e.g. the resolution used.
    """

    value: float
    reference: float
    tolerance: float
    plot: Plot | None = None
    details: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Case:
    """A verification case (module docstring).

    Parameters
    ----------
    name : str
        Identifier used on the command line (``fivid verify --case NAME``): lower case, digits, underscores.
    title : str
        Heading of the case's section in the manual.
    quantity : str
        The quantity compared, with its unit in words.
    unit : str
        Unit of ``value`` and ``reference`` (``""`` for a ratio).
    reference : str
        What the reference is (the closed form or the measured value).
    source : str
        Its citation (paper, standard, data set with licence).
    method : str
        How fivid computes the quantity (the functions and the resolution, full and ``--quick``).
    tolerance_basis : str
        Where the tolerance comes from (convergence order, estimator variance, float resolution, ...).
    compute : callable
        ``compute(quick: bool, data: Path | None) -> Outcome``; a module-level function (it is pickled to dask
        workers by reference).
    error : str
        One of :data:`ERROR_KINDS`.
    real_data : str, optional
        Path of the measured data the case needs, relative to a real-data folder (``profiles/dektak-1.csv``);
        ``data`` is then that file or folder, and the case is skipped with the reason when it is absent.
    """

    name: str
    title: str
    quantity: str
    unit: str
    reference: str
    source: str
    method: str
    tolerance_basis: str
    compute: Callable[[bool, Path | None], Outcome]
    error: str = "relative"
    real_data: str | None = None

    def __post_init__(self):
        if self.error not in ERROR_KINDS:
            raise ValueError(f"verification case {self.name!r}: error {self.error!r} is not one of {ERROR_KINDS}")
        if not self.name or not all(c.islower() or c.isdigit() or c == "_" for c in self.name):
            raise ValueError(f"verification case name {self.name!r}: use lower-case letters, digits and underscores")

    def measure_error(self, value: float, reference: float) -> float:
        """The error of ``value`` against ``reference`` as this case measures it (NaN when undefined)."""
        if not (math.isfinite(value) and math.isfinite(reference)):
            return math.nan
        if self.error == "absolute":
            return abs(value - reference)
        return abs(value - reference) / abs(reference) if reference != 0 else math.nan


@dataclass(frozen=True)
class Result:
    """A case's result as the manual and ``--json`` show it.

    Parameters
    ----------
    case : Case
        The case.
    status : str
        ``passed``, ``failed`` (outside tolerance, or the computation raised), ``skipped`` (its real data are
        absent).
    outcome : Outcome, optional
        What the case computed (None when skipped or when it raised).
    error : float
        Error of the value (NaN when not computed).
    seconds : float
        Wall time of the case [s].
    reason : str
        Why it was skipped, or the exception of a computation that raised.
    quick : bool
        Whether it ran at the ``--quick`` resolution.
    """

    case: Case
    status: str
    outcome: Outcome | None
    error: float
    seconds: float
    reason: str = ""
    quick: bool = False

    @property
    def passed(self) -> bool | None:
        """True/False; None for a skipped case."""
        return None if self.status == "skipped" else self.status == "passed"

    def as_json(self) -> dict:
        """The ``--json`` entry: name, quantity, reference, source, value, error, tolerance, passed and more."""
        o = self.outcome
        return {
            "name": self.case.name,
            "quantity": self.case.quantity,
            "unit": self.case.unit,
            "reference": None if o is None else float(o.reference),
            "reference_description": self.case.reference,
            "source": self.case.source,
            "value": None if o is None else float(o.value),
            "error": self.error,
            "error_kind": self.case.error,
            "tolerance": None if o is None else float(o.tolerance),
            "tolerance_basis": self.case.tolerance_basis,
            "passed": self.passed,
            "status": self.status,
            "reason": self.reason,
            "seconds": self.seconds,
            "quick": self.quick,
            "details": {} if o is None else dict(o.details),
        }
