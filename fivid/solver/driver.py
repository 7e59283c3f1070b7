"""The explicit transient solver's driver: validate, choose the step, allocate, run the kernel, wrap the result.

See DESIGN §5 for the method and :mod:`fivid.solver._loop_kernels` for the time loop. The public entry
point is :func:`simulate`.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace

import numpy as np

from fivid.errors import ConfigError, SimulationDiverged
from fivid.fe.build import load_model
from fivid.fe.model import Model
from fivid.fe.prestress import preload_ramp_end, prestress_state
from fivid.fe.static import Preload
from fivid.friction.curve import slave_coefficients
from fivid.friction.injection import FrictionTable, friction_table
from fivid.friction.inputs import FrictionInput, OperatingCondition
from fivid.signal.compare import band_distance, steady_psds
from fivid.signal.welch import default_nperseg
from fivid.solver.inputs import check_energy_balance, check_simulation_inputs
from fivid.solver.integrate import integrate
from fivid.solver.options import (
    DEFAULT_REDUCED_TOLERANCE,
    IntegrationOptions,
    OutputOptions,
    RunSchedule,
    SimulationInputs,
)
from fivid.solver.preload_cache import cached_preload
from fivid.solver.reduced import ReducedSystem, integrate_reduced, reduced_system
from fivid.solver.reduced_error import DEFAULT_ERROR_BAND, band_error_estimate, scored_contact_switches
from fivid.solver.setup import KernelArrays, LoadingSequence, kernel_arrays
from fivid.solver.stencil import BlockStencils, block_stencils
from fivid.solver.timestep import stable_step, stable_step_of

__all__ = ["IntegrationSettings", "PreparedRun", "simulate", "prepare_run", "AUTO_SCALING_FACTOR",
           "DEFAULT_REDUCED_TOLERANCE"]

log = logging.getLogger("fivid")

#: the reduced path's cut-off and mass-scaling target with ``reduced="auto"``/``"reduced"``, in units of the band
#: top ``sample_rate / 2``: 18 x 25.6 kHz = 460.8 kHz (docs/solver.md, "Reduced-order path")
AUTO_SCALING_FACTOR = 18.0


@dataclass(frozen=True)
class IntegrationSettings:
    """Settings of the time integration of a run: step, output intervals, contact iterations (recorded in the
    output attrs)."""

    time_step: float
    critical_time_step: float
    omega_max: float
    steps_per_interval: int
    oversample: int
    n_intervals: int
    gs_max_iterations: int
    gs_tolerance: float


def _positive(name, value, *, allow_zero=False):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v) or v < 0.0 or (v == 0.0 and not allow_zero):
        raise ConfigError(f"{name} must be a finite number {'>=' if allow_zero else '>'} 0, got {value!r}")
    return v


@dataclass(frozen=True)
class PreparedRun:
    """A run ready for the time loop: model, stencils, kernel arrays, friction table, settings, loading sequence.

    Attributes
    ----------
    model : Model
    stencils : BlockStencils
        The block stencils of the model (:func:`fivid.solver.stencil.block_stencils`).
    arrays : KernelArrays
        The kernel arrays (:func:`fivid.solver.setup.kernel_arrays`).
    friction : FrictionTable
        ``mu0 + mu_p(t)`` of every slave node on the solver's time grid (:func:`fivid.friction.friction_table`).
    settings : IntegrationSettings
        Step [s], intervals and contact iterations as chosen.
    loading : LoadingSequence
        The loading sequence [s] and amplitudes.
    preload : Preload or None
        The static preload solve (None without a target normal load).
    inputs : SimulationInputs
        The validated inputs (SI floats; ``condition.sliding_velocity`` the magnitude run [m s-1]).
    reduced : ReducedSystem or None
        The reduced system of a reduced run (None: the full model).
    choice : dict or None
        Which path and why (:func:`choice_attrs`).
    """

    model: Model
    stencils: BlockStencils
    arrays: KernelArrays
    friction: FrictionTable
    settings: IntegrationSettings
    loading: LoadingSequence
    preload: Preload | None
    inputs: SimulationInputs
    reduced: ReducedSystem | None = None
    choice: dict | None = None

    def run(self, *, progress=None):
        """Integrate and wrap the RunDataset (see :func:`simulate`); ``progress`` (bool or None: only on a
        terminal) overrides ``inputs.output.progress``."""
        from fivid.solver.output import run_dataset  # lazy: pulls numba

        progress = self.inputs.output.progress if progress is None else progress
        if self.reduced is not None:
            raw = integrate_reduced(self.model, self.reduced, self.friction, self.settings, progress=progress)
        else:
            raw = integrate(self.model, self.stencils, self.arrays, self.friction, self.settings, progress=progress)
        ds = run_dataset(self.model, raw, self.settings, self.loading, self.friction, self.preload, self.inputs)
        if self.reduced is not None:
            ds.attrs.update(self.reduced.attrs())
        ds.attrs.update(choice_attrs(self.choice))
        if self.reduced is not None and self.choice and self.choice.get("estimate"):
            # the a-posteriori premise of the estimate's step-resolution bound (fivid.solver.reduced_error)
            ds.attrs["reduced_error_contact_switches"] = scored_contact_switches(ds)
        check_energy_balance(ds)  # a run whose balance does not close is no result (fivid.solver.inputs)
        return ds


_CONDITION = OperatingCondition()
_FRICTION = FrictionInput()
_INTEGRATION = IntegrationOptions()
_OUTPUT = OutputOptions()


def simulate(model, condition: OperatingCondition = _CONDITION, friction: FrictionInput = _FRICTION, *,
             schedule: RunSchedule, integration: IntegrationOptions = _INTEGRATION,
             output: OutputOptions = _OUTPUT):
    """Simulate the rig: preload, settle, base-velocity ramp, steady sliding; return a RunDataset.

    Parameters
    ----------
    model : Model or str or path-like
        The FE model (or its config file, or the name of a shipped model).
    condition : OperatingCondition
        Sliding velocity [m s-1], normal load [N] and roughness Ra [m] (each None: as configured).
    friction : FrictionInput
        A friction law (``mu_k(t) = mu0 + mu_p,k(t)``), a constant ``mu`` [-] or each pair's own ``mu``, and the
        seed of the law's synthesis.
    schedule : RunSchedule
        Steady-sliding duration [s], output sample rate [Hz], settling and ramp times [s].
    integration : IntegrationOptions
        Time step [s] (or the safety fraction of the critical step), contact Gauss-Seidel limits, and the solver
        path (full, ``"auto"``, ``"reduced"``, a number of modes; its tolerance [dB], band [Hz], basis cache).
    output : OutputOptions
        Oversampling of the recording, run id, final state for tests, progress bar.

    Returns
    -------
    xarray.Dataset
        RunDataset: ``acceleration`` [m s-2] (dims time[, sensor]), ``friction_force`` [N],
        ``normal_force`` [N], contact diagnostics and the energy balance.

    Raises
    ------
    ConfigError
        Bad settings or model (message names the value and what is allowed).
    SimulationDiverged
        NaN or runaway energy (step, time, node).

    Examples
    --------
    Coulomb friction mu = 0.3 at 10 mm/s and 5 N, 0.1 s of steady sliding recorded at 51.2 kHz:

    >>> ds = simulate("triboair_coarse", OperatingCondition(0.01, 5.0), FrictionInput(mu=0.3),
    ...               schedule=RunSchedule(duration=0.1, sample_rate=51200.0))  # doctest: +SKIP
    """
    prep = prepare_run(model, condition, friction, schedule=schedule, integration=integration, output=output)
    ds = prep.run()
    if prep.reduced is None or not integration.reduced_check:
        return ds
    return _checked(prep, ds, condition, friction, schedule, integration, output)


def _checked(prep, ds, condition, friction, schedule, integration, output):
    """The a-posteriori check of the reduced run ``ds`` (``IntegrationOptions.reduced_check``): the same reduced
    system at exactly half the run's step (``dt' = dt / 2``, which fits the recording interval twice as often as
    ``dt``: ratio ``r = 1/2``; halving ``safety`` instead and fitting that into the interval gave ``r`` 0.52 on the
    coarse rig). If the run's distance to the exact one grows as ``dt^p`` with ``p >= 1`` (central
    differences: 2, the damping force's half-step-old velocity: 1), ``LSD(dt, exact) ~ LSD(dt, dt') / (1 - r^p)
    <= LSD(dt, dt') / (1 - r)`` (at most twice the pair's distance); the full run's own, shorter step errs the same
    way, so this bounds the reduced-vs-full distance (docs/solver.md, "The error estimate"). Recorded as
    ``reduced_error_check_db``; under ``reduced="auto"`` a figure above the tolerance runs the full model instead,
    and its attrs say so."""
    half = replace(integration, reduced="reduced" if integration.reduced == "auto" else integration.reduced,
                   reduced_check=False, time_step=0.5 * float(ds.attrs["time_step"]))
    twin = prepare_run(prep.model, condition, friction, schedule=schedule, integration=half,
                       output=replace(output, progress=False, record_state=False)).run()
    f, (p_run, p_half), _ = steady_psds([ds, twin])
    band = prep.choice["band"]
    ratio = float(twin.attrs["time_step"]) / float(ds.attrs["time_step"])
    figure = float(band_distance(f, p_run, p_half, band)[0]) / (1.0 - ratio)
    check = {"reduced_error_check_db": figure, "reduced_error_check_step_ratio": ratio}
    tolerance = float(prep.choice["tolerance"])
    if integration.reduced != "auto" or figure <= tolerance:
        ds.attrs.update(check)
        return ds
    full = prepare_run(prep.model, condition, friction, schedule=schedule,
                       integration=replace(integration, reduced=None, reduced_mass_scaling=None, reduced_check=False),
                       output=output).run()
    reason = (f"{prep.choice['reason']}, but the a-posteriori check (the reduced run against one at {ratio:.3g} of "
              f"its step) reads {figure:.3g} dB > tolerance {tolerance:g} dB: ran the full model")
    full.attrs.update(choice_attrs({**prep.choice, "path": "full", "reason": reason}))
    full.attrs.update(check)
    return full


def prepare_run(model, condition: OperatingCondition = _CONDITION, friction: FrictionInput = _FRICTION, *,
                schedule: RunSchedule, integration: IntegrationOptions = _INTEGRATION,
                output: OutputOptions = _OUTPUT) -> PreparedRun:
    """Validate the inputs and build everything :func:`simulate` integrates (same parameters)."""
    if not isinstance(model, Model):
        model = load_model(model)
    for name, value, kind in (("condition", condition, OperatingCondition), ("friction", friction, FrictionInput),
                              ("schedule", schedule, RunSchedule), ("integration", integration, IntegrationOptions),
                              ("output", output, OutputOptions)):
        if not isinstance(value, kind):
            raise ConfigError(f"{name} must be a {kind.__module__}.{kind.__name__}, got {type(value).__name__}")
    law, mu, seed = friction.law, friction.mu, friction.seed
    sliding_velocity, normal_load, roughness_ra = condition.sliding_velocity, condition.normal_load, \
        condition.roughness_ra
    duration = _positive("duration", schedule.duration)
    sample_rate = _positive("sample_rate", schedule.sample_rate)
    if duration * sample_rate < 2.0:  # e.g. '51.2 Hz' typed for kHz: a one-sample run is no record
        raise ConfigError(f"duration x sample_rate = {duration:g} s x {sample_rate:g} Hz = {duration * sample_rate:.3g} "
                          "samples: the steady-sliding record needs at least 2; raise the sample rate or the duration")
    if sliding_velocity is not None:
        sliding_velocity = _positive("sliding_velocity", sliding_velocity, allow_zero=True)
    if normal_load is not None:
        normal_load = _positive("normal_load", normal_load)
    if roughness_ra is not None:
        roughness_ra = _positive("roughness_ra", roughness_ra, allow_zero=True)
    check_simulation_inputs(model, law=law, mu=mu, sliding_velocity=sliding_velocity, normal_load=normal_load)
    safety = integration.safety
    if not (0.0 < float(safety) <= 1.0):
        raise ConfigError(f"safety must be in (0, 1], got {safety!r}")
    oversample = int(output.oversample)
    if oversample < 1:
        raise ConfigError(f"oversample must be an integer >= 1, got {output.oversample!r}")
    settle_time = _positive("settle_time", schedule.settle_time, allow_zero=True)
    # numpy.random.default_rng refuses a negative or fractional seed with a bare ValueError deep in the law
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ConfigError(f"seed must be an integer >= 0, got {seed!r}")

    mu_slave = slave_coefficients(model, float(getattr(law, "mu0", 0.0)) if law is not None else mu)
    loading, signs, preload = _loading(model, sliding_velocity, normal_load,
                                       replace(schedule, settle_time=settle_time), mu_slave, integration)
    total = loading.transient_end + duration
    n_out = max(1, math.ceil(total * sample_rate - 1e-9))
    n_int = n_out * oversample
    prestress = None
    if model.prestress:  # vibrations about the prestressed state: K_sigma of the same static state as modes/CEA
        u0 = preload.u if preload is not None else prestress_state(model)
        prestress = (u0, max(preload_ramp_end(model), loading.load_ramp if preload is not None else 0.0))
    st = block_stencils(model, prestress=None if prestress is None else prestress[0])
    ka = kernel_arrays(model, st, loading, tangential_sign=signs[0], normal_sign=signs[1], prestress=prestress)
    base = model.motion("base")
    v_max = abs(sliding_velocity if sliding_velocity is not None else base.amplitude if base else 0.0)
    t_int = 1.0 / (sample_rate * oversample)
    rs, choice = _choose_path(model, ka, integration, sliding_distance=v_max * total, sample_rate=sample_rate,
                              interval=t_int, record_samples=int(round(duration * sample_rate)),
                              active=None if preload is None else np.isin(
                                  ka.slave_global, preload.geometry.slave_node[preload.active]))
    stab = _reduced_stable_step(model, rs) if rs is not None else stable_step(model)
    dt_crit = stab.critical_time_step
    time_step = integration.time_step
    if time_step is not None:
        time_step = _positive("time_step", time_step)
        if time_step > dt_crit:
            raise ConfigError(
                f"time step {time_step:.4g} s is above the critical step {dt_crit:.4g} s of this model "
                f"(omega_max = {stab.omega_max:.4g} rad/s, {stab.damping_scheme} damping, beta-damping ratio of that "
                f"mode xi = {stab.xi:.3g}; classic Rayleigh: dt_crit = (2/omega_max)(sqrt(1+xi^2) - xi)); central "
                f"differences would diverge. "
                f"Use a step <= {dt_crit:.4g} s or leave it out ({safety:g} * dt_crit is used)")
        dt_max = time_step
    else:
        dt_max = float(safety) * dt_crit
    dt, n_sub = _step_in_interval(t_int, dt_max)

    v_signed = (sliding_velocity if sliding_velocity is not None else abs(base.amplitude) if base else 0.0)
    if base is not None and base.amplitude < 0:
        v_signed = -v_signed
    comp = base.component if base is not None else 0
    slave_x = model.coords[ka.slave_global, comp] if ka.slave_global.size else np.zeros(0)
    run_condition = OperatingCondition(v_signed, normal_load, roughness_ra)  # signed along the base motion
    fric = friction_table(model, ka.slave_pair, slave_x, friction, run_condition, total_time=n_int * t_int, dt=dt,
                          sample_rate=sample_rate)
    settings = IntegrationSettings(dt, dt_crit, stab.omega_max, n_sub, oversample, n_int,
                                   int(integration.gs_max_iterations), float(integration.gs_tolerance))
    inputs = SimulationInputs(replace(run_condition, sliding_velocity=abs(v_signed)), friction,
                              replace(schedule, duration=duration, sample_rate=sample_rate, settle_time=settle_time),
                              integration, replace(output, oversample=oversample))
    return PreparedRun(model, st, ka, fric, settings, loading, preload, inputs, rs, choice)


def _reduced_options(reduced, reduced_mass_scaling, sample_rate):
    """``(n_modes, cutoff, mass scaling)`` of a requested reduced path; ConfigError on a bad combination."""
    if reduced in ("auto", "reduced"):
        if reduced_mass_scaling is not None:
            scaling = _positive("reduced_mass_scaling", reduced_mass_scaling)
            return None, scaling, scaling
        target = AUTO_SCALING_FACTOR * sample_rate / 2.0
        return None, target, target
    if isinstance(reduced, str) or (not isinstance(reduced, (bool, int, np.integer))):
        raise ConfigError(f"reduced must be None, 'auto', 'reduced', True or a number of modes >= 1, got {reduced!r}")
    n_modes = None if reduced is True else int(reduced)
    if n_modes is not None and n_modes < 1:
        raise ConfigError(f"reduced must be True or a number of modes >= 1, got {reduced!r}")
    scaling = None
    if reduced_mass_scaling is not None:
        scaling = _positive("reduced_mass_scaling", reduced_mass_scaling)
        if n_modes is not None:
            raise ConfigError("give reduced=True with reduced_mass_scaling (its frequency sets the modes kept), "
                              f"not a number of modes ({reduced!r})")
    return n_modes, scaling, scaling


def _step_in_interval(interval, dt_max):
    """``(dt, n_sub)``: the largest step <= ``dt_max`` [s] that fits a whole number of times in ``interval`` [s]."""
    n_sub = max(1, math.ceil(interval / dt_max * (1.0 - 1e-12)))
    return interval / n_sub, n_sub


def _reduced_stable_step(model, rs):
    """The :class:`fivid.solver.timestep.StableStep` of the reduced system ``rs`` under ``model``'s damping."""
    return stable_step_of(rs.omega_max(), float(model.rayleigh_alpha), float(model.rayleigh_beta),
                          float(model.damping_cutoff))


def _choose_path(model, ka, integration: IntegrationOptions, *, sliding_distance, sample_rate, interval=None,
                 record_samples=None, active=None):
    """The reduced system to run (None: the full model) and the record of the choice (:func:`choice_attrs`).
    ``interval`` [s]: the recording interval (the reduced step is fitted into it); ``record_samples``: the steady
    record's length (the scored PSD's resolution, :func:`fivid.signal.welch.default_nperseg`); ``active``: the slaves
    closed after the preload (the estimate's contact states)."""
    reduced, reduced_mass_scaling = integration.reduced, integration.reduced_mass_scaling
    error_band = integration.error_band
    if reduced is None or reduced is False:
        if reduced_mass_scaling is not None:
            raise ConfigError("reduced_mass_scaling needs reduced=True (it scales the reduced system's modes)")
        return None, {"path": "full", "choice": "requested", "reason": "full model requested", "estimate": None}
    tolerance = _positive("reduced_tolerance", integration.reduced_tolerance, allow_zero=True)
    band = tuple(float(b) for b in (error_band if error_band is not None else
                                    (DEFAULT_ERROR_BAND[0], min(DEFAULT_ERROR_BAND[1], sample_rate / 2.0))))
    if len(band) != 2 or not (0.0 <= band[0] < band[1]):
        raise ConfigError(f"error_band must be (low, high) [Hz] with 0 <= low < high, got {error_band!r}")
    n_modes, cutoff, scaling = _reduced_options(reduced, reduced_mass_scaling, sample_rate)
    auto = reduced == "auto"
    if model.prestress:  # the reduced basis is built from the elastic K alone
        if not auto:
            raise ConfigError("the reduced path does not carry the prestress stiffness (model 'prestress: true'); "
                              "run the full model (IntegrationOptions(reduced=None), --full)")
        return None, {"path": "full", "choice": "auto", "estimate": None, "tolerance": tolerance, "band": band,
                      "reason": "the model is prestressed ('prestress: true'), which the reduced basis does not carry"}
    if model.ties:  # the reduced kernels do not eliminate tied nodes (fivid.fe.transition)
        if not auto:
            raise ConfigError("the reduced path does not carry a mesh transition's ties; run the full model "
                              "(IntegrationOptions(reduced=None), --full)")
        return None, {"path": "full", "choice": "auto", "estimate": None, "tolerance": tolerance, "band": band,
                      "reason": "the model has tied mesh transitions (fivid.fe.transition), which the reduced path "
                                "does not carry"}
    compliant = [c.name for c in model.contacts if getattr(c.law, "is_penalty", False)]
    if auto and compliant:
        # the estimate ties the contact rigidly; a compliant normal law's contact springs act on the mass-scaled
        # local modes, which it does not see (measured 6.6 dB in-band on triboair_rough.yaml, docs/solver.md)
        return None, {"path": "full", "choice": "auto", "estimate": None, "tolerance": tolerance, "band": band,
                      "reason": f"contact pair(s) {', '.join(compliant)} have a compliant normal law, outside what "
                                "the reduced path's error estimate covers (rigid contact)"}
    try:
        rs = reduced_system(model, ka, sliding_distance=sliding_distance, band_top=sample_rate / 2.0,
                            n_modes=n_modes, cutoff=cutoff, mass_scaling=scaling, cache=integration.basis_cache,
                            cache_dir=integration.cache_dir)
    except ConfigError as exc:
        if not auto:
            raise
        return None, {"path": "full", "choice": "auto", "estimate": None, "tolerance": tolerance, "band": band,
                      "reason": f"the model cannot be reduced: {exc}"}
    if integration.time_step is not None:
        step = float(integration.time_step)
    else:
        step = float(integration.safety) * _reduced_stable_step(model, rs).critical_time_step
    step = _step_in_interval(interval if interval is not None else 1.0 / sample_rate, step)[0]
    n_rec = int(record_samples) if record_samples is not None else 256
    est = band_error_estimate(rs, band, alpha=float(model.rayleigh_alpha), beta=float(model.rayleigh_beta),
                              damping_cutoff=float(model.damping_cutoff), time_step=step,
                              bin_width=sample_rate / default_nperseg(sample_rate, max(n_rec, 1)), active=active)
    record = {"choice": "auto" if auto else "requested", "estimate": est, "tolerance": tolerance, "band": band}
    if auto and est["lsd_db"] > tolerance:
        return None, {**record, "path": "full", "reason": f"estimated in-band error {est['lsd_db']:.3g} dB > "
                                                          f"tolerance {tolerance:g} dB"}
    reason = (f"estimated in-band error {est['lsd_db']:.3g} dB <= tolerance {tolerance:g} dB" if auto
              else "reduced path requested")
    return rs, {**record, "path": "reduced", "reason": reason}


def choice_attrs(choice) -> dict:
    """The output attrs recording which solver path ran and why (``solver_path``, ``solver_choice``,
    ``solver_choice_reason``, ``reduced_error_estimate_db`` (NaN: not estimated), its contact state, per-state
    breakdown and step-resolution part ``reduced_error_resolution_db``, band and tolerance)."""
    if not choice:
        return {}
    est = choice.get("estimate")
    out = {"solver_path": choice["path"], "solver_choice": choice["choice"], "solver_choice_reason": choice["reason"],
           "reduced_error_estimate_db": float(est["lsd_db"]) if est else math.nan}
    if est:
        out["reduced_error_estimate_state"] = est["state"]
        out["reduced_error_estimate_states"] = "; ".join(
            f"{k}: {v['lsd_db']:.3g} dB (step resolution {v['resolution_db']:.3g}, modal {v['modal_db']:.3g}: truncation "
            f"{v['truncation_db']:.3g}, mass scaling {v['mass_scaling_db']:.3g}, time step {v['time_step_db']:.3g}, "
            f"{v['modes']} modes)" for k, v in est["states"].items())
        out["reduced_error_resolution_db"] = float(est["resolution_db"])
    if "band" in choice:
        out["reduced_error_band"] = [float(b) for b in choice["band"]]
        out["reduced_error_band_units"] = "Hz"
        out["reduced_error_tolerance_db"] = float(choice["tolerance"])
    return out


def _loading(model, sliding_velocity, normal_load, schedule: RunSchedule, mu_slave, integration: IntegrationOptions):
    """The loading sequence, the transducer signs and the preload (None without a target load; solved once per
    model, load and friction and kept in the basis cache, :mod:`fivid.solver.preload_cache`, unless
    ``integration.basis_cache`` is False)."""
    preload_time, base_ramp_time, settle_time = schedule.preload_time, schedule.base_ramp_time, schedule.settle_time
    load = model.motion("load")
    base = model.motion("base")
    load_ramp = float(preload_time) if preload_time is not None else (load.ramp_time if load else 0.0)
    base_ramp = float(base_ramp_time) if base_ramp_time is not None else (base.ramp_time if base else 0.0)
    direction = 1.0 if load is None or load.amplitude >= 0 else -1.0
    base_dir = 1.0 if base is None or base.amplitude >= 0 else -1.0
    signs = (-base_dir, direction)
    preload = None
    load_disp = None
    if normal_load is not None:
        preload, source, _ = cached_preload(model, normal_load, mu=mu_slave, cache=integration.basis_cache,
                                            folder=integration.cache_dir)
        log.debug("static preload: %s", source)
        load_disp = direction * preload.displacement  # preload solved for u = delta * direction on the clamp
    base_start = (load_ramp + settle_time) if load is not None else 0.0
    base_velocity = None
    if sliding_velocity is not None:
        if base is None:
            raise ConfigError("sliding_velocity was given but the model has no motion with role 'base'")
        base_velocity = base_dir * sliding_velocity
    # the pressure loads' and rigid surfaces' ramps are part of the transient too
    pressure_ramp = max([float(ld.start + ld.ramp_time) for ld in model.loads]
                        + [float(c.rigid.start + c.rigid.ramp_time) for c in model.contacts if c.rigid is not None],
                        default=0.0)
    return LoadingSequence(load_disp, load_ramp, base_start, base_velocity, base_ramp, pressure_ramp), signs, preload
