"""Kernel arrays of a model: constraints and their motions, springs, contact, sensors, transducer weights.

The loading sequence (DESIGN §5) is encoded here as ramp parameters of the constrained dofs:
the "load" motion ramps its displacement to the preload value over ``[0, t_load]``; the model then
settles until ``t_base``; the "base" motion ramps its velocity to the sliding velocity over
``[t_base, t_base + base ramp]`` (the end of the transient); then steady sliding. Other motions run as
configured from t = 0.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fivid.contact import kernel_row, kernel_tables
from fivid.contact._layout_kernels import NPAR
from fivid.errors import ConfigError
from fivid.fe.assembly import lumped_mass
from fivid.fe.contact_nodes import slave_areas
from fivid.fe.loads import pressure_forces
from fivid.fe.prestress import geometric_stiffness_matrix
from fivid.solver.stencil import BlockStencils

__all__ = ["LoadingSequence", "KernelArrays", "kernel_arrays", "constrained_contact_dofs", "KIND_FIXED",
           "KIND_DISPLACEMENT", "KIND_VELOCITY"]

KIND_FIXED = 0
KIND_DISPLACEMENT = 1
KIND_VELOCITY = 2


@dataclass(frozen=True)
class LoadingSequence:
    """The loading sequence [s] and amplitudes as the driver resolved them (from a :class:`fivid.solver.RunSchedule`
    and the model's motions).

    Attributes
    ----------
    load_displacement : float or None
        Clamp displacement of the "load" motion [m] (None: as configured).
    load_ramp : float
        Ramp time of the clamp [s].
    base_start : float
        Start of the base-velocity ramp (end of settling) [s].
    base_velocity : float or None
        Velocity of the "base" motion [m s-1] (None: as configured).
    base_ramp : float
        Ramp time of the base velocity [s].
    pressure_ramp : float
        Latest end of the ramps of the pressure loads and of the rigid surfaces' motion [s].
    """

    load_displacement: float | None
    load_ramp: float
    base_start: float
    base_velocity: float | None
    base_ramp: float
    pressure_ramp: float = 0.0

    @property
    def transient_end(self) -> float:
        """End of the base ramp (and of the pressure ramps): steady sliding from here [s]."""
        return max(self.base_start + self.base_ramp, self.pressure_ramp)


@dataclass
class KernelArrays:
    """The model's arrays of :func:`fivid.solver._loop_kernels.run_steps` (grouped by
    :func:`fivid.solver.integrate.loop_arguments`) besides the stencils, the state and the outputs."""

    mass: np.ndarray
    minv: np.ndarray
    minv_c: np.ndarray
    X: np.ndarray
    spr_dof: np.ndarray
    spr_kc: np.ndarray
    con_dof: np.ndarray
    con_grp: np.ndarray
    grp_par: np.ndarray
    con_react: np.ndarray
    con_global: np.ndarray
    slave_node: np.ndarray
    slave_pair: np.ndarray
    slave_global: np.ndarray
    master_ptr: np.ndarray
    master_nodes: np.ndarray
    pair_sign: np.ndarray
    seg: np.ndarray
    cnodes: np.ndarray
    cnode_slot: np.ndarray
    sens_node: np.ndarray
    sens_dir: np.ndarray
    ld_dof: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    ld_force: np.ndarray = field(default_factory=lambda: np.zeros(0))
    ld_grp: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    ld_par: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    pair_par: np.ndarray = field(default_factory=lambda: np.zeros((0, 15)))
    s_area: np.ndarray = field(default_factory=lambda: np.zeros(0))
    law_tab: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 2)))
    #: index into ``con_dof`` of each contact node's constrained x and y dof (-1: free), (n_cnodes, 2); (0, 2)
    #: when no contact node has a constrained dof (:func:`constrained_contact_dofs`)
    con_cnode: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    extras: dict = field(default_factory=dict)


def _idx(a, dtype=np.int64):
    return np.ascontiguousarray(np.asarray(a, dtype=dtype))


def kernel_arrays(model, st: BlockStencils, loading: LoadingSequence, *, tangential_sign: float,
                  normal_sign: float, prestress=None) -> KernelArrays:
    """Assemble the kernel arrays of ``model`` in the layout of ``st`` with the ``loading`` sequence.

    ``tangential_sign``/``normal_sign`` orient the transducer: ``friction_force = tangential_sign * sum R_t``,
    ``normal_force = normal_sign * sum R_n`` over the reaction nodes of the first Reaction.
    ``prestress`` ``(u0, ramp_end)``, optional: the static state [m] whose initial-stress stiffness ``st``
    carries (:func:`fivid.solver.stencil.block_stencils`) and the end of its ramp [s]; its reference force
    ``K_sigma u0`` becomes one more load, ramped over ``[0, ramp_end]``, so the internal force is
    ``K w + K_sigma (w - r(t) u0)``.
    """
    mass = st.to_kernel(lumped_mass(model))
    minv = np.zeros_like(mass)
    minv[mass > 0] = 1.0 / mass[mass > 0]
    # ---- constrained dofs: fixed unless a motion drives them
    kind, par = _motion_parameters(model, loading)
    con_global = np.flatnonzero(kind >= 0)
    con_react = _transducer_weights(model, con_global, tangential_sign, normal_sign)
    # motion groups: dofs sharing (kind, amplitude, start, ramp) get one velocity evaluation per step
    rows = np.column_stack([kind[con_global], par[con_global]]).astype(float)
    grp_par, grp = np.unique(rows, axis=0, return_inverse=True) if rows.size else (np.zeros((0, 4)), np.zeros(0))
    grp = np.asarray(grp).ravel()
    minv_c = minv.copy()
    minv_c[st.dof_index(con_global)] = 0.0
    # ---- springs
    spr_dof = np.array([[st.dof_index(2 * s.node_a + s.component),
                         st.dof_index(2 * s.node_b + s.component) if s.node_b >= 0 else -1] for s in model.springs],
                       dtype=np.int64).reshape(-1, 2)
    spr_kc = np.array([[s.stiffness, s.damping] for s in model.springs], dtype=float).reshape(-1, 2)
    # ---- sensors
    sens_node = _idx([st.node_index(s.node) for s in model.sensors])
    sens_dir = np.array([np.asarray(s.direction, float) for s in model.sensors]).reshape(-1, 2)
    contact = _contact_arrays(model, st)
    con_dof = _idx(st.dof_index(con_global))
    return KernelArrays(
        mass=mass, minv=minv, minv_c=minv_c, X=st.to_kernel(model.coords.ravel()),
        spr_dof=_idx(spr_dof), spr_kc=np.ascontiguousarray(spr_kc),
        con_dof=con_dof, con_grp=_idx(grp), grp_par=np.ascontiguousarray(grp_par),
        con_react=con_react, con_global=con_global,
        sens_node=sens_node, sens_dir=np.ascontiguousarray(sens_dir),
        con_cnode=constrained_contact_dofs(con_dof, contact["cnode_slot"], contact["cnodes"].size, st.npd),
        **contact, **_load_arrays(model, st, prestress),
    )


def constrained_contact_dofs(con_dof: np.ndarray, cnode_slot: np.ndarray, n_cnodes: int, npd: int) -> np.ndarray:
    """For each contact node (slot of ``cnode_slot``), the index into ``con_dof`` of its constrained x and y dof,
    -1 where free; shape (n_cnodes, 2), or (0, 2) when no contact node has a constrained dof.

    A slave (or master) node on a clamped or driven edge -- the corner of a slider held by its carriage, say --
    takes contact forces that do not move it: its constraint takes them, so its reaction (the transducer's
    force, the imposed motion's work) includes them (:func:`fivid.solver._contact_kernels.contact_reactions`).
    Without them the friction on the driven corner of the 5 x 1 mm flat cut of rough_pair_short.yaml was
    counted as dissipated but not as supplied by the drive: an energy-balance error of 19 % of its scale.
    ``con_dof`` and ``npd`` in the kernel layout (x dofs ``[0, npd)``, y dofs ``[npd, 2 npd)``).
    """
    table = np.full((n_cnodes, 2), -1, dtype=np.int64)
    for c, d in enumerate(np.asarray(con_dof, dtype=np.int64)):
        comp, node = divmod(int(d), npd)
        if cnode_slot[node] >= 0:
            table[cnode_slot[node], comp] = c
    return table if (table >= 0).any() else np.zeros((0, 2), dtype=np.int64)


def _motion_parameters(model, loading: LoadingSequence) -> tuple[np.ndarray, np.ndarray]:
    """Per global dof: the kind of its motion (-1 free, ``KIND_*``) and ``(amplitude, start, ramp time)``, the
    "load" and "base" motions set by the ``loading`` sequence."""
    kind = np.full(model.n_dofs, -1, dtype=np.int64)
    par = np.zeros((model.n_dofs, 3))
    kind[model.fixed_dofs] = KIND_FIXED
    for mo in model.motions:
        dofs = mo.dofs
        k = KIND_DISPLACEMENT if mo.kind == "displacement" else KIND_VELOCITY
        amp, t0, tr = float(mo.amplitude), 0.0, float(mo.ramp_time)
        if mo.role == "load" and loading.load_displacement is not None:
            if k != KIND_DISPLACEMENT:
                raise ConfigError(f"motions.{mo.name}: the 'load' motion must be of kind displacement, got {mo.kind!r}")
            amp, tr = loading.load_displacement, loading.load_ramp
        if mo.role == "base":
            if k != KIND_VELOCITY:
                raise ConfigError(f"motions.{mo.name}: the 'base' motion must be of kind velocity, got {mo.kind!r}")
            if loading.base_velocity is not None:
                amp = loading.base_velocity
            t0, tr = loading.base_start, loading.base_ramp
        kind[dofs] = k
        par[dofs] = (amp, t0, tr)
    return kind, par


def _transducer_weights(model, con_global, tangential_sign: float, normal_sign: float) -> np.ndarray:
    """``(tangential, normal)`` weight of each constrained dof's reaction in the force transducer (the first
    Reaction's nodes, signed); a transducer node that is not constrained is a ConfigError."""
    con_react = np.zeros((con_global.size, 2))
    if model.reactions:
        r = model.reactions[0]
        slot = {int(d): i for i, d in enumerate(con_global)}
        for node in np.asarray(r.nodes):
            for col, comp, sign in ((0, r.tangential_component, tangential_sign), (1, r.normal_component, normal_sign)):
                d = 2 * int(node) + comp
                if d not in slot:
                    raise ConfigError(
                        f"reactions.{r.name}: node {int(node)} component {'xy'[comp]} is not constrained; a force "
                        "transducer must sit on clamped or driven dofs")
                con_react[slot[d], col] = sign
    return con_react


def _contact_arrays(model, st: BlockStencils) -> dict:
    """The contact fields of :class:`KernelArrays`: slaves, master segments, contact nodes, initial segments,
    the pairs' law rows and tables, the slaves' tributary areas."""
    slave_nodes, slave_pair, master, ptr = [], [], [], [0]
    for p, pair in enumerate(model.contacts):
        slave_nodes.extend(int(s) for s in pair.slave_nodes)
        slave_pair.extend([p] * len(pair.slave_nodes))
        master.extend(int(m) for m in pair.master_nodes)
        ptr.append(len(master))
    slave_global = _idx(slave_nodes)
    cnodes_g = np.unique(np.concatenate([slave_global, _idx(master)])) if slave_nodes else _idx([])
    cnode_slot = np.full(st.npd, -1, dtype=np.int64)
    cnode_slot[st.node_index(cnodes_g)] = np.arange(cnodes_g.size)
    # initial segment of each slave: the nearest master segment midpoint (a rigid master has none)
    seg = np.zeros(slave_global.size, dtype=np.int64)
    for k, (s, p) in enumerate(zip(slave_global, slave_pair)):
        m = _idx(master[ptr[p]:ptr[p + 1]])
        if m.size < 2:
            continue
        mid = 0.5 * (model.coords[m[:-1]] + model.coords[m[1:]])
        seg[k] = int(np.argmin(np.linalg.norm(mid - model.coords[s], axis=1)))
    pair_par = np.array([kernel_row(c.law, c.friction, c.rigid) for c in model.contacts]).reshape(
        len(model.contacts), NPAR)
    s_area = np.concatenate([slave_areas(model, c) for c in model.contacts]) if model.contacts else np.zeros(0)
    law_tab = kernel_tables([c.law for c in model.contacts])
    return dict(
        slave_node=_idx(st.node_index(slave_global)), slave_pair=_idx(slave_pair), slave_global=slave_global,
        master_ptr=_idx(ptr), master_nodes=_idx(st.node_index(_idx(master))),
        pair_sign=np.ones(len(model.contacts)), seg=seg,
        cnodes=_idx(st.node_index(cnodes_g)), cnode_slot=cnode_slot,
        pair_par=np.ascontiguousarray(pair_par, dtype=float), s_area=np.ascontiguousarray(s_area, dtype=float),
        law_tab=np.ascontiguousarray(law_tab, dtype=float),
    )


def _load_arrays(model, st: BlockStencils, prestress=None) -> dict:
    """The pressure-load fields of :class:`KernelArrays`: the non-zero nodal forces of each load and its ramp;
    with ``prestress`` ``(u0, ramp_end)`` one more group, the prestress term's reference force ``K_sigma u0``
    (see :func:`kernel_arrays`)."""
    forces = [pressure_forces(model, load) for load in model.loads]
    par = [[float(ld.start), float(ld.ramp_time)] for ld in model.loads]
    if prestress is not None:
        u0, ramp_end = prestress
        forces.append(geometric_stiffness_matrix(model, u0) @ np.asarray(u0, dtype=float))
        par.append([0.0, float(ramp_end)])
    ld_dof, ld_force, ld_grp = [], [], []
    for g, fl in enumerate(forces):
        nz = np.flatnonzero(fl)
        ld_dof.append(st.dof_index(nz))
        ld_force.append(fl[nz])
        ld_grp.append(np.full(nz.size, g))
    ld_par = np.array(par).reshape(-1, 2)
    return dict(
        ld_dof=_idx(np.concatenate(ld_dof) if ld_dof else []),
        ld_force=np.ascontiguousarray(np.concatenate(ld_force) if ld_force else np.zeros(0)),
        ld_grp=_idx(np.concatenate(ld_grp) if ld_grp else []), ld_par=np.ascontiguousarray(ld_par),
    )
