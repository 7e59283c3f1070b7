"""Estimated in-band error of a Craig-Bampton reduced run (issue 30 item 2), from the reduced system alone.

The acceleration PSD of a lightly damped structure is, near each of its modes ``r`` (frequency ``f_r``, damping
ratio ``zeta_r``), a Lorentzian of half-width ``zeta_r f_r``: ``P(f) ~ 1 / (1 + u^2)``, ``u = (f - f_r) /
(zeta_r f_r)``. A reduction that moves the mode by a relative ``delta_r`` moves the Lorentzian by
``d_r = delta_r / zeta_r`` half-widths, and the log-spectral distance of the two PSDs over a band of width ``B``
(the RMS over frequency of ``10 log10(P_red / P_full)``) is, summing the modes' disjoint contributions,

    LSD^2 = (1 / B) sum_r zeta_r f_r g(delta_r / zeta_r),
    g(d)  = integral over u of [10 log10((1 + (u - d)^2) / (1 + u^2))]^2 du  (~ 2 pi (10 / ln 10)^2 d^2 for d << 1).

So an in-band relative frequency error is amplified by ``1 / zeta``: 1e-4 on a mode with 0.5 % damping is
``d = 0.02``. The two sources of ``delta_r`` on this path:

- **truncated modes' static contribution**: the fixed-interface modes ``j`` left out would add
  ``-omega^4 L_j L_j^T / (omega_j^2 - omega^2)`` to the boundary's dynamic stiffness (``L_j = phi_j^T M_II Psi``,
  the inertial coupling of boundary motion into mode ``j``). Dropping them is a Rayleigh-Ritz restriction: the
  reduced frequencies err high, by ``Delta(omega_r^2) = omega_r^4 x_b^T G x_b`` to first order with
  ``omega_r << omega_j``, where ``G = sum_{j > k} L_j L_j^T / omega_j^2 = Psi^T M_II (K_II^-1 - Phi_k
  Lambda_k^-1 Phi_k^T) M_II Psi`` is the truncated modes' static contribution (computed with the basis from the
  static-correction residual) and ``x_b`` the mode's boundary displacement (mass-normalised): ``delta_r^trunc =
  omega_r^2 x_b^T G x_b / 2``;
- **mass-scaled modes' frequency shift**: the selective scaling keeps the *free* reduced system's modes below
  the target exactly, but the contact ties boundary nodes together and the tied system's modes mix in the scaled
  ones. ``delta_r^scale`` is computed directly: the tied system's in-band frequencies with the scaled mass over
  those with the unscaled one (small dense eigenproblems on the reduced coordinates).

The contact state changes the modes, so the estimate is taken for three linear states of every slave against
the master segment under it (:func:`contact_states`): open, sliding (normal tied) and stuck (normal and
tangential tied); the largest is the run's estimate. What it leaves out: the nonlinear stick/slip switching
itself (resolved by the step, not the basis), and modes outside the band whose tails reach into it.
"""

from __future__ import annotations

import math

import numpy as np

from fivid.fe.damping import damping_ratio

__all__ = ["DEFAULT_ERROR_BAND", "lorentzian_lsd_integral", "contact_states", "band_error_estimate"]

#: band [Hz] of the estimate when no scoring band is given (that of docs/solver.md's full-vs-reduced checks)
DEFAULT_ERROR_BAND = (200.0, 10000.0)

_DB = 10.0 / math.log(10.0)


def lorentzian_lsd_integral(d: float) -> float:
    """``g(d) = integral of [10 log10((1 + (u - d)^2) / (1 + u^2))]^2 du`` over the real line [dB^2], the squared
    log-spectral distance (times the band, per half-width) of a Lorentzian peak moved by ``d`` half-widths."""
    from scipy.integrate import quad

    d = abs(float(d))
    if d == 0.0:
        return 0.0
    half = 50.0 + 2.0 * d

    def f(u):
        return (_DB * math.log((1.0 + (u - d) ** 2) / (1.0 + u * u))) ** 2

    inner, _ = quad(f, -half, half, points=[0.0, d], limit=200)
    # tails: ln ratio ~ -2 d / u for |u| >> d, so each side adds (10/ln10)^2 4 d^2 / half
    return inner + 2.0 * _DB ** 2 * 4.0 * d * d / half


def contact_states(rs) -> dict:
    """Constraint rows (``(n_rows, n_free)``) of the three linear contact states of the reduced system ``rs``:
    ``open`` (none), ``sliding`` (each slave's normal gap to the master segment under it tied) and ``stuck``
    (normal and tangential tied). Rigid masters are skipped (their motion is imposed, not a reduced coordinate)."""
    a = rs.kernel
    nb, nf = int(a["nb"]), rs.n_free
    X = np.column_stack([a["X"][:nb], a["X"][nb:]])
    normal, tangential = [], []
    for k, s in enumerate(a["slave_node"]):
        p = int(a["slave_pair"][k])
        mm = a["master_nodes"][a["master_ptr"][p]:a["master_ptr"][p + 1]]
        if mm.size < 2:
            continue
        j = int(min(max(a["seg"][k], 0), mm.size - 2))
        na, nbb = int(mm[j]), int(mm[j + 1])
        t = X[nbb] - X[na]
        length = float(np.hypot(*t))
        t = t / length
        xi = float(np.clip((X[s] - X[na]) @ t / length, 0.0, 1.0))
        nrm = np.array([-t[1], t[0]])
        for direction, rows in ((nrm, normal), (t, tangential)):
            row = np.zeros(nf)
            for node, w in ((int(s), 1.0), (na, -(1.0 - xi)), (nbb, -xi)):
                row[node] += w * direction[0]
                row[nb + node] += w * direction[1]
            rows.append(row)
    empty = np.zeros((0, nf))
    nrows = np.array(normal).reshape(-1, nf) if normal else empty
    trows = np.array(tangential).reshape(-1, nf) if tangential else empty
    return {"open": empty, "sliding": nrows, "stuck": np.vstack([nrows, trows])}


def _tied_modes(k, m, rows, omega2_max):
    """In-band modes of ``(k, m)`` with ``rows @ x = 0``: ``(omega^2, x)``, x mass-normalised in ``m``."""
    import scipy.linalg

    if rows.shape[0]:
        z = scipy.linalg.null_space(rows)
        kz, mz = z.T @ k @ z, z.T @ m @ z
    else:
        z, kz, mz = None, k, m
    lam, y = scipy.linalg.eigh(0.5 * (kz + kz.T), 0.5 * (mz + mz.T), subset_by_value=(-np.inf, omega2_max))
    return lam, (y if z is None else z @ y)


def band_error_estimate(rs, band, *, alpha: float, beta: float, damping_cutoff: float | None = None) -> dict:
    """Estimated log-spectral distance [dB] between the reduced and the full run's PSDs over ``band`` (module
    docstring).

    Parameters
    ----------
    rs : ReducedSystem
        With ``unscaled_mass`` and ``truncation_flexibility`` (built by :func:`fivid.solver.reduced.reduced_system`).
    band : (float, float)
        Scoring band [Hz].
    alpha, beta, damping_cutoff
        The model's Rayleigh damping [s-1, s, Hz] (``fivid.fe.damping.damping_ratio``).

    Returns
    -------
    dict
        ``lsd_db`` (the largest over the contact states), ``state`` (which one), ``band`` [Hz], and per state
        ``lsd_db``, ``truncation_db`` and ``mass_scaling_db`` (each source alone), ``modes`` (in the band) and
        ``largest_shift`` (the largest ``|delta_r|`` [-]).
    """
    from threadpoolctl import threadpool_limits

    lo, hi = float(band[0]), float(band[1])
    if not (0.0 <= lo < hi):
        raise ValueError(f"band must be (low, high) with 0 <= low < high, got {band!r}")
    nf, nb2 = rs.n_free, 2 * int(rs.kernel["nb"])
    kf = rs.K[:nf, :nf]
    m0 = (rs.unscaled_mass if rs.unscaled_mass is not None else rs.M)[:nf, :nf]
    ms = rs.M[:nf, :nf]
    flex = rs.truncation_flexibility
    w2_max = (2.0 * math.pi * hi * 1.05) ** 2
    states = {}
    with threadpool_limits(limits=1, user_api="blas"):
        for name, rows in contact_states(rs).items():
            lam0, x = _tied_modes(kf, m0, rows, w2_max)
            lam0 = np.clip(lam0, 0.0, None)
            if ms is m0 or lam0.size == 0:
                shift_s = np.zeros(lam0.size)
            else:
                lam_s, _ = _tied_modes(kf, ms, rows, w2_max * 1.2)
                n = min(lam0.size, lam_s.size)
                shift_s = np.zeros(lam0.size)
                shift_s[:n] = np.sqrt(np.clip(lam_s[:n], 0.0, None) / np.maximum(lam0[:n], 1e-300)) - 1.0
            xb = x[:nb2]
            shift_t = (0.5 * lam0 * np.einsum("ir,ij,jr->r", xb, flex, xb) if flex is not None
                       else np.zeros(lam0.size))
            f = np.sqrt(lam0) / (2.0 * math.pi)
            inband = (f >= lo) & (f <= hi)
            zeta = np.asarray(damping_ratio(np.maximum(f, 1e-9), float(alpha), float(beta), damping_cutoff))

            def lsd(shift):
                total = sum(zeta[r] * f[r] * lorentzian_lsd_integral(shift[r] / zeta[r])
                            for r in np.flatnonzero(inband))
                return math.sqrt(total / (hi - lo))

            states[name] = {"lsd_db": lsd(shift_t + shift_s), "truncation_db": lsd(shift_t),
                            "mass_scaling_db": lsd(shift_s), "modes": int(inband.sum()),
                            "largest_shift": float(np.abs(shift_t + shift_s)[inband].max()) if inband.any() else 0.0}
    worst = max(states, key=lambda s: states[s]["lsd_db"])
    return {"lsd_db": states[worst]["lsd_db"], "state": worst, "band": [lo, hi], "states": states}
