"""Memory of a simulation, estimated before any work, against the memory this machine has now.

A simulation holds, at once: the kernel's per-interval records (``oversample * sample_rate`` rows of
the record columns, the sensors' velocity and displacement and five numbers per contact pair, see
:mod:`fivid.solver.integrate`), the friction table (law samples at ``min(8 fs, 1/dt)`` per slave node,
:mod:`fivid.friction.injection`), the state and stencil arrays (per degree of freedom) and the
output RunDataset. Their sizes are known from the model and the settings alone, so a run that cannot
fit is refused in a second instead of failing with ``MemoryError`` after minutes, or never ending.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

from fivid.errors import ConfigError

__all__ = ["SimulationSize", "available_memory", "simulation_memory", "check_simulation_memory", "format_bytes",
           "MEMORY_FRACTION", "FLOATS_PER_DOF"]

#: Largest fraction of the available memory a run may be estimated to need. The estimate counts the
#: large arrays only; the interpreter, numba's compiled code and the libraries take a few hundred MB
#: more, and the page cache and other processes need some room.
MEMORY_FRACTION = 0.8
#: float64 arrays per degree of freedom while the time loop runs: u, v, w, filtered v, f, scratch,
#: mass and its inverse, coordinates, and the stencil coefficients (18 per node on a mapped block,
#: i.e. 9 per dof) -- about 20; 24 leaves room for the contact and constraint arrays.
FLOATS_PER_DOF = 24
_FLOAT = 8  # bytes


def format_bytes(n: float) -> str:
    """``n`` bytes in binary units with 3 significant digits: ``'1 MiB'``, ``'470 TiB'``."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if abs(n) < 1024:
            return f"{n:.3g} {unit}"
        n /= 1024
    return f"{n:.3g} PiB"


def available_memory() -> tuple[int, str] | None:
    """Bytes a new allocation can get now, and where the number comes from; None when unknown.

    ``psutil.virtual_memory().available`` when psutil is installed, else ``MemAvailable`` of
    ``/proc/meminfo`` (Linux), else the free physical pages of ``os.sysconf`` (which ignores the page
    cache the kernel would give back, so it under-states).
    """
    try:
        import psutil
    except ImportError:
        pass
    else:
        return int(psutil.virtual_memory().available), "available memory (psutil)"
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024, "MemAvailable (/proc/meminfo)"
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"), "free physical pages (os.sysconf)"
    except (ValueError, OSError, AttributeError):
        return None


@dataclass(frozen=True)
class SimulationSize:
    """What a simulation will hold and do.

    Attributes
    ----------
    output_samples : int
        Rows of the output RunDataset (transient + duration at the sample rate).
    intervals : int
        Recorded intervals (``oversample`` per output sample).
    steps : int
        Solver time steps.
    time_step : float
        The step the driver will use [s] (``0.9 dt_crit`` unless given).
    parts : dict
        Bytes of each group of arrays.
    """

    output_samples: int
    intervals: int
    steps: int
    time_step: float
    parts: dict = field(default_factory=dict)

    @property
    def bytes(self) -> int:
        """The whole estimate [bytes]."""
        return int(sum(self.parts.values()))

    def describe(self) -> str:
        """One line: output samples, solver steps and time step [s], estimated memory by part [bytes, human units]."""
        parts = ", ".join(f"{k} {format_bytes(v)}" for k, v in self.parts.items())
        return (f"{self.output_samples:,} output samples, {self.steps:,} solver steps of {self.time_step:.3g} s; "
                f"memory about {format_bytes(self.bytes)} ({parts})")


def _transient(model, settle_time: float) -> float:
    """Time before steady sliding with the driver's default schedule [s] (its ``Schedule.transient_end``)."""
    load, base = model.motion("load"), model.motion("base")
    base_start = (float(load.ramp_time) + settle_time) if load is not None else 0.0
    base_ramp = float(base.ramp_time) if base is not None else 0.0
    return max(base_start + base_ramp, max((float(ld.ramp_time) for ld in model.loads), default=0.0))


def simulation_memory(model, *, duration: float, sample_rate: float, oversample: int = 4, time_step=None,
                      law=None, settle_time: float = 1e-3, safety: float = 0.9) -> SimulationSize:
    """Estimate the size of :func:`fivid.solver.simulate` of ``model`` (same parameters) without running it.

    Parameters
    ----------
    model : fivid.fe.Model
    duration : float
        Steady-sliding time [s].
    sample_rate : float
        Output sample rate [Hz].
    oversample, time_step, settle_time, safety
        As :func:`fivid.solver.simulate` (``time_step`` None: ``safety`` x the critical step).
    law : friction-law object, optional
        With a law the friction table has a row per law sample (at ``min(8 fs, 1/dt)``) and, unless
        its injection is ``uniform``, a column per slave node; Coulomb needs one row.

    Raises
    ------
    ConfigError
        A duration or sample rate that is not a positive finite number.
    """
    from fivid.solver._kernels import N_REC
    from fivid.solver.timestep import stable_step

    for name, value in (("duration", duration), ("sample_rate", sample_rate)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ConfigError(f"{name} must be a finite number > 0, got {value!r}", key=name)
    dt = float(time_step) if time_step is not None else safety * stable_step(model).critical_time_step
    total = _transient(model, settle_time) + duration
    n_out = max(1, math.ceil(total * sample_rate - 1e-9))
    n_int = n_out * oversample
    n_sub = max(1, math.ceil(1.0 / (sample_rate * oversample) / dt * (1.0 - 1e-12)))
    n_sens, n_pairs = len(model.sensors), len(model.contacts)
    n_slave = sum(len(c.slave_nodes) for c in model.contacts)
    if law is None:
        friction_floats = n_slave
    else:
        rows = math.ceil(n_int / (sample_rate * oversample) * min(8.0 * sample_rate, 1.0 / dt)) + 2
        friction_floats = rows * (1 if getattr(law, "injection", "uniform") == "uniform" else max(1, n_slave))
    parts = {
        "records": n_int * (N_REC + 2 * n_sens + 5 * n_pairs) * _FLOAT,
        "friction table": friction_floats * _FLOAT,
        "state": 2 * model.n_nodes * FLOATS_PER_DOF * _FLOAT,
        # the RunDataset (10 energy/force series, the sensors, the contact diagnostics) and one copy
        # while it is decimated and written
        "output": 2 * n_out * (10 + n_sens + 5 * n_pairs) * _FLOAT,
    }
    return SimulationSize(n_out, n_int, n_int * n_sub, 1.0 / (sample_rate * oversample) / n_sub, parts)


def check_simulation_memory(size: SimulationSize, *, key: str = "--duration") -> None:
    """Refuse a run estimated to need more than :data:`MEMORY_FRACTION` of the available memory.

    Raises
    ------
    ConfigError
        With the estimate, its parts, the available memory and what to change; ``key`` names the
        option or config key to change first.
    """
    available = available_memory()
    if available is None:
        return
    free, source = available
    if size.bytes <= MEMORY_FRACTION * free:
        return
    raise ConfigError(
        f"this simulation would need about {format_bytes(size.bytes)} of memory ({size.describe()}), but "
        f"{format_bytes(free)} available ({source}); at most {MEMORY_FRACTION:.0%} of it may be planned. Shorten "
        "--duration, lower --sample-rate or coarsen the mesh", key=key)
