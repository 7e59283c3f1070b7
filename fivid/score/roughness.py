"""What a rough-pair run tells about roughness noise (seed 003), over its steady part:

* ``vibration_level`` Lv [dB] = 20 log10(V_RMS / 1e-9 m s-1), V_RMS the RMS over time and back-face nodes of the
  normal velocity (each node's mean removed) -- seed 003's definition, over the whole record bandwidth (up to the
  output Nyquist frequency, 1 MHz at 2 MHz);
* ``band_vibration_level`` (:func:`band_vibration_level`): the same level restricted to :data:`LV_BAND`, 1-20 kHz,
  the audible band seed 003's roughness noise lives in (its own model carries nothing above a few hundred kHz).
  Measured on the 120 mm pair (Ra 20, Rsm/8 and /12): 67-75 % of V_RMS**2 lies in this band, < 1 % above
  200 kHz, and neither level converges with the surface resolution over a 1 ms window of 1-3 shocks
  (docs/roughness.md, "Where Lv's power lives");
* shocks (:func:`detect_shocks`): closing events of the contact, with rate [s-1] and mean impulse [N s];
* ``friction_power`` [W]: slope of ``friction_dissipation`` (least squares) over the steady part, mu Fn V on
  average (until 2026-11 called ``dissipated_power``: it is not seed 003's vibratory power);
* ``vibratory_power`` [W] (seed 003's Fig. 7, the vibratory power dissipated by the N shocks): slope of
  ``damping_dissipation`` over the steady part -- the power the blocks' structural damping dissipates, which in
  steady sliding is the power fed into vibration (stiffness-proportional damping does no work on the rigid
  sliding); ``shock_energy`` [J] = vibratory power / shock rate, the paper's ``P = n_c E``;
* ``impact_power`` [W]: slope of ``impact_dissipation`` (the kinetic energy the rigid contact removes at
  closing nodes);
* the friction coefficient the force transducer reads (:func:`friction_coefficient_statistics`);
* per landing of a bouncing slider (:func:`landing_transfer`): its normal impulse ``J`` [N s], the band energy the
  back face gains from it ``E`` [J] and the transfer ``E / J**2`` [J (N s)-2], the resolution-convergence yardstick
  that does not need a window of hundreds of landings (docs/roughness.md, "The per-landing transfer").
"""

from __future__ import annotations

import logging

import numpy as np

from fivid.errors import ConfigError
from fivid.signal.levels import VELOCITY_REFERENCE, bin_weights
from fivid.signal.steady import steady_part

__all__ = ["LV_REFERENCE", "LV_BAND", "SHOCK_MIN_CLOSING", "SHOCK_BASELINE", "vibration_level",
           "band_vibration_level", "subwindow_levels", "tip_following_speed", "detect_shocks",
           "friction_power", "vibratory_power", "impact_power", "dissipation_rate", "roughness_metrics",
           "friction_coefficient_statistics", "steady_record", "band_energy_envelope", "contact_episodes",
           "LANDING_FIT", "band_impulse", "landing_transfer"]

log = logging.getLogger(__name__)

#: seed 003's velocity reference of the vibration level [m s-1] (ISO 1683's, :data:`fivid.signal.levels.VELOCITY_REFERENCE`)
LV_REFERENCE = VELOCITY_REFERENCE


def steady_record(ds, start=None):
    """The run from ``start`` [s], by default its steady part (:func:`fivid.signal.steady_part`)."""
    return steady_part(ds) if start is None else ds.sel(time=slice(float(start), None))


def vibration_level(ds, *, start=None, reference: float = LV_REFERENCE) -> tuple[float, float]:
    """(Lv [dB], V_RMS [m s-1]): RMS over the steady time and every sensor of ``sensor_velocity``, each sensor's
    mean removed; ``Lv = 20 log10(V_RMS / reference)`` (seed 003: reference 1e-9 m s-1, back-face nodes)."""
    v = np.asarray(steady_record(ds, start)["sensor_velocity"].values, float)
    v = v.reshape(v.shape[0], -1)
    v = v - v.mean(axis=0)
    vrms = float(np.sqrt(np.mean(v * v)))
    return (20.0 * np.log10(vrms / reference) if vrms > 0 else -np.inf), vrms


#: band of :func:`band_vibration_level` [Hz]: seed 003's subject is audible noise (upper edge 20 kHz); its
#: ~1 ms records resolve nothing below ~1 kHz (lower edge) -- docs/roughness.md, "The band of Lv"
LV_BAND = (1.0e3, 20.0e3)


def band_vibration_level(ds, band=LV_BAND, *, start=None, reference: float = LV_REFERENCE) -> tuple[float, float]:
    """(Lv_band [dB], V_band [m s-1]): the vibration level of :func:`vibration_level` restricted to ``band``.

    ``V_band**2`` is the mean over the back-face sensors of ``s_i * sum(P_i * w) / sum(P_i * df)``: the mean square
    ``s_i`` of sensor ``i``'s ``sensor_velocity`` over the steady record (``start`` [s] as in :func:`steady_record`;
    mean removed: every sample weighs the same, as in :func:`vibration_level` and seed 003's definition) times the
    band's share of its one-sided periodogram ``P_i`` (mean removed, periodic Hann taper), ``w`` the share of each
    bin's rectangle inside ``band`` times its width (:func:`fivid.signal.levels.bin_weights`). The taper weighs the
    record's middle most; taking only the band's *share* from it keeps a record that is quiet at one end (a
    slider landing in the window) from reading louder in the band than over all frequencies: ``V_band <=``
    V_RMS always. ``Lv_band = 20 log10(V_band / reference)``.

    Parameters
    ----------
    ds : xarray.Dataset
        A rough-pair run with ``sensor_velocity`` [m s-1] (``time`` x ``sensor``, or ``time``).
    band : (float, float)
        ``(f_lo, f_hi)`` [Hz], ``0 < 1 / (2 T) <= f_lo < f_hi <= fs / 2`` for a steady record of ``T`` [s]
        sampled at ``fs`` [Hz] (its first bin above 0 Hz is centred on ``1 / T``).
    start : float, optional
        Start of the steady record [s].
    reference : float
        Velocity reference [m s-1] (seed 003: 1e-9).

    Raises
    ------
    fivid.errors.ConfigError
        If the band is empty, reaches the 0 Hz bin of a record of this length, or passes the Nyquist frequency.
    """
    from scipy.signal import periodogram  # noqa: PLC0415 (scipy.signal: imported where used)

    part = steady_record(ds, start)
    t = np.asarray(part["time"].values, float)
    v = np.asarray(part["sensor_velocity"].values, float).reshape(t.size, -1)
    f_lo, f_hi = (float(b) for b in band)
    fs = 1.0 / float(np.median(np.diff(t))) if t.size > 1 else np.inf
    span = t.size / fs
    if not (0.0 < f_lo < f_hi <= fs / 2.0 * (1 + 1e-12)) or f_lo < 0.5 / span * (1 - 1e-9):
        raise ConfigError(f"Lv band [{f_lo:g}, {f_hi:g}] Hz for a steady record of {span * 1e3:.4g} ms at "
                          f"{fs:g} Hz: needs 1/(2T) = {0.5 / span:g} Hz <= f_lo < f_hi <= fs/2 = {fs / 2:g} Hz "
                          "(a longer record resolves a lower edge)", key="band")
    v = v - v.mean(axis=0)
    f, p = periodogram(v, fs=fs, window="hann", detrend=False, axis=0, scaling="density")
    total = p.sum(axis=0)
    share = np.divide(bin_weights(f, f_lo, f_hi) @ p, total * (f[1] - f[0]), out=np.zeros_like(total),
                      where=total > 0)
    power = float(np.mean(np.mean(v * v, axis=0) * share))
    vrms = float(np.sqrt(power))
    return (20.0 * np.log10(vrms / reference) if vrms > 0 else -np.inf), vrms


def subwindow_levels(ds, length: float, *, band=None, start=None, reference: float = LV_REFERENCE) -> dict:
    """Lv over successive sub-windows of ``length`` [s] of the steady record, and what their scatter says about
    the whole window's Lv: has the window settled, and how precise is its level.

    The record from ``start`` (as :func:`steady_record`) is cut into ``K = floor(N / n)`` sub-windows of
    ``n = round(length fs)`` samples (a trailing remainder is dropped); sub-window ``k``'s level is
    :func:`vibration_level` of it (``band`` None) or :func:`band_vibration_level` of it in ``band``, each sensor's
    mean removed per sub-window. From their mean squares ``s_k = (reference 10^(L_k / 20))^2``:
    ``level_of_mean = 10 log10(mean(s_k) / reference^2)`` (the whole window's level but for the per-sub-window
    mean removal) and its standard error ``standard_error_db = (10 / ln 10) std(s_k, ddof=1) / (sqrt(K) mean(s_k))``
    (first-order propagation of the sample mean's standard error), a fair estimate when the sub-windows are
    longer than the time over which the back face's mean square stays correlated (the band modes' ringing: a
    shock's energy decays with time constant ``1 / (2 zeta omega)``, ~0.4-0.9 ms in 4.5-20 kHz at 2 % and less,
    docs/roughness.md); shorter, correlated sub-windows make it an underestimate.

    Parameters
    ----------
    ds : xarray.Dataset
        A rough-pair run with ``sensor_velocity`` [m s-1] (``time`` x ``sensor``, or ``time``).
    length : float
        Sub-window length [s]; with ``band`` at least ``1 / (2 f_lo)`` (:func:`band_vibration_level`).
    band : (float, float), optional
        ``(f_lo, f_hi)`` [Hz] (e.g. :data:`LV_BAND`); None: all frequencies (seed 003's Lv).
    start : float, optional
        Start of the steady record [s].
    reference : float
        Velocity reference [m s-1] (seed 003: 1e-9).

    Returns
    -------
    dict
        ``start``, ``stop`` [s] (arrays, each sub-window's first and one-past-last sample time), ``level`` [dB]
        (array), ``mean_square`` [m2 s-2] (array), ``level_of_mean`` [dB], ``standard_error_db`` [dB] (NaN for one
        sub-window), ``count``.

    Raises
    ------
    fivid.errors.ConfigError
        If ``length`` is not positive or the record holds no whole sub-window (and as
        :func:`band_vibration_level` for a sub-window too short for ``band``).
    """
    part = steady_record(ds, start)
    t = np.asarray(part["time"].values, float)
    fs = 1.0 / float(np.median(np.diff(t))) if t.size > 1 else np.nan
    n = int(round(float(length) * fs)) if length > 0 and np.isfinite(fs) else 0
    count = t.size // n if n > 0 else 0
    if count < 1:
        raise ConfigError(f"sub-window length {length!r} s: needs 0 < length <= the steady record "
                          f"({t.size} samples at {fs:g} Hz)", key="length")
    levels, starts, stops = np.empty(count), np.empty(count), np.empty(count)
    for k in range(count):
        piece = part.isel(time=slice(k * n, (k + 1) * n))
        a = float(t[k * n])
        levels[k] = (vibration_level(piece, start=a, reference=reference) if band is None else
                     band_vibration_level(piece, band, start=a, reference=reference))[0]
        starts[k], stops[k] = a, a + n / fs
    ms = (reference * 10.0 ** (levels / 20.0)) ** 2
    mean = float(np.mean(ms))
    se = (10.0 / np.log(10.0)) * float(np.std(ms, ddof=1)) / (np.sqrt(count) * mean) if count > 1 and mean > 0 \
        else np.nan
    return {"start": starts, "stop": stops, "level": levels, "mean_square": ms,
            "level_of_mean": 10.0 * np.log10(mean / reference ** 2) if mean > 0 else -np.inf,
            "standard_error_db": se, "count": count}


def tip_following_speed(lower, upper, normal_load: float, mass: float, *, tip_quantile: float = 0.9) -> dict:
    """The sliding speed up to which a dead-loaded slider can stay seated while its supporting asperity pair
    passes tip over tip: ``V* = sqrt(a / kappa)``, ``a = normal_load / mass`` the load's acceleration and
    ``kappa`` the gap's curvature at the passage, the two tips' curvatures added. Faster, ``V^2 kappa > a``: the
    slider leaves the tips and flies (its bouncing is physics, not a start-up artefact; docs/roughness.md,
    "Lv convergence: the slider's bouncing is physical").

    A tip is a local maximum of a profile whose height is above the profile's ``tip_quantile`` quantile; its
    curvature ``-z''`` is the central second difference (relative error ``(k h)^2 / 12`` for a wavenumber ``k``
    sampled at ``h``); ``kappa`` is the sum of the two profiles' median tip curvatures.

    Parameters
    ----------
    lower, upper : xarray.DataArray
        Height profiles [m] over a uniformly sampled ``x`` [m].
    normal_load : float
        Dead load [N].
    mass : float
        The slider's mass [kg].
    tip_quantile : float
        Height quantile above which a local maximum counts as a tip, in (0, 1).

    Returns
    -------
    dict
        ``following_speed`` [m s-1], ``load_acceleration`` [m s-2], ``tip_curvature`` [m-1] (lower, upper),
        ``rms_curvature`` [m-1] (lower, upper: the RMS of ``z''`` over each profile), ``gap_curvature`` [m-1]
        (the sum of the tips').
    """
    if not (normal_load > 0 and mass > 0 and 0 < tip_quantile < 1):
        raise ConfigError(f"tip_following_speed: needs normal_load > 0 N, mass > 0 kg and 0 < tip_quantile < 1; "
                          f"got {normal_load!r}, {mass!r}, {tip_quantile!r}", key="normal_load")
    rms, tips = [], []
    for prof in (lower, upper):
        x = np.asarray(prof["x"].values, float)
        z = np.asarray(prof.values, float)
        h = float(np.median(np.diff(x)))
        zpp = (z[2:] - 2.0 * z[1:-1] + z[:-2]) / h ** 2
        mid = z[1:-1]
        tip = (mid > z[:-2]) & (mid >= z[2:]) & (mid > np.quantile(z, tip_quantile))
        rms.append(float(np.sqrt(np.mean(zpp ** 2))))
        tips.append(float(np.median(-zpp[tip])) if np.any(tip) else np.nan)
    kappa = tips[0] + tips[1]
    a = float(normal_load) / float(mass)
    return {"following_speed": float(np.sqrt(a / kappa)) if kappa > 0 else np.inf, "load_acceleration": a,
            "tip_curvature": tuple(tips), "rms_curvature": tuple(rms), "gap_curvature": kappa}


#: shock detector defaults: closed-node rise and baseline window (docs/roughness.md)
SHOCK_MIN_CLOSING = 0.1
SHOCK_BASELINE = 0.5e-3


def detect_shocks(time, contact_normal_force, open_fraction, n_slave: int, *, min_closing: float = SHOCK_MIN_CLOSING,
                  baseline_time: float = SHOCK_BASELINE) -> dict:
    """Closing events of a node-to-segment contact (shocks between asperities) from its per-sample records.

    A shock is a run of consecutive samples over which the number of closed slave nodes,
    ``n_closed = (1 - open_fraction) n_slave``, rises by at least ``min_closing`` nodes in total (the records
    are averages over each output period, so one node closing mid-period shows as two partial rises). Its
    impulse is the excess of the contact normal force over its running median (window ``baseline_time`` [s])
    summed over the run and the sample after it, times the sample period [N s].

    Returns
    -------
    dict
        ``count``, ``rate`` [s-1] (count / record duration), ``mean_impulse`` [N s] (NaN without shocks),
        ``start_times`` [s] and ``impulses`` [N s] (arrays), and the thresholds used.
    """
    from scipy.ndimage import median_filter  # noqa: PLC0415 (scipy.ndimage: imported where used)

    t = np.asarray(time, float)
    fc = np.asarray(contact_normal_force, float)
    closed = (1.0 - np.asarray(open_fraction, float)) * int(n_slave)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    w = max(3, int(round(baseline_time / dt)) | 1) if dt > 0 else 3
    excess = fc - median_filter(fc, size=w, mode="nearest")
    d = np.diff(closed)
    starts, impulses = [], []
    i = 0
    while i < d.size:
        if d[i] <= 0:
            i += 1
            continue
        j = i
        while j + 1 < d.size and d[j + 1] > 0:
            j += 1
        if closed[j + 1] - closed[i] >= min_closing:
            starts.append(t[i + 1])
            impulses.append(float(np.sum(np.clip(excess[i + 1:j + 3], 0.0, None)) * dt))
        i = j + 1
    duration = t[-1] - t[0] + dt if t.size else 0.0
    imp = np.array(impulses)
    return {"count": len(starts), "rate": len(starts) / duration if duration > 0 else np.nan,
            "mean_impulse": float(imp.mean()) if imp.size else np.nan, "start_times": np.array(starts),
            "impulses": imp, "min_closing": float(min_closing), "baseline_time": float(baseline_time)}


def dissipation_rate(ds, name: str, *, start=None) -> float:
    """Mean rate [W] of the cumulative energy record ``name`` [J]: least-squares slope over the steady part."""
    part = steady_record(ds, start)
    t, e = part["time"].values, part[name].values
    return float(np.polyfit(t - t[0], e, 1)[0]) if t.size > 1 else np.nan


def friction_power(ds, *, start=None) -> float:
    """Mean friction power [W]: slope of ``friction_dissipation`` over the steady part (:func:`dissipation_rate`)."""
    return dissipation_rate(ds, "friction_dissipation", start=start)


def vibratory_power(ds, *, start=None) -> float:
    """Seed 003's vibratory power [W]: slope of ``damping_dissipation`` over the steady part, the power the
    structural damping dissipates, equal in steady sliding to the vibratory power the shocks inject."""
    return dissipation_rate(ds, "damping_dissipation", start=start)


def impact_power(ds, *, start=None) -> float:
    """Mean impact dissipation [W]: slope of ``impact_dissipation`` over the steady part."""
    return dissipation_rate(ds, "impact_dissipation", start=start)


def roughness_metrics(ds, n_slave: int, *, start=None, **shock_options) -> dict:
    """Lv and V_RMS (full band and :data:`LV_BAND`), shocks (rate, impulse, vibratory energy per shock), friction,
    vibratory and impact power and mean forces of a rough-pair run (steady part)."""
    part = steady_record(ds, start)
    lv, vrms = vibration_level(ds, start=start)
    try:
        lv_band, vrms_band = band_vibration_level(ds, start=start)
    except ConfigError as exc:  # a record shorter than 0.5 ms resolves no 1 kHz edge: no band level, not no point
        log.warning("no band vibration level: %s", exc)
        lv_band, vrms_band = np.nan, np.nan
    sh = detect_shocks(part["time"].values, part["contact_normal_force"].values, part["open_fraction"].values,
                       n_slave, **shock_options)
    pv = vibratory_power(ds, start=start)
    return {"vibration_level": lv, "velocity_rms": vrms, "band_vibration_level": lv_band,
            "band_velocity_rms": vrms_band, "shock_rate": sh["rate"], "shock_impulse": sh["mean_impulse"],
            "shock_count": sh["count"], "friction_power": friction_power(ds, start=start), "vibratory_power": pv,
            "shock_energy": pv / sh["rate"] if sh["rate"] > 0 else np.nan,
            "impact_power": impact_power(ds, start=start),
            "mean_normal_force": float(np.mean(part["contact_normal_force"].values)),
            "mean_friction_force": float(np.mean(part["friction_force"].values)),
            "open_fraction": float(np.mean(part["open_fraction"].values)), "shocks": sh,
            **friction_coefficient_statistics(ds, start=start)}


def friction_coefficient_statistics(ds, *, start=None) -> dict:
    """mu(t) = |friction_force(t)| / mean normal force over the steady part: the transducer's force over the
    dead load as the interface carries it (the mean of ``contact_normal_force``; momentary losses of contact,
    frequent on rough surfaces at a few cm/s, would make a pointwise Ft/Fn diverge). ``friction_coefficient``:
    its mean; ``friction_coefficient_rms``: RMS of mu - mean (the perturbation's amplitude over all frequencies
    up to the output Nyquist). The same mu(t) as :func:`identification_run` hands to ``fivid identify``. NaN
    without a transducer (a zero friction_force)."""
    part = steady_record(ds, start)
    ft = np.abs(np.asarray(part["friction_force"].values, float))
    fn = float(np.mean(np.asarray(part["contact_normal_force"].values, float))) if part.sizes["time"] else 0.0
    if not np.any(ft) or not fn > 0:
        return {"friction_coefficient": np.nan, "friction_coefficient_rms": np.nan}
    mu = ft / fn
    return {"friction_coefficient": float(np.mean(mu)), "friction_coefficient_rms": float(np.std(mu))}


def band_energy_envelope(ds, mass: float, band=LV_BAND, *, order: int = 2) -> np.ndarray:
    """Band vibratory energy envelope of the back face [J] per sample: ``e(t) = mass / 2 * mean_s |a_s(t)|**2``.

    ``a_s`` is the analytic signal (:func:`scipy.signal.hilbert`) of sensor ``s``'s ``sensor_velocity`` after a
    zero-phase Butterworth band-pass on ``band`` (:func:`scipy.signal.sosfiltfilt`, ``order`` per edge, so no
    delay shifts a landing's jump; its response to an impulse falls under 2 % of its peak envelope 50 us away).
    For one mode of modal mass ``m`` ringing at modal velocity amplitude ``A`` with sensor shapes of mean square 1,
    ``|a_s|**2`` averages to ``A**2`` and ``e = m A**2 / 2`` with ``mass = m``: the mode's energy. For the rough
    pair, ``mass`` is the lower block's (its back face standing for it): ``e`` is then the energy the block would
    hold if all of it rang at the back face's band velocity -- a proxy whose changes between meshes are the
    back face's, the mass cancelling in any ratio.
    """
    from scipy.signal import butter, hilbert, sosfiltfilt  # noqa: PLC0415 (scipy.signal: imported where used)

    t = np.asarray(ds["time"].values, float)
    v = np.asarray(ds["sensor_velocity"].values, float).reshape(t.size, -1)
    fs = 1.0 / float(np.median(np.diff(t)))
    f_lo, f_hi = (float(b) for b in band)
    if not (mass > 0 and 0.0 < f_lo < f_hi < fs / 2.0):
        raise ConfigError(f"band_energy_envelope: needs mass > 0 kg and 0 < f_lo < f_hi < fs/2 = {fs / 2:g} Hz; got "
                          f"mass {mass!r}, band [{f_lo:g}, {f_hi:g}] Hz", key="band")
    sos = butter(int(order), [f_lo, f_hi], btype="bandpass", fs=fs, output="sos")
    a = hilbert(sosfiltfilt(sos, v - v.mean(axis=0), axis=0), axis=0)
    return 0.5 * float(mass) * np.mean(np.abs(a) ** 2, axis=1)


def contact_episodes(time, contact_normal_force, *, min_flight: float = 50e-6, threshold: float = 0.0) -> dict:
    """Landings of a bouncing slider: maximal runs of samples with ``contact_normal_force > threshold`` [N], runs
    separated by less than ``min_flight`` [s] of no force joined into one episode.

    Returns
    -------
    dict of arrays, one entry per episode
        ``start``, ``stop`` [s] (first sample with force, one sample past the last), ``centroid`` [s] (the
        force-weighted mean time), ``impulse`` [N s] (force summed times the sample period); ``first``,
        ``last``: the sample indices of ``start`` and the last sample with force.
    """
    t = np.asarray(time, float)
    f = np.asarray(contact_normal_force, float)
    dt = float(np.median(np.diff(t)))
    on = np.flatnonzero(f > threshold)
    if on.size == 0:
        empty = np.empty(0)
        return {"start": empty, "stop": empty, "centroid": empty, "impulse": empty, "first": empty.astype(int),
                "last": empty.astype(int)}
    cut = np.flatnonzero(np.diff(on) * dt > min_flight + 0.5 * dt)
    firsts = np.concatenate([[on[0]], on[cut + 1]])
    lasts = np.concatenate([on[cut], [on[-1]]])
    imp = np.array([f[i:j + 1].sum() * dt for i, j in zip(firsts, lasts)])
    cen = np.array([np.sum(t[i:j + 1] * f[i:j + 1]) / np.sum(f[i:j + 1]) for i, j in zip(firsts, lasts)])
    return {"start": t[firsts], "stop": t[lasts] + dt, "centroid": cen, "impulse": imp, "first": firsts,
            "last": lasts}


def band_impulse(force, dt: float, band=LV_BAND) -> float:
    """RMS over ``band`` [Hz] of the force pulse's Fourier transform ``|F(f)| = |sum_n F_n exp(-2 pi i f n dt)| dt``
    [N s]: ``sqrt(int_band |F|**2 df / (f_hi - f_lo))`` (zero-padded FFT, bins of at most ``f_lo / 8``, the
    integral by :func:`fivid.signal.levels.bin_weights`). A pulse short against ``1 / f_hi`` has ``|F| = J`` (its
    impulse) over the band; a longer one puts less than ``J`` into the band, which is what a band mode feels
    (``E = |F(f_k)|**2 phi**2 / (2 m_k)`` for a mode ``k`` of modal mass ``m_k`` and shape ``phi`` at the force)."""
    f_lo, f_hi = (float(b) for b in band)
    x = np.asarray(force, float)
    n = int(2 ** np.ceil(np.log2(max(x.size, 8.0 / (f_lo * dt)))))
    spec = np.abs(np.fft.rfft(x, n)) * dt
    freq = np.fft.rfftfreq(n, dt)
    return float(np.sqrt(bin_weights(freq, f_lo, f_hi) @ spec ** 2 / (f_hi - f_lo)))


def _decay_fit_at(t, e, lo: float, hi: float, at: float, min_fit: float) -> float:
    """``exp`` of the least-squares line through ``ln e`` over ``lo <= t < hi``, evaluated at ``at``; a rising
    line is replaced by the window's mean log (no energy enters the back face in flight: a rise there is the band
    filter's spread of a landing or a beat between modes). NaN if the window is shorter than ``min_fit``, 0 if
    the envelope is 0 there."""
    sel = (t >= lo) & (t < hi)
    if hi - lo < min_fit * (1 - 1e-9) or np.count_nonzero(sel) < 2:
        return np.nan
    y = e[sel]
    if not np.any(y > 0):
        return 0.0
    x, ly = t[sel] - at, np.log(np.maximum(y, np.max(y) * 1e-300))
    slope, icpt = np.polyfit(x, ly, 1)
    return float(np.exp(icpt) if slope <= 0 else np.exp(np.mean(ly)))


#: :func:`landing_transfer`'s fit windows [s]: kept ``guard_before`` off the next landing (the zero-phase band filter
#: and the analytic signal spread a loud landing's onset back over ~0.2 ms: on the rough pair a landing 300x louder
#: than the ringing before it raises the envelope 0.25 ms ahead to 0.3 % and 0.1 ms ahead to 5 % of its level
#: after) and ``guard_after`` off the last contact (the filter's own ringing after a kick, at its band edges, beats
#: with the modes: on one kicked 5 kHz mode the transfer reads 1/(2m) within 1 % at 0.1 ms and 0.4 ms windows, and
#: 2-6 % low at 50 us and 0.2 ms); each up to ``fit_length``, at least ``min_fit`` long
LANDING_FIT = {"guard_before": 0.15e-3, "guard_after": 0.1e-3, "fit_length": 0.4e-3, "min_fit": 40e-6}


def landing_transfer(ds, mass: float, *, band=LV_BAND, start=None, min_flight=None, threshold: float = 0.0,
                     order: int = 2, **fit):
    """Per landing of a bouncing slider: normal impulse ``J``, band energy gained by the back face ``E`` and the
    transfer ``E / J**2`` -- deterministic given the landing, unlike a window's Lv, which is the ringing of its
    last few landings (docs/roughness.md, "The per-landing transfer").

    Landings are :func:`contact_episodes` of ``contact_normal_force`` (flights of at least ``min_flight``)
    starting at or after ``start`` [s]. ``E`` is the jump of :func:`band_energy_envelope` across the landing,
    free of the ringing left by earlier ones: ``ln e(t)`` is fitted by a line (one exponential decay; a rising
    fit is replaced by the window's mean: no energy enters in flight) over the flight before the landing and over
    the flight after it -- windows of :data:`LANDING_FIT` (``guard_before`` off the landing's start,
    ``guard_after`` off the previous contact; ``guard_after`` off the landing's end, ``guard_before`` off the
    next) -- and both lines are evaluated at the landing's force centroid ``t_c``:
    ``E = e_after(t_c) - e_before(t_c)``: the ringing before counts with its own decay, the landing's energy with
    its decay since ``t_c``. For a single mode kicked while its velocity is zero, ``E = J**2 / (2 m)`` exactly;
    kicked at another phase, the cross term ``v J`` (``v`` the modal velocity at the kick) adds, zero on average
    over uniform phases -- on the rough pair many modes and sensors average it further, and what is left is
    per-landing scatter, not bias. The default ``min_flight`` is the shortest flight that leaves both windows
    ``min_fit`` (``guard_before + guard_after + min_fit``, 0.29 ms): landings closer than that are one episode,
    its impulse the sum.

    Parameters
    ----------
    ds : xarray.Dataset
        A rough-pair run: ``sensor_velocity`` [m s-1] (``time`` x ``sensor``), ``contact_normal_force`` [N].
    mass : float
        Mass [kg] of :func:`band_energy_envelope` (the lower block's, e.g. 74.9 g for 120 x 8 x 10 mm steel).
    band : (float, float)
        Band [Hz] (:data:`LV_BAND`).
    start : float, optional
        Landings starting before it [s] are not reported (e.g. the drive's ramp); the fits still see the record.
    min_flight : float, optional
        [s], as above; a landing whose flight before or after leaves less than ``min_fit`` for a window (shorter
        ``min_flight``) gets NaN.
    threshold : float
        Contact force [N] above which the slider touches.
    order : int
        Butterworth order per band edge.
    **fit
        Overrides of :data:`LANDING_FIT` [s].

    Returns
    -------
    xarray.Dataset
        Along ``landing``: ``start``, ``stop``, ``centroid`` [s], ``flight_before``, ``flight_after`` [s] (to the
        neighbouring landings or the record's ends), ``impulse`` [N s], ``energy_before``, ``energy_after``,
        ``energy`` [J], ``transfer`` [J (N s)-2] and ``transfer_db`` (``10 log10(transfer)``, re 1 J (N s)-2;
        NaN when ``energy <= 0`` or a fit is missing); ``band_impulse`` [N s] (:func:`band_impulse` of the
        episode's force), ``band_transfer`` = ``energy / band_impulse**2`` [J (N s)-2] and ``band_transfer_db``:
        the transfer freed of the pulse's length (a landing of 0.1-0.4 ms puts less than ``J`` into the band).
    """
    import xarray as xr  # noqa: PLC0415 (xarray: imported where used, `import fivid` stays light)

    unknown = set(fit) - set(LANDING_FIT)
    if unknown:
        raise ConfigError(f"landing_transfer: unknown fit option(s) {sorted(unknown)}; allowed {sorted(LANDING_FIT)}",
                          key=sorted(unknown)[0])
    w = {**LANDING_FIT, **{k: float(v) for k, v in fit.items()}}
    gb, ga, span, min_fit = w["guard_before"], w["guard_after"], w["fit_length"], w["min_fit"]
    if min_flight is None:
        min_flight = gb + ga + min_fit
    t = np.asarray(ds["time"].values, float)
    dt = float(np.median(np.diff(t)))
    e = band_energy_envelope(ds, mass, band, order=order)
    ep = contact_episodes(t, ds["contact_normal_force"].values, min_flight=min_flight, threshold=threshold)
    prev_stop = np.concatenate([[t[0]], ep["stop"][:-1]])
    next_start = np.concatenate([ep["start"][1:], [t[-1] + dt]])
    keep = ep["start"] >= (t[0] if start is None else float(start))
    before, after = [], []
    for k in np.flatnonzero(keep):
        s0, s1, tc = ep["start"][k], ep["stop"][k], ep["centroid"][k]
        lo = max(prev_stop[k] + (ga if k > 0 else 0.0), s0 - gb - span)
        before.append(_decay_fit_at(t, e, lo, s0 - gb, tc, min_fit))
        hi = min(next_start[k] - (gb if k + 1 < ep["start"].size else 0.0), s1 + ga + span)
        after.append(_decay_fit_at(t, e, s1 + ga, hi, tc, min_fit))
    before, after = np.array(before), np.array(after)
    imp = ep["impulse"][keep]
    force = np.asarray(ds["contact_normal_force"].values, float)
    bimp = np.array([band_impulse(force[i:j + 1], dt, band) for i, j in zip(ep["first"][keep], ep["last"][keep])])
    gain = after - before
    tr, btr = gain / imp ** 2, gain / bimp ** 2
    tr_db, btr_db = (np.where(x > 0, 10.0 * np.log10(np.where(x > 0, x, 1.0)), np.nan) for x in (tr, btr))
    dims = ("landing",)
    return xr.Dataset(
        {"start": (dims, ep["start"][keep]), "stop": (dims, ep["stop"][keep]), "centroid": (dims, ep["centroid"][keep]),
         "flight_before": (dims, (ep["start"] - prev_stop)[keep]), "flight_after": (dims, (next_start - ep["stop"])[keep]),
         "impulse": (dims, imp), "energy_before": (dims, before), "energy_after": (dims, after), "energy": (dims, gain),
         "transfer": (dims, tr), "transfer_db": (dims, tr_db), "band_impulse": (dims, bimp),
         "band_transfer": (dims, btr), "band_transfer_db": (dims, btr_db)},
        attrs={"mass": float(mass), "band": list(map(float, band)), "min_flight": float(min_flight), **w})
