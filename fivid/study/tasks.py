"""The per-point analyses the study kinds share, run on a dask worker, returned as a small Dataset (no ``point``
dimension).

:func:`fe_point` (an FE model's point, the FE kinds' ``evaluate``) and :func:`transient_variables` (a response
record's analyses, any kind with a transient) take plain data (picklable): ``system`` is ``{"model_path": str}``
(plus the study-wide ``coupling_bounds``, :func:`coupling_system`), ``tasks`` the study's per-point settings
(SI), ``conditions`` the point's ``{axis: value}``. Variables (each only when its task ran):

- ``modes``: ``mode_frequency(mode)`` [Hz], preloaded at the point's normal load (FE); with a contact, the
  coupling indicator ``coupling_indicator`` and ``coupling`` (weak/strong, :mod:`fivid.study.coupling`);
- ``transient``: ``regime``, ``growth_rate`` [s-1], ``growth_rate_stderr``, ``onset_time`` [s], ``response_frequency`` [Hz],
  ``amplitude`` (limit-cycle RMS), ``stick_fraction``, ``rms`` and ``level_db`` (of the second half of the
  response's steady part: the start-up ring-down excluded),
  ``narrowband_fraction`` (share of its power in prominent peaks: tonal vs broadband); with
  ``coulomb_reference: true`` (and a law) also ``rms_coulomb`` and ``perturbation_gain_db``, the same point
  simulated with the law's mu0 alone (what the perturbation adds);
- ``psd``: ``psd(frequency)`` of the second half of the response's steady part (Welch, Hann, half overlap).

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
from fivid.study.coupling import WEAK_STRONG_THRESHOLD, coupling_bounds, coupling_indicator
from fivid.surface.rough_pair import RQ_PER_RA

__all__ = ["REGIMES", "TRANSIENT_KEYS", "COUPLING_KEYS", "element_size", "fe_point", "coupling_system", "transient_variables", "refined_model"]

REGIMES = ("stable", "mode_coupling", "stick_slip")
#: (point variable, summary.json key) of the transient analyses, copied into a study summary's points
TRANSIENT_KEYS = (("regime", "regime"), ("growth_rate", "growth_rate"), ("response_frequency", "frequency"),
                  ("onset_time", "onset_time"), ("rms", "rms"), ("level_db", "level_db"),
                  ("stick_fraction", "stick_fraction"), ("narrowband_fraction", "narrowband_fraction"),
                  ("perturbation_gain_db", "perturbation_gain_db"))
#: (point variable, summary.json key) of the weak/strong coupling indicator
COUPLING_KEYS = (("coupling_indicator", "coupling_indicator"), ("coupling", "coupling"))


def fe_point(system: dict, tasks: dict, conditions: dict):
    """An FE model's point: element size, ``modes`` (and the coupling indicator with ``system["coupling_bounds"]``),
    ``transient`` and ``psd`` (see the module docstring); an xarray Dataset."""
    import xarray as xr

    data, coords = {}, {}
    model = refined_model(system["model_path"], conditions.get("mesh", 1.0), conditions.get("roughness_ra"))
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
            data["coupling_indicator"] = ((), kappa, {"units": "1", "long_name": "coupling indicator kappa "
                                                      "(0 uncoupled, 1 interface tied)"})
            data["coupling"] = ((), np.array("weak" if kappa < WEAK_STRONG_THRESHOLD else "strong", dtype=object),
                                {"long_name": "weak or strong contact (kappa < 0.5: weak)"})
    if "transient" in tasks:
        t, x, units, state = _fe_transient(model, tasks, conditions)

        def coulomb(mu0):  # the same point with the law's mean friction only
            ref = dict(tasks["transient"])
            del ref["law"], ref["coulomb_reference"]
            return _fe_transient(model, {"transient": ref}, {**conditions, "mu": mu0})[1]

        transient_variables(t, x, units, state, tasks, data, coords, coulomb=coulomb)
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
    if units == "m s-2":  # level re 1e-6 m s-2 (ISO 1683 acceleration reference)
        data["level_db"] = ((), 20.0 * np.log10(rms / 1e-6) if rms > 0 else -np.inf,
                            {"units": "dB", "long_name": "acceleration level re 1e-6 m s-2"})
    if "psd" in tasks:
        n = min(tasks["psd"]["nperseg"], late.size)
        f, p = welch_density(late, fs, nperseg=n)
        if "band" in tasks["psd"]:
            sel = (f >= tasks["psd"]["band"][0]) & (f <= tasks["psd"]["band"][1])
            f, p = f[sel], p[sel]
        data["psd"] = (("frequency",), p, {"units": f"({units})^2 Hz-1", "long_name": "Welch PSD of the response",
                                            "nperseg": n, "window": "hann", "noverlap": n // 2})
        coords["frequency"] = ("frequency", f, {"units": "Hz", "long_name": "frequency"})


def refined_model(path, factor: float = 1.0, roughness_ra: float | None = None):
    """The FE model of ``path`` with every body's divisions multiplied by ``factor`` (rounded, at least 1; a full
    ring keeps at least 3 around); ``factor`` 1 is the model as configured. With ``roughness_ra`` [m], every
    Greenwood-Williamson contact gets the summit-height deviation of a Gaussian surface of that Ra,
    ``sigma = sqrt(pi/2) Ra`` (the rest of its surface parameters as configured)."""
    gw = False
    if roughness_ra is not None:
        raw = read_yaml(path, "model config").data
        gw = any(isinstance(c.get("normal"), dict) and c["normal"].get("law") == "greenwood-williamson"
                 for c in raw.get("contacts") or [])
    if factor == 1.0 and not gw:
        return load_model(path)
    data = read_config(path)[0]
    for body in data["bodies"].values():
        body["divisions"] = [max(3 if "annulus" in body and i == 0 else 1, int(round(float(d) * factor)))
                             for i, d in enumerate(body["divisions"])]
    name = f"{data.get('name', 'model')} (mesh x{factor:g}"
    if gw:
        for c in data.get("contacts") or []:
            if isinstance(c.get("normal"), dict) and c["normal"].get("law") == "greenwood-williamson":
                c["normal"]["sigma"] = f"{RQ_PER_RA * float(roughness_ra)!r} m"
        name += f", GW sigma from Ra {roughness_ra:g} m"
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
    integration = IntegrationOptions(safety=float(conditions["time_step"])) if "time_step" in conditions \
        else IntegrationOptions()
    ds = simulate(model, condition, FrictionInput(law=law, mu=mu, seed=int(conditions.get("seed", 0))),
                  schedule=RunSchedule(duration=tr["duration"], sample_rate=tr["sample_rate"]),
                  integration=integration, output=OutputOptions(progress=False))
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
    return t, x, "m s-2", {"sliding": sliding, "stick": stick}

