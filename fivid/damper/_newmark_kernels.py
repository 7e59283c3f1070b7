"""Newmark (average acceleration) march of a modal structure with one Jenkins contact (L0 kernel)."""

import math

from numba import njit

__all__ = ["newmark_jenkins"]


@njit(cache=True)
def newmark_jenkins(omega2, damping, phi_c, phi_e, phi_m, force_amplitude, angular_frequency, dt, t0,
                    stiffness, slip_force, q, v, a, state, xm_out, xc_out, fc_out):
    """March ``q'' + c q' + omega^2 q = phi_e P cos(Omega t) - phi_c f`` with a Jenkins force ``f``.

    Average-acceleration Newmark (gamma = 1/2, beta = 1/4). Per step the modal equations are
    diagonal except for the contact force, a scalar function of the contact displacement ``x_c``, so
    the Newton-Raphson iteration reduces to one scalar equation ``x_c + g f(x_c) = x_lin``; ``f`` is
    piecewise linear (stick: ``f_n + k (x_c - x_c,n)``; slip: ``+-F_s``), so Newton with the
    consistent tangent ends after the stick trial and at most one slip correction (return mapping).

    Parameters
    ----------
    omega2, damping, phi_c, phi_e, phi_m : ndarray, shape (n_modes,)
        ``omega_r^2`` [rad^2/s^2], ``2 zeta_r omega_r`` [1/s], mode shapes at contact, excitation,
        measurement.
    force_amplitude, angular_frequency, dt, t0 : float
        ``P`` [N], ``Omega`` [rad/s], time step [s], time of the state on entry [s].
    stiffness, slip_force : float
        Jenkins ``k`` [N/m], ``F_s`` [N].
    q, v, a : ndarray, shape (n_modes,)
        Modal displacement, velocity, acceleration (updated in place).
    state : ndarray, shape (2,)
        ``[f, x_c]`` contact force and displacement of the last step (updated in place).
    xm_out, xc_out, fc_out : ndarray, shape (n_steps,)
        Measured and contact displacement [m] and contact force [N] after each step (written).
    """
    n = q.size
    c0 = 4.0 / (dt * dt)
    c1 = 2.0 / dt
    g = 0.0
    for r in range(n):
        g += phi_c[r] * phi_c[r] / (c0 + c1 * damping[r] + omega2[r])
    f_prev = state[0]
    xc_prev = state[1]
    for s in range(xm_out.size):
        t = t0 + (s + 1) * dt
        load = force_amplitude * math.cos(angular_frequency * t)
        x_lin = 0.0
        for r in range(n):
            rhs = phi_e[r] * load + c0 * (q[r] + dt * v[r]) + a[r] + damping[r] * (c1 * q[r] + v[r])
            x_lin += phi_c[r] * rhs / (c0 + c1 * damping[r] + omega2[r])
        # stick trial, then return to the slip surface
        xc = (x_lin + g * (stiffness * xc_prev - f_prev)) / (1.0 + g * stiffness)
        f = f_prev + stiffness * (xc - xc_prev)
        if f > slip_force or f < -slip_force:
            f = slip_force if f > 0 else -slip_force
            xc = x_lin - g * f
        xm = 0.0
        for r in range(n):
            rhs = phi_e[r] * load + c0 * (q[r] + dt * v[r]) + a[r] + damping[r] * (c1 * q[r] + v[r])
            qn = (rhs - phi_c[r] * f) / (c0 + c1 * damping[r] + omega2[r])
            an = c0 * (qn - q[r] - dt * v[r]) - a[r]
            v[r] = v[r] + 0.5 * dt * (a[r] + an)
            a[r] = an
            q[r] = qn
            xm += phi_m[r] * qn
        f_prev = f
        xc_prev = xc
        xm_out[s] = xm
        xc_out[s] = xc
        fc_out[s] = f
    state[0] = f_prev
    state[1] = xc_prev
    return 0
