"""The weak/strong kind (``kind: weak_strong``, seeds 000/001): the contact's coupling over the normal load, told
by the response.

Seed 001 defines weak contact by what the beams do: they answer the contact's broadband excitation with their own
modes; in strong contact the response follows the coupled system's modes. The **response criterion** reads each
point's sensor PSD:

- the reference frequencies (once per study, :func:`fivid.study.coupling.reference_frequencies`): *uncoupled*,
  the beams on their own supports without any contact spring, and *coupled*, the interface's contact set under
  the sweep's heaviest load tied rigidly (the rigid limit of the preloaded modes);
- the ``n_peaks`` strongest PSD peaks (``prominence_db``; :func:`fivid.signal.peaks.strongest_peaks`; below
  ``1 - band_width`` times the top of a band-limited law's band, whose brick-wall edge makes a spurious
  one-sided maximum where the response rises toward the next mode), each
  placed between the two sets, 0 on an uncoupled frequency, 1 on a coupled one
  (:func:`fivid.study.coupling.peak_positions`), and averaged with the peaks' power as weights:
  ``coupling_response`` in [0, 1]; ``coupling`` is "strong" from 0.5 up, else "weak";
- beside it the broadband/narrowband share (``narrowband_fraction``: power in prominent peaks), which seed 001
  pairs with the two regimes (weak: broadband with the eigenfrequency peaks; strong: narrowband) but which here
  is not part of the label (it also follows the damping and the record length).

The modal index kappa of the preloaded modes stays as a second, linear view (``coupling_modal``); the summary
says where the two labels agree. ``transition_load``: where ``coupling_response`` first crosses 0.5 along the
load (log-interpolated between the bracketing loads), ``transition_load_modal`` kappa's.

The GW surfaces of the ``roughness_ra`` levels come from profiles through the spectral-moment estimator
(:mod:`fivid.surface.contact_law`): a measured profile where there is one (``points.weak_strong.profile``), else
a Gaussian profile synthesised to the level's Ra (SYNTHETIC, :func:`fivid.surface.gaussian_random_profile`,
the section's correlation length and seed).

**Settling** (``settle_level``, 40 dB by default): the clamp's displacement ramp rings the beams' modes, and a
light load's friction cannot drive anything near that ring-down. Each transient's schedule waits
:func:`settle_time` between the preload ramp and the base ramp (:class:`fivid.solver.RunSchedule`'s
``settle_time``): the time the slowest reference mode inside the PSD band (the exact decay rate ``-Re(s)`` of
its Rayleigh damping, :func:`fivid.fe.damping.modal_root`) needs to decay by ``settle_level``; the analysed
record (the second half of the steady part) then starts that long plus the base ramp and half the record after
the clamp stopped. The summary's ``settle`` gives the time, the mode and its rate.

What the perturbation adds (``coulomb_reference``): per point the PSD with the law and with Coulomb mu0, split
into the band of the reference modes (within ``band_width`` of either set) and the rest:
``gain_modes_db``, ``gain_rest_db``; the perturbation's own response (law minus Coulomb on the same start-up)
in each band, ``power_*_perturbation``, and per unit of its friction force (``A N``, the law's amplitude at
the point's velocity and roughness times the load), ``transfer_modes_db``, ``transfer_rest_db`` [dB re
1 (m s-2)^2 N-2]: what the contact passes from the friction force to the sensor, load by load.

``regime``: the envelope analysis's label (kept as ``regime_transient``) unless :func:`forced_regime` reads its
"mode_coupling" as the forced response building up from the settled, quiet start (CEA at mu0 stable, the
Coulomb record decaying).
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import Field

from fivid.config_layer import ConfigModel, Number, Quantity
from fivid.errors import ConfigError
from fivid.fe.cea import complex_eigenvalue_analysis
from fivid.fe.damping import modal_root
from fivid.friction import load_law
from fivid.report.html import figure_data_uri, new_figure, table
from fivid.signal.peaks import near_frequencies, strongest_peaks
from fivid.storage import dumps_json
from fivid.study.axes import AXES
from fivid.study.coupling import WEAK_STRONG_THRESHOLD, peak_positions, reference_frequencies, response_coupling
from fivid.study.kinds.sweep import FeSweep
from fivid.study.seed_checks import twin_amplitude_linearity, twin_broadband_levels
from fivid.study.tasks import COUPLING_KEYS, TRANSIENT_KEYS, fe_point, refined_model
from fivid.surface import evaluate_profile, gaussian_random_profile, read_profile
from fivid.surface.contact_law import gw_parameters
from fivid.surface.rough_pair import RQ_PER_RA

__all__ = ["WeakStrong", "WeakStrongSettings", "KIND", "transitions", "study_surfaces", "RESPONSE_KEYS", "agreement",
           "seed_checks", "peak_figure", "dumps_checks", "DEFAULTS", "settle_time",
           "forced_regime"]

#: per-point results of the response criterion and the band decomposition copied into summary.json
RESPONSE_KEYS = (("coupling", "coupling"), ("coupling_response", "coupling_response"),
                 ("gain_modes_db", "gain_modes_db"), ("gain_rest_db", "gain_rest_db"),
                 ("modes_share", "modes_share"), ("modes_share_coulomb", "modes_share_coulomb"),
                 ("power_rest", "power_rest"), ("power_rest_coulomb", "power_rest_coulomb"),
                 ("power_modes", "power_modes"), ("power_modes_coulomb", "power_modes_coulomb"),
                 ("power_modes_perturbation", "power_modes_perturbation"),
                 ("power_rest_perturbation", "power_rest_perturbation"), ("transfer_modes_db", "transfer_modes_db"),
                 ("transfer_rest_db", "transfer_rest_db"), ("coulomb_decay_db", "coulomb_decay_db"),
                 ("regime_transient", "regime_transient"),
                 ("cea_growth_mu0", "cea_growth_mu0"))
#: the section's defaults (SI)
DEFAULTS = {"correlation_length": 10e-6, "profile_length": 4e-3, "profile_step": 0.5e-6, "profile_seed": 1,
            "n_peaks": 5, "prominence_db": 10.0, "reference_modes": 12, "band_width": 0.05, "twin": None,
            "cea_at_mu0": True, "settle_level": 40.0}


class WeakStrongSettings(ConfigModel):
    """``points.weak_strong``: the surfaces of the roughness levels and the response criterion's settings."""

    profile: str | None = Field(None, description="a measured profile (Dektak CSV, x/z text, X3P) whose GW "
                                                  "parameters every point takes (then no roughness_ra axis)")
    correlation_length: Quantity("m", positive=True, bare_is_si=True) = None
    profile_length: Quantity("m", positive=True, bare_is_si=True) = None
    profile_step: Quantity("m", positive=True, bare_is_si=True) = None
    profile_seed: Annotated[int, Field(ge=0)] = None
    n_peaks: Annotated[int, Field(ge=1)] = None
    prominence_db: Annotated[Number, Field(gt=0)] = None
    reference_modes: Annotated[int, Field(ge=1)] = None
    band_width: Annotated[Number, Field(gt=0, lt=0.5)] = None
    twin: str | None = Field(None, description="folder of the twin's rig CSVs (relative to the study file) for "
                                               "seed 000's checks: amplitude linear in V, Coulomb's broadband level")
    cea_at_mu0: bool | None = Field(None, description="a CEA at the law's mu0 at every point (default true)")
    settle_level: Annotated[Number, Field(gt=0)] = Field(
        None, description="decay [dB] of the slowest reference mode in the PSD band before the base ramp starts "
                          "(default 40): sets each transient's settle_time")


class WeakStrong(FeSweep):
    """Weak and strong contact over the normal load (:class:`fivid.study.kind.StudyKind`)."""

    name = "weak_strong"
    description = "weak and strong contact over the normal load (seeds 000/001): response criterion, transition load"
    section = ("points", "weak_strong")
    config = WeakStrongSettings
    point_keys = TRANSIENT_KEYS[:8] + COUPLING_KEYS + RESPONSE_KEYS + TRANSIENT_KEYS[8:]

    def guess(self, data: dict) -> bool:
        """An FE study with a ``points.weak_strong`` section."""
        return "weak_strong" in (data.get("points") or {})

    def check(self, cfg) -> list[tuple[str, str]]:
        """The response criterion reads the PSD of a transient over a load sweep."""
        if cfg.points.transient is None or cfg.points.psd is None:
            return [("points", "a weak/strong study reads the response: give points.transient and points.psd")]
        return []

    def settings(self, section) -> dict:
        """The section in SI over :data:`DEFAULTS`."""
        return {**DEFAULTS, **(section.model_dump(exclude_unset=True) if section is not None else {})}

    def system(self, study) -> dict:
        """The base system (kappa's bounds when modes are computed), the GW surface per roughness level
        (:func:`study_surfaces`) and the two reference sets, on the swept mesh at the heaviest swept load."""
        out = super().system(study)
        cfg = study.points["weak_strong"]
        surfaces = study_surfaces(cfg, study.axes.get("roughness_ra"), study.source)
        out["surfaces"] = surfaces
        mesh = float(np.unique(study.axes.get("mesh", [1.0]))[0])
        loads = study.axes.get("normal_load")
        if loads is None:
            return out
        ra = next(iter(surfaces), None)
        model = refined_model(study.model_path, mesh, None if ra is None else float(ra),
                              surface=None if ra is None else surfaces[ra])
        f0, f1 = reference_frequencies(model, cfg["reference_modes"], float(np.max(loads)))
        out["reference_frequencies"] = {"uncoupled": f0.tolist(), "coupled": f1.tolist()}
        band = (study.points.get("psd") or {}).get("band", (0.0, np.inf))
        inside = [f for f in np.concatenate([f0, f1]) if band[0] <= f <= band[1]]
        out["settle"] = settle_time(inside, model.rayleigh_alpha, model.rayleigh_beta, model.damping_cutoff,
                                    cfg["settle_level"])
        return out

    def evaluate(self, system: dict, tasks: dict, conditions: dict):
        """:func:`fivid.study.tasks.fe_point` and the response criterion on its PSD (module docstring)."""
        if "settle" in system and "transient" in tasks:
            tasks = {**tasks, "transient": {**tasks["transient"], "settle_time": system["settle"]["time"]}}
        ds = fe_point(system, tasks, conditions)
        if "settle" in system and "transient" in tasks:
            st = system["settle"]
            ds["settle_time"] = ((), st["time"], {"units": "s", "long_name": "wait between preload and base ramp",
                                                  "level_db": st["level_db"], "mode_frequency": st["mode_frequency"],
                                                  "decay_rate": st["decay_rate"], "rule": st["rule"]})
        ref = system.get("reference_frequencies")
        if ref is None or "psd" not in ds:
            return ds
        cfg = tasks["weak_strong"]
        for k in ("uncoupled", "coupled"):
            ds[f"reference_{k}"] = (("reference_mode",), np.asarray(ref[k]),
                                    {"units": "Hz", "long_name": f"{k} reference frequencies (study-wide)"})
        f, p = ds["frequency"].values, ds["psd"].values
        # a band-limited law's brick-wall edge makes a one-sided maximum just below it (the response rising toward
        # the next mode, then cut): not a mode of the response; its peaks are read below the edge's guard band
        top = _law_band_top(tasks, cfg["band_width"])
        keep = f <= top
        pf, pp = strongest_peaks(f[keep], p[keep], prominence_db=cfg["prominence_db"], max_peaks=cfg["n_peaks"])
        pad = np.full(cfg["n_peaks"], np.nan)
        ds["peak_frequency"] = (("peak",), np.concatenate([pf, pad])[:cfg["n_peaks"]],
                                {"units": "Hz", "long_name": "PSD peak frequency, strongest first"})
        ds["peak_position"] = (("peak",), np.concatenate([peak_positions(pf, ref["uncoupled"], ref["coupled"]),
                                                          pad])[:cfg["n_peaks"]],
                               {"units": "1", "long_name": "peak between uncoupled (0) and coupled (1) frequencies"})
        c = response_coupling(pf, pp, ref["uncoupled"], ref["coupled"])
        ds["coupling_response"] = ((), c, {"units": "1", "long_name": "response coupling (0 the beams' own "
                                                                      "frequencies, 1 the coupled system's)"})
        label = "" if not np.isfinite(c) else "strong" if c >= WEAK_STRONG_THRESHOLD else "weak"
        ds["coupling"] = ((), np.array(label, dtype=object), {"long_name": "weak or strong contact, from the "
                                                                           "response (coupling_response >= 0.5)"})
        band = near_frequencies(f, np.concatenate([ref["uncoupled"], ref["coupled"]]), cfg["band_width"])
        for name, suffix in (("psd", ""), ("psd_coulomb", "_coulomb")):
            if name in ds:
                q = ds[name].values
                ds["modes_share" + suffix] = ((), float(q[band].sum() / q.sum()) if q.sum() > 0 else np.nan, {
                    "units": "1", "long_name": "share of the PSD power within band_width of the reference modes"
                    + (" (Coulomb mu0)" if suffix else "")})
        df = float(f[1] - f[0]) if f.size > 1 else 0.0
        for name, suffix in (("psd", ""), ("psd_coulomb", "_coulomb"), ("psd_perturbation", "_perturbation")):
            if name in ds:
                q = ds[name].values
                for part, sel in (("modes", band), ("rest", ~band)):
                    ds[f"power_{part}{suffix}"] = ((), float(q[sel].sum() * df), {
                        "units": "(m s-2)^2", "long_name": f"response power in the {part} band"
                        + (" (Coulomb mu0)" if suffix else "")})
        if cfg.get("cea_at_mu0", True) and "transient" in tasks and "law" in tasks["transient"]:
            ds["cea_growth_mu0"] = ((), _cea_growth_at_mu0(system, tasks, conditions), {
                "units": "s-1", "long_name": "largest CEA real part at the law's mu0 and the point's load"})
        if "regime" in ds and "cea_growth_mu0" in ds and "coulomb_decay_db" in ds:
            ds["regime_transient"] = ds["regime"].copy()
            ds["regime_transient"].attrs["long_name"] = "regime of the law's record by its envelope alone"
            ds["regime"] = ((), np.array(forced_regime(str(ds["regime"].values), float(ds["cea_growth_mu0"]),
                                                       float(ds["coulomb_decay_db"])), dtype=object),
                            {**ds["regime"].attrs, "rule": "forced_regime: a mode_coupling envelope is the forced "
                             "response building up when the CEA at mu0 is stable and the Coulomb record decays"})
        if "psd_coulomb" in ds:
            q, qc = ds["psd"].values, ds["psd_coulomb"].values
            for key, sel, what in (("gain_modes_db", band, "the reference modes' band"),
                                   ("gain_rest_db", ~band, "the rest of the PSD band")):
                num, den = q[sel].sum(), qc[sel].sum()
                ds[key] = ((), 10 * np.log10(num / den) if num > 0 and den > 0 else np.nan,
                           {"units": "dB", "long_name": f"law minus Coulomb mu0, power in {what}"})
        if "power_modes_perturbation" in ds and conditions.get("normal_load"):
            force = _perturbation_force(tasks, conditions)
            for part in ("modes", "rest"):
                q = float(ds[f"power_{part}_perturbation"])
                ds[f"transfer_{part}_db"] = ((), 10 * np.log10(q / force**2) if q > 0 and force > 0 else np.nan, {
                    "units": "dB re 1 (m s-2)^2 N-2", "long_name": f"perturbation's response power in the {part} band "
                    "per unit friction-force power (A N)^2", "force_rms": force})
        return ds

    def report(self, page, ds, summary: dict) -> None:
        """The peak frequencies over load with the reference sets (seed 001's figure), where the response and
        modal labels agree, and the seed checks."""
        if summary.get("reference_frequencies") and any(p.get("peak_frequencies") for p in summary["points"]):
            page.heading("Weak and strong contact by the response", 3)
            page.figure(peak_figure(summary), "PSD peak frequencies (marker size: strongest largest) against the "
                        "normal load, over the uncoupled beams' frequencies (dashed) and the coupled system's (solid).",
                        "peak frequencies against load")
            rows = [[p.get("normal_load"), p.get("roughness_ra"), p.get("coupling"), p.get("coupling_response"),
                     p.get("coupling_modal"), p.get("narrowband_fraction"), p.get("gain_modes_db"),
                     p.get("gain_rest_db"), p.get("transfer_modes_db"), p.get("transfer_rest_db")]
                    for p in summary["points"] if p.get("status") == "done"]
            page.raw(table(["normal_load [N]", "roughness_ra [m]", "coupling (response)", "coupling_response",
                            "coupling_modal (kappa)", "narrowband_fraction", "gain in modes' band [dB]",
                            "gain elsewhere [dB]", "perturbation transfer, modes' band [dB re 1 (m s-2)^2 N-2]",
                            "perturbation transfer elsewhere [dB]"], rows))
            st = summary.get("settle")
            if st:
                page.paragraph(f"Every transient waited {st['time']:.3g} s between the preload ramp and the base "
                               f"ramp: the {st.get('mode_frequency', float('nan')):.0f} Hz reference mode, the "
                               f"slowest in the PSD band ({st.get('decay_rate', float('nan')):.3g} s-1), decays by "
                               f"{st.get('level_db', float('nan')):g} dB in that time.")
            a = summary.get("coupling_agreement") or {}
            if a:
                page.paragraph(f"Response and modal labels agree at {a['n_agree']} of {a['n_points']} points.")
        checks = summary.get("seed_checks")
        if checks:
            page.pre(dumps_checks(checks))

    def summarise(self, study, ds, points: list[dict]) -> dict:
        """The transition loads (response and modal), the reference sets, each point's ``peak_frequencies``,
        where the response and modal labels agree, the GW ``surfaces`` (per roughness level, with their
        ``source``), the ``settle`` time and the response's power law (``fits.rms``)."""
        out = super().summarise(study, ds, points)
        if "peak_frequency" in ds:
            pk = ds["peak_frequency"].transpose("point", "peak").values
            for i, p in enumerate(points):
                if p.get("status") == "done":
                    p["peak_frequencies"] = [float(x) for x in pk[i] if np.isfinite(x)]
        if "reference_uncoupled" in ds:
            ref = {k: ds[f"reference_{k}"] for k in ("uncoupled", "coupled")}
            out["reference_frequencies"] = {k: [float(x) for x in (v.isel(point=0) if "point" in v.dims else v).values]
                                            for k, v in ref.items()}
        if "settle_time" in ds:
            st = ds["settle_time"]
            st = st.isel(point=0) if "point" in st.dims else st
            out["settle"] = {"time": float(st), **{k: st.attrs[k] for k in ("level_db", "mode_frequency",
                                                                              "decay_rate", "rule") if k in st.attrs},
                             "units": {"time": "s", "mode_frequency": "Hz", "decay_rate": "s-1", "level_db": "dB"}}
        out.update(transitions(points))
        modal = transitions(points, key="coupling_modal")
        if modal:
            out["transition_load_modal"] = modal["transition_load"]
        out["coupling_agreement"] = agreement(points)
        cfg = {**DEFAULTS, **(study.points.get("weak_strong") or {})}
        # the GW surface each roughness level's points ran with, and where it came from (a few ms to redo)
        out["surfaces"] = study_surfaces(cfg, study.axes.get("roughness_ra"), study.source)  # SI
        cfg["band"] = (study.points.get("psd") or {}).get("band", (100.0, 20e3))
        out["seed_checks"] = seed_checks(points, cfg, out.get("reference_frequencies"), study.source)
        return out


def settle_time(frequencies, alpha: float, beta: float, cutoff: float, level_db: float) -> dict:
    """How long the slowest of ``frequencies`` [Hz] takes to decay by ``level_db`` [dB] under Rayleigh damping.

    The decay rate of a mode is ``-Re(s)`` of its exact root (:func:`fivid.fe.damping.modal_root`: classic or
    band-limited Rayleigh, ``alpha`` [s-1], ``beta`` [s], ``cutoff`` [Hz]; to first order ``alpha/2 +
    beta omega^2/2``, the lowest mode slowest); the amplitude falls by ``level_db`` in
    ``ln(10) level_db / 20 / rate``.

    Returns ``{"time" [s], "level_db", "mode_frequency" [Hz], "decay_rate" [s-1], "rule"}``.

    Examples
    --------
    >>> round(settle_time([1000.0], 50.0, 0.0, float("inf"), 40.0)["time"], 4)   # rate alpha/2 = 25 s-1
    0.1842
    """
    f = np.asarray(frequencies, dtype=float)
    if f.size == 0:
        raise ConfigError("settle_time needs at least one reference mode inside the PSD band (points.psd.band)",
                          key="points.psd.band")
    rates = -np.real(modal_root(f, float(alpha), float(beta), float(cutoff)))
    i = int(np.argmin(rates))
    if not rates[i] > 0:
        raise ConfigError(f"the mode at {f[i]:.6g} Hz has no damping (alpha {alpha!r}, beta {beta!r}): it never "
                          "settles; give the model damping (model config 'damping')", key="damping")
    return {"time": float(np.log(10.0) * level_db / 20.0 / rates[i]), "level_db": float(level_db),
            "mode_frequency": float(f[i]), "decay_rate": float(rates[i]),
            "rule": "the slowest reference mode in the PSD band decays by level_db (Rayleigh damping's exact rate)"
                    " between the preload ramp and the base ramp (RunSchedule.settle_time)"}


def forced_regime(regime: str, cea_growth: float, coulomb_decay_db: float) -> str:
    """The regime of a point whose friction law forces the response: a "mode_coupling" label of the law's record
    (its envelope rose and saturated) is the random forcing's response building up from the quiet, settled
    start when the CEA at mu0 is stable (``cea_growth`` [s-1] < 0) and the same point with Coulomb mu0 alone
    decays (``coulomb_decay_db`` > 0): then "stable"; otherwise ``regime`` unchanged.

    Examples
    --------
    >>> forced_regime("mode_coupling", -29.6, 12.6), forced_regime("mode_coupling", 5.0, 12.6)
    ('stable', 'mode_coupling')
    """
    if regime == "mode_coupling" and cea_growth < 0 and coulomb_decay_db > 0:
        return "stable"
    return regime


def _perturbation_force(tasks, conditions) -> float:
    """RMS of the perturbation's friction force [N]: the law's amplitude at the point's velocity and roughness
    times the normal load (``injection: uniform``: every sliding node's mu_p(t) is the same)."""
    law = load_law(tasks["transient"]["law"])
    a = law.amplitude(conditions.get("sliding_velocity"), conditions.get("roughness_ra"), conditions["normal_load"])
    return float(a) * float(conditions["normal_load"])


def _law_band_top(tasks, guard: float) -> float:
    """Highest frequency [Hz] whose PSD peaks the criterion reads: ``(1 - guard)`` times the top of the law's
    band when the transient has a band-limited law, else no limit."""
    tr = tasks.get("transient") or {}
    if "law" not in tr:
        return np.inf

    band = getattr(load_law(tr["law"]), "band", None)
    return np.inf if band is None else (1.0 - guard) * float(band[1])


def _cea_growth_at_mu0(system, tasks, conditions) -> float:
    """The largest real part [s-1] of the CEA (:func:`fivid.fe.cea.complex_eigenvalue_analysis`) at the law's mu0
    about the point's preload: seed 000's rig is stable there (< 0)."""
    ra = conditions.get("roughness_ra")
    model = refined_model(system["model_path"], conditions.get("mesh", 1.0), ra,
                          surface=None if ra is None else system.get("surfaces", {}).get(repr(float(ra))))
    mu0 = load_law(tasks["transient"]["law"]).mu0
    cea = complex_eigenvalue_analysis(model, [mu0], normal_load=conditions.get("normal_load"))
    return float(np.nanmax(cea["real_part"].values))


def seed_checks(points, cfg: dict, reference: dict | None, source=None) -> dict:
    """Seeds 000/001's four checks from the points (and the twin, ``cfg["twin"]``; :mod:`fivid.study.seed_checks`):
    ``cea_stable_at_mu0``, ``amplitude_linear_in_velocity``, ``coulomb_broadband``, ``peaks_follow_load``."""
    from pathlib import Path

    out = {}
    growth = [p["cea_growth_mu0"] for p in points if p.get("cea_growth_mu0") is not None]
    if growth:
        out["cea_stable_at_mu0"] = {"stable": bool(max(growth) < 0), "largest_growth_rate": max(growth),
                                    "n_points": len(growth), "units": "s-1"}
    twin = cfg.get("twin")
    if twin:
        folder = (Path(source).parent if source else Path(".")) / twin
        out["amplitude_linear_in_velocity"] = twin_amplitude_linearity(folder)
        if reference is not None:
            measured = twin_broadband_levels(folder, np.concatenate([reference["uncoupled"], reference["coupled"]]),
                                             cfg["band_width"], cfg.get("band", (100.0, 20e3)))
            rows = []
            for m in measured:
                row = _at_condition(points, m)
                if row is not None:
                    rows.append({**{k: m[k] for k in ("file", "sliding_velocity", "roughness_ra", "normal_load")},
                                 "measured_rest_db": _db(m["power_rest"]), **row})
            under = [r["coulomb_rest_db"] < r["measured_rest_db"] for r in rows]
            out["coulomb_broadband"] = {"runs": rows, "coulomb_under_predicts": bool(rows) and all(under),
                                        "levels": "dB re 1 (m s-2)^2 over the PSD band off the reference modes"}
    if reference is not None:
        out["peaks_follow_load"] = _peaks_follow_load(points, reference)
    return out


def dumps_checks(checks: dict) -> str:
    """The seed checks as indented JSON (the report's block)."""
    return dumps_json(checks)


def _at_condition(points, m) -> dict | None:
    """The study's law and Coulomb off-mode levels [dB] at a twin run's condition: same velocity and roughness
    (5 %), interpolated linearly in log load between the bracketing swept loads; None outside the sweep."""
    same = sorted((p for p in points if p.get("power_rest_coulomb") and p.get("power_rest")
                   and np.isclose(p.get("roughness_ra", m["roughness_ra"]), m["roughness_ra"], rtol=0.05)
                   and np.isclose(p.get("sliding_velocity", m["sliding_velocity"]), m["sliding_velocity"], rtol=0.05)),
                  key=lambda p: p["normal_load"])
    loads = np.log([p["normal_load"] for p in same])
    if len(same) < 2 or not loads[0] <= np.log(m["normal_load"]) <= loads[-1]:
        return None
    x = np.log(m["normal_load"])
    return {"coulomb_rest_db": float(np.interp(x, loads, [_db(p["power_rest_coulomb"]) for p in same])),
            "law_rest_db": float(np.interp(x, loads, [_db(p["power_rest"]) for p in same])),
            "study_loads": [float(np.exp(loads[0])), float(np.exp(loads[-1]))]}


def _db(x):
    return float(10 * np.log10(x)) if x and x > 0 else None


def _peaks_follow_load(points, reference) -> dict:
    """The dominant peak of the lightest and the heaviest load against the reference sets: relative distance to
    the nearest uncoupled and coupled frequency (the acceptance: within 5 % of the uncoupled at the lightest, of
    the coupled at the heaviest)."""
    pts = sorted((p for p in points if p.get("peak_frequencies")), key=lambda p: p["normal_load"])
    if not pts:
        return {}

    def dist(f, ref):
        r = np.asarray(ref, float)
        return float(np.min(np.abs(f - r) / r))

    out = {}
    for name, group in (("lightest", [p for p in pts if p["normal_load"] == pts[0]["normal_load"]]),
                        ("heaviest", [p for p in pts if p["normal_load"] == pts[-1]["normal_load"]])):
        out[name] = [{**{k: p[k] for k in p if k in AXES}, "dominant_peak": p["peak_frequencies"][0],
                      "to_uncoupled": dist(p["peak_frequencies"][0], reference["uncoupled"]),
                      "to_coupled": dist(p["peak_frequencies"][0], reference["coupled"]),
                      "coupling": p.get("coupling")} for p in group]
    out["moves_from_uncoupled_to_coupled"] = bool(
        all(r["to_uncoupled"] <= 0.05 for r in out["lightest"]) and all(r["to_coupled"] <= 0.05 for r in out["heaviest"]))
    return out


def peak_figure(summary: dict) -> str:
    """Peak frequencies against the normal load over the two reference sets (a PNG data URI): each point's peaks,
    the strongest largest, coloured by roughness; the uncoupled frequencies dashed, the coupled solid."""
    import matplotlib.ticker


    ref = summary["reference_frequencies"]
    pts = [p for p in summary["points"] if p.get("peak_frequencies")]
    top = 1.1 * max(max(f for p in pts for f in p["peak_frequencies"]), 1.0)
    fig, ax = new_figure(7.5, 4.5)
    for f in ref["uncoupled"]:
        if f <= top:
            ax.axhline(f / 1e3, color="C0", ls="--", lw=0.8)
    for f in ref["coupled"]:
        if f <= top:
            ax.axhline(f / 1e3, color="C3", ls="-", lw=0.8)
    levels = sorted({p.get("roughness_ra") for p in pts}, key=lambda x: -1 if x is None else x)
    for p in pts:
        c = f"C{2 + levels.index(p.get('roughness_ra')) % 6}"
        for rank, f in enumerate(p["peak_frequencies"]):
            ax.plot(p["normal_load"], f / 1e3, "o", color=c, ms=max(9 - 1.6 * rank, 3), alpha=0.8, mec="k", mew=0.3)
    for k, lv in enumerate(levels):
        ax.plot([], [], "o", color=f"C{2 + k % 6}", label="PSD peaks" + ("" if lv is None else f", Ra {lv * 1e6:g} um"))
    ax.plot([], [], "--", color="C0", label="uncoupled beams")
    ax.plot([], [], "-", color="C3", label="coupled system")
    t = summary.get("transition_load") or {}
    if t.get("value"):
        ax.axvline(t["value"], color="k", lw=0.8, ls=":", label=f"transition {t['value']:.3g} N")
    ax.set_xscale("log")
    ax.xaxis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda x, _: f"{x:g}"))  # 0.01, not 0.0
    ax.set_ylim(0, top / 1e3)
    ax.set_xlabel("normal load [N]")
    ax.set_ylabel("frequency [kHz]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    return figure_data_uri(fig)


def study_surfaces(cfg: dict, roughness_levels, source=None) -> dict:
    """``{repr(Ra): GW parameters}`` [SI] of each roughness level, each with its ``source``.

    With ``cfg["profile"]`` (a measured profile, relative to the study file ``source``): its
    :func:`fivid.surface.contact_law.gw_parameters` after a least-squares line, for every level (none or one).
    Otherwise a Gaussian profile of ``Rq = sqrt(pi/2) Ra`` (SYNTHETIC: :func:`fivid.surface.gaussian_random_profile`,
    Gaussian ACF of ``correlation_length``, ``profile_length`` every ``profile_step``, ``profile_seed``).
    """
    from pathlib import Path

    levels = [] if roughness_levels is None else [float(r) for r in np.unique(roughness_levels)]
    out = {}
    if cfg.get("profile"):
        base = Path(source).parent if source else Path(".")
        path = base / cfg["profile"]
        if len(levels) > 1:
            raise ConfigError("points.weak_strong.profile gives one measured surface: sweep no more than one "
                              f"roughness_ra (got {levels})", key="points.weak_strong.profile")
        ev = evaluate_profile(read_profile(path))
        gw = gw_parameters(ev.roughness, float(ev.settings["step"]))
        gw["source"] = f"measured profile {path.name}, spectral moments (McCool 1986)"
        return {repr(levels[0] if levels else float(ev.parameters["Ra"])): gw}
    for ra in levels:
        prof = gaussian_random_profile(RQ_PER_RA * ra, cfg["correlation_length"], cfg["profile_length"],
                                       cfg["profile_step"], seed=cfg["profile_seed"])
        gw = gw_parameters(prof.values, cfg["profile_step"])
        gw["source"] = (f"SYNTHETIC profile ({prof.attrs['generator']}: {prof.attrs['parameters']}, seed "
                        f"{cfg['profile_seed']}), spectral moments (McCool 1986)")
        out[repr(ra)] = gw
    return out


def agreement(points) -> dict:
    """Where the response label and kappa's (``coupling_modal`` >= 0.5: strong) agree: counts and the points
    (their conditions) where they do not."""
    both = [p for p in points if p.get("coupling") in ("weak", "strong") and p.get("coupling_modal") is not None]
    disagree = [{k: v for k, v in p.items() if k in AXES} | {"coupling": p["coupling"],
                                                             "coupling_modal": p["coupling_modal"]}
                for p in both if (p["coupling_modal"] >= WEAK_STRONG_THRESHOLD) != (p["coupling"] == "strong")]
    return {"n_points": len(both), "n_agree": len(both) - len(disagree), "disagree": disagree}


def transitions(points, *, key: str = "coupling_response") -> dict:
    """``transition_load`` (the first group's, see :func:`_transition_load`) and, when other conditions vary,
    ``transition_loads``: one per combination of them (the contact's compliance follows roughness, say)."""
    transition = _transition_load(points, key)
    if transition is None:
        return {}
    out = {"transition_load": transition}
    others = sorted({k for p in points for k in p if k in AXES and k not in ("normal_load", "seed")
                     and len({q.get(k) for q in points}) > 1})
    if others:
        groups = {}
        for p in points:
            groups.setdefault(tuple(p.get(k) for k in others), []).append(p)
        out["transition_loads"] = [{**dict(zip(others, group)), **(_transition_load(grp, key) or {})}
                                   for group, grp in groups.items()]
    return out


_CRITERIA = {"coupling_response": "response: power-weighted PSD peak position between the uncoupled (0) and "
                                  "coupled (1) frequencies >= 0.5",
             "coupling_modal": "modal: kappa of the preloaded modes >= 0.5"}
_LABELS = {"coupling_response": "response coupling", "coupling_modal": "coupling indicator κ"}


def _transition_load(points, key: str = "coupling_response") -> dict | None:
    """Where ``key`` (``coupling_response`` or kappa's ``coupling_modal``) first crosses 0.5 along the load.

    ``{"value" [N], "bracket": [lo, hi] [N], "criterion", "threshold"}``: interpolated linearly in log load between
    the two swept loads that bracket the crossing (other axes: the first point of each load, in sweep order).
    None without a load sweep or the key; ``value`` null when it stays on one side over the swept loads.
    """
    by_load = {}
    for p in points:
        if "normal_load" in p and p.get(key) is not None and np.isfinite(p[key]):
            by_load.setdefault(p["normal_load"], p[key])
    if len(by_load) < 2:
        return None
    loads = np.array(sorted(by_load))
    kappa = np.array([by_load[f] for f in loads])
    above = kappa >= WEAK_STRONG_THRESHOLD
    head = {"criterion": _CRITERIA[key], "criterion_label": _LABELS[key], "threshold": WEAK_STRONG_THRESHOLD}
    k = np.flatnonzero(~above[:-1] & above[1:])
    if k.size == 0:
        return {"value": None, "bracket": None, **head,
                "note": "strong at every swept load" if above.all() else "weak at every swept load"
                if not above.any() else "it does not rise through the threshold"}
    i = int(k[0])
    w = (WEAK_STRONG_THRESHOLD - kappa[i]) / (kappa[i + 1] - kappa[i])
    value = float(np.exp(np.log(loads[i]) + w * (np.log(loads[i + 1]) - np.log(loads[i]))))
    return {"value": value, "bracket": [float(loads[i]), float(loads[i + 1])], **head}


#: the registered instance
KIND = WeakStrong()
