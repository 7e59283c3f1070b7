"""Euler-Bernoulli beam elements (bending in one plane) and a clamped-free beam model.

Two-node Hermite elements with dofs ``(w, theta)`` per node: transverse displacement [m] and
rotation [rad]. Consistent mass. Points of interest (contact, excitation, measurement) become nodes,
so forces and responses there need no interpolation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError

__all__ = [
    "beam_element_stiffness",
    "beam_element_mass",
    "CantileverBeam",
    "cantilever_beam",
]


def beam_element_stiffness(bending_stiffness: float, length: float) -> np.ndarray:
    """Euler-Bernoulli element stiffness matrix (4x4) for dofs (w1, theta1, w2, theta2).

    Parameters
    ----------
    bending_stiffness : float
        ``E I`` [N m^2].
    length : float
        Element length ``l`` [m].

    Returns
    -------
    ndarray, shape (4, 4)
        [N/m, N, N m] blocks (``EI/l^3`` times the classical integer matrix).
    """
    l = float(length)
    return bending_stiffness / l**3 * np.array(
        [
            [12.0, 6 * l, -12.0, 6 * l],
            [6 * l, 4 * l * l, -6 * l, 2 * l * l],
            [-12.0, -6 * l, 12.0, -6 * l],
            [6 * l, 2 * l * l, -6 * l, 4 * l * l],
        ]
    )


def beam_element_mass(mass_per_length: float, length: float) -> np.ndarray:
    """Consistent mass matrix (4x4) of a Hermite beam element, ``rho A l / 420`` times the classical matrix.

    Parameters
    ----------
    mass_per_length : float
        ``rho A`` [kg/m].
    length : float
        Element length [m].
    """
    l = float(length)
    return mass_per_length * l / 420.0 * np.array(
        [
            [156.0, 22 * l, 54.0, -13 * l],
            [22 * l, 4 * l * l, 13 * l, -3 * l * l],
            [54.0, 13 * l, 156.0, -22 * l],
            [-13 * l, -3 * l * l, -22 * l, 4 * l * l],
        ]
    )


@dataclass(frozen=True)
class CantileverBeam:
    """Assembled clamped-free beam (clamp at x = 0 removed from the matrices).

    Attributes
    ----------
    node_x : ndarray
        Node positions from the clamp [m] of the nodes with dofs (x = 0 only for a compliant clamp).
    mass, stiffness : ndarray, shape (2 n_nodes, 2 n_nodes)
        Mass [kg, kg m, kg m^2] and stiffness matrices, dofs ``(w_i, theta_i)`` node by node
        (with a compliant clamp the first dof is the clamp rotation ``theta_0``).
    first_dof_node : int
        1 for a rigid clamp, 0 for a compliant one.
    """

    node_x: np.ndarray
    mass: np.ndarray
    stiffness: np.ndarray
    first_dof_node: int = 1

    def transverse_dof(self, position: float) -> int:
        """Index of the transverse-displacement dof of the node at ``position`` [m] (not the clamp)."""
        i = int(np.argmin(np.abs(self.node_x - position)))
        if abs(self.node_x[i] - position) > 1e-9 * max(1.0, self.node_x[-1]) or self.node_x[i] == 0.0:
            raise ConfigError(f"no free beam node at x = {position} m (nodes are at {self.node_x.min()}..{self.node_x.max()} m)")
        # rigid clamp: dofs (w_i, theta_i) for nodes 1..n; compliant clamp: theta_0, then (w_i, theta_i)
        return 2 * i if self.first_dof_node == 1 else 2 * i - 1


def cantilever_beam(
    length: float,
    width: float,
    thickness: float,
    youngs_modulus: float,
    density: float,
    *,
    n_elements: int = 20,
    points=(),
    tip_mass: float = 0.0,
    clamp_rotational_stiffness: float = np.inf,
) -> CantileverBeam:
    """Clamped-free Euler-Bernoulli beam bending through its thickness.

    Parameters
    ----------
    length, width, thickness : float
        Beam length, section width and thickness (bending direction) [m].
    youngs_modulus : float
        ``E`` [Pa].
    density : float
        ``rho`` [kg/m^3].
    n_elements : int, default 20
        Elements of a uniform mesh; the ``points`` are added as extra nodes.
    points : sequence of float
        Positions from the clamp that must be nodes [m] (contact, excitation, measurement).
    tip_mass : float, default 0
        Point mass at the free end [kg] (transverse dof only).
    clamp_rotational_stiffness : float, default inf
        Rotational spring of a compliant clamp [N m/rad]; ``inf`` clamps the rotation too. The
        transverse displacement at the clamp is always fixed.

    Returns
    -------
    CantileverBeam
    """
    for name, value in (("length", length), ("width", width), ("thickness", thickness),
                        ("youngs_modulus", youngs_modulus), ("density", density)):
        if not (np.isfinite(value) and value > 0):
            raise ConfigError(f"beam {name} must be finite and > 0, got {value!r}", key=f"beam.{name}")
    if not clamp_rotational_stiffness > 0:
        raise ConfigError(f"clamp rotational stiffness must be > 0 N m/rad (inf for a rigid clamp), "
                          f"got {clamp_rotational_stiffness!r}", key="beam.clamp_rotational_stiffness")
    if tip_mass < 0:
        raise ConfigError(f"tip mass must be >= 0 kg, got {tip_mass!r}", key="beam.tip_mass")
    if int(n_elements) < 1:
        raise ConfigError(f"n_elements must be >= 1, got {n_elements!r}", key="beam.n_elements")
    for p in points:
        if not (0.0 < p <= length):
            raise ConfigError(f"point x = {p} m is not on the beam (0, {length}] m", key="beam")
    x = np.linspace(0.0, length, int(n_elements) + 1)
    x = np.unique(np.concatenate([x, np.asarray(points, dtype=float)]))
    # merge nodes closer than a thousandth of an element (a point on a mesh node)
    keep = np.concatenate([[True], np.diff(x) > 1e-3 * length / n_elements])
    x = x[keep]
    for p in points:  # snap merged nodes onto the requested points
        x[np.argmin(np.abs(x - p))] = p
    ei = youngs_modulus * width * thickness**3 / 12.0
    rho_a = density * width * thickness
    n_dof = 2 * x.size
    m = np.zeros((n_dof, n_dof))
    k = np.zeros((n_dof, n_dof))
    for e, le in enumerate(np.diff(x)):
        idx = slice(2 * e, 2 * e + 4)
        k[idx, idx] += beam_element_stiffness(ei, le)
        m[idx, idx] += beam_element_mass(rho_a, le)
    m[-2, -2] += tip_mass
    if np.isinf(clamp_rotational_stiffness):  # rigid clamp: remove w and theta of node 0
        return CantileverBeam(node_x=x[1:], mass=m[2:, 2:], stiffness=k[2:, 2:], first_dof_node=1)
    k[1, 1] += clamp_rotational_stiffness  # compliant clamp: keep theta_0, remove w_0
    return CantileverBeam(node_x=x, mass=m[1:, 1:], stiffness=k[1:, 1:], first_dof_node=0)
