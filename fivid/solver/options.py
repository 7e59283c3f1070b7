"""The grouped settings of a simulation: schedule, time integration, output (SI units).

``simulate(model, condition, friction, *, schedule=RunSchedule(...), integration=IntegrationOptions(...),
output=OutputOptions(...))`` (:func:`fivid.solver.simulate`); the condition and the friction are
:class:`fivid.friction.OperatingCondition` and :class:`fivid.friction.FrictionInput`. Plain frozen records: the
driver (:func:`fivid.solver.driver.prepare_run`) validates them and names the bad value. Change one field of a
group with :func:`dataclasses.replace`.
"""

from __future__ import annotations

from dataclasses import dataclass
from os import PathLike
from typing import Annotated, Literal

from pydantic import Field

from fivid.friction.inputs import FrictionInput, OperatingCondition

__all__ = ["RunSchedule", "IntegrationOptions", "OutputOptions", "SimulationInputs", "DEFAULT_REDUCED_TOLERANCE"]

#: largest estimated in-band error [dB] for which ``reduced="auto"`` takes the reduced path
DEFAULT_REDUCED_TOLERANCE = 0.5

#: the ``solver`` key of the run and study configs (a pydantic field type; default ``"auto"``)
SolverPathField = Annotated[Literal["auto", "full", "reduced"], Field(
    description="solver path: auto (reduced when its estimated error in the scoring band is within "
                "reduced_tolerance, as fivid simulate), full or reduced (docs/solver.md)")]

#: the ``reduced_tolerance`` key of the run and study configs [dB] (default :data:`DEFAULT_REDUCED_TOLERANCE`)
ReducedToleranceField = Annotated[float, Field(
    ge=0.0, description="largest estimated in-band log-spectral distance [dB] of the reduced path that solver: auto "
                        "accepts")]


@dataclass(frozen=True)
class RunSchedule:
    """How long the run records and at what rate, and the loading sequence's times.

    Attributes
    ----------
    duration : float
        Steady-sliding time recorded after the transient [s]; the output covers transient + duration.
    sample_rate : float
        Output sample rate [Hz] (the rig's DAQ rate).
    settle_time : float
        Time between the end of the preload ramp and the start of the base ramp [s] (default 1 ms).
    preload_time, base_ramp_time : float or None
        Ramp times of the clamp and of the base velocity [s] (None: the motions' ``ramp_time``).

    Examples
    --------
    >>> RunSchedule(duration=0.1, sample_rate=51200.0)  # 0.1 s of steady sliding at 51.2 kHz
    RunSchedule(duration=0.1, sample_rate=51200.0, settle_time=0.001, preload_time=None, base_ramp_time=None)
    """

    duration: float
    sample_rate: float
    settle_time: float = 1e-3
    preload_time: float | None = None
    base_ramp_time: float | None = None


@dataclass(frozen=True)
class IntegrationOptions:
    """The time integration: step, contact iterations and the solver path (full model or reduced).

    Attributes
    ----------
    time_step : float or None
        Solver step [s]; refused above the critical step. None: ``safety * dt_crit``.
    safety : float
        Fraction (0 < safety <= 1) of the critical step used when ``time_step`` is None (default 0.9).
    gs_max_iterations : int
        Contact Gauss-Seidel sweeps per step at most (default 100).
    gs_tolerance : float
        Largest node-pair correction of the last sweep as a fraction of the shortest master segment [-]
        (default 1e-10).
    reduced : None, "auto", "reduced", True or int
        The solver path. None (or False): the full model. ``"auto"``: the Craig-Bampton reduced system
        (:mod:`fivid.solver.reduced`; fixed-interface modes and mass scaling at
        :data:`fivid.solver.driver.AUTO_SCALING_FACTOR` x ``sample_rate / 2``, basis from the cache) when its
        estimated in-band error (:mod:`fivid.solver.reduced_error`) is at most ``reduced_tolerance``, else the
        full model (also when the model cannot be reduced: dashpots, pressure loads, constrained contact nodes).
        ``"reduced"``: those reduced settings, whatever the estimate. ``True``: fixed-interface modes up to
        3 x ``sample_rate / 2`` (or up to ``reduced_mass_scaling``), an int that many modes. Every run records the
        path and why (``solver_path``, ``solver_choice``, ``reduced_error_estimate_db``...) and a reduced one its
        truncation (``reduced_*`` attrs).
    reduced_mass_scaling : float or None
        With ``reduced``: keep the fixed-interface modes up to this frequency [Hz] and mass-scale every mode of the
        reduced system above it down to it (:func:`fivid.solver.reduced.scale_high_modes`), which lengthens the
        stable step; recorded as ``reduced_mass_scaling`` and ``reduced_added_mass_fraction``.
    reduced_tolerance : float
        Largest estimated in-band log-spectral distance [dB] for which ``reduced="auto"`` runs reduced
        (default :data:`DEFAULT_REDUCED_TOLERANCE`, 0.5 dB).
    error_band : (float, float) or None
        Band [Hz] of that estimate (None: :data:`fivid.solver.reduced_error.DEFAULT_ERROR_BAND` clipped to
        ``sample_rate / 2``).
    basis_cache : bool
        Read/store the reduced basis in the on-disk cache (:mod:`fivid.solver.basis_cache`; default True).
    cache_dir : path-like or None
        The cache folder (None: ``$FIVID_CACHE_DIR`` or the user cache folder).
    reduced_check : bool
        After a reduced run, check it a posteriori against a second reduced run at half its step (a Richardson
        pair, twice the reduced run's steps; default False): ``reduced_error_check_db``, and with ``reduced="auto"``
        the full model instead when that figure exceeds ``reduced_tolerance`` (:func:`fivid.solver.simulate`).

    Examples
    --------
    >>> IntegrationOptions(reduced="auto").reduced_tolerance  # dB
    0.5
    """

    time_step: float | None = None
    safety: float = 0.9
    gs_max_iterations: int = 100
    gs_tolerance: float = 1e-10
    reduced: bool | int | str | None = None
    reduced_mass_scaling: float | None = None
    reduced_tolerance: float = DEFAULT_REDUCED_TOLERANCE
    error_band: tuple[float, float] | None = None
    basis_cache: bool = True
    cache_dir: str | PathLike | None = None
    reduced_check: bool = False


@dataclass(frozen=True)
class OutputOptions:
    """What the run records and shows.

    Attributes
    ----------
    oversample : int
        Internal recording rate = ``oversample * sample_rate`` (>= 1, default 4); the records are decimated with a
        zero-phase FIR low-pass (anti-aliasing) to ``sample_rate``.
    run_id : str or None
        Run identifier recorded in the output (None: ``sim-<model hash>-s<seed>``).
    record_state : bool
        Also return the final displacement [m] and velocity [m s-1] (global dofs) in ``attrs`` -- for tests.
    progress : bool or None
        Progress bar; None: only when stderr is a terminal.

    Examples
    --------
    >>> OutputOptions(oversample=1, progress=False)
    OutputOptions(oversample=1, run_id=None, record_state=False, progress=False)
    """

    oversample: int = 4
    run_id: str | None = None
    record_state: bool = False
    progress: bool | None = None


@dataclass(frozen=True)
class SimulationInputs:
    """All the inputs of one run, grouped as :func:`fivid.solver.simulate` takes them (after validation in a
    :class:`fivid.solver.driver.PreparedRun`: SI floats, the sliding velocity resolved to the magnitude run)."""

    condition: OperatingCondition
    friction: FrictionInput
    schedule: RunSchedule
    integration: IntegrationOptions
    output: OutputOptions
