"""Modal model of a linear structure seen from a few dofs (contact, excitation, measurement).

The friction element acts on one dof, the shaker on another, the sensor reads a third. Everything
the harmonic balance needs from the linear structure is the receptance between those dofs,
``H_ab(Omega) = sum_r phi_ar phi_br / (omega_r^2 - Omega^2 + 2 i zeta_r omega_r Omega)``, and the
time-domain reference integrates the same modes. With all modes of the FE model kept this is an
exact (not truncated) reduction of the FE model to the dofs of interest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError

__all__ = ["ModalModel", "modal_model_from_matrices"]


@dataclass(frozen=True)
class ModalModel:
    """Mass-normalised modes at the contact, excitation and measurement dofs.

    Attributes
    ----------
    natural_frequencies : ndarray, shape (n_modes,)
        Undamped natural angular frequencies ``omega_r`` [rad/s].
    damping_ratios : ndarray, shape (n_modes,)
        Modal damping ratios ``zeta_r`` [1].
    contact, excitation, measurement : ndarray, shape (n_modes,)
        Mode shapes at the contact, excitation and measurement dofs [kg^-1/2].
    """

    natural_frequencies: np.ndarray
    damping_ratios: np.ndarray
    contact: np.ndarray
    excitation: np.ndarray
    measurement: np.ndarray

    def receptance(self, angular_frequency, a: str, b: str) -> np.ndarray:
        """Receptance ``H_ab(Omega)`` [m/N] between two of the dofs ``'contact'``, ``'excitation'``,
        ``'measurement'``, at angular frequencies ``Omega`` [rad/s] (any shape)."""
        om = np.asarray(angular_frequency, dtype=float)[..., None]
        w = self.natural_frequencies
        den = w**2 - om**2 + 2j * self.damping_ratios * w * om
        return np.sum(getattr(self, a) * getattr(self, b) / den, axis=-1)

    def with_contact_spring(self, stiffness: float) -> np.ndarray:
        """Natural frequencies [rad/s] of the structure with a spring ``stiffness`` [N/m] from the
        contact dof to ground (the stuck limit), from the modal stiffness ``diag(omega^2) + k phi phi^T``."""
        kmat = np.diag(self.natural_frequencies**2) + stiffness * np.outer(self.contact, self.contact)
        return np.sqrt(np.linalg.eigvalsh(kmat))


def modal_model_from_matrices(mass, stiffness, contact_dof: int, excitation_dof: int, measurement_dof: int,
                              damping_ratio: float, n_modes: int | None = None) -> ModalModel:
    """Modes of ``K phi = omega^2 M phi`` (mass normalised) restricted to three dofs.

    Parameters
    ----------
    mass, stiffness : ndarray, shape (n, n)
        Symmetric mass [kg] and stiffness [N/m] matrices.
    contact_dof, excitation_dof, measurement_dof : int
        Dof indices.
    damping_ratio : float
        Modal damping ratio of every mode [1].
    n_modes : int, optional
        Lowest modes kept (all by default: the reduction is then exact).
    """
    from scipy.linalg import eigh

    if not (0 <= damping_ratio < 1):
        raise ConfigError(f"modal damping ratio must be in [0, 1), got {damping_ratio!r}", key="beam.modal_damping_ratio")
    w2, phi = eigh(stiffness, mass)
    if n_modes is not None:
        w2, phi = w2[:n_modes], phi[:, :n_modes]
    return ModalModel(
        natural_frequencies=np.sqrt(np.maximum(w2, 0.0)),
        damping_ratios=np.full(w2.size, float(damping_ratio)),
        contact=phi[contact_dof].copy(),
        excitation=phi[excitation_dof].copy(),
        measurement=phi[measurement_dof].copy(),
    )
