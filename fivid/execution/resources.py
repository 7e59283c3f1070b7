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

from fivid.builtin import find_builtin
from fivid.errors import ConfigError

__all__ = ["SimulationSize", "available_memory", "simulation_memory", "check_simulation_memory", "format_bytes",
           "MEMORY_FRACTION", "FLOATS_PER_DOF", "MAX_DOF_STEPS", "DOF_STEPS_PER_SECOND", "check_monte_carlo_size",
           "modal_memory", "check_modal_memory"]

#: Largest fraction of the available memory a run may be estimated to need. The estimate counts the
#: large arrays only; the interpreter, numba's compiled code and the libraries take a few hundred MB
#: more, and the page cache and other processes need some room.
MEMORY_FRACTION = 0.8
#: float64 arrays per degree of freedom while the time loop runs: u, v, w, filtered v, f, scratch,
#: mass and its inverse, coordinates, and the stencil coefficients (18 per node on a mapped block,
#: i.e. 9 per dof) -- about 20; 24 leaves room for the contact and constraint arrays.
FLOATS_PER_DOF = 24
_FLOAT = 8  # bytes
#: Most solver work planned for one command [degree-of-freedom updates]: 1e15 is about 4 days at
#: :data:`DOF_STEPS_PER_SECOND`; a larger run is a typo (a duration in ms written as s, 1e9 s) or needs a
#: coarser model, not a bigger machine.
MAX_DOF_STEPS = 1e15
#: Throughput of the full explicit path, measured on an idle 2-core machine (default rig, 13 524 dofs,
#: 0.1 s in 46 s) [dof updates per second]; used to say how long a refused run would take.
DOF_STEPS_PER_SECOND = 3e9


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
    from fivid.solver._kernels import N_REC  # lazy: pulls numba
    from fivid.solver.timestep import stable_step  # lazy: pulls pydantic

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


def _advice(key: str) -> str:
    if key.startswith("--"):
        return "Shorten --duration, lower --sample-rate or coarsen the mesh"
    prefix = key.rpartition(".")[0] + "." if "." in key else ""
    return f"Shorten {prefix}duration, lower {prefix}sample_rate or coarsen the mesh"


def check_simulation_memory(size: SimulationSize, *, key: str = "--duration", n_dofs: int | None = None,
                            runs: int = 1) -> None:
    """Refuse a run estimated to need more than :data:`MEMORY_FRACTION` of the available memory, or
    (with ``n_dofs``) more than :data:`MAX_DOF_STEPS` of solver work over its ``runs`` runs.

    Raises
    ------
    ConfigError
        With the estimate, its parts, the available memory (or the work and its time) and what to
        change; ``key`` names the option (``--duration``: the advice names options) or config key
        (``simulate.duration``: the advice names keys) to change first.
    """
    available = available_memory()
    if available is not None and size.bytes > MEMORY_FRACTION * available[0]:
        free, source = available
        raise ConfigError(
            f"this simulation would need about {format_bytes(size.bytes)} of memory ({size.describe()}), but "
            f"{format_bytes(free)} available ({source}); at most {MEMORY_FRACTION:.0%} of it may be planned. "
            f"{_advice(key)}", key=key)
    if n_dofs is not None and size.steps * float(n_dofs) * runs > MAX_DOF_STEPS:
        work = size.steps * float(n_dofs) * runs
        days = work / DOF_STEPS_PER_SECOND / 86400
        raise ConfigError(
            f"this simulation would take {runs} run(s) x {size.steps:,} solver steps x {n_dofs:,} dofs = {work:.3g} dof "
            f"updates, about {days:.3g} days at {DOF_STEPS_PER_SECOND:.0e} per second (the full path on an idle "
            f"2-core machine); at most {MAX_DOF_STEPS:.0e} may be planned. {_advice(key)}", key=key)


def check_monte_carlo_size(size: SimulationSize, *, samples: int, nperseg: int, n_dofs: int,
                           workers: int = 1) -> None:
    """Refuse ``simulate --samples N`` that cannot fit: the N runs' solver work, ``workers`` runs held at
    once, and the envelope (each sample's PSD of ``nperseg // 2 + 1`` bins, kept for the percentiles).

    Raises
    ------
    ConfigError
        With key ``--samples``, the estimate and the limit.
    """
    if samples * size.steps * float(n_dofs) > MAX_DOF_STEPS:
        work = samples * size.steps * float(n_dofs)
        raise ConfigError(
            f"{samples:,} samples x {size.steps:,} solver steps x {n_dofs:,} dofs = {work:.3g} dof updates, about "
            f"{work / DOF_STEPS_PER_SECOND / 86400:.3g} days at {DOF_STEPS_PER_SECOND:.0e} per second; at most "
            f"{MAX_DOF_STEPS:.0e} may be planned: use fewer samples (a 5-95 % envelope settles within a few hundred)",
            key="--samples")
    envelope = samples * (nperseg // 2 + 1 + 64) * _FLOAT
    held = max(1, min(int(workers), samples)) * size.bytes + envelope
    available = available_memory()
    if available is not None and held > MEMORY_FRACTION * available[0]:
        raise ConfigError(
            f"{samples:,} samples would need about {format_bytes(held)} of memory ({max(1, min(int(workers), samples))} "
            f"run(s) at once of {format_bytes(size.bytes)} each, and {format_bytes(envelope)} of PSDs for the "
            f"envelope), but {format_bytes(available[0])} available ({available[1]}); use fewer samples or workers",
            key="--samples")


def modal_memory(n_dofs: int, n_modes: int, band: int) -> int:
    """Bytes a modal analysis (shift-invert Lanczos) of ``n_dofs`` free dofs holds, about [bytes].

    The mesh and its arrays (:data:`FLOATS_PER_DOF` per dof), the sparse stiffness and mass (18 entries per
    row each for bilinear Q4 elements, 12 bytes an entry), the sparse LU factors of ``K - sigma M``
    (``band`` dofs either side of the diagonal: the half-bandwidth of a structured block ordered across
    its short side, 2 (short divisions + 1)) and the Lanczos vectors (``2 n_modes + 1``). The dense
    path below 600 dofs holds two dense matrices.
    """
    if n_dofs <= 600:
        return 2 * n_dofs * n_dofs * _FLOAT
    return int(n_dofs * (FLOATS_PER_DOF * _FLOAT + 2 * 18 * 12 + 2 * band * _FLOAT + (2 * n_modes + 1) * _FLOAT))


def _mesh_counts(model_source) -> tuple[int, int] | None:
    """``(nodes, band)`` from a model config's bodies' ``divisions``, read without meshing; None if unreadable."""
    from fivid.config_layer import read_yaml  # lazy: pulls pydantic

    path = model_source
    if not os.path.exists(str(path)):
        path = find_builtin("models", str(path)) or path
    try:
        data = read_yaml(path, "model config").data
        nodes, band = 0, 0
        for body in (data.get("bodies") or {}).values():
            nx, ny = (int(v) for v in body["divisions"])
            if nx < 1 or ny < 1:
                return None
            nodes += (nx + 1) * (ny + 1)
            band = max(band, 2 * (min(nx, ny) + 1))
        return nodes, band
    except (ConfigError, KeyError, TypeError, ValueError, AttributeError, OSError):
        return None  # the model's own validation reports it, with its line


def check_modal_memory(model_source, n_modes: int) -> None:
    """Refuse a modal analysis (``fivid modes``, ``fivid cea``) whose mesh cannot fit, before it is built.

    The node count comes from the config's ``divisions`` (no mesh is built): a 50 000 x 5 000 block is
    refused in a second instead of being killed by the kernel's out-of-memory killer.

    Raises
    ------
    ConfigError
        Naming the model file, the estimate and the available memory.
    """
    counts = _mesh_counts(model_source)
    available = available_memory()
    if counts is None or available is None:
        return
    nodes, band = counts
    need = modal_memory(2 * nodes, n_modes, band)
    if need <= MEMORY_FRACTION * available[0]:
        return
    raise ConfigError(
        f"this model has {nodes:,} nodes ({2 * nodes:,} dofs, from the bodies' divisions); its modal "
        f"analysis would need about {format_bytes(need)} of memory (mesh, K and M, the sparse factorisation, the "
        f"Lanczos vectors), but {format_bytes(available[0])} available ({available[1]}); at most "
        f"{MEMORY_FRACTION:.0%} of it may be planned. Lower the bodies' divisions", file=str(model_source),
        key="bodies")
