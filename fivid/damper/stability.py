"""Stability of periodic solutions: Floquet multipliers of the linearised motion along the orbit.

Method (Floquet, in the time domain along the harmonic-balance orbit, not Hill's method): the
stick/slip pattern of the converged AFT samples gives, sample by sample, a linear system for the
perturbation ``(dq, dq', dz)`` of the modal coordinates and the slider position::

    stick:  dq'' + C dq' + W dq = -phi_c k (phi_c . dq - dz),   dz' = 0
    slip:   dq'' + C dq' + W dq = 0,                             dz' = phi_c . dq'

Entering slip the slider jumps onto the slip surface, ``dz <- phi_c . dq`` (the saltation matrix of
the switch ``k (x - z) = +-F_s``); leaving slip (a velocity reversal) needs no correction because the
vector field is continuous there. The monodromy matrix is the ordered product of the interval
propagators ``expm(A dt)`` and saltations (applied at both ends of each slip run: in slip
``dz = phi_c . dq`` is a constraint); the orbit is stable when every multiplier has ``|mu| <= 1``
(a fully stuck orbit has one multiplier exactly 1: the slider offset is neutral; a fully slipping
one has a multiplier 0 for the slaved slider).
Only the lowest modes enter (the higher ones are linear, damped and weakly coupled).
"""

from __future__ import annotations

import numpy as np

__all__ = ["floquet_multipliers"]


def _state_matrices(omega_r, damping, phi_c, stiffness):
    n = omega_r.size
    a_slip = np.zeros((2 * n + 1, 2 * n + 1))
    a_slip[:n, n:2 * n] = np.eye(n)
    a_slip[n:2 * n, :n] = -np.diag(omega_r**2)
    a_slip[n:2 * n, n:2 * n] = -np.diag(damping)
    a_slip[2 * n, n:2 * n] = phi_c
    a_stick = a_slip.copy()
    a_stick[2 * n, :] = 0.0
    a_stick[n:2 * n, :n] -= stiffness * np.outer(phi_c, phi_c)
    a_stick[n:2 * n, 2 * n] = stiffness * phi_c
    return a_stick, a_slip


def floquet_multipliers(modal, contact_stiffness: float, slipping, angular_frequency: float,
                        n_modes: int = 8) -> np.ndarray:
    """Floquet multipliers of a periodic solution with a Jenkins contact.

    Parameters
    ----------
    modal : ModalModel
    contact_stiffness : float
        Jenkins ``k`` [N/m].
    slipping : ndarray of bool, shape (n_samples,)
        Whether the contact slips at each of the ``N`` equally spaced samples of the period (the
        state over the interval ending at that sample).
    angular_frequency : float
        ``Omega`` [rad/s]; the period is ``2 pi / Omega``.
    n_modes : int, default 8
        Lowest modes kept.

    Returns
    -------
    ndarray of complex
        The ``2 n_modes + 1`` multipliers, sorted by decreasing modulus.
    """
    from scipy.linalg import expm

    m = min(int(n_modes), modal.natural_frequencies.size)
    w = modal.natural_frequencies[:m]
    c = 2 * modal.damping_ratios[:m] * w
    phi = modal.contact[:m]
    slipping = np.asarray(slipping, dtype=bool)
    dt = 2 * np.pi / angular_frequency / slipping.size
    a_stick, a_slip = _state_matrices(w, c, phi, float(contact_stiffness))
    e_stick, e_slip = expm(a_stick * dt), expm(a_slip * dt)
    salt = np.eye(2 * m + 1)
    salt[2 * m, :] = 0.0
    salt[2 * m, :m] = phi
    # run-length encode the pattern; a run of n equal intervals is a matrix power
    edges = np.flatnonzero(np.diff(slipping.astype(int))) + 1
    starts = np.concatenate([[0], edges])
    ends = np.concatenate([edges, [slipping.size]])
    mono = np.eye(2 * m + 1)
    for s, e in zip(starts, ends):
        if slipping[s]:
            # entering slip: dz <- phi_c . dq; while slipping dz stays on phi_c . dq (a constraint,
            # so re-projecting at the end of the run removes the spurious neutral direction of dz)
            mono = salt @ np.linalg.matrix_power(e_slip, int(e - s)) @ salt @ mono
        else:
            mono = np.linalg.matrix_power(e_stick, int(e - s)) @ mono
    mu = np.linalg.eigvals(mono)
    return mu[np.argsort(-np.abs(mu))]
