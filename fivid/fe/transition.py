"""Meshes that coarsen along the surface with depth: a profiled block re-meshed as a stack of structured blocks
whose column width doubles from level to level, joined by ties (seed 003's Fig. 3: fine at the contact, coarse
at the back).

Why blocks and ties (not transition elements): the explicit kernel (DESIGN §7, :mod:`fivid.solver.stencil`) is
fast on structured blocks -- a rectangular block shares one 3x3 stencil (13 multiply-adds per force, no
coefficient stream), a profiled block streams per-node coefficients -- and a 2:1 transition element or a
hanging node couples a node with more than its 3x3 neighbourhood. A stack of structured blocks keeps every node
in a stencil patch: only the thin profiled surface level is mapped; every coarser level is a uniform rectangle
block. Neighbouring levels share an edge: the finer level's edge nodes are tied to the coarser level's edge
(:class:`fivid.fe.model.Tie`): a node at a coarse node's position follows it, a node half-way follows the mean
of its two neighbours -- linear interpolation along the edge, which is exactly the Q4 edge's displacement field,
so the joint is conforming and passes the patch test. The explicit kernel eliminates the tied nodes
(``f = T^T K T w``, their mass lumped onto the masters); assembly does the same (:func:`fivid.fe.assembly.tie_matrix`).

Levels (from the profiled edge): level 0 has ``nx`` columns of width ``h`` and ``surface_rows`` rows of
thickness ``h``, the profile's heights fading linearly to zero across it (so the deeper levels are exact
rectangles); level ``k >= 1`` has ``nx / 2^k`` columns and ``rows_per_level`` rows of thickness ``h 2^k``
(square elements); the last level takes the rest of the depth. The stable step is then the surface level's
(elements ``h x h`` distorted by the profile), every deeper element being at least twice as large.

Units: SI (m).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

import fivid.fe.model as fm

__all__ = ["DEPTH_PER_MAX_WIDTH", "WIDTH_TOLERANCE", "TransitionLevels", "transition_levels", "transition_columns", "surface_rows_for", "transition_model"]


#: the widest element of a coarsening stack is the block's depth over this (8: 1 mm in seed 003's 8 mm blocks):
#: the bulk's bending is then resolved to ~0.5 % in frequency below 20 kHz (docs/roughness.md, tests/fe/test_fe_transition.py)
DEPTH_PER_MAX_WIDTH = 8


#: relative slack of the ``max_width`` cap: the surface step is ``length / nx`` (a few % under the asked one) and a
#: block's depth (to its profile's mean line) differs from the nominal one by the profile's mean height; neither
#: may drop a level whose width is the nominal cap (1.026 mm for Ra 26's 64.1 um x 16)
WIDTH_TOLERANCE = 0.05


@dataclasses.dataclass(frozen=True)
class TransitionLevels:
    """The levels of a coarsening stack, from the profiled edge inward.

    Attributes
    ----------
    columns : tuple of int
        Element columns per level (``nx / 2^k``).
    rows : tuple of int
        Element rows per level.
    thickness : tuple of float
        Row thickness per level [m] (level 0: before the profile's displacement).
    """

    columns: tuple
    rows: tuple
    thickness: tuple

    @property
    def n_levels(self) -> int:
        """Number of levels."""
        return len(self.columns)


def transition_levels(nx: int, step: float, depth: float, *, surface_rows: int = 2, rows_per_level: int = 2,
                      max_width: float | None = None) -> TransitionLevels:
    """Levels of a block ``depth`` [m] deep whose profiled edge has ``nx`` columns of ``step`` [m].

    Level 0: ``surface_rows`` rows of ``step``; level ``k``: ``rows_per_level`` square rows of ``step 2^k`` while
    the rest of the depth holds that level and the next one, ``nx`` divides by ``2^k`` and ``step 2^k`` is at most
    ``max_width`` [m] (None: no cap; within :data:`WIDTH_TOLERANCE`); the last level fills the remaining depth with rows as close to square as
    whole rows allow.

    Raises
    ------
    ValueError
        The surface level does not fit in ``depth``, or an argument is not positive.
    """
    if nx < 1 or step <= 0 or depth <= 0 or surface_rows < 1 or rows_per_level < 1:
        raise ValueError(f"transition_levels needs nx >= 1, step > 0, depth > 0 and rows >= 1; got nx {nx}, "
                         f"step {step:g} m, depth {depth:g} m, surface_rows {surface_rows}, "
                         f"rows_per_level {rows_per_level}")
    if surface_rows * step >= depth:
        raise ValueError(f"the surface level ({surface_rows} rows of {step:g} m) does not fit in the block's depth "
                         f"{depth:g} m")
    cap = math.inf if max_width is None else float(max_width)
    top = 0  # the coarsest level allowed by divisibility and the cap
    while nx % 2 ** (top + 1) == 0 and step * 2 ** (top + 1) <= cap * (1 + WIDTH_TOLERANCE):
        top += 1
    cols, rows, thick = [nx], [surface_rows], [step]
    rest = depth - surface_rows * step
    for k in range(1, top + 1):
        s = step * 2 ** k
        if k < top and rest - rows_per_level * s >= rows_per_level * 2 * s:
            cols.append(nx // 2 ** k)
            rows.append(rows_per_level)
            thick.append(s)
            rest -= rows_per_level * s
            continue
        if rest < s:  # too thin for this width: the previous width takes the rest
            s, k = s / 2, k - 1
        n = max(1, int(round(rest / s)))
        cols.append(nx // 2 ** k)
        rows.append(n)
        thick.append(rest / n)
        return TransitionLevels(tuple(cols), tuple(rows), tuple(thick))
    n = max(1, int(round(rest / step)))  # no coarsening allowed: one more level of the surface's width
    cols.append(nx)
    rows.append(n)
    thick.append(rest / n)
    return TransitionLevels(tuple(cols), tuple(rows), tuple(thick))


def transition_columns(length: float, step: float, depth: float, *, surface_rows: int = 2,
                       rows_per_level: int = 2, max_width: float | None = None) -> int:
    """Columns ``nx`` of the profiled edge: the fewest with width ``length / nx <= step`` [m] that divide by
    ``2^K``, ``K`` the coarsenings the depth [m] holds at that width (:func:`transition_levels`)."""
    n0 = max(1, math.ceil(length / step * (1.0 - 1e-12)))
    k = transition_levels(2 ** 30, length / n0, depth, surface_rows=surface_rows, rows_per_level=rows_per_level,
                          max_width=max_width).n_levels - 1
    return math.ceil(n0 / 2 ** k) * 2 ** k


def surface_rows_for(heights, step: float) -> int:
    """Rows of the profiled level for profile ``heights`` [m] on columns of ``step`` [m]: enough that the profile,
    faded linearly across the level, thins no surface element below 2/3 of ``step`` (``3 max|z - mean| / step``),
    and at least 2. (A thinner surface element would set a smaller stable step.)"""
    z = np.asarray(heights, float)
    return max(2, math.ceil(3.0 * float(np.max(np.abs(z - z.mean()))) / step - 1e-9))


def _level_coords(x0: float, length: float, y_inner: float, y_outer: float, ncols: int, nrows: int,
                  heights: np.ndarray | None) -> np.ndarray:
    """Grid (nrows+1, ncols+1, 2) from ``y_inner`` (share 0) to ``y_outer`` (share 1 of ``heights``), rows in
    increasing y."""
    x = x0 + length * np.arange(ncols + 1) / ncols
    lo, hi = min(y_inner, y_outer), max(y_inner, y_outer)
    t = np.linspace(0.0, 1.0, nrows + 1)
    y = lo + (hi - lo) * t
    xy = np.empty((nrows + 1, ncols + 1, 2))
    xy[..., 0] = x[None, :]
    xy[..., 1] = y[:, None]
    if heights is not None:
        share = t if y_outer > y_inner else 1.0 - t
        xy[..., 1] += share[:, None] * heights[None, :]
    return xy


def _stack(block: fm.Block, edge: str, levels: TransitionLevels, offset: int):
    """The level blocks replacing ``block`` (profiled on ``edge``) and their ties."""
    c = block.coords
    prof_row = c[-1] if edge == "top" else c[0]
    x0, x1 = float(c[0, 0, 0]), float(c[0, -1, 0])
    length = x1 - x0
    y_flat = float(np.mean(prof_row[:, 1]))  # the profile's mean line: the profiled edge keeps its nodes exactly
    y_back = float(c[0, 0, 1] if edge == "top" else c[-1, 0, 1])
    heights = prof_row[:, 1] - y_flat
    sign = -1.0 if edge == "top" else 1.0  # from the profiled edge inward
    blocks, ties = [], []
    y_outer = y_flat
    for k, (ncols, nrows, th) in enumerate(zip(levels.columns, levels.rows, levels.thickness)):
        y_inner = y_back if k == levels.n_levels - 1 else y_outer + sign * nrows * th
        xy = _level_coords(x0, length, y_inner, y_outer, ncols, nrows, heights if k == 0 else None)
        name = block.name if k == 0 else f"{block.name}~{k}"
        b = fm.Block(name=name, corners=xy[[0, 0, -1, -1], [0, -1, -1, 0]].copy(), nx=ncols, ny=nrows,
                     material=block.material, thickness=block.thickness, plane=block.plane, node_offset=offset,
                     coords=xy, initial_velocity=block.initial_velocity, shape="profile" if k == 0 else "quad")
        offset += b.n_nodes
        if blocks:  # tie the previous (finer) level's inner edge to this level's outer edge
            fine, ratio = blocks[-1], blocks[-1].nx // ncols
            fine_row = 0 if edge == "top" else fine.ny
            coarse_row = nrows if edge == "top" else 0
            i = np.arange(fine.nx + 1)
            lo_col = np.minimum(i // ratio, ncols - 1)
            frac = (i - lo_col * ratio) / ratio
            ties.append(fm.Tie(f"{block.name}~{k - 1}:{k}", fine.node(i, fine_row).astype(np.int64),
                               np.column_stack([b.node(lo_col, coarse_row), b.node(lo_col + 1, coarse_row)]).astype(np.int64),
                               np.column_stack([1.0 - frac, frac])))
        blocks.append(b)
        y_outer = y_inner
    return blocks, ties, offset


def _edge_of(block: fm.Block, nodes: np.ndarray) -> str | None:
    for e in fm.EDGES:
        if np.isin(nodes, block.edge_nodes(e)).all():
            return e
    return None


def _stack_edge(blocks: list, edge: str, profiled: str, tied: np.ndarray) -> np.ndarray:
    """Nodes of the stack's ``edge`` in edge order (tied nodes left out)."""
    if edge == profiled:
        return blocks[0].edge_nodes(edge)
    back = {"top": "bottom", "bottom": "top"}[profiled]
    if edge == back:
        return blocks[-1].edge_nodes(edge)
    nodes = np.concatenate([b.edge_nodes(edge) for b in blocks])
    nodes = nodes[~np.isin(nodes, tied)]
    coords = np.concatenate([b.coords.reshape(-1, 2) for b in blocks])
    first = blocks[0].node_offset
    y = coords[nodes - first, 1]
    return nodes[np.argsort(y if edge == "right" else -y, kind="stable")]


def transition_model(model: fm.Model, bodies, *, surface_rows: int | None = None, rows_per_level: int = 2,
                     max_width: float | None = None) -> fm.Model:
    """``model`` with each profiled block named in ``bodies`` re-meshed as a coarsening stack (module docstring).

    The block must be an axis-aligned rectangle profiled on its ``top`` or ``bottom`` edge (a rough pair's body,
    :func:`fivid.fe.rough_pair.rough_pair_config`), with ``nx`` dividing by ``2^K`` (:func:`transition_columns`);
    its divisions through the depth are replaced. References into it are carried over edge by edge: whole clamped
    edges stay clamped, motions, contacts and pressure loads keep the same edge and coordinate range, sensors go
    to the nearest node of their edge (one sensor per node), reactions keep their edge. The profiled edge keeps its nodes exactly.

    Parameters
    ----------
    model : Model
    bodies : iterable of str
        Block names to re-mesh.
    surface_rows : int, optional
        Rows of the profiled level (element thickness = its column width); None: :func:`surface_rows_for` the
        block's profile.
    rows_per_level : int
        Rows of each coarser level.
    max_width : float, optional
        Widest element [m] (the coarsening stops there); None: an eighth of the block's depth
        (:data:`DEPTH_PER_MAX_WIDTH`).

    Raises
    ------
    ValueError
        A named block is not a profiled rectangle, or springs or point masses use its nodes.
    """
    names = list(bodies)
    new_blocks, ties, replaced = [], [], {}
    offset = 0
    for b in model.blocks:
        if b.name not in names:
            nb = dataclasses.replace(b, node_offset=offset)
            new_blocks.append(nb)
            replaced[b.name] = (b, [nb], None)
            offset += nb.n_nodes
            continue
        if b.shape != "profile":
            raise ValueError(f"transition_model: block {b.name!r} is not a profiled rectangle (shape {b.shape!r})")
        edge = _profiled_edge(model, b)
        depth = float(abs(np.mean(b.coords[-1, :, 1]) - np.mean(b.coords[0, :, 1])))
        h = float(b.coords[0, -1, 0] - b.coords[0, 0, 0]) / b.nx
        rows0 = surface_rows or surface_rows_for((b.coords[-1] if edge == "top" else b.coords[0])[:, 1], h)
        levels = transition_levels(b.nx, h, depth, surface_rows=rows0, rows_per_level=rows_per_level,
                                   max_width=max_width or depth / DEPTH_PER_MAX_WIDTH)
        blocks, bt, offset = _stack(b, edge, levels, offset)
        new_blocks += blocks
        ties += bt
        replaced[b.name] = (b, blocks, edge)
    tied = np.concatenate([t.slave_nodes for t in ties]) if ties else np.zeros(0, dtype=np.int64)
    coords = np.concatenate([b.coords.reshape(-1, 2) for b in new_blocks])

    def owner(nodes):
        return model.block_of_node(int(np.asarray(nodes).ravel()[0]))

    def remap(nodes):
        """Old nodes of one edge of one block -> the new nodes of that edge in the same coordinate range."""
        nodes = np.asarray(nodes, dtype=np.int64)
        old, blocks, edge = replaced[owner(nodes).name]
        if edge is None:
            return nodes - old.node_offset + blocks[0].node_offset
        e = _edge_of(old, nodes)
        if e is None:
            raise ValueError(f"transition_model: nodes of {old.name!r} that are not on one edge cannot be carried over")
        new = _stack_edge(blocks, e, edge, tied)
        xy_old = model.coords[nodes]
        axis = 0 if e in ("top", "bottom") else 1
        tol = 1e-9 * float(np.ptp(old.coords.reshape(-1, 2), axis=0).max())
        lo, hi = xy_old[:, axis].min() - tol, xy_old[:, axis].max() + tol
        if e not in ("top", "bottom") and nodes.size == old.ny + 1:
            lo, hi = -np.inf, np.inf  # the whole side edge (its rows moved)
        c = coords[new, axis]
        return new[(c >= lo) & (c <= hi)]

    for p in model.point_masses:
        _refuse(replaced, model, p.node, "point mass", p.name)
    for s in model.springs:
        _refuse(replaced, model, s.node_a, "spring", s.name)
        if s.node_b >= 0:
            _refuse(replaced, model, s.node_b, "spring", s.name)

    fixed = set()
    fixed_old = set(int(d) for d in model.fixed_dofs)
    for old, blocks, edge in replaced.values():
        if edge is None:
            own = old.node_numbers().ravel()
            for d in (2 * own, 2 * own + 1):
                for dof in d[np.isin(d, model.fixed_dofs)]:
                    fixed.add(int(dof - 2 * old.node_offset + 2 * blocks[0].node_offset))
            continue
        for e in fm.EDGES:
            en = old.edge_nodes(e)
            for comp in (0, 1):
                if all(2 * int(n) + comp in fixed_old for n in en):
                    fixed.update(int(2 * n + comp) for n in _stack_edge(blocks, e, edge, tied))
    motions = []
    for m in model.motions:
        nodes = remap(m.nodes)
        motions.append(dataclasses.replace(m, nodes=nodes))
        fixed.update(int(2 * n + m.component) for n in nodes)
    reactions = tuple(dataclasses.replace(r, nodes=remap(r.nodes)) for r in model.reactions)
    contacts = tuple(dataclasses.replace(c, slave_nodes=remap(c.slave_nodes),
                                         master_nodes=remap(c.master_nodes) if len(c.master_nodes) else c.master_nodes)
                     for c in model.contacts)
    loads = []
    for ld in model.loads:
        old, blocks, edge = replaced[owner(ld.segments).name]
        nodes = remap(np.unique(ld.segments))
        blk = next(b for b in blocks if np.isin(nodes, b.node_numbers()).all())
        e = _edge_of(old, np.unique(ld.segments))
        loads.append(dataclasses.replace(ld, body=blk.name, segments=blk.edge_segments(e, nodes)))
    sensors, seen = [], set()
    for s in model.sensors:
        old, blocks, edge = replaced[model.block_of_node(s.node).name]
        if edge is None:
            node = int(s.node - old.node_offset + blocks[0].node_offset)
        else:
            e = _edge_of(old, np.array([s.node]))
            cand = (_stack_edge(blocks, e, edge, tied) if e is not None
                    else np.concatenate([b.node_numbers().ravel() for b in blocks]))
            cand = cand[~np.isin(cand, tied)]
            node = int(cand[np.argmin(np.hypot(*(coords[cand] - model.coords[s.node]).T))])
        if node not in seen:
            seen.add(node)
            sensors.append(dataclasses.replace(s, node=node))
    fixed_dofs = np.array(sorted(fixed), dtype=np.int64)
    fixed_dofs = fixed_dofs[~np.isin(fixed_dofs // 2, tied)]
    return dataclasses.replace(model, blocks=tuple(new_blocks), n_nodes=int(coords.shape[0]), coords=coords,
                               fixed_dofs=fixed_dofs, motions=tuple(motions), contacts=contacts, loads=tuple(loads),
                               sensors=tuple(sensors), reactions=reactions, ties=tuple(ties))


def _profiled_edge(model: fm.Model, block: fm.Block) -> str:
    """``"top"`` or ``"bottom"``: the block's profiled edge (its config's ``profile.edge``; else the uneven one)."""
    body = (model.config.get("bodies") or {}).get(block.name) if isinstance(model.config, dict) else None
    prof = body.get("profile") if isinstance(body, dict) else None
    if isinstance(prof, dict) and prof.get("edge") in ("top", "bottom"):
        return prof["edge"]
    return "top" if np.ptp(block.coords[-1, :, 1]) >= np.ptp(block.coords[0, :, 1]) else "bottom"


def _refuse(replaced, model, node: int, what: str, name: str) -> None:
    if replaced[model.block_of_node(int(node)).name][2] is not None:
        raise ValueError(f"transition_model: {what} {name!r} uses a node of re-meshed block "
                         f"{model.block_of_node(int(node)).name!r} (not carried over)")
