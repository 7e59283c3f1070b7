"""Model file -> :class:`~fivid.fe.model.Model`: the mesh, the references into it and the laws.

The file is validated as a whole by its schema (:class:`fivid.fe.config.ModelConfig`); this module builds the
blocks (:func:`fivid.fe.geometry.block_coords`), resolves what names a part of the mesh (a body, an edge, a
point on a body) and builds the contact laws (:mod:`fivid.contact.config`) and the damping
(:func:`fivid.fe.damping.rayleigh_through_two_ratios`). What only the mesh can tell is checked here, in the
config layer's one error format (file, line, key path, value, what is allowed).
"""

from __future__ import annotations

import math
import os
from os import PathLike
from pathlib import Path
from typing import Any, Mapping

import numpy as np

import fivid.fe.model as fm
from fivid.builtin import builtin_names, find_builtin
from fivid.config_layer import ConfigSource, validate
from fivid.contact.config import normal_law, rigid_surface
from fivid.errors import ConfigError
from fivid.fe.config import COMPONENTS, ContactConfig, DampingConfig, EdgeRefConfig, ModelConfig, read_config
from fivid.fe.damping import rayleigh_through_two_ratios
from fivid.fe.geometry import block_coords
from fivid.fe.static import resolve_expansions

__all__ = ["build_model", "load_model"]


def build_model(source: str | PathLike | Mapping[str, Any]) -> fm.Model:
    """Validate a config (path or mapping) and build the :class:`Model` (see :func:`fivid.fe.load_model`)."""
    data, ctx, origin = read_config(source)
    cfg = validate(ModelConfig, ctx)
    materials = {name: fm.Material(m.E, m.nu, m.rho) for name, m in cfg.materials.items()}
    blocks = tuple(_blocks(ctx, cfg, materials))
    fixed = []
    for (name, body), b in zip(cfg.bodies.items(), blocks):
        for i, edge in enumerate(body.clamp):
            _edge_name(ctx, b, edge, f"bodies.{name}.clamp[{i}]")
            nodes = b.edge_nodes(edge)
            fixed += [2 * nodes, 2 * nodes + 1]

    motions = []
    for i, m in enumerate(cfg.motions):
        _, nodes = _edge_ref(ctx, blocks, m, f"motions[{i}]")
        comp = COMPONENTS[m.component]
        motions.append(fm.Motion(m.name, nodes, comp, m.kind, m.amplitude_si, m.ramp_time, m.role))
        fixed.append(2 * nodes + comp)
    fixed_dofs = np.unique(np.concatenate(fixed)) if fixed else np.zeros(0, dtype=np.int64)

    point_masses = tuple(fm.PointMass(p.name, _point_ref(ctx, blocks, p, f"point_masses[{i}]"), p.mass)
                         for i, p in enumerate(cfg.point_masses))
    springs = []
    for i, s in enumerate(cfg.springs):
        key = f"springs[{i}]"
        a = _point_ref(ctx, blocks, s.a, f"{key}.a")
        b = -1 if s.b == "ground" else _point_ref(ctx, blocks, s.b, f"{key}.b")
        if a == b:
            raise ctx.error(f"{key}.b", "both ends of the spring are the same node")
        springs.append(fm.Spring(s.name, a, b, COMPONENTS[s.component], s.stiffness, s.damping))
    contacts = tuple(_contact(ctx, c, f"contacts[{i}]", blocks) for i, c in enumerate(cfg.contacts))
    sensors = tuple(fm.Sensor(s.name, _point_ref(ctx, blocks, s, f"sensors[{i}]"), s.unit_direction, s.quantity)
                    for i, s in enumerate(cfg.sensors))
    reactions = []
    for i, r in enumerate(cfg.reactions):
        key = f"reactions[{i}]"
        block, nodes = _edge_ref(ctx, blocks, r, key)
        t, n = COMPONENTS[r.tangential], COMPONENTS[r.normal]
        free = np.setdiff1d(np.concatenate([2 * nodes + t, 2 * nodes + n]), fixed_dofs)
        if free.size:
            raise ctx.error(key, f"a reaction needs constrained nodes (a clamp or a motion), but {free.size} of its "
                                 f"dofs are free; clamp edge {r.edge!r} of {block.name!r}")
        reactions.append(fm.Reaction(r.name, nodes, t, n))
    loads = []
    for i, p in enumerate(cfg.loads):
        key = f"loads[{i}]"
        block, nodes = _edge_ref(ctx, blocks, p, key)
        if nodes.size < 2:
            raise ctx.error(key, "a pressure load needs at least 2 nodes of the edge (one segment)")
        loads.append(fm.PressureLoad(p.name, block.name, block.edge_segments(p.edge, nodes), p.pressure, p.ramp_time,
                                     p.start))

    alpha, beta, cutoff = _damping(ctx, cfg.damping)
    model = fm.Model(plane=cfg.plane, blocks=blocks, n_nodes=sum(b.n_nodes for b in blocks),
                    coords=np.concatenate([b.coords.reshape(-1, 2) for b in blocks]), fixed_dofs=fixed_dofs,
                    motions=tuple(motions), point_masses=point_masses, springs=tuple(springs), contacts=contacts,
                    sensors=sensors, reactions=tuple(reactions), loads=tuple(loads), rayleigh_alpha=alpha,
                    rayleigh_beta=beta, damping_cutoff=cutoff, source=origin, config=data,
                    prestress=bool(cfg.prestress))
    try:  # a rigid circle expanding to a target mean pressure: its radial displacement from the static preload
        return resolve_expansions(model)
    except ConfigError as exc:
        raise ctx.error(exc.key or "contacts", str(exc)) from None


def _blocks(ctx: ConfigSource, cfg: ModelConfig, materials: dict):
    offset = 0
    for name, b in cfg.bodies.items():
        coords, shape, periodic = block_coords(b, ctx, f"bodies.{name}")
        m = b.material
        material = materials[m] if isinstance(m, str) else fm.Material(m.E, m.nu, m.rho)
        nx, ny = b.divisions
        block = fm.Block(name=str(name), corners=coords[[0, 0, -1, -1], [0, -1, -1, 0]].copy(), nx=nx, ny=ny,
                         material=material, thickness=b.thickness, plane=cfg.plane, node_offset=offset, coords=coords,
                         initial_velocity=np.array(b.initial_velocity, dtype=float), shape=shape, periodic=periodic)
        offset += block.n_nodes
        yield block


def _edge_name(ctx, block: fm.Block, edge: str, key: str) -> None:
    if edge not in block.edge_names:
        raise ctx.error(key, f"expected one of {', '.join(block.edge_names)} (the edges of body {block.name!r}), "
                             f"found {edge!r}")


def _block_ref(ctx, blocks, value, key) -> fm.Block:
    for b in blocks:
        if b.name == value:
            return b
    raise ctx.error(key, f"body {value!r} does not exist; bodies are: {', '.join(b.name for b in blocks)}")


def _edge_ref(ctx, blocks, ref: EdgeRefConfig, key: str) -> tuple[fm.Block, np.ndarray]:
    """``{body, edge, x: [lo, hi] | y: [lo, hi]}`` -> (block, its nodes in edge order within the ranges)."""
    block = _block_ref(ctx, blocks, ref.body, f"{key}.body")
    _edge_name(ctx, block, ref.edge, f"{key}.edge")
    nodes = block.edge_nodes(ref.edge)
    coords = block.coords.reshape(-1, 2)[nodes - block.node_offset]
    for axis, c in (("x", 0), ("y", 1)):
        if getattr(ref, axis) is not None:
            lo, hi = getattr(ref, axis)
            tol = 1e-9 * float(np.ptp(block.coords.reshape(-1, 2), axis=0).max())
            keep = (coords[:, c] >= min(lo, hi) - tol) & (coords[:, c] <= max(lo, hi) + tol)
            nodes, coords = nodes[keep], coords[keep]
            if nodes.size == 0:
                raise ctx.error(f"{key}.{axis}", f"no node of edge {ref.edge!r} of body {block.name!r} has "
                                                 f"{axis} in [{lo}, {hi}] m")
    return block, nodes


def _point_ref(ctx, blocks, ref, key: str) -> int:
    """``{body, at: [x, y]}`` -> the nearest node of the body (must lie within one element of the point)."""
    block = _block_ref(ctx, blocks, ref.body, f"{key}.body")
    at = np.array(ref.at, dtype=float)
    xy = block.coords.reshape(-1, 2)
    d = np.hypot(*(xy - at).T)
    k = int(np.argmin(d))
    size = max(float(np.hypot(*np.diff(block.coords, axis=a).reshape(-1, 2).T).max()) if block.coords.shape[a] > 1
               else 0.0 for a in (0, 1))  # the longest element side
    if d[k] > size:
        raise ctx.error(f"{key}.at", f"point {at.tolist()} m is not on body {block.name!r} (nearest node "
                                     f"{xy[k].tolist()} is {d[k]:.3g} m away)")
    return int(block.node_offset + k)


def _contact(ctx, c: ContactConfig, key: str, blocks) -> fm.ContactPair:
    """One ``contacts`` item: slave edge against a master edge or a rigid surface, with its laws."""
    sb, snodes = _edge_ref(ctx, blocks, c.slave, f"{key}.slave")
    mb, mnodes, rigid = None, np.zeros(0, dtype=np.int64), None
    if c.master is not None:
        mb, mnodes = _edge_ref(ctx, blocks, c.master, f"{key}.master")
        if sb is mb:
            raise ctx.error(f"{key}.master", "slave and master must be edges of different bodies")
        if mnodes.size < 2:
            raise ctx.error(f"{key}.master", "the master edge needs at least 2 nodes (one segment)")
    else:
        rigid = rigid_surface(c.rigid)
    if c.normal_stiffness is not None:
        kn = c.normal_stiffness
    else:  # 10 x the slave body's own normal stiffness per unit area E/D (D: its depth normal to the edge):
        # stiff against the body, and independent of the mesh (an element-size penalty is not)
        corners = sb.corners
        if c.slave.edge in ("bottom", "top"):
            depth = np.hypot(*(corners[3] - corners[0]))
        elif c.slave.edge in ("left", "right"):
            depth = np.hypot(*(corners[1] - corners[0]))
        else:  # annulus: the wall
            depth = float(np.ptp(np.hypot(*(sb.coords.reshape(-1, 2) - sb.coords.reshape(-1, 2).mean(0)).T)))
        kn = 10.0 * sb.material.E / float(depth)
    try:
        law = normal_law(c.normal, [sb.material] + ([mb.material] if mb is not None else []))
    except ConfigError as exc:
        if getattr(exc, "key", None):
            raise
        raise ctx.error(f"{key}.normal", str(exc)) from None
    return fm.ContactPair(c.name, sb.name, snodes, mb.name if mb else "", mnodes, c.mu, kn, law=law,
                          friction=c.friction_curve(), rigid=rigid)


def _damping(ctx, spec: DampingConfig | None) -> tuple[float, float, float]:
    """``(alpha [s-1], beta [s], cutoff [Hz])`` of the ``damping`` section (cutoff inf: classic Rayleigh)."""
    if spec is None:
        return 0.0, 0.0, math.inf
    if spec.ratios is None:
        return spec.alpha, spec.beta, spec.cutoff
    (f1, z1), (f2, z2) = ((r.frequency, r.ratio) for r in spec.ratios)
    alpha, beta = rayleigh_through_two_ratios(f1, z1, f2, z2, cutoff=spec.cutoff)
    if alpha < 0 or beta < 0:
        raise ctx.error("damping.ratios", f"these ratios need a negative Rayleigh coefficient (alpha {alpha:.4g} "
                                          f"s-1, beta {beta:.4g} s): no Rayleigh curve passes through both points")
    return alpha, beta, spec.cutoff


def load_model(source: str | PathLike | Mapping[str, Any]) -> fm.Model:
    """Build a :class:`~fivid.fe.model.Model` from a YAML config file (path) or an already-parsed mapping.

    The configuration format is documented in ``docs/model-config.md``. Every problem raises
    :class:`~fivid.errors.ConfigError` naming the file, line and key path (``bodies.upper.material.nu``),
    the value given and what is allowed.

    A name without a folder or suffix (``"triboair_coarse"``) that is not a file is one of the example
    models shipped with fivid (``configs/models/``, installed with the package: :mod:`fivid.builtin`).
    """
    return build_model(_resolve_model_name(source))


def _resolve_model_name(source):
    """``source`` unchanged, or the built-in model file when it is the name of one and not an existing file."""
    if isinstance(source, (str, os.PathLike)) and not Path(source).exists():
        found = find_builtin("models", str(source))
        if found is not None:
            return found
        text = str(source)
        if not any(c in text for c in "/\\") and not text.endswith((".yaml", ".yml")):  # meant as a name
            raise ConfigError(f"no model file or built-in model named {text!r}; built-in models: "
                              f"{', '.join(builtin_names('models')) or '(none)'}; or give the path of a YAML file")
    return source
