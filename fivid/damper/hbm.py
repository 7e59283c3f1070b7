"""Harmonic balance with alternating frequency-time (AFT) evaluation of a Jenkins contact force.

Unknowns: the complex amplitudes ``X_h`` (odd harmonics ``h``) of the contact displacement,
``x_c(t) = Re sum_h X_h exp(i h Omega t)``. The linear structure is condensed exactly onto the contact
dof through its receptances (:class:`~fivid.damper.modal.ModalModel`), so the equations are::

    R_h = X_h - H_ce(h Omega) P delta_h1 + H_cc(h Omega) F_h(X) = 0,

with ``F_h`` the Fourier coefficients of the Jenkins force. AFT: sample ``x_c`` at ``N`` points of a
period, march the element over two periods (it is history dependent), take the discrete Fourier
coefficients of the last period. The Jacobian is exact: while stuck since sample ``s`` the force is
``+-F_s + k (x_j - x_s)``, so ``dF_j/dX = k (e_j - e_s)``; while slipping it is 0.

Odd harmonics only: with symmetric forcing the steady loop is half-wave symmetric
(``x(t + T/2) = -x(t)``), which the Jenkins element preserves, so even harmonics and the mean vanish.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from fivid.damper.model import DamperModel
from fivid.damper.modal import ModalModel
from fivid.errors import FividError
from fivid.friction.jenkins import jenkins_periodic_force

_log = logging.getLogger("fivid")

__all__ = ["HarmonicBalance", "PeriodicSolution"]


@dataclass(frozen=True)
class PeriodicSolution:
    """A converged periodic response at one excitation frequency.

    Attributes
    ----------
    frequency : float
        Excitation frequency [Hz].
    contact : ndarray of complex, shape (n_harmonics,)
        Complex amplitudes of the contact displacement per harmonic [m].
    measurement : ndarray of complex, shape (n_harmonics,)
        Complex amplitudes of the measured displacement per harmonic [m].
    force : ndarray of complex, shape (n_harmonics,)
        Complex amplitudes of the contact force [N].
    iterations : int
        Newton iterations used.
    slipping : ndarray of bool, shape (n_samples,)
        Whether the contact slips at each AFT sample of the period.
    """

    frequency: float
    contact: np.ndarray
    measurement: np.ndarray
    force: np.ndarray
    iterations: int
    slipping: np.ndarray


class HarmonicBalance:
    """Harmonic-balance equations of a modal structure with one Jenkins contact.

    Parameters
    ----------
    modal : ModalModel
        Linear structure.
    contact_stiffness : float
        Jenkins stiffness ``k`` [N/m].
    slip_force : float
        Jenkins slip force ``F_s = mu F_n`` [N].
    excitation_amplitude : float
        Harmonic force amplitude ``P`` [N].
    harmonics : sequence of int
        Odd harmonics kept (1 must be one of them).
    samples_per_period : int
        AFT samples per period ``N``.
    """

    def __init__(self, modal: ModalModel, contact_stiffness: float, slip_force: float, excitation_amplitude: float,
                 harmonics=(1, 3, 5, 7), samples_per_period: int = 128):
        self.modal = modal
        self.k = float(contact_stiffness)
        self.fs = float(slip_force)
        if not (self.k > 0 and self.fs > 0 and np.isfinite(self.k) and np.isfinite(self.fs)):
            raise FividError(f"contact stiffness ({contact_stiffness}) and slip force ({slip_force}) must be finite and > 0")
        self.p = float(excitation_amplitude)
        self.harmonics = np.asarray(harmonics, dtype=int)
        if self.harmonics[0] != 1 or np.any(self.harmonics % 2 == 0):
            raise FividError(f"harmonics must be odd and start at 1, got {list(harmonics)}")
        n = int(samples_per_period)
        if n < 4 * self.harmonics.max():
            raise FividError(f"samples_per_period {n} is below 4 x the highest harmonic {self.harmonics.max()}")
        self.n_samples = n
        theta = 2 * np.pi * np.arange(n) / n
        ht = np.outer(theta, self.harmonics)
        # x_j = sum_h Re X_h cos(h theta_j) - Im X_h sin(h theta_j); u = [Re X_1, Im X_1, Re X_3, ...]
        self.basis = np.empty((n, 2 * self.harmonics.size))
        self.basis[:, 0::2] = np.cos(ht)
        self.basis[:, 1::2] = -np.sin(ht)
        self.projection = (2.0 / n) * self.basis.T  # force samples -> [Re F_h, Im F_h]
        self._basis_mean = self.basis.mean(axis=0)
        self.n_unknowns = 2 * self.harmonics.size

    @classmethod
    def from_model(cls, model: DamperModel, normal_force: float) -> "HarmonicBalance":
        """The equations for a :class:`DamperModel` at a normal force [N]."""
        if not (np.isfinite(normal_force) and normal_force > 0):
            raise FividError(f"normal force must be finite and > 0 N, got {normal_force!r}")
        return cls(model.modal, model.series_stiffness, model.slip_force(normal_force), model.excitation_amplitude,
                   model.harmonics, model.samples_per_period)

    # --- pieces -------------------------------------------------------------------------------
    def _real_block(self, h: np.ndarray) -> np.ndarray:
        """Block-diagonal real matrix of complex multiplication by ``h`` (one 2x2 block per harmonic)."""
        m = np.zeros((self.n_unknowns, self.n_unknowns))
        i = np.arange(0, self.n_unknowns, 2)
        m[i, i] = m[i + 1, i + 1] = h.real
        m[i, i + 1] = -h.imag
        m[i + 1, i] = h.imag
        return m

    def linear_part(self, omega: float):
        """``u_lin`` (the response without contact force) and the receptance block ``H_cc`` at ``Omega`` [rad/s]."""
        hw = self.harmonics * omega
        u_lin = np.zeros(self.n_unknowns)
        h_ce = self.modal.receptance(omega, "contact", "excitation") * self.p
        u_lin[0], u_lin[1] = h_ce.real, h_ce.imag
        return u_lin, self._real_block(self.modal.receptance(hw, "contact", "contact"))

    def linear_start(self, omega: float, stuck: bool) -> np.ndarray:
        """First-harmonic response with the contact free (``stuck=False``) or replaced by its spring."""
        h_ce = self.modal.receptance(omega, "contact", "excitation") * self.p
        if stuck:
            h_ce = h_ce / (1.0 + self.k * self.modal.receptance(omega, "contact", "contact"))
        u = np.zeros(self.n_unknowns)
        u[0], u[1] = h_ce.real, h_ce.imag
        return u

    def contact_force(self, u: np.ndarray, jacobian: bool = True):
        """Fourier coefficients ``[Re F_h, Im F_h]`` [N] of the Jenkins force and their derivative [N/m]."""
        x = (self.basis @ u)[None, :]
        f, anchor = jenkins_periodic_force(x, self.k, self.fs, n_passes=2)
        coeffs = self.projection @ f[0]
        if not jacobian:
            return coeffs, None
        a = anchor[0]
        dfdu = np.zeros_like(self.basis)
        stick = a >= 0
        dfdu[stick] = self.k * (self.basis[stick] - self.basis[a[stick]])
        init = a == -2
        dfdu[init] = self.k * (self.basis[init] - self._basis_mean)
        return coeffs, self.projection @ dfdu

    def residual(self, u: np.ndarray, omega: float, *, frequency_derivative: bool = False):
        """Residual ``R`` [m] and Jacobian ``dR/du`` [1] of the harmonic-balance equations.

        With ``frequency_derivative`` also ``dR/dOmega`` [m s/rad] (by a forward difference of the
        receptances only: the Jenkins force is rate independent, ``F(u)`` does not depend on ``Omega``;
        step ``1e-7 Omega`` -> relative error ~1e-7 against the continuation's needs of ~1e-3).
        """
        u_lin, h = self.linear_part(omega)
        coeffs, dcoeffs = self.contact_force(u)
        r = u - u_lin + h @ coeffs
        jac = np.eye(self.n_unknowns) + h @ dcoeffs
        if not frequency_derivative:
            return r, jac
        d = 1e-7 * omega
        u_lin2, h2 = self.linear_part(omega + d)
        return r, jac, ((u - u_lin2 + h2 @ coeffs) - r) / d

    def solution(self, u: np.ndarray, omega: float, iterations: int = 0) -> PeriodicSolution:
        """Package a solution vector ``u`` at ``Omega`` [rad/s]."""
        f, anchor = jenkins_periodic_force((self.basis @ u)[None, :], self.k, self.fs, n_passes=2)
        coeffs = self.projection @ f[0]
        fc = coeffs[0::2] + 1j * coeffs[1::2]
        xc = u[0::2] + 1j * u[1::2]
        hw = self.harmonics * omega
        xm = -self.modal.receptance(hw, "measurement", "contact") * fc
        xm[0] += self.modal.receptance(omega, "measurement", "excitation") * self.p
        return PeriodicSolution(frequency=omega / (2 * np.pi), contact=xc, measurement=xm, force=fc, iterations=iterations,
                                slipping=anchor[0] == -1)

    # --- solvers ------------------------------------------------------------------------------
    def solve(self, omega: float, u0=None, *, rtol: float = 1e-10, max_iterations: int = 20):
        """Newton-Raphson at a fixed ``Omega`` [rad/s].

        The residual is piecewise linear in ``u`` (the force is linear in ``u`` while the stick/slip
        pattern of the samples does not change), so Newton ends in a few iterations; a backtracking
        line search on ``|R|`` guards the first ones. Starts: ``u0``, then the free and stuck linear
        responses; then MINPACK ``hybr``; last, the best point is accepted if its residual is
        below the AFT resolution (see the comment in the code), else :class:`FividError`.

        Returns
        -------
        u : ndarray
            ``[Re X_1, Im X_1, ...]`` [m].
        iterations : int
        """
        u_lin, _ = self.linear_part(omega)
        scale = max(np.linalg.norm(u_lin), self.fs / self.k, 1e-300)
        best = (None, np.inf)
        if u0 is not None:  # the given guess first (continuation), then the linear starts
            u = np.array(u0, dtype=float)
            out = self._newton(omega, u, *self.residual(u, omega), rtol * scale, rtol, max_iterations)
            if out[1] is not None:
                return out[0], out[1]
            best = min(best, (out[0], out[2]), key=lambda t: t[1])
        # free contact and stuck contact, the smaller residual first
        starts = [self.linear_start(omega, stuck) for stuck in (False, True)]
        tried = sorted(((u, *self.residual(u, omega)) for u in starts), key=lambda t: np.linalg.norm(t[1]))
        for u, r, j in tried:
            out = self._newton(omega, u, r, j, rtol * scale, rtol, max_iterations)
            if out[1] is not None:
                return out[0], out[1]
            best = min(best, (out[0], out[2]), key=lambda t: t[1])
        # Newton can cycle between stick/slip patterns of the samples: MINPACK's hybrid method
        # (trust region, same exact Jacobian) from the best point so far
        from scipy.optimize import root

        sol = root(lambda v: self.residual(v, omega), best[0], jac=True, method="hybr",
                   options={"xtol": rtol, "maxfev": 50 * max_iterations})
        r_end = np.linalg.norm(self.residual(sol.x, omega)[0])
        if r_end <= max(rtol * scale, rtol * np.linalg.norm(sol.x)):
            return sol.x, int(sol.nfev)
        best = min(best, (sol.x, r_end), key=lambda t: t[1])
        # With a stiff contact the stick phases can be shorter than a sample: the sampled force then
        # jumps (a reversal moves by one sample) and the discrete residual may have no exact root.
        # Accept the best point when |R| is below that resolution: one sample's jump of 2 F_s at each
        # of the two reversals changes every force harmonic by <= 8 F_s / N, and R by
        # <= |H_cc(h Omega)|_2 8 F_s / N.
        resolution = np.sqrt(np.sum(np.abs(self.modal.receptance(self.harmonics * omega, "contact", "contact")) ** 2))
        resolution *= 8 * self.fs / self.n_samples
        if best[1] <= resolution:
            _log.debug("HBM at %.4g Hz: |R| = %.3g m accepted (AFT resolution %.3g m)", omega / (2 * np.pi), best[1],
                       resolution)
            return best[0], max_iterations
        raise FividError(f"harmonic balance did not converge at {omega / (2 * np.pi):.4g} Hz "
                         f"(|R| = {best[1]:.3g} m, above the AFT resolution {resolution:.3g} m, from each start); "
                         "try more samples_per_period")

    def _newton(self, omega, u, r, j, abs_tol, rtol, max_iterations):
        """Damped Newton; returns ``(u, iterations, |R|)`` with ``iterations`` None if not converged."""
        norm = np.linalg.norm(r)
        best_u, best_norm = u, norm
        # |R| in metres against the response scale: float resolution x the condition of the Jacobian
        # (~1/(2 zeta) near a resonance) is ~1e-13, so 1e-10 is reachable and far below any physical tolerance
        for it in range(max_iterations + 1):
            if norm <= max(abs_tol, rtol * np.linalg.norm(u)):
                return u, it, norm
            try:
                du = np.linalg.solve(j, -r)
            except np.linalg.LinAlgError:  # singular at this stick/slip pattern: let the caller restart
                break
            step = 1.0
            while True:
                u_new = u + step * du
                r_new, j_new = self.residual(u_new, omega)
                if np.linalg.norm(r_new) < norm or step < 1e-4:
                    break
                step *= 0.5
            u, r, j, norm = u_new, r_new, j_new, np.linalg.norm(r_new)
            if norm < best_norm:
                best_u, best_norm = u, norm
        return best_u, None, best_norm

    def sweep(self, frequencies, *, rtol: float = 1e-10):
        """Periodic solutions at the given frequencies [Hz], each started from the previous one.

        Returns
        -------
        list of PeriodicSolution
        """
        out = []
        u, om_prev = None, None
        for f in np.asarray(frequencies, dtype=float):
            om = 2 * np.pi * f
            u, it = self._reach(om, om_prev, u, rtol, depth=6)
            out.append(self.solution(u, om, it))
            om_prev = om
        return out

    def _reach(self, om, om_prev, u_prev, rtol, depth):
        """Solve at ``om`` from the solution at ``om_prev``; on failure halve the frequency step."""
        try:
            return self.solve(om, u_prev, rtol=rtol)
        except FividError:
            if depth == 0 or om_prev is None:
                raise
        mid = 0.5 * (om + om_prev)
        u_mid, _ = self._reach(mid, om_prev, u_prev, rtol, depth - 1)
        return self._reach(om, mid, u_mid, rtol, depth - 1)
