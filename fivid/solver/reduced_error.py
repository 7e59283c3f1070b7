"""Estimated in-band error of a Craig-Bampton reduced run (issue 30 item 2), from the reduced system alone.

**What is estimated.** The log-spectral distance (LSD, the RMS over the band's bins of ``10 log10(P_red / P_full)``)
between the acceleration PSDs of the reduced and the full run, scored as the pipeline scores them: Welch PSD,
bins of width ``Delta f = fs / nperseg`` over a band ``[f_lo, f_hi]`` of width ``B``.

**Peaks.** Near an in-band mode ``r`` (frequency ``f_r``, damping ratio ``zeta_r``) the PSD is a peak of half-width
``w_r``: the mode's own ``zeta_r f_r`` as seen through the Hann window, whose main lobe has a half-power half-width
of ``0.72 Delta f`` (:data:`HANN_HALF_WIDTH`): ``w_r = hypot(zeta_r f_r, 0.72 Delta f)`` (a Lorentzian of that
width; exact in both limits, the damped and the resolution-limited peak). On the rig ``zeta f`` is 5-100 Hz
against 144 Hz, so the resolution sets the width; an undamped model gets finite, resolution-limited peaks.
A mode moved by a relative ``delta_r`` and widened by ``rho_r`` contributes, summing the peaks' disjoint
neighbourhoods (``u = (f - f_r) / w_r``),

    LSD^2 = (1 / B) sum_r w_r g(delta_r f_r / w_r, rho_r),
    g(d, rho) = integral of [10 log10((1 + u^2) / (rho^2 + (u - d)^2))]^2 du   (~ 2 pi (10 / ln 10)^2 d^2, d << 1).

**Sources of ``delta_r``**, first order each, so they add per mode (first-order perturbations of one eigenvalue):

- *truncated modes' static contribution*: the fixed-interface modes ``j`` left out would add
  ``-omega^4 L_j L_j^T / (omega_j^2 - omega^2)`` to the boundary's dynamic stiffness (``L_j = phi_j^T M_II Psi``,
  the inertial coupling of boundary motion into mode ``j``). Dropping them is a Rayleigh-Ritz restriction: the
  reduced frequencies err high, by ``Delta(omega_r^2) = omega_r^4 x_b^T G x_b`` to first order with
  ``omega_r << omega_j``, where ``G = sum_{j > k} L_j L_j^T / omega_j^2 = Psi^T M_II (K_II^-1 - Phi_k
  Lambda_k^-1 Phi_k^T) M_II Psi`` is the truncated modes' static contribution (computed with the basis from the
  static-correction residual) and ``x_b`` the mode's boundary displacement (mass-normalised): ``delta_r^trunc =
  omega_r^2 x_b^T G x_b / 2``;
- *mass-scaled modes' frequency shift*: the selective scaling keeps the *free* reduced system's modes below
  the target exactly, but the contact ties boundary nodes together and the tied system's modes mix in the scaled
  ones. ``delta_r^scale`` is computed directly: the tied system's in-band frequencies with the scaled mass over
  those with the unscaled one (small dense eigenproblems on the reduced coordinates);
- *the step the scaling buys*: the reduced run steps at ``dt`` several times the full run's. Central differences
  with the solver's damping (the force from ``q_n + beta v_{n-1/2}``, ``alpha v_{n-1/2}``, the band-limited
  filter) turn a mode's root ``s`` into ``ln(z) / dt``, ``z`` the eigenvalue of its one-mode step
  (:func:`discrete_root`): ``delta_r^dt = (omega_r dt)^2 / 24 + zeta_r omega_r dt / 2`` for classic Rayleigh
  (dispersion plus the half-step-old damping velocity), and a damping change ``rho_r``. Taken against the exact
  root, not against the full run's own step: the full run's error has the same sign and is smaller, so this
  bounds the difference from above.

**Contact states.** The contact state changes the modes, so the estimate is taken for three linear states of the
slaves closed after the preload (:func:`contact_states`; on the rigs the upper beam rests on one corner node, not
on its whole 10 mm): open, sliding (normal tied) and stuck (normal and tangential tied); the largest is the run's
estimate.

**What it leaves out** (measured in docs/solver.md, "The error estimate"): the nonlinear stick/slip and contact
switching itself, modes outside the band whose tails reach into it, and the spectrum's floor between the peaks,
60-100 dB below them, where the two runs' small contact-solve differences are not small against the signal.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import quad
from threadpoolctl import threadpool_limits

from fivid.fe.damping import modal_root
from fivid.solver.integrate import velocity_filter_gain

__all__ = ["DEFAULT_ERROR_BAND", "DEFAULT_BIN_WIDTH", "HANN_HALF_WIDTH", "lorentzian_lsd_integral", "discrete_root",
           "contact_states", "band_error_estimate"]

#: band [Hz] of the estimate when no scoring band is given (that of docs/solver.md's full-vs-reduced checks)
DEFAULT_ERROR_BAND = (200.0, 10000.0)

#: PSD resolution [Hz] when none is given: Welch segments of 256 samples at 51.2 kHz (fivid's shortest default)
DEFAULT_BIN_WIDTH = 200.0

#: modes up to this factor times the band's top enter the estimate (the flank of one just above it reaches in)
OUTSIDE_REACH = 1.5

#: half-width at half power of the Hann window's main lobe [bins]: a peak narrower than that is seen this wide
HANN_HALF_WIDTH = 0.72

_DB = 10.0 / math.log(10.0)


def lorentzian_lsd_integral(d: float, rho: float = 1.0, lower: float = -math.inf, upper: float = math.inf) -> float:
    """``g(d, rho) = integral of [10 log10((1 + u^2) / (rho^2 + (u - d)^2))]^2 du`` over ``lower < u < upper`` (default
    the real line) [dB^2]: the squared log-spectral distance (times the band, per half-width) of a Lorentzian peak
    moved by ``d`` half-widths and widened by the factor ``rho`` (``rho = 1``: moved only); ``u`` is the distance
    from the peak in half-widths, so a finite ``(lower, upper)`` is the band seen from a peak near or outside it."""
    d, rho = float(d), float(rho)
    if (d == 0.0 and rho == 1.0) or not lower < upper:
        return 0.0

    def f(u):
        return (_DB * math.log((1.0 + u * u) / (rho * rho + (u - d) ** 2))) ** 2

    half = 50.0 + 2.0 * abs(d)
    lo, hi = max(lower, -half), min(upper, half)
    inner = quad(f, lo, hi, points=[p for p in (0.0, d) if lo < p < hi] or None, limit=200)[0] if lo < hi else 0.0
    # beyond |u| = half: ln ratio ~ (2 u d + 1 - rho^2 - d^2) / u^2 ~ 2 d / u, so [lo', hi'] adds (20 d / ln 10)^2 (1/lo' - 1/hi')
    tail = 0.0
    for a, b in ((max(lower, half), upper), (max(-upper, half), -lower)):
        if a < b:
            tail += (2.0 * _DB * d) ** 2 * (1.0 / a - (0.0 if math.isinf(b) else 1.0 / b))
    return inner + tail


def discrete_root(frequency: float, alpha: float, beta: float, cutoff: float | None, dt: float) -> complex:
    """The complex root ``s = ln(z) / dt`` [rad s-1] (upper half-plane) that the solver's central-difference step
    ``dt`` [s] gives a mode of undamped ``frequency`` [Hz] under the damping scheme (``alpha`` [s-1], ``beta`` [s],
    velocity-filter ``cutoff`` [Hz], None/inf: classic Rayleigh): ``z`` the eigenvalue of the one-mode step of
    :mod:`fivid.solver._reduced_kernels` (state ``q_n``, ``v_{n-1/2}``, filtered ``v``):
    ``v' = v - dt (omega^2 (q + beta v_f) + alpha v)``, ``q' = q + dt v'``, ``v_f' = v_f + a (v' - v_f)`` with
    ``a = 1 - exp(-2 pi cutoff dt)`` (``v_f = v``, classic). Against :func:`fivid.fe.damping.modal_root` it gives
    the step's frequency error (``(omega dt)^2 / 24`` of central differences plus ``zeta omega dt / 2`` of the
    damping force's half-step-old velocity) and its damping error."""
    w2 = (2.0 * math.pi * float(frequency)) ** 2
    a = velocity_filter_gain(math.inf if cutoff is None else float(cutoff), float(dt))
    vrow = np.array([-dt * w2, 1.0 - dt * alpha, -dt * w2 * beta])
    qrow = np.array([1.0, 0.0, 0.0]) + dt * vrow
    if a >= 1.0:  # classic Rayleigh: w = q + beta v
        amp = np.array([[qrow[0], qrow[1] + qrow[2]], [vrow[0], vrow[1] + vrow[2]]])
    else:
        amp = np.array([qrow, vrow, a * vrow + np.array([0.0, 0.0, 1.0 - a])])
    s = np.log(np.linalg.eigvals(amp).astype(complex)) / dt
    return complex(s[np.argmax(s.imag)])


def contact_states(rs, active=None) -> dict:
    """Constraint rows (``(n_rows, n_free)``) of the three linear contact states of the reduced system ``rs``:
    ``open`` (none), ``sliding`` (each closed slave's normal gap to the master segment under it tied) and ``stuck``
    (normal and tangential tied). ``active`` (bool per slave, e.g. the preload's ``Preload.active``): the slaves
    closed in the run (None: all). Rigid masters are skipped (their motion is imposed, not a reduced coordinate)."""
    a = rs.kernel
    nb, nf = int(a["nb"]), rs.n_free
    X = np.column_stack([a["X"][:nb], a["X"][nb:]])
    normal, tangential = [], []
    closed = np.ones(len(a["slave_node"]), dtype=bool) if active is None else np.asarray(active, dtype=bool)
    for k, s in enumerate(a["slave_node"]):
        if not closed[k]:
            continue
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


def band_error_estimate(rs, band, *, alpha: float, beta: float, damping_cutoff: float | None = None,
                        time_step: float | None = None, bin_width: float = DEFAULT_BIN_WIDTH, active=None) -> dict:
    """Estimated log-spectral distance [dB] between the reduced and the full run's PSDs over ``band`` (module
    docstring).

    Parameters
    ----------
    rs : ReducedSystem
        With ``unscaled_mass`` and ``truncation_flexibility`` (built by :func:`fivid.solver.reduced.reduced_system`).
    band : (float, float)
        Scoring band [Hz].
    alpha, beta, damping_cutoff
        The model's Rayleigh damping [s-1, s, Hz] (``fivid.fe.damping.damping_ratio``); zero damping is allowed
        (the peaks' width is then the PSD's resolution).
    time_step : float, optional
        The reduced run's step [s] (None: the step's error left out).
    bin_width : float
        Frequency resolution of the scored Welch PSD, ``sample_rate / nperseg`` [Hz] (> 0).
    active : array of bool, optional
        The slaves closed in the run (the preload's ``Preload.active``; None: all).

    Returns
    -------
    dict
        ``lsd_db`` (the largest over the contact states), ``state`` (which one), ``band`` [Hz], and per state
        ``lsd_db``, ``truncation_db``, ``mass_scaling_db`` and ``time_step_db`` (each source alone), ``modes`` (in
        the band) and ``largest_shift`` (the largest ``|delta_r|`` [-]).
    """
    lo, hi = float(band[0]), float(band[1])
    if not (0.0 <= lo < hi):
        raise ValueError(f"band must be (low, high) with 0 <= low < high, got {band!r}")
    if not (float(bin_width) > 0.0):
        raise ValueError(f"bin_width must be a frequency resolution > 0 Hz, got {bin_width!r}")
    window_hw = HANN_HALF_WIDTH * float(bin_width)
    nf = rs.n_free
    kf = rs.K[:nf, :nf]
    m0 = (rs.unscaled_mass if rs.unscaled_mass is not None else rs.M)[:nf, :nf]
    ms = rs.M[:nf, :nf]
    flex = rs.truncation_flexibility
    w2_max = (2.0 * math.pi * hi * OUTSIDE_REACH) ** 2
    nb2 = 2 * int(rs.kernel["nb"])
    states = {}
    with threadpool_limits(limits=1, user_api="blas"):
        for name, rows in contact_states(rs, active).items():
            lam0, x = _tied_modes(kf, m0, rows, w2_max)
            lam0 = np.clip(lam0, 0.0, None)
            f = np.sqrt(lam0) / (2.0 * math.pi)
            near = np.flatnonzero(f > 0.0)  # every mode up to OUTSIDE_REACH x the band top: their flanks reach in
            inband = (f >= lo) & (f <= hi)
            shift_s = np.zeros(lam0.size)
            if ms is not m0 and lam0.size:
                lam_s, _ = _tied_modes(kf, ms, rows, w2_max * 1.2)
                n = min(lam0.size, lam_s.size)
                shift_s[:n] = np.sqrt(np.clip(lam_s[:n], 0.0, None) / np.maximum(lam0[:n], 1e-300)) - 1.0
            xb = x[:nb2]
            shift_t = (0.5 * lam0 * np.einsum("ir,ij,jr->r", xb, flex, xb) if flex is not None
                       else np.zeros(lam0.size))
            shift_dt, width_dt = np.zeros(lam0.size), np.ones(lam0.size)
            half = np.zeros(lam0.size)  # the peaks' half-width in the PSD [Hz]
            for r in near:
                exact = complex(modal_root(f[r], float(alpha), float(beta), damping_cutoff))
                half[r] = math.hypot(-exact.real / (2.0 * math.pi), window_hw)
                if time_step is not None:
                    step = discrete_root(f[r], float(alpha), float(beta), damping_cutoff, float(time_step))
                    shift_dt[r] = step.imag / exact.imag - 1.0
                    width_dt[r] = math.hypot(-step.real / (2.0 * math.pi), window_hw) / half[r]

            def lsd(shift, width=None):
                total = sum(half[r] * lorentzian_lsd_integral(shift[r] * f[r] / half[r],
                                                              1.0 if width is None else width[r],
                                                              (lo - f[r]) / half[r], (hi - f[r]) / half[r])
                            for r in near)
                return math.sqrt(total / (hi - lo))

            total_shift = shift_t + shift_s + shift_dt
            states[name] = {"lsd_db": lsd(total_shift, width_dt), "truncation_db": lsd(shift_t),
                            "mass_scaling_db": lsd(shift_s), "time_step_db": lsd(shift_dt, width_dt),
                            "modes": int(inband.sum()),
                            "largest_shift": float(np.abs(total_shift[inband]).max()) if inband.any() else 0.0}
    worst = max(states, key=lambda s: states[s]["lsd_db"])
    return {"lsd_db": states[worst]["lsd_db"], "state": worst, "band": [lo, hi], "states": states}
