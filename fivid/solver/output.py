"""Wrap the solver's records into a RunDataset: anti-aliased decimation, energy balance, provenance attrs.

Anti-aliasing: the kernel records interval averages at ``oversample * sample_rate`` -- sensor
acceleration as ``(v(t+T) - v(t))/T`` (the exact mean acceleration over the interval), transducer forces
averaged over every step of the interval -- which is already a boxcar low-pass; the records are then
decimated to ``sample_rate`` as :func:`scipy.signal.decimate` does (zero-phase FIR, Hamming window, cutoff at
the new Nyquist frequency; :func:`_decimate`), never by plain subsampling. Sample ``i`` is the interval average centred on
``time[i] = (i * oversample + 1/2) * T``, ``T = 1/(oversample * sample_rate)``. The boxcar's droop at
20 kHz with ``oversample = 4`` and 51.2 kHz is ``sinc(20/204.8) = 0.984`` (-0.14 dB).
Contact totals and fractions are averaged over each output period; energies are the values at the
end of the first oversampled interval of each period.
"""

from __future__ import annotations

import numpy as np

from fivid.fe.damping import scheme_name
from fivid.schema import apply_cf_attrs, new_history, with_condition_coords
from fivid.solver import _kernels as K

__all__ = ["run_dataset"]


def _decimation_filter(q: int) -> np.ndarray:
    """The FIR of ``scipy.signal.decimate(x, q, ftype="fir")``: ``firwin(20 q + 1, 1/q, window="hamming")``, a
    Hamming-windowed sinc with its cut-off at the new Nyquist frequency, unit gain at 0 Hz."""
    m = np.arange(20 * q + 1) - 10.0 * q
    h = np.sinc(m / q) * (0.54 + 0.46 * np.cos(np.pi * m / (10.0 * q)))
    return h / h.sum()


def _decimate(x: np.ndarray, q: int) -> np.ndarray:
    """``x`` (time along axis 0) low-passed and decimated by ``q``: ``scipy.signal.decimate(x, q, ftype="fir",
    zero_phase=True)`` (its ``resample_poly``: the centred convolution with the filter, zero outside the record,
    sampled every ``q``), written with numpy -- importing scipy.signal costs a third of a second per
    ``fivid simulate``; tests/solver/test_solver_decimation.py checks it against scipy's."""
    if q == 1:
        return x
    n_out = x.shape[0] // q
    if x.shape[0] <= 20 * q * 3 + 3:  # too short for the FIR's padding: block means (boxcar)
        return _block_mean(x, q)
    h = _decimation_filter(q)
    flat = x.reshape(x.shape[0], -1)
    y = np.empty((n_out, flat.shape[1]))
    for j in range(flat.shape[1]):
        y[:, j] = np.convolve(flat[:, j], h)[10 * q::q][:n_out]
    return y.reshape(n_out, *x.shape[1:])


def _block_mean(x: np.ndarray, q: int) -> np.ndarray:
    n_out = x.shape[0] // q
    return x[:n_out * q].reshape(n_out, q, *x.shape[1:]).mean(axis=1)


def run_dataset(model, raw, settings, loading, fric, preload, inputs):
    """The RunDataset of a finished run (see the module docstring).

    ``loading`` is the run's :class:`fivid.solver.setup.LoadingSequence`, ``inputs`` its validated
    :class:`fivid.solver.SimulationInputs` (``condition.sliding_velocity`` the magnitude run [m s-1]).
    """
    import xarray as xr

    normal_load, roughness_ra = inputs.condition.normal_load, inputs.condition.roughness_ra
    sample_rate = inputs.schedule.sample_rate
    q = settings.oversample
    t_int = 1.0 / (sample_rate * q)
    n_out = raw.rec.shape[0] // q
    time = (np.arange(n_out) * q + 0.5) * t_int
    ft = _decimate(raw.rec[:, K.R_FT], q)
    fn = _decimate(raw.rec[:, K.R_FN], q)
    data = {"friction_force": (("time",), ft), "normal_force": (("time",), fn), **_energy_variables(raw, q, n_out)}
    coords = {"time": time}
    sensors = [s.name for s in model.sensors]
    _add_sensor_variables(data, coords, sensors, raw, q, t_int, n_out)
    if model.contacts:
        _add_contact_variables(data, coords, [c.name for c in model.contacts], raw, q)
    ds = xr.Dataset(data, coords=coords)
    _describe_variables(ds, sensors)
    fn_nominal = normal_load if normal_load is not None else float(np.mean(fn[time >= loading.transient_end])) \
        if np.any(time >= loading.transient_end) else 0.0
    ds.attrs.update(_run_attrs(model, raw, settings, loading, fric, inputs, normal_load=fn_nominal))
    if roughness_ra is None:
        ds.attrs["roughness_ra_note"] = "not given: recorded as 0"
    if inputs.output.record_state:
        ds.attrs["final_u"] = raw.u
        ds.attrs["final_v"] = raw.v
    return apply_cf_attrs(with_condition_coords(ds))


def _energy_variables(raw, q, n_out) -> dict:
    """The energy balance at the end of the first oversampled interval of each output period [J]: energies,
    works, dissipations and the balance's closure error."""
    e = raw.rec[::q][:n_out]
    ke = e[:, K.R_KE]
    strain = e[:, K.R_U]
    damping = e[:, K.R_DA] + (e[:, K.R_WINT] - strain)
    friction = -e[:, K.R_WCT]
    contact_energy = e[:, K.R_EPEN]
    impact = -e[:, K.R_WCN] - contact_energy
    wext = e[:, K.R_WEXT]
    wload = e[:, K.R_WLOAD]
    wdrive = e[:, K.R_WDRIVE]
    closure = wext + wload + wdrive - (ke - raw.ke0 + strain + contact_energy + damping + friction + impact)
    return {
        "kinetic_energy": (("time",), ke),
        "strain_energy": (("time",), strain),
        "external_work": (("time",), wext),
        "load_work": (("time",), wload),
        "drive_work": (("time",), wdrive),
        "contact_energy": (("time",), contact_energy),
        "damping_dissipation": (("time",), damping),
        "friction_dissipation": (("time",), friction),
        "impact_dissipation": (("time",), impact),
        "energy_balance_error": (("time",), closure),
    }


def _add_sensor_variables(data, coords, sensors, raw, q, t_int, n_out):
    """Acceleration (interval differences of the sensors' velocity, anti-aliased), velocity and displacement of
    the sensors into ``data`` (dim ``sensor`` when there are several); zero acceleration without sensors."""
    sv = np.concatenate([raw.sens_v0[None, :], raw.sens_v[:, :, 0]], axis=0)
    sens_u = raw.sens_v[::q, :, 1][:n_out]
    acc = _decimate(np.diff(sv, axis=0) / t_int, q)
    vel = _decimate(0.5 * (sv[1:] + sv[:-1]), q)  # interval mean (trapezoid), anti-aliased like acceleration
    if len(sensors) == 1:
        data["acceleration"] = (("time",), acc[:, 0])
        data["sensor_displacement"] = (("time",), sens_u[:, 0])
        data["sensor_velocity"] = (("time",), vel[:, 0])
    elif sensors:
        data["acceleration"] = (("time", "sensor"), acc)
        data["sensor_displacement"] = (("time", "sensor"), sens_u)
        data["sensor_velocity"] = (("time", "sensor"), vel)
        coords["sensor"] = np.array(sensors, dtype=object)
    else:
        data["acceleration"] = (("time",), np.zeros(n_out))


def _add_contact_variables(data, coords, pairs, raw, q):
    """Per-pair contact forces and stick/slip/open fractions, averaged over each output period, into ``data``
    (dim ``contact`` when there are several pairs)."""
    cb = _block_mean(raw.contact, q)
    names = ("contact_normal_force", "contact_tangential_force", "stick_fraction", "slip_fraction", "open_fraction")
    for i, name in enumerate(names):
        if len(pairs) == 1:
            data[name] = (("time",), cb[:, 0, i])
        else:
            data[name] = (("time", "contact"), cb[:, :, i])
    if len(pairs) > 1:
        coords["contact"] = np.array(pairs, dtype=object)


def _describe_variables(ds, sensors):
    """The descriptions of the simulation's own variables (beyond the schema's long names)."""
    if "sensor_displacement" in ds:
        ds["sensor_displacement"].attrs.update(
            units="m", long_name="displacement at the sensors along their direction (diagnostic)",
            description="value at the end of the first oversampled interval of each output period")
        ds["sensor_velocity"].attrs.update(
            units="m s-1", long_name="velocity at the sensors along their direction",
            description="(v(t) + v(t + T)) / 2 of the velocities at the ends of each oversampled interval T, "
                        "decimated like acceleration")
    ds["impact_dissipation"].attrs["description"] = ("minus the work of the normal contact forces, less the energy "
                                                     "stored in the compliant contact laws (contact_energy)")
    ds["drive_work"].attrs["description"] = "work of the moving rigid contact surfaces (belt, rotating cylinder)"
    ds["contact_energy"].attrs["description"] = "energy stored in the compliant normal contact laws, sum of A int p dd"
    ds["energy_balance_error"].attrs["description"] = (
        "external_work + load_work + drive_work - (kinetic - kinetic(0) + strain + contact_energy + damping + "
        "friction + impact); round-off for a correct run")
    if len(sensors) == 1:
        ds["acceleration"].attrs["sensor"] = sensors[0]


def _run_attrs(model, raw, settings, loading, fric, inputs, *, normal_load) -> dict:
    """The run's attrs: conditions (``normal_load`` the target or the mean transducer force of the steady part
    [N]), provenance, the integration settings, damping and contact method, Gauss-Seidel statistics."""
    seed, run_id = inputs.friction.seed, inputs.output.run_id
    roughness_ra = inputs.condition.roughness_ra
    q = settings.oversample
    mu_desc = fric.description
    law_part = f"law sha256:{fric.sha256}" if fric.sha256 else "law none"
    return {
        "run_id": run_id or f"sim-{model.sha256[:8] or 'model'}-s{int(seed)}",
        "rig": str(model.config.get("name", "model")) if isinstance(model.config, dict) else "model",
        "sliding_velocity": float(inputs.condition.sliding_velocity),
        "normal_load": float(normal_load),
        "roughness_ra": float(roughness_ra) if roughness_ra is not None else 0.0,
        "sample_rate": float(inputs.schedule.sample_rate),
        "source": f"simulation: model {model.source}; {law_part}; seed {int(seed)}",
        "history": new_history(
            f"simulate: {mu_desc}; dt {settings.time_step:.6g} s; {settings.n_intervals // q} samples"),
        "simulated": 1,
        "friction": mu_desc,
        "seed": int(seed),
        "time_step": settings.time_step,
        "critical_time_step": settings.critical_time_step,
        "omega_max": settings.omega_max,
        "oversample": q,
        "transient_end": loading.transient_end,
        "base_start": loading.base_start,
        "transient_description": "time < transient_end: preload ramp, settling and base-velocity ramp",
        "preload_displacement": float(loading.load_displacement) if loading.load_displacement is not None else np.nan,
        "rayleigh_alpha": float(model.rayleigh_alpha),
        "rayleigh_beta": float(model.rayleigh_beta),
        "damping_scheme": scheme_name(model.rayleigh_beta, model.damping_cutoff),
        "damping_cutoff": float(model.damping_cutoff),
        "contact_method": "node-to-segment (or node-to-rigid-surface), forward-increment multipliers (rigid law: "
                          "Lagrange; compliant laws: the penalty force at the end-of-step penetration), Coulomb "
                          "stick/slip with static/kinetic coefficients, Gauss-Seidel",
        "contact_laws": "; ".join(f"{c.name}: normal {c.law.describe()}; friction {c.friction.describe(c.mu)}"
                                  + (f"; master {c.rigid.describe()}" if c.rigid is not None else "")
                                  for c in model.contacts),
        "contact_gs_tolerance": settings.gs_tolerance,
        "contact_gs_mean_sweeps": float(raw.acc[K.GS_SWEEPS] / max(raw.steps, 1)),
        "contact_gs_max_sweeps": int(raw.acc[K.GS_MAX]),
        "contact_gs_steps_at_limit": int(raw.acc[K.GS_CAPPED]),
        "steps": int(raw.steps),
    }
