"""The ring kind (``kind: ring``, seed 002): a ring's instability regimes over mu -- transients classified as
stable, mode coupling or stick-slip, each beside the study-level CEA at the same mu (critical mu, the coalescing
doublet, the CEA's growth rate and frequency) -- and, mode by mode, the transient against the CEA (the paper's
Fig. 5) with the contact states along the bore (Fig. 8).

Linearisation: the ring kind's CEA (study level and per point) is the prestressed one (``prestress=True``:
:mod:`fivid.fe.prestress`), as the paper's ("a prestressing static analysis ... then the prestressed CEA").

Per transient point, from probes at every contact (bore) node -- two sensors each, along the rigid circle's
radius and its counter-clockwise tangent, added after the model's own sensors (the response stays the first):

``mac_with_cea``
    MAC between the CEA's most unstable mode at the point's mu (:func:`fivid.fe.cea.cea_mode_shapes`, at the
    probes: radial and tangential components) and the transient's velocity field at the probes during growth.
    The velocity field is real; the CEA mode complex (a travelling/standing mix): the field's complex amplitude at
    its dominant frequency ``ods_frequency`` (Hann-weighted DFT of each probe's velocity over the growth window:
    the analytic signal's phasor at that frequency) is compared with the complex MAC ``|phi^H v|^2 /
    (|phi|^2 |v|^2)``, which takes the best phase (and scale) automatically. Growth window: the 1 ms before
    ``onset_time`` (10 periods at 10 kHz); without an onset (stable, stick-slip) the record's last 1 ms.
``best_cea_mac``, ``best_cea_frequency``, ``best_cea_growth_rate``
    Which CEA mode the transient grows: the largest MAC of the same phasor with any mode unstable at the point's
    mu, and that mode's frequency and real part (several pairs may grow at nearly the same rate; the nonlinear
    transient -- partial stick during growth, its start from the preload's ringing -- need not pick the fastest).
``contact_state(map_time, bore_angle)``
    0 stick, 1 slip, 2 open at each bore node over the steady part (at most ``MAP_SAMPLES`` times): open where
    the node's radial displacement exceeds, by more than ``OPEN_GAP``, the smallest one around the bore (rigid
    law: the closed nodes' common radius, the rigid core's) or the core's radial expansion (compliant law: the
    closed nodes penetrate the core, :func:`fivid.fe.static.resolve_expansions`); stick where its tangential velocity is within ``STICK_SPEED`` of the
    core's surface speed; else slip.
``vibration_to_sliding_speed``
    The bore's tangential vibration velocity amplitude in the last quarter (median over the nodes) over the core's
    surface speed: near 1 when the limit cycle is bounded by local stick within each cycle (the vibration speed
    catches up with the sliding speed), which sets the limit-cycle level to about ``2 pi f V``.
``limit_cycle_peak``
    The response's (first sensor's) largest excursion from its mean in the last quarter [m s-2]: the paper's
    "amplitude of vibration" of its Fig. 9 (a time signal's envelope, not an RMS).
``regime`` (seed 002's stick-slip), ``regime_transient``, ``harmonic_share``, ``sustained_sticks``, ``longest_stick_periods``
    The regime by the paper's own stick-slip marks (:func:`fivid.study.analysis.zone_stick_slip`, on the second
    half of the response and of every bore node's stick state at the full sample rate), the envelope analysis's
    label it replaces, and the marks' measures.
``ods_shape_*``, ``cea_shape_*``, ``velocity_snapshot``
    The two shapes (phase-aligned, unit largest component) and four radial-velocity snapshots a quarter period
    apart at the end of the growth window, for the report's figures.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import ConfigError
from fivid.fe.cea import Linearisation, cea_mode_shapes, complex_eigenvalue_analysis
from fivid.fe.modal import modal_analysis
from fivid.fe.static import resolve_expansions
from fivid.report.html import figure_data_uri, table
from fivid.study.analysis import zone_stick_slip
from fivid.study.kinds.sweep import FeSweep
from fivid.study.tasks import TRANSIENT_KEYS, fe_point, refined_model

__all__ = ["RingRegimes", "KIND", "bore_probes", "MAP_SAMPLES", "OPEN_GAP", "STICK_SPEED", "COUNT_BELOW_HZ"]

#: time columns of a contact-state map
MAP_SAMPLES = 400
#: radial gap above the core's radius from which a bore node is open [m] (the rigid law closes to ~1e-13 m)
OPEN_GAP = 1e-9
#: a bore node sticks while its tangential velocity is within this share of the core's surface speed
STICK_SPEED = 0.05
#: the frequency below which the preloaded ring's eigenvalues are counted (seed 002, Fig. 2) [Hz]
COUNT_BELOW_HZ = 15e3
_WINDOW = 1e-3  # growth window [s]


def bore_probes(model) -> list[dict]:
    """Sensor entries (model-config form) at every slave node of the model's first contact, whose master is a
    rigid circle: ``bore_r###`` along the radius, ``bore_t###`` along the counter-clockwise tangent."""
    c = model.contacts[0]
    if c.rigid is None or c.rigid.kind != "circle":
        raise ConfigError("the ring kind probes the bore of a rigid circle contact: the model's first contact "
                          f"{c.name!r} has no rigid circle master", key="contacts[0].rigid")
    out = []
    for k, n in enumerate(c.slave_nodes):
        x, y = model.coords[n]
        th = np.arctan2(y - c.rigid.point[1], x - c.rigid.point[0])
        at = [f"{float(x)!r} m", f"{float(y)!r} m"]
        out.append({"name": f"bore_r{k:03d}", "body": c.slave_block, "at": at,
                    "direction": [float(np.cos(th)), float(np.sin(th))]})
        out.append({"name": f"bore_t{k:03d}", "body": c.slave_block, "at": at,
                    "direction": [float(-np.sin(th)), float(np.cos(th))]})
    return out


def _window(t, data) -> np.ndarray:
    onset = float(data["onset_time"][1]) if "onset_time" in data else float("nan")
    end = onset if np.isfinite(onset) else t[-1]
    return (t >= end - _WINDOW) & (t <= end)


def _phasors(v, fs: float, lo: float = 1e3, hi: float = 25e3):
    """Dominant frequency of the (time, probe) field ``v`` (Hann, zero-padded x8 DFT, summed power in [lo, hi])
    and each probe's complex amplitude there."""
    w = np.hanning(v.shape[0])[:, None]
    n = 8 * v.shape[0]
    spec = np.fft.rfft((v - v.mean(axis=0)) * w, n=n, axis=0)
    f = np.fft.rfftfreq(n, 1.0 / fs)
    band = (f >= lo) & (f <= min(hi, 0.45 * fs))
    k = np.flatnonzero(band)[np.argmax(np.sum(np.abs(spec[band]) ** 2, axis=1))]
    return float(f[k]), spec[k]


def _complex_mac(phi, v) -> float:
    """Complex MAC ``|phi^H v|^2 / (|phi|^2 |v|^2)`` [1] of a (complex) mode shape and a field phasor: 1 when they
    are the same shape whatever the complex scale (phase) between them."""
    return float(abs(np.vdot(phi, v)) ** 2 / np.real(np.vdot(phi, phi) * np.vdot(v, v)))


def _bore_analysis(model, run, data, coords, conditions, *, prestress: bool = True) -> None:
    """The per-point variables of the module docstring, into ``data``/``coords``."""
    c = model.contacts[0]
    names = list(run["sensor"].values)
    r_idx = [names.index(s) for s in names if s.startswith("bore_r")]
    t_idx = [names.index(s) for s in names if s.startswith("bore_t")]
    t = run["time"].values
    fs = 1.0 / float(np.median(np.diff(t)))
    vel = run["sensor_velocity"].values
    disp = run["sensor_displacement"].values
    xy = model.coords[c.slave_nodes] - c.rigid.point
    angle = np.degrees(np.arctan2(xy[:, 1], xy[:, 0])) % 360.0
    coords["bore_angle"] = ("bore_angle", angle, {"units": "degree", "long_name": "angle of the bore node"})
    coords["component"] = ("component", np.array(["radial", "tangential"], dtype=object))
    # the regime by seed 002's own stick-slip marks (fivid.study.analysis.zone_stick_slip), from every bore node's
    # state at the full sample rate over the record's second half (the map below is subsampled)
    speed = abs(c.rigid.angular_velocity * c.rigid.radius)
    stuck = np.abs(vel[:, t_idx] - c.rigid.angular_velocity * c.rigid.radius) <= STICK_SPEED * speed
    _paper_regime(run, stuck, fs, data)
    # contact states over the steady part
    step = max(1, t.size // MAP_SAMPLES)
    sel = slice(0, step * (t.size // step), step)
    ur = disp[sel][:, r_idx]
    state = np.where(stuck[sel], 0, 1)  # the map's states: the stick test above, subsampled
    if c.law is not None and c.law.is_penalty:  # compliant: closed while inside the expanded core (d > 0)
        gap = ur - resolve_expansions(model).contacts[0].rigid.expansion
    else:  # rigid: the closed nodes share the cylinder's radius
        gap = ur - ur.min(axis=1, keepdims=True)
    state = np.where(gap > OPEN_GAP, 2, state).astype(np.int8)
    coords["map_time"] = ("map_time", t[sel] - t[0], {"units": "s", "long_name": "time since the steady part began"})
    data["contact_state"] = (("map_time", "bore_angle"), state, {
        "long_name": "contact state of the bore node", "flag_values": "0 1 2", "flag_meanings": "stick slip open"})
    # what bounds the limit cycle: the bore's tangential vibration speed against the core's surface speed (once it
    # reaches it, the nodes stick within each cycle and friction stops feeding the mode)
    tail = vel[3 * t.size // 4:][:, t_idx]
    amp = np.max(np.abs(tail - tail.mean(axis=0)), axis=0)
    acc = run["acceleration"]
    x = (acc.isel(sensor=0) if "sensor" in acc.dims else acc).values[3 * t.size // 4:]
    data["limit_cycle_peak"] = ((), float(np.max(np.abs(x - x.mean()))), {
        "units": "m s-2", "long_name": "largest excursion of the response from its mean, last quarter"})
    data["vibration_to_sliding_speed"] = ((), float(np.median(amp) / speed), {
        "units": "1", "long_name": "median over the bore of the tangential vibration velocity amplitude (last "
                                   "quarter) over the core's surface speed"})
    # transient velocity field during growth against the CEA's most unstable mode at this mu
    win = _window(t, data)
    field = np.concatenate([vel[win][:, r_idx], vel[win][:, t_idx]], axis=1)
    f_ods, ods = _phasors(field, fs)
    lam, shapes = cea_mode_shapes(model, float(conditions["mu"]), prestress=prestress)
    k = int(np.argmax(lam.real))
    rad = np.stack([np.cos(np.radians(angle)), np.sin(np.radians(angle))], axis=1)
    tan = np.stack([-rad[:, 1], rad[:, 0]], axis=1)
    sh = shapes[k][c.slave_nodes]
    phi = np.concatenate([np.sum(sh * rad, axis=1), np.sum(sh * tan, axis=1)])
    mac = _complex_mac(phi, ods)
    data["mac_with_cea"] = ((), float(mac), {"units": "1", "long_name": "MAC of the CEA's most unstable mode "
                                                "and the transient's bore velocity field during growth"})
    # which CEA mode the transient grows: the best MAC among the modes unstable at this mu (several pairs may grow
    # at nearly the same rate; the transient need not pick the fastest)
    macs = np.array([_complex_mac(np.concatenate([np.sum(shapes[j][c.slave_nodes] * rad, axis=1),
                                                  np.sum(shapes[j][c.slave_nodes] * tan, axis=1)]), ods)
                     if lam[j].real > 0 else -1.0 for j in range(lam.size)])
    best = int(np.argmax(macs))
    for key, value, unit, text in (
            ("best_cea_mac", max(float(macs[best]), 0.0), "1", "best MAC of the transient's bore velocity field "
                                                                "with a CEA mode unstable at this mu"),
            ("best_cea_frequency", float(lam[best].imag / (2 * np.pi)) if macs[best] >= 0 else np.nan, "Hz",
             "frequency of that best-matching unstable CEA mode"),
            ("best_cea_growth_rate", float(lam[best].real) if macs[best] >= 0 else np.nan, "s-1",
             "real part of that best-matching unstable CEA mode")):
        data[key] = ((), value, {"units": unit, "long_name": text})
    data["ods_frequency"] = ((), f_ods, {"units": "Hz", "long_name": "dominant frequency of the bore velocity "
                                                                      "field in the growth window"})
    data["cea_mode_frequency"] = ((), float(lam[k].imag / (2 * np.pi)), {
        "units": "Hz", "long_name": "frequency of the CEA's most unstable mode at this mu"})
    phi = phi * np.exp(-1j * np.angle(np.vdot(ods, phi)))  # phase-aligned with the field
    for name, z in (("ods", ods), ("cea", phi)):
        z = z / np.max(np.abs(z))
        for part, v in (("real", z.real), ("imag", z.imag)):
            data[f"{name}_shape_{part}"] = (("bore_angle", "component"), v.reshape(2, -1).T, {
                "units": "1", "long_name": f"{name.upper()} shape at the bore ({part} part), unit largest"})
    period = int(round(fs / f_ods)) if f_ods > 0 else 4
    idx = np.flatnonzero(win)[-1] - np.arange(4)[::-1] * max(1, period // 4)
    coords["snapshot"] = ("snapshot", t[idx] - t[0], {"units": "s", "long_name": "snapshot time"})
    data["velocity_snapshot"] = (("snapshot", "bore_angle"), vel[idx][:, r_idx], {
        "units": "m s-1", "long_name": "radial velocity of the bore nodes"})


def _paper_regime(run, stuck, fs: float, data: dict) -> None:
    """``regime`` by :func:`fivid.study.analysis.zone_stick_slip` on the second half of the response (first
    sensor) and of the bore's stick states; the envelope analysis's label stays as ``regime_transient``. Without
    the paper's stick-slip marks a point keeps the envelope's label, unless that label was the gross-stick rule's
    stick-slip: then mode coupling if its envelope grew significantly, else stable."""
    acc = run["acceleration"]
    x = (acc.isel(sensor=0) if "sensor" in acc.dims else acc).values
    h = slice(x.size // 2, x.size)
    out = zone_stick_slip(x[h], fs, stuck[h])
    old = str(data["regime"][1])
    rate, err = float(data["growth_rate"][1]), float(data["growth_rate_stderr"][1])
    regime = "stick_slip" if out["stick_slip"] else old if old != "stick_slip" else (
        "mode_coupling" if rate > 3.0 * err else "stable")
    data["regime_transient"] = ((), np.array(old, dtype=object), {
        "long_name": "regime by the envelope and gross-stick rules (fivid.study.analysis.analyse_transient)"})
    data["regime"] = ((), np.array(regime, dtype=object), {
        **data["regime"][2], "rule": "seed 002's stick-slip (p. 7, Fig. 8): fivid.study.analysis.zone_stick_slip"})
    for key, unit, text in (
            ("harmonic_share", "1", "share of the response power (second half) at its dominant frequency and "
                                    "harmonics"),
            ("sustained_sticks", "1", "bore stick runs longer than one period that release (second half)"),
            ("longest_stick_periods", "1", "longest bore stick run (second half), in periods of the dominant "
                                           "frequency")):
        data[key] = ((), int(out[key]) if key == "sustained_sticks" else float(out[key]),
                     {"units": unit, "long_name": text})


def _state_map_figure(ds, summary) -> str:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    pts = [i for i, p in enumerate(summary["points"]) if "mu" in p]
    fig, axes = plt.subplots(1, len(pts), figsize=(4 * len(pts), 3.6), layout="constrained", squeeze=False)
    cmap = ListedColormap(["#1f77b4", "#ffbf00", "#d62728"])
    for ax, i in zip(axes[0], pts):
        st = ds["contact_state"].isel(point=i)
        order = np.argsort(ds["bore_angle"].values)
        im = ax.pcolormesh(ds["map_time"].values * 1e3, ds["bore_angle"].values[order], st.values[:, order].T,
                           cmap=cmap, vmin=-0.5, vmax=2.5, shading="nearest")
        ax.set_title(f"μ = {summary['points'][i]['mu']:g}")
        ax.set_xlabel("time in steady part [ms]")
        ax.set_ylabel("bore angle [°]")
    cb = fig.colorbar(im, ax=axes[0, -1], ticks=[0, 1, 2])
    cb.ax.set_yticklabels(["stick", "slip", "open"])
    return figure_data_uri(fig)


def _shape_figure(ds, summary) -> str:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    pts = [i for i, p in enumerate(summary["points"]) if "mu" in p]
    fig, axes = plt.subplots(2, len(pts), figsize=(4 * len(pts), 5.5), layout="constrained", squeeze=False)
    order = np.argsort(ds["bore_angle"].values)
    ang = ds["bore_angle"].values[order]
    for j, i in enumerate(pts):
        p = summary["points"][i]
        ax = axes[0, j]
        for name, style in (("ods", "-"), ("cea", "--")):
            ax.plot(ang, ds[f"{name}_shape_real"].isel(point=i, component=0).values[order], style,
                    label=f"{'transient' if name == 'ods' else 'CEA'} (radial, real)")
        ax.set_title(f"μ = {p['mu']:g}: MAC {p.get('mac_with_cea', float('nan')):.2f}")
        ax.set_xlabel("bore angle [°]")
        ax.legend(fontsize=7)
        ax = axes[1, j]
        snaps = ds["velocity_snapshot"].isel(point=i).values
        for s in range(snaps.shape[0]):
            ax.plot(ang, 1e3 * snaps[s][order], lw=1, label=f"t{s}")
        ax.set_xlabel("bore angle [°]")
        ax.set_ylabel("radial velocity [mm/s]")
    return figure_data_uri(fig)


class RingRegimes(FeSweep):
    """Regimes of the transients against the CEA (:class:`fivid.study.kind.StudyKind`)."""

    name = "ring"
    description = "instability regimes over mu (seed 002): transients classified and compared with the CEA"
    point_keys = FeSweep.point_keys + (("mac_with_cea", "mac_with_cea"), ("ods_frequency", "ods_frequency"),
                                       ("cea_mode_frequency", "cea_mode_frequency"), ("amplitude", "amplitude"),
                                       ("best_cea_mac", "best_cea_mac"), ("best_cea_frequency", "best_cea_frequency"),
                                       ("best_cea_growth_rate", "best_cea_growth_rate"),
                                       ("vibration_to_sliding_speed", "vibration_to_sliding_speed"),
                                       ("regime_transient", "regime_transient"),
                                       ("limit_cycle_peak", "limit_cycle_peak"), ("harmonic_share", "harmonic_share"),
                                       ("sustained_sticks", "sustained_sticks"),
                                       ("longest_stick_periods", "longest_stick_periods"))

    def guess(self, data: dict) -> bool:
        """An FE study with a CEA and transients."""
        return bool(data.get("cea")) and "transient" in (data.get("points") or {})

    def evaluate(self, system: dict, tasks: dict, conditions: dict):
        """:func:`fivid.study.tasks.fe_point` with bore probes and the mode-by-mode comparison (module docstring)."""
        if "transient" not in tasks or "mu" not in conditions:
            return fe_point(system, tasks, conditions)
        return fe_point(system, tasks, conditions, probes=bore_probes, run_analysis=_bore_analysis)

    def cea(self, study, mu) -> dict:
        """The prestressed CEA (the paper's) on the swept mesh."""
        meshes = np.unique(study.axes.get("mesh", [1.0]))
        model = refined_model(study.model_path, float(meshes[0]))
        ds = complex_eigenvalue_analysis(model, mu, normal_load=study.cea.get("normal_load"), n_modes=30,
                                         linearisation=Linearisation(prestress=True))
        lam = ds["real_part"].transpose("mu", "mode").values + 2j * np.pi * ds["frequency"].transpose("mu", "mode").values
        p = ds["partner"].values
        return {"eigenvalues": lam, "critical_mu": ds["critical_mu"].values, "partner": np.where(p > 0, p - 1, -1)}

    def summarise(self, study, ds, points: list[dict]) -> dict:
        """``eigenvalues_below_15khz``: the preloaded, prestressed ring's modes below 15 kHz (seed 002, Fig. 2;
        :func:`fivid.fe.modal.modal_analysis` on the swept mesh), with their frequencies."""
        meshes = np.unique(study.axes.get("mesh", [1.0]))
        model = refined_model(study.model_path, float(meshes[0]))
        f = modal_analysis(model, 40, include_contact=True, normal_load=study.cea.get("normal_load") if study.cea
                           else None, prestress=True)["frequency"].values
        f = f[f > 1e-6 * f.max()]
        return {"eigenvalues_below_15khz": int(np.sum(f < COUNT_BELOW_HZ)),
                "modal_frequencies_hz": [float(x) for x in f[f < 1.2 * COUNT_BELOW_HZ]]}

    def report(self, page, ds, summary: dict) -> None:
        """Each transient's regime, frequency and MAC beside the CEA's at the same mu; contact-state maps and
        velocity snapshots."""
        rows = [[p.get("mu"), p.get("regime"), p.get("growth_rate"), p.get("cea_growth_rate"), p.get("frequency"),
                 p.get("cea_frequency"), p.get("ods_frequency"), p.get("mac_with_cea"), p.get("best_cea_frequency"),
                 p.get("best_cea_mac"), p.get("amplitude"), p.get("limit_cycle_peak"), p.get("vibration_to_sliding_speed"),
                 p.get("harmonic_share"), p.get("sustained_sticks"), p.get("regime_transient")]
                for p in summary["points"] if "regime" in p and "mu" in p]
        if not rows:
            return
        page.heading("Transients against the CEA", level=3)
        page.paragraph(f"Eigenvalues of the preloaded ring below 15 kHz: {summary.get('eigenvalues_below_15khz')} "
                       "(seed 002: 20).")
        page.raw(table(["mu", "regime", "growth rate [1/s]", "CEA growth rate [1/s]", "frequency [Hz]",
                        "CEA frequency [Hz]", "growth-window frequency [Hz]", "MAC with CEA",
                        "best-matching unstable CEA mode [Hz]", "its MAC",
                        "limit-cycle RMS [m/s²]", "limit-cycle peak [m/s²]", "vibration / sliding speed",
                        "harmonic share", "bore sticks > 1 period", "envelope rule's regime"], rows))
        page.paragraph("Regime: stick-slip by seed 002's marks (p. 7, Fig. 8): a stick zone that releases (a bore "
                       "node stuck longer than one period of the dominant vibration) and a response that is not "
                       "harmonic (harmonic share < 0.5); fivid.study.analysis.zone_stick_slip.")
        if "contact_state" in ds:
            page.figure(_state_map_figure(ds, summary), "Contact state along the bore (stick / slip / open) against "
                        "time, per μ (seed 002, Fig. 8).", "contact states")
        if "ods_shape_real" in ds:
            page.figure(_shape_figure(ds, summary), "Top: the transient's bore velocity field at its growth-window "
                        "frequency against the CEA's most unstable mode (phase-aligned; seed 002, Fig. 5). Bottom: "
                        "radial velocity snapshots a quarter period apart at the end of the growth window.",
                        "velocity field")


#: the registered instance
KIND = RingRegimes()
