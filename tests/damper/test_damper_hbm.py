"""Harmonic balance of Jenkins contacts against closed forms, linear limits and the time domain."""

from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import eigh

from fivid.damper.hbm import HarmonicBalance
from fivid.damper.modal import ModalModel
from fivid.damper.model import load_damper_model
from fivid.damper.timedomain import steady_state_response
from fivid.fe.beam import cantilever_beam

CONFIGS = Path(__file__).resolve().parents[2] / "configs" / "dampers"


@pytest.fixture(scope="module")
def model1():
    return load_damper_model(CONFIGS / "seed004_model1.yaml")


# --- Den Hartog (1931): forced oscillator m x'' + k x + F sgn(x') = P cos(w t), non-stop motion -------------
# Half cycle with x' > 0, tau = w_n t, r = w / w_n, theta = pi / r (half period in tau):
#   x = A cos tau + B sin tau + X_p cos(r tau + phi) - F/k,  X_p = P / (k (1 - r^2)).
# x'(0) = 0 gives B = X_p r sin(phi); x'(theta) = 0 gives A = X_p r sin(phi) (1 + cos theta) / sin theta;
# x(0) + x(theta) = 0 gives X_p sin(phi) = (F/k) U with U = sin(theta) / (r (1 + cos theta));
# x(theta) - x(0) = 2 X0 gives X0 = -X_p cos(phi), hence
#   X0 = sqrt(X_p^2 - (F U / k)^2)                                        (Den Hartog's closed form)
def den_hartog(r, friction, force=1.0, k=1.0, m=1.0):
    theta = np.pi / r
    u = np.sin(theta) / (r * (1 + np.cos(theta)))
    xp = force / (k * (1 - r * r))
    x0 = np.sqrt(xp**2 - (friction / k * u) ** 2)
    # the closed form holds only for non-stop motion: check x' > 0 inside the half cycle
    sin_phi = friction / k * u / xp
    cos_phi = -x0 / xp
    b = xp * r * sin_phi
    a = xp * r * sin_phi * (1 + np.cos(theta)) / np.sin(theta)
    tau = np.linspace(0, theta, 2001)[1:-1]
    v = -a * np.sin(tau) + b * np.cos(tau) - xp * r * (np.sin(r * tau) * cos_phi + np.cos(r * tau) * sin_phi)
    assert np.all(v > 0), "Den Hartog closed form outside its non-stop regime"
    return x0


def _peak(hb, sol, n=20001):
    th = np.linspace(0, 2 * np.pi, n)
    return np.max(np.abs(np.real(np.exp(1j * np.outer(th, hb.harmonics)) @ sol.contact)))


@pytest.mark.parametrize("r", [0.8, 1.2, 1.5])
def test_den_hartog_forced_coulomb_oscillator(r):
    friction = 0.3  # F / P, inside the non-stop regime for these r (checked in den_hartog)
    one = np.ones(1)
    sdof = ModalModel(one.copy(), np.zeros(1), one.copy(), one.copy(), one.copy())
    k_contact = 1e5  # Coulomb as a stiff Jenkins element: amplitude error ~ F / k_contact = 3e-6
    n = 2048
    amp = {}
    for h_max in (15, 31):
        hb = HarmonicBalance(sdof, k_contact, friction, 1.0, harmonics=tuple(range(1, h_max + 1, 2)), samples_per_period=n)
        u, it = hb.solve(r)
        amp[h_max] = _peak(hb, hb.solution(u, r, it))
    exact = den_hartog(r, friction)
    # Tolerance: (1) AFT sampling: the stick/slip switch is located to one sample, a phase error
    # <= 2 pi / N of a square wave of first harmonic 4F/pi -> |H(w)| (4F/pi)(2 pi/N);
    # (2) harmonic truncation: the error decays slowly (observed order ~0.7 in H over 15..63 for the
    # switching instant), so twice the change from H=15 to H=31 bounds the error left at H=31
    # (error(H) / |A(H) - A(H/2)| = 1 / (2^p - 1) < 2 for p > 0.59); (3) the contact compliance F/k_contact.
    h1 = 1.0 / abs(1 - r * r)
    tol = h1 * 4 * friction / np.pi * 2 * np.pi / n + 2 * abs(amp[31] - amp[15]) + friction / k_contact
    assert abs(amp[31] - exact) <= tol
    assert tol < 0.01 * exact  # the check is sharp: better than 1 %


def _fe_response(model_yaml_beam, spring, omega, zeta):
    """Direct FE solve (no modes): (K + k e e^T - w^2 M + i w C) x = P e_exc, C = modal damping in FE form."""
    b = cantilever_beam(0.5, 0.04, 0.008, 210e9, 7850, n_elements=20, points=(0.5, 0.25, 0.35), tip_mass=0.0725)
    w2, phi = eigh(b.stiffness, b.mass)
    c = b.mass @ phi @ np.diag(2 * zeta * np.sqrt(w2)) @ phi.T @ b.mass
    kk = b.stiffness.copy()
    ic = b.transverse_dof(0.5)
    kk[ic, ic] += spring
    rhs = np.zeros(kk.shape[0])
    rhs[b.transverse_dof(0.25)] = 2.0
    x = np.linalg.solve(kk - omega**2 * b.mass + 1j * omega * c, rhs)
    return x[b.transverse_dof(0.35)], b, kk


@pytest.mark.parametrize("slip_force, spring", [(1e-7, 0.0), (1e7, 3.9e5)])
def test_limits_free_and_stuck_beam(model1, slip_force, spring):
    """mu Fn -> 0: the free beam; mu Fn -> inf: the beam with a tip spring k_d (direct FE solves)."""
    hb = HarmonicBalance(model1.modal, model1.contact_stiffness, slip_force, 2.0)
    zeta = 0.005
    for f in (20.0, 50.0, 100.0):
        om = 2 * np.pi * f
        u, it = hb.solve(om)
        xm = hb.solution(u, om, it).measurement[0]
        ref, _, _ = _fe_response(None, spring, om, zeta)
        # free: |contact force| <= F_s, so its first harmonic is <= 4 F_s / pi (a square wave) and moves
        # x_m by <= (4 F_s/pi) |H_mc| (0 when stuck: then the model is linear and exact);
        # Newton stops at |R| <= 1e-10 |u|, times the condition (< 1e3 off resonance) -> 1e-7 |ref|
        friction = 4 * slip_force / np.pi * abs(model1.modal.receptance(om, "measurement", "contact")) if spring == 0 else 0
        assert abs(xm - ref) <= friction + 1e-7 * abs(ref)
    # peak frequency of the FRF against the FE eigenfrequency
    _, b, kk = _fe_response(None, spring, 1.0, zeta)
    f_r = np.sqrt(eigh(kk, b.mass, eigvals_only=True)[0]) / (2 * np.pi)
    freqs = np.linspace(f_r - 1, f_r + 1, 401)
    amp = [abs(s.measurement[0]) for s in hb.sweep(freqs)]
    f_peak = freqs[int(np.argmax(amp))]
    # grid step, plus the displacement peak's shift from damping: f_r sqrt(1 - 2 zeta^2) -> zeta^2 f_r,
    # times 10 for the other modes' background at the sensor (same order: zeta^2 x |B| / |R_peak| x ...)
    assert abs(f_peak - f_r) <= (freqs[1] - freqs[0]) + 10 * zeta**2 * f_r
    expected = {0.0: 24.09, 3.9e5: 103.88}[spring]  # this model; the seed measured 24 Hz and 86 Hz
    assert f_r == pytest.approx(expected, abs=0.01)


def _longest_stick_run(slipping):
    stick = np.concatenate([~slipping, ~slipping])  # cyclic
    run = best = 0
    for v in stick:
        run = run + 1 if v else 0
        best = max(best, run)
    return min(best, slipping.size)


@pytest.mark.parametrize("config, normal_load, frequency", [
    ("seed004_model1", 0.5, 22.0), ("seed004_model1", 2.0, 60.0), ("seed004_model1", 2.0, 90.0),
    pytest.param("seed004_model2", 0.5, 60.0, marks=pytest.mark.slow),
    pytest.param("seed004_model2", 10.0, 117.0, marks=pytest.mark.slow),
])
def test_hbm_against_newmark_time_domain(config, normal_load, frequency):
    """HBM (harmonics 1..31, N = 1024) against the Newmark reference (1024 steps per period)."""
    model = load_damper_model(CONFIGS / f"{config}.yaml")
    fs = model.slip_force(normal_load)
    n, n_td = 1024, 1024

    def hbm(h_max):
        hb = HarmonicBalance(model.modal, model.contact_stiffness, fs, 2.0, harmonics=tuple(range(1, h_max + 1, 2)),
                             samples_per_period=n)
        return hb, hb.sweep([frequency])[0]

    hb, sol = hbm(31)
    _, sol_half = hbm(15)
    td = steady_state_response(model.modal, model.contact_stiffness, fs, 2.0, frequency, steps_per_period=n_td)
    assert td.converged
    x_td = abs(td.harmonic("measurement", 1))
    om = 2 * np.pi * frequency
    # Tolerance, relative to |x_td|, from the discretisations:
    # - harmonic truncation, two estimates added: (a) the contact-displacement content above harmonic 31
    #   measured in the time-domain response; (b) twice the change from 15 to 31 harmonics (the switching
    #   instants converge slowly in H, order ~0.7 for a Coulomb-like contact: see the Den Hartog test);
    # - AFT sampling: the element is exact at the samples except that a reversal between samples is
    #   missed, which offsets the slider by the overshoot k |x''| dt^2 / 8 (<= 2 F_s) for the stick run
    #   that follows (<= n_s + 1 samples, two reversals per period): |dF_1| <= (2/N) 2 (n_s + 1) delta;
    # - Newmark average acceleration: period elongation (w dt)^2/12; near a resonance with damping
    #   zeta the amplitude moves by at most that / (2 zeta).
    x1 = abs(td.harmonic("contact", 1))
    content = np.sqrt(sum(abs(td.harmonic("contact", h)) ** 2 for h in range(33, n_td // 2, 2))) / x1
    truncation = 2 * abs(abs(sol.measurement[0]) - abs(sol_half.measurement[0])) / x_td
    overshoot = model.contact_stiffness * np.sum(hb.harmonics**2 * np.abs(sol.contact)) * (2 * np.pi / n) ** 2 / 8
    delta = min(2 * fs, overshoot)
    aft = abs(model.modal.receptance(om, "measurement", "contact")) * (2 / n) * 2 * (_longest_stick_run(sol.slipping) + 1)
    aft *= delta / x_td
    newmark = (2 * np.pi / n_td) ** 2 / 12 / (2 * 0.005)
    tol = content + truncation + aft + newmark
    assert abs(abs(sol.measurement[0]) / x_td - 1) <= tol
    # the time-domain loop is really stick-slip here (not a linear case)
    assert np.max(np.abs(td.force)) == pytest.approx(fs, rel=1e-12)
    if config == "seed004_model1":
        assert tol < 0.002  # sharp where the contact is soft (measured 0.04-0.14 %)


def test_seed_frf_sequence_model1(model1):
    """Seed 004, Fig. 3/9: the peak moves from the free beam to the stuck beam as Fn grows, with a
    damped plateau between."""
    freqs = np.linspace(15, 130, 200)
    loads = [0.1, 0.5, 2.0, 5.0, 10.0, 20.0, 40.0, 80.0]
    peaks, amps = [], []
    for fn in loads:
        a = np.array([abs(s.measurement[0]) for s in HarmonicBalance.from_model(model1, fn).sweep(freqs)])
        peaks.append(freqs[np.argmax(a)])
        amps.append(a.max())
    f_free = model1.modal.natural_frequencies[0] / (2 * np.pi)
    f_stuck = model1.modal.with_contact_spring(model1.series_stiffness)[0] / (2 * np.pi)
    step = freqs[1] - freqs[0]
    assert abs(peaks[0] - f_free) <= step
    assert abs(peaks[-1] - f_stuck) <= 0.02 * f_stuck  # 80 N: nearly stuck (2 N force against mu Fn = 36 N)
    assert np.all(np.diff(peaks) >= 0)
    inner = np.array(amps[1:-1])
    assert inner.min() < 0.2 * amps[-1] and inner.min() < 0.2 * amps[0]


def test_aft_jacobian_is_exact(model1):
    """The analytic Jacobian against central differences (the residual is piecewise linear: where the
    stick/slip pattern of the samples does not change inside the step, differences are exact up to
    rounding, ~eps |R| / h)."""
    hb = HarmonicBalance.from_model(model1, 2.0)
    om = 2 * np.pi * 60.0
    u, _ = hb.solve(om)
    sol = hb.solution(u, om)
    assert 0 < sol.slipping.mean() < 1  # a stick-slip point
    _, jac = hb.residual(u, om)
    h = 1e-7 * np.linalg.norm(u)
    fd = np.empty_like(jac)
    for i in range(u.size):
        e = np.zeros(u.size)
        e[i] = h
        fd[:, i] = (hb.residual(u + e, om)[0] - hb.residual(u - e, om)[0]) / (2 * h)
    assert np.allclose(fd, jac, rtol=0, atol=1e-6 * np.abs(jac).max())
