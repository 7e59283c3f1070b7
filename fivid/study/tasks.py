"""The per-point analyses the study kinds share, run on a dask worker, returned as a small Dataset (no ``point``
dimension).

:func:`fe_point` (an FE model's point, the FE kinds' ``evaluate``) and :func:`transient_variables` (a response
record's analyses, any kind with a transient) take plain data (picklable): ``system`` is ``{"model_path": str}``
(plus the study-wide ``coupling_bounds``, :func:`coupling_system`), ``tasks`` the study's per-point settings
(SI), ``conditions`` the point's ``{axis: value}``. Variables (each only when its task ran):

- ``modes``: ``mode_frequency(mode)`` [Hz], preloaded at the point's normal load (FE); with a contact, the
  modal coupling indicator ``coupling_modal`` (kappa, :mod:`fivid.study.coupling`; the weak/strong label of a
  point is the response's, :mod:`fivid.study.kinds.weak_strong`);
- ``transient``: ``regime``, ``growth_rate`` [s-1], ``growth_rate_stderr``, ``onset_time`` [s], ``response_frequency`` [Hz],
  ``amplitude`` (limit-cycle RMS), ``stick_fraction``, ``rms`` and ``level_db`` (of the second half of the
  response's steady part: the start-up ring-down excluded),
  ``narrowband_fraction`` (share of its power in prominent peaks: tonal vs broadband); with
  ``coulomb_reference: true`` (and a law) also ``rms_coulomb`` and ``perturbation_gain_db``, the same point
  simulated with the law's mu0 alone (what the perturbation adds), ``coulomb_decay_db`` (its ring-down), and
  with ``psd`` its ``psd_coulomb`` and ``psd_perturbation`` (of the law's response minus Coulomb's);
- ``solver_path`` (full or reduced, the choice's reason in its attrs) and ``reduced_error_estimate_db`` of an FE
  transient (:func:`solver_choice`: the automatic path unless the study's ``points.transient.solver`` forces one);
- ``psd``: ``psd(frequency)`` of the second half of the response's steady part (Welch, Hann, half overlap).

``tasks["transient"]["settle_time"]`` [s] (optional, a kind sets it: :mod:`fivid.study.kinds.weak_strong`) is
the schedule's time between the preload ramp and the base ramp (:class:`fivid.solver.RunSchedule`), 1 ms if
absent.

The response is the first sensor's acceleration for FE models (steady part from the run's ``transient_end``); a
lumped kind hands its own record (:mod:`fivid.study.kinds.hoffmann`: the normal displacement ``y``).
"""

from __future__ import annotations

import numpy as np

from fivid.config_layer import read_yaml
from fivid.fe import load_model
from fivid.fe.config import read_config
from fivid.fe.modal import modal_analysis
from fivid.friction import load_law
from fivid.execution.resources import check_simulation_memory, simulation_memory
from fivid.signal.spectral import welch_density
from fivid.signal.steady import steady_part
from fivid.signal.transient import narrowband_fraction
from fivid.solver import FrictionInput, IntegrationOptions, OperatingCondition, OutputOptions, RunSchedule, simulate
from fivid.study.analysis import analyse_transient
from fivid.study.coupling import coupling_bounds, coupling_indicator
from fivid.surface.rough_pair import RQ_PER_RA

__all__ = ["REGIMES", "TRANSIENT_KEYS", "COUPLING_KEYS", "element_size", "fe_point", "coupling_system", "transient_variables", "refined_model",
           "solver_choice"]

REGIMES = ("stable", "mode_coupling", "stick_slip")
#: (point variable, summary.json key) of the transient analyses, copied into a study summary's points
TRANSIENT_KEYS = (("regime", "regime"), ("growth_rate", "growth_rate"), ("response_frequency", "frequency"),
                  ("onset_time", "onset_time"), ("rms", "rms"), ("level_db", "level_db"),
                  ("stick_fraction", "stick_fraction"), ("narrowband_fraction", "narrowband_fraction"),
                  ("perturbation_gain_db", "perturbation_gain_db"))
#: (point variable, summary.json key) of the modal coupling indicator kappa
COUPLING_KEYS = (("coupling_modal", "coupling_modal"),)


def fe_point(system: dict, tasks: dict, conditions: dict, *, probes=None, run_analysis=None):
    """An FE model's point: element size, ``modes`` (and the coupling indicator with ``system["coupling_bounds"]``),
    ``transient`` and ``psd`` (see the module docstring); an xarray Dataset.

    ``probes(model)`` (optional) returns extra sensor entries (model-config form) added after the model's own
    (the response stays the first sensor); ``run_analysis(model, run, data, coords, conditions)`` (optional) adds
    a kind's own variables from the transient's run dataset (its steady part)."""
    import xarray as xr

    data, coords = {}, {}
    ra = conditions.get("roughness_ra")
    surface = None if ra is None else system.get("surfaces", {}).get(repr(float(ra)))
    model = refined_model(system["model_path"], conditions.get("mesh", 1.0), ra, surface=surface)
    if probes is not None:
        model = refined_model(system["model_path"], conditions.get("mesh", 1.0), ra, surface=surface,
                              sensors=probes(model))
    if "transient" in tasks:  # its size before any work (the modes first), as fivid simulate and fivid run do
        check_simulation_memory(simulation_memory(model, duration=tasks["transient"]["duration"],
                                                  sample_rate=tasks["transient"]["sample_rate"]),
                                key="points.transient.duration", n_dofs=2 * model.n_nodes)
    data["element_size"] = ((), element_size(model), {"units": "m", "long_name": "largest element side"})
    if "modes" in tasks:
        load = conditions.get("normal_load")
        ds = modal_analysis(model, tasks["modes"]["n_modes"], include_contact=load is not None and bool(model.contacts),
                            normal_load=load)
        data["mode_frequency"] = (("mode",), ds["frequency"].values, {"units": "Hz", "long_name": "natural frequency"})
        coords["mode"] = ("mode", np.arange(1, ds.sizes["mode"] + 1), {"units": "1",
                                                                        "long_name": "mode number, by frequency"})
        if "coupling_bounds" in system:
            kappa = coupling_indicator(ds["frequency"].values,
                                       *system["coupling_bounds"][repr(float(conditions.get("mesh", 1.0)))])
            data["coupling_modal"] = ((), kappa, {"units": "1", "long_name": "modal coupling indicator kappa "
                                                  "(0 uncoupled, 1 interface tied)"})
    if "transient" in tasks:
        t, x, units, state = _fe_transient(model, tasks, conditions)

        def coulomb(mu0):  # the same point with the law's mean friction only
            ref = dict(tasks["transient"])
            del ref["law"], ref["coulomb_reference"]
            return _fe_transient(model, {"transient": ref}, {**conditions, "mu": mu0})[1]

        transient_variables(t, x, units, state, tasks, data, coords, coulomb=coulomb)
        data["solver_path"] = ((), np.array(state["solver"]["solver_path"], dtype=object), {
            "long_name": "solver path of the transient (full or reduced)",
            "reason": state["solver"]["solver_choice_reason"]})
        data["reduced_error_estimate_db"] = ((), state["solver"]["reduced_error_estimate_db"], {
            "units": "dB", "long_name": "estimated in-band error of the reduced path (NaN: not estimated)"})
        if run_analysis is not None:
            run_analysis(model, state["run"], data, coords, conditions)
    return xr.Dataset(data, coords=coords)


def coupling_system(model_path, mesh_factors, n_modes: int) -> dict:
    """``{"coupling_bounds": {repr(mesh factor): (f0, f_inf)}}`` for the meshes of a sweep whose model has contacts
    (computed once for the study, not at every point; :func:`fivid.study.coupling.coupling_bounds`), else ``{}``."""
    bounds = {}
    for factor in np.unique(mesh_factors):  # per mesh of the sweep
        model = refined_model(model_path, float(factor))
        if model.contacts:
            f0, fi = coupling_bounds(model, n_modes)
            bounds[repr(float(factor))] = (f0.tolist(), fi.tolist())
    return {"coupling_bounds": bounds} if bounds else {}


def transient_variables(t, x, units: str, state: dict, tasks: dict, data: dict, coords: dict, *, coulomb=None):
    """Add a response record's analyses to ``data``/``coords`` (the ``transient`` and ``psd`` variables of the
    module docstring). ``state``: ``sliding`` and ``stick`` per sample; ``coulomb(mu0)``: the same point's
    response with Coulomb friction mu0 (for ``coulomb_reference``)."""
    fs = 1.0 / float(np.median(np.diff(t)))
    a = analyse_transient(t, x, sliding=state["sliding"], stick=state["stick"])
    late = x[x.size // 2:]  # levels and spectra of the steady state: the record's second half
    rms = float(np.sqrt(np.mean((late - late.mean()) ** 2)))
    n_nb = min(late.size, 4096)
    fb, pb = welch_density(late, fs, nperseg=n_nb)
    data["narrowband_fraction"] = ((), narrowband_fraction(fb, pb), {
        "units": "1", "long_name": "share of the response power in prominent spectral peaks",
        "nperseg": n_nb})
    data.update({
        "regime": ((), np.array(a["regime"], dtype=object), {"long_name": "regime of the transient", "allowed": " ".join(REGIMES)}),
        "growth_rate": ((), a["growth_rate"], {"units": "s-1", "long_name": "envelope growth rate"}),
        "growth_rate_stderr": ((), a["growth_rate_stderr"], {"units": "s-1",
                                                             "long_name": "standard error of the growth rate"}),
        "onset_time": ((), a["onset_time"], {"units": "s", "long_name": "end of the linear growth phase"}),
        "response_frequency": ((), a["frequency"], {"units": "Hz",
                                                    "long_name": "dominant frequency of the last quarter"}),
        "amplitude": ((), a["amplitude"], {"units": units, "long_name": "RMS of the last quarter"}),
        "stick_fraction": ((), a["stick_fraction"], {"units": "1", "long_name": "stick share, second half"}),
        "rms": ((), rms, {"units": units, "long_name": "RMS of the response, second half of the record"}),
    })
    if tasks["transient"].get("coulomb_reference"):
        # the same point with the law's mean friction only: what the perturbation adds (seed 001's claim)
        xc = coulomb(load_law(tasks["transient"]["law"]).mu0)
        xc = xc[xc.size // 2:]
        rms_c = float(np.sqrt(np.mean((xc - xc.mean()) ** 2)))
        data["rms_coulomb"] = ((), rms_c, {"units": units, "long_name": "RMS with Coulomb friction mu0 only"})
        data["perturbation_gain_db"] = ((), 20 * np.log10(rms / rms_c) if rms_c > 0 else np.inf, {
            "units": "dB", "long_name": "response level with the law minus with Coulomb mu0"})
        q = xc.size // 2  # the Coulomb record's second half: its last two quarters
        r3, r4 = (float(np.sqrt(np.mean((y - y.mean()) ** 2))) for y in (xc[:q], xc[q:]))
        data["coulomb_decay_db"] = ((), 20 * np.log10(r3 / r4) if r3 > 0 and r4 > 0 else np.nan, {
            "units": "dB", "long_name": "Coulomb response, level of the third quarter minus the fourth "
                                        "(> 0: a ring-down of the start-up, not a steady vibration)"})
        if "psd" in tasks:
            _psd_variable("psd_coulomb", xc, fs, tasks, units, data, coords, "Welch PSD of the response, Coulomb mu0")
            if xc.size == late.size:  # same start-up in both runs: the difference is what the perturbation drives
                _psd_variable("psd_perturbation", late - xc, fs, tasks, units, data, coords,
                              "Welch PSD of the response with the law minus with Coulomb mu0 (the perturbation's)")
    if units == "m s-2":  # level re 1e-6 m s-2 (ISO 1683 acceleration reference)
        data["level_db"] = ((), 20.0 * np.log10(rms / 1e-6) if rms > 0 else -np.inf,
                            {"units": "dB", "long_name": "acceleration level re 1e-6 m s-2"})
    if "psd" in tasks:
        _psd_variable("psd", late, fs, tasks, units, data, coords, "Welch PSD of the response")


def _psd_variable(name, x, fs, tasks, units, data, coords, long_name):
    """``data[name]``: the Welch PSD of ``x`` over ``tasks["psd"]``'s band (and the ``frequency`` coordinate)."""
    n = min(tasks["psd"]["nperseg"], x.size)
    f, p = welch_density(x, fs, nperseg=n)
    if "band" in tasks["psd"]:
        sel = (f >= tasks["psd"]["band"][0]) & (f <= tasks["psd"]["band"][1])
        f, p = f[sel], p[sel]
    data[name] = (("frequency",), p, {"units": f"({units})^2 Hz-1", "long_name": long_name,
                                      "nperseg": n, "window": "hann", "noverlap": n // 2})
    coords["frequency"] = ("frequency", f, {"units": "Hz", "long_name": "frequency"})


def refined_model(path, factor: float = 1.0, roughness_ra: float | None = None, *, surface: dict | None = None,
                  sensors: list | None = None):
    """The FE model of ``path`` with every body's divisions multiplied by ``factor`` (rounded, at least 1; a full
    ring keeps at least 3 around); ``factor`` 1 is the model as configured. With ``roughness_ra`` [m], every
    Greenwood-Williamson contact gets the surface of that Ra: ``surface`` (``sigma``, ``asperity_radius``,
    ``asperity_density`` in SI, e.g. :func:`fivid.surface.contact_law.gw_parameters` of a profile, with its
    ``source``) when given, else the summit-height deviation of a Gaussian surface of that Ra,
    ``sigma = sqrt(pi/2) Ra`` (the rest of its surface parameters as configured). ``sensors``: extra sensor
    entries (model-config form) appended to the model's own."""
    gw = False
    if roughness_ra is not None:
        raw = read_yaml(path, "model config").data
        gw = any(isinstance(c.get("normal"), dict) and c["normal"].get("law") == "greenwood-williamson"
                 for c in raw.get("contacts") or [])
    if factor == 1.0 and not gw and not sensors:
        return load_model(path)
    data = read_config(path)[0]
    if sensors:
        data["sensors"] = list(data.get("sensors") or []) + list(sensors)
    for body in data["bodies"].values():
        body["divisions"] = [max(3 if "annulus" in body and i == 0 else 1, int(round(float(d) * factor)))
                             for i, d in enumerate(body["divisions"])]
    name = f"{data.get('name', 'model')} (mesh x{factor:g}"
    if gw:
        for c in data.get("contacts") or []:
            if isinstance(c.get("normal"), dict) and c["normal"].get("law") == "greenwood-williamson":
                if surface is not None:
                    c["normal"].update(sigma=f"{float(surface['sigma'])!r} m",
                                       asperity_radius=f"{float(surface['asperity_radius'])!r} m",
                                       asperity_density=f"{float(surface['asperity_density'])!r} m^-2")
                else:
                    c["normal"]["sigma"] = f"{RQ_PER_RA * float(roughness_ra)!r} m"
        name += (f", GW surface of Ra {roughness_ra:g} m: {surface.get('source', 'given')}" if surface is not None
                 else f", GW sigma from Ra {roughness_ra:g} m")
    data["name"] = name + ")"
    return load_model(data)


def element_size(model) -> float:
    """Largest element side over the model [m] (the h of a convergence study)."""
    h = 0.0
    for block in model.blocks:
        xy = block.element_corners().reshape(-1, 4, 2)
        sides = np.roll(xy, -1, axis=1) - xy
        h = max(h, float(np.max(np.hypot(sides[..., 0], sides[..., 1]))))
    return h


def _fe_transient(model, tasks, conditions):
    tr = tasks["transient"]
    law = load_law(tr["law"]) if "law" in tr else None
    mu = float(conditions["mu"]) if law is None and "mu" in conditions else None
    # (mesh, time_step: the model and step)
    condition = OperatingCondition(*(float(conditions[name]) if name in conditions else None
                                     for name in ("sliding_velocity", "normal_load", "roughness_ra")))
    kw = solver_choice(tr, conditions)
    if "time_step" in conditions:
        kw["safety"] = float(conditions["time_step"])
    integration = IntegrationOptions(**kw)
    ds = simulate(model, condition, FrictionInput(law=law, mu=mu, seed=int(conditions.get("seed", 0))),
                  schedule=RunSchedule(duration=tr["duration"], sample_rate=tr["sample_rate"],
                                       **({"settle_time": tr["settle_time"]} if "settle_time" in tr else {})),
                  integration=integration, output=OutputOptions(progress=False))
    solver = {"solver_path": ds.attrs.get("solver_path", "full"),
              "solver_choice_reason": ds.attrs.get("solver_choice_reason", ""),
              "reduced_error_estimate_db": float(ds.attrs.get("reduced_error_estimate_db", np.nan))}
    ds = steady_part(ds)  # from the run's transient_end
    acc = ds["acceleration"]
    if "sensor" in acc.dims:
        acc = acc.isel(sensor=0)
    t = ds["time"].values
    x = acc.values
    if "stick_fraction" in ds:  # per pair: share of the slave nodes sticking (open ones count as neither)
        stick = ds["stick_fraction"]
        stick = (stick.mean("contact") if "contact" in stick.dims else stick).values
    else:
        stick = np.zeros(t.size)
    # the CEA's sliding equilibrium: the contact slides as a whole (most of it; a few nodes of a large contact
    # may stick where the pressure peaks, and a held ring winds up with a shrinking stick zone)
    sliding = stick < 0.5
    return t, x, "m s-2", {"sliding": sliding, "stick": stick, "solver": solver, "run": ds}


def solver_choice(transient: dict, conditions: dict) -> dict:
    """The solver-path fields of :class:`fivid.solver.IntegrationOptions` for a point's transient:
    ``transient["solver"]`` (``auto``, the default: the reduced path when its estimated in-band error is within
    ``transient["reduced_tolerance"]`` [dB], 0.5 by default, as ``fivid simulate``; ``full``; ``reduced``: the
    automatic path's reduced settings whatever the estimate). A point
    that refines the ``mesh`` or the ``time_step`` studies the full model's discretisation: ``auto`` runs it on the
    full path."""
    solver = transient.get("solver", "auto")
    if solver == "auto" and ({"mesh", "time_step"} & set(conditions)):
        solver = "full"
    kw = {"reduced": {"full": None}.get(solver, solver)}
    if solver == "auto":
        kw["reduced_tolerance"] = float(transient.get("reduced_tolerance", 0.5))
    return kw

