"""Jenkins element kernels (L0: numpy and numba only).

A Jenkins element is a spring of stiffness ``k`` in series with a Coulomb slider of slip force
``fs``. Its one update rule, :func:`jenkins_return_map` (elastic predictor, return to the slip surface), serves
both kernels here: :func:`jenkins_march` drives the element by a displacement history (rate independent:
exact for a piecewise-linear path between samples), :func:`newmark_jenkins` marches a modal structure with
one Jenkins contact in time (the friction dampers of seed 004, :mod:`fivid.damper.timedomain`).
"""

import math

from numba import njit

__all__ = ["jenkins_return_map", "jenkins_march", "newmark_jenkins"]


@njit(cache=True)
def jenkins_return_map(f_prev, dx, stiffness, slip_force):
    """Force after a displacement increment ``dx`` [m] from force ``f_prev`` [N]: ``(f [N], slipped)``.

    Elastic predictor ``f_prev + stiffness dx``, returned to ``+-slip_force`` when it leaves the slip surface.
    """
    trial = f_prev + stiffness * dx
    if trial > slip_force:
        return slip_force, True
    if trial < -slip_force:
        return -slip_force, True
    return trial, False


@njit(cache=True)
def jenkins_march(x, stiffness, slip_force, initial_force, n_passes, force_out, anchor_out):
    """March a batch of Jenkins elements along displacement histories.

    Parameters
    ----------
    x : ndarray, shape (n_paths, n_samples)
        Displacements [m]. With ``n_passes > 1`` each row is one period, marched repeatedly.
    stiffness, slip_force : float
        Spring stiffness [N/m] and slip force [N] (> 0).
    initial_force : ndarray, shape (n_paths,)
        Force before the first sample's increment [N] (|f| <= slip_force), taken at ``x[:, 0]``.
    n_passes : int
        Number of passes over the samples; the outputs hold the last pass.
    force_out : ndarray, shape (n_paths, n_samples)
        Element force [N] (written).
    anchor_out : ndarray of int64, shape (n_paths, n_samples)
        Where the element sticks, the sample index at which the current stick phase began
        (its force there was +-slip_force); ``-1`` while slipping; ``-2`` while still stuck in the
        initial state (never slipped).
    """
    n_paths, n = x.shape
    for p in range(n_paths):
        f = initial_force[p]
        anchor = -2
        if abs(f) >= slip_force:
            anchor = -1
        xprev = x[p, 0]
        for _ in range(n_passes):
            for j in range(n):
                xj = x[p, j]
                f, slipped = jenkins_return_map(f, xj - xprev, stiffness, slip_force)
                if slipped:
                    anchor = -1
                elif anchor == -1:
                    anchor = j - 1 if j > 0 else n - 1
                force_out[p, j] = f
                anchor_out[p, j] = anchor
                xprev = xj
    return 0


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
        # stick trial (x_c from the linear system with the stick law), then return to the slip surface
        xc = (x_lin + g * (stiffness * xc_prev - f_prev)) / (1.0 + g * stiffness)
        f, slipped = jenkins_return_map(f_prev, xc - xc_prev, stiffness, slip_force)
        if slipped:
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
