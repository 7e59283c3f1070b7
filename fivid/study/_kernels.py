"""Numba kernel of the lumped 2-DOF mode-coupling model's transient (L0: numpy and numba only)."""

from numba import njit

__all__ = ["hoffmann_steps"]


@njit(cache=True)
def hoffmann_steps(n_out, n_sub, dt, m, c, k11, k12, k22, k3, d0, mu_s, mu_k, belt_velocity, u, v, out):
    """March the mass on the belt ``n_out * n_sub`` central-difference steps, recording every ``n_sub``.

    ``m x'' + c x' + k11 x + k12 y = F_t``, ``m y'' + c y' + k12 x + k22 y = N``, with the contact spring's normal
    force ``N = k3 (d0 - y)`` while positive (unilateral: 0 once the mass lifts off) and the belt's friction
    ``F_t``: the force that makes the mass move with the belt (stick) if ``|F_t| <= mu_s N``, else
    ``mu_k N`` along the belt's velocity relative to the mass (slip) — the forward-increment treatment of the
    FE solver's contact, exact for stick.

    Parameters
    ----------
    u, v : ndarray, shape (2,)
        Displacement [m] and half-step velocity [m s-1] of (x, y), updated in place.
    out : ndarray, shape (n_out, 6)
        Written: x, y [m], vx, vy [m s-1], N, F_t [N] at the end of each recording interval.
    """
    for r in range(n_out):
        for _ in range(n_sub):
            fx = k11 * u[0] + k12 * u[1] + c * v[0]
            fy = k12 * u[0] + k22 * u[1] + c * v[1]
            normal = k3 * (d0 - u[1])
            if normal < 0.0:
                normal = 0.0
            vx_free = v[0] - dt * fx / m
            f_stick = m * (belt_velocity - vx_free) / dt
            if f_stick <= mu_s * normal and f_stick >= -mu_s * normal:
                ft = f_stick
            else:
                ft = mu_k * normal if f_stick > 0.0 else -mu_k * normal
            v[0] = vx_free + dt * ft / m
            v[1] = v[1] + dt * (normal - fy) / m
            u[0] += dt * v[0]
            u[1] += dt * v[1]
        out[r, 0] = u[0]
        out[r, 1] = u[1]
        out[r, 2] = v[0]
        out[r, 3] = v[1]
        out[r, 4] = normal
        out[r, 5] = ft
    return 0
