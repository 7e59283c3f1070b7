"""The finite-element model of a rig: structured Q4 blocks, constraints, discrete elements, contact, sensors.

A :class:`Model` is built from a YAML configuration by :func:`fivid.fe.build.load_model` (validation in
:mod:`fivid.fe.config`) and is plain data: numpy arrays and frozen dataclasses, no behaviour beyond
index arithmetic. Assembly (:mod:`fivid.fe.assembly`), modal analysis (:mod:`fivid.fe.modal`), CEA
(:mod:`fivid.fe.cea`) and the explicit solver (:mod:`fivid.solver`) read it.

Numbering
---------
A block is a quadrilateral with corners ``c0..c3`` counter-clockwise from bottom-left, meshed
``nx x ny`` with bilinear Q4 elements by the bilinear map of the corners. Local node ``(i, j)``,
``i = 0..nx`` along ``c0 -> c1``, ``j = 0..ny`` along ``c0 -> c3``, has the global number
``node_offset + j*(nx+1) + i``; its dofs are ``2*node`` (x) and ``2*node + 1`` (y). Blocks do not
share nodes; contact pairs couple them. Edges: ``bottom`` (c0 -> c1), ``right`` (c1 -> c2),
``top`` (c2 -> c3), ``left`` (c3 -> c0); :meth:`Block.edge_nodes` lists an edge's nodes in that
direction (so the outward normal of a segment ``(a, b)`` is the tangent ``b - a`` turned clockwise).

Mapped blocks keep this numbering; only the node coordinates change. An annular block (``shape =
"annulus"``) runs ``i`` clockwise (decreasing angle, from the end angle to the start angle) and ``j``
outward from the inner radius, so that its elements are counter-clockwise: ``bottom`` is the inner
surface (alias ``inner``), ``top`` the outer (``outer``), ``right`` the start-angle side (``start``),
``left`` the end-angle side (``end``). A full ring is ``periodic``: it has ``nx`` node columns, not
``nx + 1`` (column ``nx`` *is* column 0, the seam), node ``(i, j)`` is ``node_offset + j*nx + i mod nx``,
and it has no left/right edge. A ``profile`` block is a rectangle whose bottom or top edge follows a
height profile h(x).

Constraints
-----------
Blocks of one body may be joined by :class:`Tie` rows (a fine block's edge nodes interpolated on a coarser
block's edge, :mod:`fivid.fe.transition`): a tied (slave) node's dofs are not independent, so they are not in
``free_dofs``; assembly (:func:`fivid.fe.assembly.tie_matrix`) and the explicit kernel eliminate them.

``fixed_dofs`` is every constrained dof: the dofs of clamped edges and the dofs carrying a
:class:`Motion`. A dof in ``fixed_dofs`` with no motion stays at zero; a dof with a motion follows it.
A motion on a clamped edge therefore moves the clamp (the moving base, the loading clamp): the other
component stays clamped. Modal analysis and CEA eliminate all of ``fixed_dofs``.

Units: SI everywhere (m, kg, s, N, Pa).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from fivid.contact import RIGID
from fivid.errors import ConfigError
from fivid.friction.curve import FrictionCurve

__all__ = [
    "EDGES",
    "Material",
    "Block",
    "Motion",
    "PointMass",
    "Spring",
    "ContactPair",
    "Sensor",
    "PressureLoad",
    "Reaction",
    "Tie",
    "Model",
]

EDGES = ("bottom", "right", "top", "left")
#: edge names of annular blocks, as aliases of :data:`EDGES`
ANNULUS_EDGES = {"inner": "bottom", "start": "right", "outer": "top", "end": "left"}
#: block shapes
SHAPES = ("quad", "annulus", "profile")


@dataclass(frozen=True)
class Material:
    """Linear elastic isotropic material.

    Parameters
    ----------
    E : float
        Young's modulus [Pa].
    nu : float
        Poisson's ratio [-], ``-1 < nu < 0.5``.
    rho : float
        Density [kg m-3].
    """

    E: float
    nu: float
    rho: float

    def elasticity_matrix(self, plane: str) -> np.ndarray:
        """The 3x3 matrix D with ``sigma = D eps`` (engineering shear strain) [Pa].

        Parameters
        ----------
        plane : {"stress", "strain"}
            Plane stress (thin plate, ``sigma_zz = 0``) or plane strain (``eps_zz = 0``).
        """
        E, nu = self.E, self.nu
        if plane == "stress":
            c = E / (1.0 - nu * nu)
            return c * np.array([[1.0, nu, 0.0], [nu, 1.0, 0.0], [0.0, 0.0, (1.0 - nu) / 2.0]])
        if plane == "strain":
            c = E / ((1.0 + nu) * (1.0 - 2.0 * nu))
            return c * np.array([[1.0 - nu, nu, 0.0], [nu, 1.0 - nu, 0.0], [0.0, 0.0, (1.0 - 2.0 * nu) / 2.0]])
        raise ConfigError(f"plane must be 'stress' or 'strain', got {plane!r}", key="plane")


@dataclass(frozen=True, eq=False)
class Block:
    """A logically structured quadrilateral block of ``nx x ny`` Q4 elements.

    Parameters
    ----------
    name : str
        Body name from the config.
    corners : ndarray, shape (4, 2)
        Corners [m], counter-clockwise from bottom-left.
    nx, ny : int
        Element divisions along ``c0 -> c1`` and ``c0 -> c3``.
    material : Material
    thickness : float
        Out-of-plane thickness (the beam width) [m].
    plane : {"stress", "strain"}
    node_offset : int
        Global number of local node (0, 0).
    coords : ndarray, shape (ny+1, nx+1, 2)
        Node coordinates [m], ``coords[j, i]`` is local node ``(i, j)``.
    initial_velocity : ndarray, shape (2,)
        Initial velocity of every node of the block [m s-1].
    shape : {"quad", "annulus", "profile"}
        How ``coords`` were generated: bilinear map of the corners, annular sector, or a rectangle with one
        edge following a height profile (see the module docstring). ``corners`` of mapped blocks are the
        coordinates of their four corner nodes (of the last column for a periodic ring).
    periodic : bool
        A full ring closing on itself: ``nx`` node columns, column ``nx`` wraps to column 0.
    mass_scale : float
        Factor on the density in the block's mass matrices only [-] (conventional mass scaling,
        :mod:`fivid.fe.mass_scaling`; 1: none). The stiffness is unchanged.
    """

    name: str
    corners: np.ndarray
    nx: int
    ny: int
    material: Material
    thickness: float
    plane: str
    node_offset: int
    coords: np.ndarray
    initial_velocity: np.ndarray = field(default_factory=lambda: np.zeros(2))
    shape: str = "quad"
    periodic: bool = False
    mass_scale: float = 1.0

    @property
    def n_cols(self) -> int:
        """Node columns per row: ``nx + 1``, or ``nx`` for a periodic ring (also the row stride)."""
        return self.nx if self.periodic else self.nx + 1

    @property
    def n_nodes(self) -> int:
        """Number of nodes ``n_cols (ny+1)``."""
        return self.n_cols * (self.ny + 1)

    @property
    def n_elements(self) -> int:
        """Number of elements ``nx*ny``."""
        return self.nx * self.ny

    def node(self, i, j):
        """Global node number(s) of local node(s) ``(i, j)`` (``i`` taken modulo ``nx`` on a periodic ring)."""
        i = np.asarray(i) % self.nx if self.periodic else np.asarray(i)
        return self.node_offset + np.asarray(j) * self.n_cols + i

    def node_numbers(self) -> np.ndarray:
        """Global node numbers, shape (ny+1, n_cols), ``[j, i]``."""
        return self.node_offset + np.arange(self.n_nodes).reshape(self.ny + 1, self.n_cols)

    @property
    def edge_names(self) -> tuple:
        """The edges this block has (annular blocks also accept the names of :data:`ANNULUS_EDGES`)."""
        names = ("bottom", "top") if self.periodic else EDGES
        if self.shape == "annulus":
            names = names + tuple(k for k, v in ANNULUS_EDGES.items() if v in names)
        return names

    def _edge(self, edge: str) -> str:
        if edge not in self.edge_names:
            raise ConfigError(f"edge must be one of {self.edge_names} for body {self.name!r}, got {edge!r}",
                              key=f"bodies.{self.name}.edge")
        return ANNULUS_EDGES.get(edge, edge)

    def edge_nodes(self, edge: str) -> np.ndarray:
        """Global node numbers along ``edge`` in its direction (bottom c0->c1, right c1->c2, top c2->c3, left c3->c0).

        On a periodic ring the inner (bottom) and outer (top) edges are closed: every node appears once, and
        the last node is followed by the first (see :meth:`edge_segments`).
        """
        n = self.node_numbers()
        edge = self._edge(edge)
        if edge == "bottom":
            return n[0, :].copy()
        if edge == "right":
            return n[:, -1].copy()
        if edge == "top":
            return n[-1, ::-1].copy()
        return n[::-1, 0].copy()

    def edge_segments(self, edge: str, nodes=None) -> np.ndarray:
        """Node pairs ``(a, b)`` of the segments of ``edge`` whose two nodes are both in ``nodes`` (default: all),
        shape (n, 2), in edge order.

        A periodic ring's inner/outer edge is closed: its last node is joined back to its first (so a subset
        across the seam keeps its segments, and never joins nodes that are not neighbours). The outward normal
        of a segment is ``b - a`` turned clockwise.
        """
        full = self.edge_nodes(edge)
        seg = np.column_stack([full[:-1], full[1:]])
        if self.periodic:
            seg = np.vstack([seg, [full[-1], full[0]]])
        if nodes is not None:
            keep = np.isin(seg, np.asarray(nodes)).all(axis=1)
            seg = seg[keep]
        return seg.astype(np.int64)

    def _wrapped(self, a: np.ndarray) -> np.ndarray:
        """``a`` (ny+1, n_cols, ...) with column 0 appended after the last on a periodic ring: (ny+1, nx+1, ...)."""
        return np.concatenate([a, a[:, :1]], axis=1) if self.periodic else a

    def element_nodes(self) -> np.ndarray:
        """Global node numbers of every element, shape (ny, nx, 4), counter-clockwise from the element's (i, j)."""
        n = self._wrapped(self.node_numbers())
        return np.stack([n[:-1, :-1], n[:-1, 1:], n[1:, 1:], n[1:, :-1]], axis=-1)

    def element_corners(self) -> np.ndarray:
        """Coordinates of every element's 4 nodes [m], shape (ny, nx, 4, 2), same order as :meth:`element_nodes`."""
        c = self._wrapped(self.coords)
        return np.stack([c[:-1, :-1], c[:-1, 1:], c[1:, 1:], c[1:, :-1]], axis=-2)

    def element_dofs(self) -> np.ndarray:
        """Global dofs of every element, shape (ny, nx, 8): ``x0, y0, x1, y1, ...``."""
        en = self.element_nodes()
        return np.stack([2 * en, 2 * en + 1], axis=-1).reshape(self.ny, self.nx, 8)

    def is_rectangular_grid(self, rtol: float = 1e-12) -> bool:
        """Whether every element is the same axis-aligned rectangle (one stencil for the whole block)."""
        xy = self.element_corners().reshape(-1, 4, 2)
        d = xy - xy[:, :1, :]
        scale = float(np.abs(self.corners).max() + np.ptp(self.corners))
        return bool(np.allclose(d, d[0], rtol=0.0, atol=rtol * scale) and abs(d[0, 1, 1]) <= rtol * scale
                    and abs(d[0, 3, 0]) <= rtol * scale)


@dataclass(frozen=True, eq=False)
class Motion:
    """An imposed motion of one displacement component on a set of nodes.

    Parameters
    ----------
    name : str
    nodes : ndarray of int
        Global node numbers (an edge's nodes, in order).
    component : {0, 1}
        0 = x, 1 = y.
    kind : {"velocity", "displacement"}
        What ``amplitude`` is: a final velocity [m s-1] or a final displacement [m].
    amplitude : float
        Target value reached after ``ramp_time`` [m s-1 or m]; the solver may override it
        (``--velocity`` for role "base", ``--load`` for role "load").
    ramp_time : float
        Duration of the smooth ramp from 0 to ``amplitude`` [s].
    role : {"base", "load", None}
        "base": the moving base (sliding velocity); "load": the loading clamp (normal load); None: other.
    """

    name: str
    nodes: np.ndarray
    component: int
    kind: str
    amplitude: float
    ramp_time: float
    role: str | None = None

    @property
    def dofs(self) -> np.ndarray:
        """Global dofs the motion drives."""
        return 2 * np.asarray(self.nodes) + self.component


@dataclass(frozen=True)
class PointMass:
    """A point mass [kg] on a node (added to both of its dofs)."""

    name: str
    node: int
    mass: float


@dataclass(frozen=True)
class Spring:
    """A spring and dashpot in one component between two nodes, or a node and the ground (``node_b = -1``).

    Parameters
    ----------
    name : str
    node_a, node_b : int
        Global node numbers; ``node_b = -1`` is the ground.
    component : {0, 1}
        0 = x, 1 = y.
    stiffness : float
        [N m-1].
    damping : float
        Dashpot coefficient [N s m-1].
    """

    name: str
    node_a: int
    node_b: int
    component: int
    stiffness: float
    damping: float = 0.0


@dataclass(frozen=True, eq=False)
class ContactPair:
    """Slave nodes of one body's edge against master segments of another body's edge.

    Parameters
    ----------
    name : str
    slave_block, master_block : str
        Body names.
    slave_nodes : ndarray of int
        Global slave node numbers in edge order.
    master_nodes : ndarray of int
        Global master node numbers in edge order; consecutive nodes form the segments, whose outward
        normal is the segment tangent turned clockwise.
    mu : float
        Nominal (mean) friction coefficient μ0 [-].
    normal_stiffness : float
        Penalty stiffness per unit contact area [N m-3] of the rigid law's linearised (CEA/modal) contact;
        the explicit solver enforces the rigid law with Lagrange multipliers and ignores it. The compliant
        laws use their own tangent instead.
    law : fivid.contact.NormalLaw
        Normal contact law (default rigid).
    friction : fivid.friction.FrictionCurve
        Static excess, Stribeck curve and viscous term over the kinetic ``mu`` (default: plain Coulomb).
    rigid : fivid.contact.RigidSurface or None
        A rigid master surface instead of a body's edge (then ``master_block`` is ``""`` and ``master_nodes``
        is empty).
    """

    name: str
    slave_block: str
    slave_nodes: np.ndarray
    master_block: str
    master_nodes: np.ndarray
    mu: float
    normal_stiffness: float
    law: object = None
    friction: object = None
    rigid: object = None

    def __post_init__(self):
        if self.law is None:
            object.__setattr__(self, "law", RIGID)
        if self.friction is None:
            object.__setattr__(self, "friction", FrictionCurve())


@dataclass(frozen=True, eq=False)
class PressureLoad:
    """A uniform pressure on (part of) a body's edge, ramped smoothly from 0 to ``pressure``.

    Positive pressure pushes on the surface (along the inward normal). The nodal forces are the consistent
    forces of a uniform traction on the reference (undeformed) segments, ``-p t L/2 n`` on each end node of a
    segment of length ``L`` and outward normal ``n``, and their direction is fixed (a dead load, not a
    follower load): the small-displacement solver has no geometry update to follow.

    Parameters
    ----------
    name : str
    body : str
    segments : ndarray of int, shape (n_seg, 2)
        Global node pairs ``(a, b)`` of the loaded segments (outward normal ``b - a`` turned clockwise).
    pressure : float
        Final pressure [Pa] (may be negative: suction).
    ramp_time : float
        Duration of the smooth ramp ``r(s) = s - sin(2 pi s)/(2 pi)`` from 0 to ``pressure`` [s].
    start : float
        Time the ramp starts [s] (0 by default; the static preload applies every load at full value).
    """

    name: str
    body: str
    segments: np.ndarray
    pressure: float
    ramp_time: float = 0.0
    start: float = 0.0


@dataclass(frozen=True, eq=False)
class Sensor:
    """An accelerometer: a node and a measuring direction (unit vector)."""

    name: str
    node: int
    direction: np.ndarray
    quantity: str = "acceleration"


@dataclass(frozen=True, eq=False)
class Reaction:
    """A force transducer: the sum of the constraint reactions on ``nodes``.

    ``tangential_component`` (0/1) gives ``friction_force``, ``normal_component`` gives ``normal_force``.
    """

    name: str
    nodes: np.ndarray
    tangential_component: int
    normal_component: int


@dataclass(frozen=True, eq=False)
class Tie:
    """Nodes of a fine block's edge that follow a coarser block's edge (a mesh transition, :mod:`fivid.fe.transition`).

    Slave node ``slave_nodes[k]`` moves as ``sum_i weights[k, i] u(master_nodes[k, i])``: linear interpolation
    along the coarse edge, so the two blocks' displacement fields agree along the whole edge (a conforming
    joint: Q4 edges are linear between their nodes).

    Attributes
    ----------
    name : str
    slave_nodes : ndarray of int, shape (n,)
    master_nodes : ndarray of int, shape (n, 2)
    weights : ndarray, shape (n, 2)
        Interpolation weights [-], each row summing to 1.
    """

    name: str
    slave_nodes: np.ndarray
    master_nodes: np.ndarray
    weights: np.ndarray


@dataclass(frozen=True, eq=False)
class Model:
    """A 2D finite-element model of a rig (see the module docstring for numbering and constraints).

    Attributes
    ----------
    plane : {"stress", "strain"}
    blocks : tuple of Block
    n_nodes : int
    coords : ndarray, shape (n_nodes, 2)
        Node coordinates [m].
    fixed_dofs : ndarray of int
        Sorted, unique constrained dofs (clamps and motions).
    motions, point_masses, springs, contacts, sensors, reactions, loads : tuple
    rayleigh_alpha : float
        Mass-proportional Rayleigh coefficient [s-1].
    rayleigh_beta : float
        Stiffness-proportional Rayleigh coefficient [s].
    damping_cutoff : float
        Cut-off of the low-pass filter on the velocity the stiffness-proportional damping acts on [Hz]
        (band-limited Rayleigh, :mod:`fivid.fe.damping`); ``inf``: classic Rayleigh.
    source : str
        ``"<path> sha256:<hex>"`` of the config (or of its canonical JSON for a mapping).
    config : dict
        The validated configuration mapping.
    prestress : bool
        Vibrations about the prestressed state: the initial-stress stiffness of the static preload
        (:mod:`fivid.fe.prestress`) in the explicit internal force, modes and CEA alike (config key
        ``prestress: true``).
    ties : tuple of Tie
        Tied (slave) nodes of mesh transitions (:mod:`fivid.fe.transition`); their dofs are not free.
    """

    plane: str
    blocks: tuple
    n_nodes: int
    coords: np.ndarray
    fixed_dofs: np.ndarray
    motions: tuple = ()
    point_masses: tuple = ()
    springs: tuple = ()
    contacts: tuple = ()
    sensors: tuple = ()
    reactions: tuple = ()
    loads: tuple = ()
    rayleigh_alpha: float = 0.0
    rayleigh_beta: float = 0.0
    damping_cutoff: float = math.inf
    source: str = ""
    config: dict = field(default_factory=dict)
    prestress: bool = False
    ties: tuple = ()

    @property
    def n_dofs(self) -> int:
        """Number of dofs, ``2 * n_nodes``."""
        return 2 * self.n_nodes

    @property
    def free_dofs(self) -> np.ndarray:
        """Sorted dofs not in ``fixed_dofs`` and not tied (:attr:`tied_dofs`)."""
        mask = np.ones(self.n_dofs, dtype=bool)
        mask[self.fixed_dofs] = False
        mask[self.tied_dofs] = False
        return np.flatnonzero(mask)

    @property
    def tied_dofs(self) -> np.ndarray:
        """Sorted dofs of the tied (slave) nodes of :attr:`ties`."""
        if not self.ties:
            return np.zeros(0, dtype=np.int64)
        nodes = np.concatenate([t.slave_nodes for t in self.ties]).astype(np.int64)
        return np.unique(np.concatenate([2 * nodes, 2 * nodes + 1]))

    @property
    def sha256(self) -> str:
        """The config's sha256 (hex), from ``source``."""
        return self.source.rsplit("sha256:", 1)[-1] if "sha256:" in self.source else ""

    def block(self, name: str) -> Block:
        """The block called ``name`` (KeyError if absent)."""
        for b in self.blocks:
            if b.name == name:
                return b
        raise KeyError(name)

    def block_of_node(self, node: int) -> Block:
        """The block that owns global ``node``."""
        for b in self.blocks:
            if b.node_offset <= node < b.node_offset + b.n_nodes:
                return b
        raise IndexError(f"node {node} is not in the model (0..{self.n_nodes - 1})")

    def motion(self, role: str) -> Motion | None:
        """The first motion with ``role`` ("base" or "load"), or None."""
        for m in self.motions:
            if m.role == role:
                return m
        return None

    def initial_velocity(self) -> np.ndarray:
        """Initial velocity vector [m s-1], shape (n_dofs,), from the blocks' ``initial_velocity``."""
        v = np.zeros(self.n_dofs)
        for b in self.blocks:
            nodes = b.node_numbers().ravel()
            v[2 * nodes] = b.initial_velocity[0]
            v[2 * nodes + 1] = b.initial_velocity[1]
        return v

    def describe(self) -> str:
        """A one-line summary: bodies, meshes and dof count."""
        parts = [f"{b.name} {b.nx}x{b.ny}" for b in self.blocks]
        return f"{len(self.blocks)} bodies ({', '.join(parts)}), {self.n_nodes} nodes, {self.n_dofs} dofs, plane {self.plane}"

