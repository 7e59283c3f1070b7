"""Estimated in-band error of a Craig-Bampton reduced run (issue 30 item 2), from the reduced system alone.

**What is estimated.** The log-spectral distance (LSD, the RMS over the band's bins of ``10 log10(P_red / P_full)``)
between the acceleration PSDs of the reduced and the full run, scored as the pipeline scores them: Welch PSD,
bins of width ``Delta f = fs / nperseg`` over a band ``[f_lo, f_hi]`` of width ``B``.

**Peaks.** Near a mode ``r`` (frequency ``f_r``, decay rate ``gamma_r = zeta_r f_r`` [Hz]) the expected Welch PSD is
the mode's Lorentzian of half-width ``gamma_r`` convolved with the Hann window's spectral window ``|W|^2``
(:func:`hann_kernel`, main lobe +-2 bins, nulls at the integers beyond): :func:`peak_psd`. On the rigs ``gamma`` is
5-100 Hz against 200 Hz bins, so the window shapes the peaks, and their flanks are far steeper than a Lorentzian
of the same width (the first version, a Lorentzian of half-width ``gamma``, read a shift 2-40 x too weakly, and
divided by zero without damping). A mode moved by ``delta_r f_r`` [Hz] (and its decay rate changed) changes the
bin ``k`` by ``e_rk = 10 log10(P_r'(f_k) / P_r(f_k))`` (:func:`peak_db_error`), and

    LSD^2 = (1 / n_bins) sum_k sum_r e_rk^2

over the band's bins and every mode up to 1.5 x the band's top (the flank of one just above it reaches in).
Summing the squares treats each bin as if every mode dominated it: an upper bound where peaks overlap. An
undamped model gets the kernel itself: a finite estimate, but a large one, since its bins near the kernel's nulls
move by decibels for a small shift (a run's PSD has these nulls too, filled only by what else is in the signal).

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
  (dispersion plus the half-step-old damping velocity), and a changed decay rate. Taken against the exact
  root, not against the full run's own step: the full run's error has the same sign and is smaller, so this
  bounds the difference from above.

**Time resolution** (:func:`step_resolution_db`): the part of the distance no modal shift makes, in the PSD's
troughs. Each run resolves its events (the contact closing, opening and switching between stick and slip, the
ramps' corners) and the response each one starts to within one step; so the reduced run holds each event's
component of the response displaced in time by some ``|tau| < dt`` against the full run's (``dt`` the reduced
run's step, the larger of the two). A bin's amplitude is the sum of the components; a displacement ``tau`` turns a
component ``A`` into ``A exp(-i omega tau)``, ``|A exp(-i omega tau) - A| <= omega |tau| |A|``, so while no
component exceeds the bin's sum (no cancellation), the bin changes by at most ``20 log10(1 + 2 pi f dt)`` [dB].
Its RMS over the band's bins is added to the modal part: ``lsd_db = modal_db + resolution_db`` (Minkowski: the RMS
of ``|e_modal| + |e_res|`` is at most the sum of the two RMS). Measured (docs/solver.md, default schedule of
``fivid simulate``): 1.1-3.1 x above the full-vs-reduced distance on the two rigid rigs. Where components of
different events cancel -- a record that starts inside the start's transient of bouncing contact -- a relative
displacement changes the bin by more, and this is no bound: :func:`scored_contact_switches` counts, after the
run, the contact switches in the scored record (output attr ``reduced_error_contact_switches``; 0 where it was
measured to hold). What covers such records is the opt-in a-posteriori check (``IntegrationOptions.reduced_check``,
:func:`fivid.solver.simulate`: the run against one at half its step, a Richardson bound; measured 1.6-2.0 x the
distance on every case, the bouncing record included, at the price of a second reduced run).

**Contact states.** The contact state changes the modes, so the estimate is taken for three linear states of the
slaves closed after the preload (:func:`contact_states`; on the rigs the upper beam rests on one corner node, not
on its whole 10 mm): open, sliding (normal tied) and stuck (normal and tangential tied); the largest is the run's
estimate.

**What it leaves out** (measured in docs/solver.md, "The error estimate"): the reduced contact solve's residual
(its boundary inverse mass couples a node's x and y, so Gauss-Seidel iterates and stops with a residual of up to
its tolerance, a white contact-force noise in the troughs: halved at 1e-12, which costs ~15 % of the warm run,
so it is left at 1e-10, inside the resolution bound), and records that start inside the start's transient (above). Without the resolution term the
modal part alone was 4-106 x below the measured distance on the rigs.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from threadpoolctl import threadpool_limits

from fivid.fe.damping import modal_root
from fivid.solver.integrate import velocity_filter_gain

__all__ = ["DEFAULT_ERROR_BAND", "DEFAULT_BIN_WIDTH", "hann_kernel", "peak_psd", "peak_db_error", "discrete_root",
           "step_resolution_db", "scored_contact_switches", "contact_states", "band_error_estimate"]

#: band [Hz] of the estimate when no scoring band is given (that of docs/solver.md's full-vs-reduced checks)
DEFAULT_ERROR_BAND = (200.0, 10000.0)

#: PSD resolution [Hz] when none is given: Welch segments of 256 samples at 51.2 kHz (fivid's shortest default)
DEFAULT_BIN_WIDTH = 200.0

#: modes up to this factor times the band's top enter the estimate (the flank of one just above it reaches in)
OUTSIDE_REACH = 1.5

#: [bins] a peak narrower than this is the kernel plus its Lorentzian's tail (no grid finer than this / 8)
NARROW_PEAK = 1.0 / 256.0

#: Welch segment length of the kernel's shape (in bins it hardly depends on it above ~64)
KERNEL_NPERSEG = 256

#: [bins] within this distance of a mode its peak is convolved on a grid (beyond: sidelobe plus Lorentzian tail)
PEAK_REACH = 6.0

_DB = 10.0 / math.log(10.0)


def hann_kernel(x, nperseg: int = KERNEL_NPERSEG) -> np.ndarray:
    """The Hann window's spectral window ``|W(x)|^2`` at ``x`` bins from its centre, normalised to unit area in bins
    (peak ``1 / 1.5``, the window's equivalent noise bandwidth): what a Welch PSD of ``nperseg``-sample periodic-Hann
    segments makes of a spectral line. Closed form, ``W = D(x) / 2 - D(x - 1) / 4 - D(x + 1) / 4`` with the
    Dirichlet kernel ``D(x) = sum_n exp(-2 pi i x n / N)``."""
    def dirichlet(y):
        s = np.sin(np.pi * y / nperseg)
        small = np.abs(s) < 1e-12
        ratio = np.where(small, nperseg * np.cos(np.pi * y) / np.where(small, np.cos(np.pi * y / nperseg), 1.0),
                         np.sin(np.pi * y) / np.where(small, 1.0, s))
        return ratio * np.exp(-1j * np.pi * y * (nperseg - 1) / nperseg)

    x = np.asarray(x, dtype=float)
    w = 0.5 * dirichlet(x) - 0.25 * dirichlet(x - 1.0) - 0.25 * dirichlet(x + 1.0)
    return np.abs(w) ** 2 / (0.375 * nperseg * nperseg)


def peak_psd(x, half_width: float) -> np.ndarray:
    """A mode's peak in a Welch PSD at ``x`` bins from the mode [1/bin, unit area]: its Lorentzian of half-width
    ``half_width`` [bins] (the decay rate ``zeta f`` over the bin width) smoothed by :func:`hann_kernel`:
    ``sum_j L(x - u_j) K(u_j) h`` over the kernel on a grid ``u_j`` of step ``h <= min(half_width / 8, 1/32)`` bin
    (a power of two) within ``PEAK_REACH + 4`` bins, at the bins within ``PEAK_REACH`` of the mode; beyond, and
    for a peak narrower than ``NARROW_PEAK``, the kernel plus the Lorentzian's tail. Zero width (undamped): the
    kernel itself."""
    x = np.atleast_1d(np.asarray(x, dtype=float))
    g = float(half_width)
    if g <= 0.0:
        return hann_kernel(x)
    out = hann_kernel(x) + (g / math.pi) / (x * x + g * g)
    near = np.abs(x) <= PEAK_REACH
    if near.any() and g >= NARROW_PEAK:  # narrower: the kernel with the Lorentzian's tail in its nulls, as beyond
        u, ku = _kernel_grid(int(math.floor(math.log2(min(g / 8.0, 1.0 / 32.0)))))
        d = x[near, None] - u[None, :]
        out[near] = ((g / math.pi) / (d * d + g * g)) @ ku
    return out


@functools.lru_cache(maxsize=16)
def _kernel_grid(exponent: int):
    """The :func:`hann_kernel` on a grid of step ``2**exponent`` bin over +-(``PEAK_REACH`` + 4) bins, times the step
    (the convolution's weights: ``P(x) = sum_j L(x - u_j) K(u_j) h``)."""
    h = 2.0 ** exponent
    u = np.arange(-PEAK_REACH - 4.0, PEAK_REACH + 4.0 + 0.5 * h, h)
    return u, hann_kernel(u) * h


def peak_db_error(frequency: float, decay: float, bins, bin_width: float, shift: float = 0.0,
                  decay_after: float | None = None) -> np.ndarray:
    """``10 log10(P' / P)`` [dB] at the PSD's ``bins`` [Hz] of a mode's :func:`peak_psd` (``frequency`` [Hz], decay
    rate ``decay = zeta f`` [Hz]) moved by ``shift`` [Hz] and with the decay rate ``decay_after`` [Hz] (None: the same)."""
    bins = np.asarray(bins, dtype=float)
    before = peak_psd((bins - frequency) / bin_width, decay / bin_width)
    after = peak_psd((bins - frequency - shift) / bin_width, (decay if decay_after is None else decay_after) / bin_width)
    return 10.0 * np.log10(after / before)


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


def step_resolution_db(bins, time_step: float) -> float:
    """The step's time-resolution bound [dB] on the LSD over the PSD's ``bins`` [Hz]: the RMS over the bins of
    ``20 log10(1 + 2 pi f dt)`` (module docstring, "Time resolution"), ``dt = time_step`` [s] (> 0)."""
    dt = float(time_step)
    if not (dt > 0.0):
        raise ValueError(f"time_step must be a step > 0 s, got {time_step!r}")
    bins = np.asarray(bins, dtype=float)
    if not bins.size:
        return 0.0
    return float(np.sqrt(np.mean((20.0 * np.log10(1.0 + 2.0 * math.pi * bins * dt)) ** 2)))


def scored_contact_switches(ds) -> int:
    """Output samples of the RunDataset ``ds`` after its ``transient_end`` [s] at which the contact's state changes
    (any of ``stick_fraction``, ``slip_fraction``, ``open_fraction``): the a-posteriori check of the step's
    resolution bound, which holds while the scored record's components do not cancel (module docstring); a record
    that switches contact holds many events' responses (0 without the fractions)."""
    names = [k for k in ("stick_fraction", "slip_fraction", "open_fraction") if k in ds]
    if not names:
        return 0
    t = ds["time"].values
    keep = t >= float(ds.attrs.get("transient_end", 0.0))
    x = np.column_stack([np.asarray(ds[k].values, dtype=float).reshape(t.size, -1) for k in names])[keep]
    return int(np.count_nonzero(np.any(x[1:] != x[:-1], axis=1)))


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
        ``lsd_db`` (the largest over the contact states), ``state`` (which one), ``band`` [Hz], ``resolution_db``
        (:func:`step_resolution_db`; 0 without ``time_step``) and per state ``lsd_db`` (``modal_db +
        resolution_db``, triangle inequality), ``modal_db`` (the modal shifts together), ``truncation_db``,
        ``mass_scaling_db`` and ``time_step_db`` (each source alone), ``modes`` (in the band) and ``largest_shift``
        (the largest ``|delta_r|`` [-]).
    """
    lo, hi = float(band[0]), float(band[1])
    if not (0.0 <= lo < hi):
        raise ValueError(f"band must be (low, high) with 0 <= low < high, got {band!r}")
    if not (float(bin_width) > 0.0):
        raise ValueError(f"bin_width must be a frequency resolution > 0 Hz, got {bin_width!r}")
    bw = float(bin_width)
    bins = bw * np.arange(math.ceil(lo / bw), math.floor(hi / bw) + 1)
    nf = rs.n_free
    kf = rs.K[:nf, :nf]
    m0 = (rs.unscaled_mass if rs.unscaled_mass is not None else rs.M)[:nf, :nf]
    ms = rs.M[:nf, :nf]
    flex = rs.truncation_flexibility
    w2_max = (2.0 * math.pi * hi * OUTSIDE_REACH) ** 2
    nb2 = 2 * int(rs.kernel["nb"])
    resolution = step_resolution_db(bins, time_step) if time_step is not None else 0.0
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
            shift_dt, decay, decay_dt = np.zeros(lam0.size), np.zeros(lam0.size), np.zeros(lam0.size)
            for r in near:
                exact = complex(modal_root(f[r], float(alpha), float(beta), damping_cutoff))
                decay[r] = decay_dt[r] = -exact.real / (2.0 * math.pi)
                if time_step is not None:
                    step = discrete_root(f[r], float(alpha), float(beta), damping_cutoff, float(time_step))
                    # relative to the damped frequency; an overdamped mode (no imaginary part: beta*omega/2 >= 1,
                    # e.g. a stiff mode under stiffness damping) has none, so its shift is taken on the undamped one
                    ref = exact.imag if exact.imag > 0.0 else 2.0 * math.pi * f[r]
                    shift_dt[r] = (step.imag - exact.imag) / ref
                    decay_dt[r] = -step.real / (2.0 * math.pi)

            def lsd(shift, with_step):
                total = sum(float(np.sum(peak_db_error(f[r], decay[r], bins, bw, shift[r] * f[r],
                                                       decay_dt[r] if with_step else None) ** 2)) for r in near)
                return math.sqrt(total / max(bins.size, 1))

            total_shift = shift_t + shift_s + shift_dt
            modal = lsd(total_shift, True)
            states[name] = {"lsd_db": modal + resolution, "modal_db": modal, "resolution_db": resolution,
                            "truncation_db": lsd(shift_t, False),
                            "mass_scaling_db": lsd(shift_s, False), "time_step_db": lsd(shift_dt, True),
                            "modes": int(inband.sum()),
                            "largest_shift": float(np.abs(total_shift[inband]).max()) if inband.any() else 0.0}
    worst = max(states, key=lambda s: states[s]["lsd_db"])
    return {"lsd_db": states[worst]["lsd_db"], "state": worst, "band": [lo, hi], "resolution_db": resolution,
            "states": states}
