"""How a study's response scales with its conditions: power laws fitted in log-log by statsmodels OLS.

``rms = c * prod_a x_a^n_a`` over the numeric condition axes that vary (normal load, sliding velocity,
roughness), i.e. ``log rms = log c + sum_a n_a log x_a``, fitted on the points that finished; exponents with
their 95 % confidence intervals (t distribution, ``n - p`` degrees of freedom), ``r2`` and the number of points.
In dB, ``level = 20 log10(rms / ref)`` has slope ``20 n_a`` per decade of ``x_a``. Seeds 001 and 003 make the
vibration level a power law of load, velocity and roughness; the exponents are results, not targets.
"""

from __future__ import annotations

import numpy as np

__all__ = ["POWER_LAW_AXES", "power_law_fit", "roughness_noise_fits", "exponent_half_widths",
           "replicates_for_exponents", "level_scatter"]

#: condition axes a power law can use (positive physical quantities)
POWER_LAW_AXES = ("normal_load", "sliding_velocity", "roughness_ra")


def power_law_fit(points: list[dict], response: str = "rms") -> dict | None:
    """Fit ``response = c prod x_a^n_a`` over the varying axes of ``points`` (summary point dicts).

    Returns ``{"response", "exponents": {axis: {"value", "ci": [lo, hi], "stderr"}}, "prefactor", "r2", "n",
    "axes"}`` or None when fewer points than parameters + 1 (no residual degree of freedom) or nothing varies.
    """
    import statsmodels.api as sm

    rows = [p for p in points if p.get("status") == "done" and p.get(response) is not None and p[response] > 0]
    axes = [a for a in POWER_LAW_AXES if len({p.get(a) for p in rows if p.get(a) is not None}) > 1
            and all(p.get(a) is not None and p[a] > 0 for p in rows)]
    if not axes or len(rows) < len(axes) + 2:
        return None
    X = sm.add_constant(np.column_stack([np.log([p[a] for p in rows]) for a in axes]), has_constant="add")
    y = np.log([p[response] for p in rows])
    res = sm.OLS(y, X).fit()
    ci = res.conf_int(alpha=0.05)
    return {
        "response": response,
        "axes": axes,
        "exponents": {a: {"value": float(res.params[i + 1]), "ci": [float(ci[i + 1, 0]), float(ci[i + 1, 1])],
                          "stderr": float(res.bse[i + 1])} for i, a in enumerate(axes)},
        "prefactor": float(np.exp(res.params[0])),
        "r2": float(res.rsquared),
        "n": int(res.nobs),
    }


def _lv_design(ra_levels, v_levels, replicates: int) -> np.ndarray:
    """Design matrix ``[1, log10 Ra, log10 V]`` of the full factorial Ra x V x ``replicates``."""
    ra, v = np.meshgrid(np.log10(np.asarray(ra_levels, float)), np.log10(np.asarray(v_levels, float)), indexing="ij")
    x = np.column_stack([np.ones(ra.size), ra.ravel(), v.ravel()])
    return np.tile(x, (int(replicates), 1))


def exponent_half_widths(ra_levels, v_levels, replicates: int, sigma_db: float, *, level: float = 0.95) -> dict:
    """Half-widths of the ``level`` confidence intervals of n and m in ``Lv = 20 n log10 Ra + 20 m log10 V + c``,
    fitted by OLS to the full factorial ``ra_levels`` x ``v_levels`` [any units] x ``replicates`` points whose Lv
    scatter about the plane with standard deviation ``sigma_db`` [dB]: ``t(level, N - 3) sigma sqrt((X'X)^-1_jj)
    / 20`` -- statsmodels' interval when ``sigma_db`` is the fit's residual standard deviation.

    Returns ``{"n": half-width, "m": half-width, "points": N, "dof": N - 3}`` (inf without a residual degree of
    freedom)."""
    from scipy.stats import t as student_t

    x = _lv_design(ra_levels, v_levels, replicates)
    dof = x.shape[0] - 3
    if dof < 1:
        return {"n": np.inf, "m": np.inf, "points": int(x.shape[0]), "dof": int(dof)}
    cov = np.linalg.inv(x.T @ x)
    q = float(student_t.ppf(0.5 + level / 2.0, dof)) * float(sigma_db) / 20.0
    return {"n": q * float(np.sqrt(cov[1, 1])), "m": q * float(np.sqrt(cov[2, 2])), "points": int(x.shape[0]),
            "dof": int(dof)}


def replicates_for_exponents(ra_levels, v_levels, sigma_db: float, *, target: float = 0.15,
                             max_replicates: int = 1000) -> int:
    """The fewest replicates (independent profile realisations per Ra x V cell) for which both 95 % half-widths of
    :func:`exponent_half_widths` are at most ``target``; ``max_replicates + 1`` when even that many do not do."""
    for r in range(1, int(max_replicates) + 1):
        hw = exponent_half_widths(ra_levels, v_levels, r, sigma_db)
        if hw["n"] <= target and hw["m"] <= target:
            return r
    return int(max_replicates) + 1


def level_scatter(points: list[dict]) -> dict:
    """How much Lv [dB] scatters about the fitted plane, for the replicate design: ``replicate_sd_db`` (pooled
    standard deviation of Lv between replicates of the same Ra x V cell, ``replicate_dof`` degrees of freedom),
    ``residual_sd_db`` (of the OLS plane ``Lv = 20 n log10 Ra + 20 m log10 V + c``: replicate scatter plus lack
    of fit) and ``sigma_db``, the larger of the two (the conservative one to design with)."""
    rows = [p for p in points if p.get("status", "done") == "done" and p.get("vibration_level") is not None
            and np.isfinite(p["vibration_level"]) and p.get("roughness_ra") and p.get("sliding_velocity")]
    cells: dict = {}
    for p in rows:
        cells.setdefault((p["roughness_ra"], p["sliding_velocity"]), []).append(p["vibration_level"])
    ss = sum(float(np.sum((np.asarray(v) - np.mean(v)) ** 2)) for v in cells.values())
    dof = sum(len(v) - 1 for v in cells.values())
    out = {"replicate_sd_db": float(np.sqrt(ss / dof)) if dof else None, "replicate_dof": int(dof),
           "residual_sd_db": None, "residual_dof": 0}
    if len(rows) > 3:
        x = np.column_stack([np.ones(len(rows)), np.log10([p["roughness_ra"] for p in rows]),
                             np.log10([p["sliding_velocity"] for p in rows])])
        y = np.array([p["vibration_level"] for p in rows])
        beta, *_ = np.linalg.lstsq(x, y, rcond=None)
        out["residual_dof"] = len(rows) - 3
        out["residual_sd_db"] = float(np.sqrt(np.sum((y - x @ beta) ** 2) / out["residual_dof"]))
    known = [v for v in (out["replicate_sd_db"], out["residual_sd_db"]) if v is not None]
    out["sigma_db"] = max(known) if known else None
    return out


def roughness_noise_fits(points: list[dict]) -> dict:
    """Seed 003's scaling of a roughness-noise study (summary points with ``vibration_level`` etc.).

    * ``n``, ``m``: ``Lv = 20 n log10 Ra + 20 m log10 V + c``, i.e. the exponents of the power law fitted to the
      back-face ``velocity_rms`` over ``roughness_ra`` and ``sliding_velocity`` (:func:`power_law_fit`): each
      ``{"value", "ci": [lo, hi]}`` (95 %), null when that axis does not vary; ``n_band``, ``m_band``: the same
      from ``band_velocity_rms`` (the 1-20 kHz level, :func:`fivid.score.roughness.band_vibration_level`; left
      out when no point has one) and ``fits.band_velocity_rms``;
    * ``fits.vibration_level_vs_rz_rsm``: ``Lv = a log10(Rz / Rsm) + b`` (OLS): ``slope`` [dB per decade], ``ci``,
      ``r2``, ``n`` (Rz, Rsm of the generated lower profiles); ``fits.vibration_level_vs_rz_rsm_per_speed``: the same
      per sliding velocity (keyed by its repr in m/s);
    * ``design``: :func:`level_scatter` of the points and the replicates :func:`replicates_for_exponents` asks for
      half-widths of 0.15 on this Ra x V grid;
    * ``fits.shock_rate``, ``fits.shock_impulse``, ``fits.shock_energy``, ``fits.vibratory_power``,
      ``fits.friction_power``, ``fits.friction_coefficient_rms``
      (the transducer's mu(t) fluctuation: the perturbation amplitude's law A(Ra, V)): power laws over Ra and V.
    """
    import statsmodels.api as sm

    out, fits = {"n": None, "m": None}, {}
    for response, suffix in (("velocity_rms", ""), ("band_velocity_rms", "_band")):
        lv = power_law_fit(points, response)
        if lv is None:
            continue
        fits[response] = lv
        for axis, key in (("roughness_ra", "n"), ("sliding_velocity", "m")):
            if axis in lv["exponents"]:
                e = lv["exponents"][axis]
                out[key + suffix] = {"value": e["value"], "ci": e["ci"], "stderr": e["stderr"], "r2": lv["r2"],
                                     "n": lv["n"]}
    rows = [p for p in points if p.get("status") == "done" and p.get("vibration_level") is not None
            and (p.get("profile_Rz") or 0) > 0 and (p.get("profile_Rsm") or 0) > 0]
    if len({round(p["profile_Rz"] / p["profile_Rsm"], 12) for p in rows}) > 1 and len(rows) >= 3:
        x = np.log10([p["profile_Rz"] / p["profile_Rsm"] for p in rows])
        res = sm.OLS(np.array([p["vibration_level"] for p in rows]), sm.add_constant(x)).fit()
        ci = res.conf_int(alpha=0.05)
        fits["vibration_level_vs_rz_rsm"] = {"slope": float(res.params[1]), "ci": [float(ci[1, 0]), float(ci[1, 1])],
                                             "intercept": float(res.params[0]), "r2": float(res.rsquared),
                                             "n": int(res.nobs), "units": "dB per decade of Rz/Rsm"}
    per_speed = {}
    for v in sorted({p["sliding_velocity"] for p in rows if p.get("sliding_velocity")}):
        sub = [p for p in rows if p.get("sliding_velocity") == v]
        x = np.log10([p["profile_Rz"] / p["profile_Rsm"] for p in sub])
        if len(sub) >= 3 and np.ptp(x) > 0:
            res = sm.OLS(np.array([p["vibration_level"] for p in sub]), sm.add_constant(x)).fit()
            ci = res.conf_int(alpha=0.05)
            per_speed[f"{v!r}"] = {"sliding_velocity": float(v), "slope": float(res.params[1]),
                                   "ci": [float(ci[1, 0]), float(ci[1, 1])], "intercept": float(res.params[0]),
                                   "r2": float(res.rsquared), "n": int(res.nobs)}
    if per_speed:
        fits["vibration_level_vs_rz_rsm_per_speed"] = per_speed
    scatter = level_scatter(points)
    ras = sorted({p["roughness_ra"] for p in rows if p.get("roughness_ra")})
    vs = sorted({p["sliding_velocity"] for p in rows if p.get("sliding_velocity")})
    if scatter["sigma_db"] is not None and len(ras) > 1 and len(vs) > 1:
        scatter["replicates_for_half_width_0.15"] = replicates_for_exponents(ras, vs, scatter["sigma_db"])
    out["design"] = scatter
    for name in ("shock_rate", "shock_impulse", "shock_energy", "vibratory_power", "friction_power",
                 "friction_coefficient_rms"):
        f = power_law_fit(points, name)
        if f is not None:
            fits[name] = f
    out["fits"] = fits
    return out
