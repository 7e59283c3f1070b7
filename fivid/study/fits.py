"""How a study's response scales with its conditions: power laws fitted in log-log by statsmodels OLS.

``rms = c * prod_a x_a^n_a`` over the numeric condition axes that vary (normal load, sliding velocity,
roughness), i.e. ``log rms = log c + sum_a n_a log x_a``, fitted on the points that finished; exponents with
their 95 % confidence intervals (t distribution, ``n - p`` degrees of freedom), ``r2`` and the number of points.
In dB, ``level = 20 log10(rms / ref)`` has slope ``20 n_a`` per decade of ``x_a``. Seeds 001 and 003 make the
vibration level a power law of load, velocity and roughness; the exponents are results, not targets.
"""

from __future__ import annotations

import numpy as np

__all__ = ["POWER_LAW_AXES", "power_law_fit", "roughness_noise_fits"]

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


def roughness_noise_fits(points: list[dict]) -> dict:
    """Seed 003's scaling of a roughness-noise study (summary points with ``vibration_level`` etc.).

    * ``n``, ``m``: ``Lv = 20 n log10 Ra + 20 m log10 V + c``, i.e. the exponents of the power law fitted to the
      back-face ``velocity_rms`` over ``roughness_ra`` and ``sliding_velocity`` (:func:`power_law_fit`): each
      ``{"value", "ci": [lo, hi]}`` (95 %), null when that axis does not vary;
    * ``fits.vibration_level_vs_rz_rsm``: ``Lv = a log10(Rz / Rsm) + b`` (OLS): ``slope`` [dB per decade], ``ci``,
      ``r2``, ``n`` (Rz, Rsm of the generated lower profiles);
    * ``fits.shock_rate``, ``fits.shock_impulse``, ``fits.dissipated_power``, ``fits.friction_coefficient_rms``
      (the transducer's mu(t) fluctuation: the perturbation amplitude's law A(Ra, V)): power laws over Ra and V.
    """
    import statsmodels.api as sm

    out, fits = {"n": None, "m": None}, {}
    lv = power_law_fit(points, "velocity_rms")
    if lv is not None:
        fits["velocity_rms"] = lv
        for axis, key in (("roughness_ra", "n"), ("sliding_velocity", "m")):
            if axis in lv["exponents"]:
                e = lv["exponents"][axis]
                out[key] = {"value": e["value"], "ci": e["ci"], "stderr": e["stderr"], "r2": lv["r2"], "n": lv["n"]}
    rows = [p for p in points if p.get("status") == "done" and p.get("vibration_level") is not None
            and (p.get("profile_Rz") or 0) > 0 and (p.get("profile_Rsm") or 0) > 0]
    if len({round(p["profile_Rz"] / p["profile_Rsm"], 12) for p in rows}) > 1 and len(rows) >= 3:
        x = np.log10([p["profile_Rz"] / p["profile_Rsm"] for p in rows])
        res = sm.OLS(np.array([p["vibration_level"] for p in rows]), sm.add_constant(x)).fit()
        ci = res.conf_int(alpha=0.05)
        fits["vibration_level_vs_rz_rsm"] = {"slope": float(res.params[1]), "ci": [float(ci[1, 0]), float(ci[1, 1])],
                                             "intercept": float(res.params[0]), "r2": float(res.rsquared),
                                             "n": int(res.nobs), "units": "dB per decade of Rz/Rsm"}
    for name in ("shock_rate", "shock_impulse", "dissipated_power", "friction_coefficient_rms"):
        f = power_law_fit(points, name)
        if f is not None:
            fits[name] = f
    out["fits"] = fits
    return out
