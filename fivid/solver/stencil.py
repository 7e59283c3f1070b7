"""Per-block stencil coefficients of the Q4 stiffness (DESIGN §7): ``K u`` as a 3x3-neighbourhood stencil.

Node ``p = (i, j)`` of a structured block couples with its 3x3 neighbourhood through 2x2 blocks of
``K``; the coefficient of dof ``a`` of ``p`` on dof ``b`` of ``p + dj*stride + di`` is the sum, over the
(up to four) elements holding both nodes, of the element stiffness entries
(:func:`fivid.fe.assembly.element_stiffness_q4`). Four storage kinds, all without per-node index arrays
except the last:

- uniform blocks (every element the same: rectangles, parallelograms of equal size): the interior and the
  four edges (corners excluded) each share one coefficient set (``c_uni``);
- rotated patches (rings and arcs): every row is one stencil seen from each node's column frame (a radial
  layer's elements are rotations of one element), stored once per row in ``c_uni`` with the columns' angles in
  ``rot``; the kernel turns the displacements into the column frames, applies the row's stencil and turns the
  forces back. The end (arc) or seam (ring) columns are listed;
- mapped blocks (profiled or general quadrilaterals): per-node coefficients ``c_map`` in component-major layout
  ``(32, n)`` (consecutive nodes contiguous, so the row loop vectorises), one patch covering the whole block
  (neighbours outside it have zero coefficients; the padding keeps their indices in bounds); on a periodic ring
  the patch covers columns 1..nx-2. Stored in float32 in difference form (:func:`_difference_form`): the force
  is ``sum_k C_k (w_k - w_m)`` over the 8 neighbours, the node's own coupling being minus the others' sum;
- listed nodes with explicit neighbour indices: the corners of uniform blocks and the end or seam columns of
  rotated patches and periodic rings.

Speed of mapped patches (issue 30 item 5; bench_solver ``curved_fraction_of_bare_stencil`` and
``*_stencil_fraction_of_bare_stencil``, measured on a loaded 2-core EPYC, AVX-512): the per-node row loop is
vectorised (8 lanes of 18 FMAs per force component), but a mapped node streamed its 36 float64 coefficients (288 B) from
L3 every step (the ring's 2.2 MB do not fit the L2), about 470 B per node and step with the update pass's
arrays: the step is bound by L3 bandwidth (main's kernel ~5 ns/node idle, the bare rectangular stencil ~1.4).
Deduplicating the coefficient table does not apply: no two nodes of the ring or of the rough pair have equal
coefficients in x, y (a ring's nodes differ by their rotation; a profiled block's heights enter every row, the
straight edge's excepted). The ring's rows are rotations of one stencil, hence the rotated patches: 36
coefficients per row instead of per node, +8 multiply-adds per node for the two rotations, cache-resident
(:func:`block_stencils` for the tolerance). Profiled blocks keep the coefficient stream; earlier layouts measured
and not kept (branches ``speed-tiled-experiment``, ``speed-symmetric-experiment``): tiles of 16 nodes with both
components in one pass (no faster on the ring, 1.2x on the rough pair) and the 19 independent coefficients of a
symmetric stencil (+5-10 %, results change at 1e-16).

The mapped coefficients in float32, difference form (issue 26 item 5): the rough pair's surface level streamed 36
float64 coefficients per node (288 B; 18 MB on the 120 mm Ra 1 pair, which with the step's 17 MB of state arrays
exceeds the 32 MB L3); 32 float32 (128 B) halve and more that stream. Accuracy: each coefficient is rounded to
float32, relative error <= 2^-24 (round to nearest), so a node's force moves by at most ``2^-24 sum_k |C_k| |w_k -
w_m|`` -- 6e-8 of the sum of the absolute coupling forces, i.e. of the local deformation's forces, not of the
displacement: in difference form a rigid translation gives exactly zero (``w_k - w_m`` is exactly 0), whatever
its size (a slider 60 um along, 1e4 times its strain displacements). Natural frequencies move by the same relative
order (< 1e-7), far below any criterion of the studies (1 dB, mode shifts of 1e-3). The stiffness applied is
then symmetric to that order, not to round-off: the energy balance's internal work and strain energy agree to
~1e-7 of the strain energy instead of 1e-15. The state (``u, v, w, f``) and every product and sum stay float64.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fivid.fe.assembly import block_element_stiffness
from fivid.fe.prestress import block_geometric_stiffness

__all__ = ["BlockStencils", "block_stencils", "stencil_index", "apply_stencils", "MAPPED_DTYPE"]

# local corner offsets (i, j) of a Q4 element, counter-clockwise from its (i, j) node
_CORNERS = ((0, 0), (1, 0), (1, 1), (0, 1))


def stencil_index(dj: int, di: int, a: int, b: int) -> int:
    """Position in a node's 36 coefficients of the coupling of its dof ``a`` with dof ``b`` of neighbour ``(di, dj)``."""
    return ((dj + 1) * 3 + (di + 1)) * 4 + 2 * a + b


#: storage type of the mapped patches' per-node coefficients (difference form, :func:`_difference_form`)
MAPPED_DTYPE = np.float32
#: the node's own coupling (neighbour position 4 of 0..8) is not stored in difference form
_OWN = slice(16, 20)

# patch kinds (column 4 of BlockStencils.blocks)
PATCH_UNIFORM = 0
PATCH_RECT = 1
PATCH_MAPPED = 2
PATCH_ROTATED = 3


@dataclass(frozen=True)
class BlockStencils:
    """Stencil data and dof layout of a model for :mod:`fivid.solver._stencil_kernels`.

    Attributes
    ----------
    n_nodes : int
    pad : int
        Zero entries before node 0 (and after the last node) in each component half.
    npd : int
        Length of one component half, ``n_nodes + 2*pad``.
    blocks : ndarray of int64, shape (n_patch, 8)
        Patches of nodes, ``first x-index, columns, rows, row stride, kind, coefficients, block start,
        angles``: kind ``PATCH_UNIFORM``/``PATCH_RECT`` share the stencil ``c_uni[coefficients]`` (rect: the xy
        couplings with the axis neighbours vanish, 13 terms per force instead of 18); ``PATCH_MAPPED`` has
        per-node stencils in ``c_map[:, coefficients + row*columns + column]``; ``PATCH_ROTATED`` one stencil
        per row in the column frames, ``c_uni[coefficients + row]``, with the angles of its block's columns
        (from x-index ``block start``, ``row stride`` columns) at ``rot[:, angles + column]``. The last two
        columns are 0 for the other kinds.
    c_uni : ndarray, shape (n_uniform, 36)
        Shared stencils [N m-1].
    c_map : ndarray of float32, shape (32, n_mapped)
        Per-node stencils of mapped patches [N m-1], component-major, in difference form: the couplings with the
        8 neighbours (positions 0-3 and 5-8 of :func:`stencil_index`'s, the node's own left out:
        :func:`_difference_form`).
    rot : ndarray, shape (2, n_angles)
        Cosine and sine of the column angles of the rotated patches' blocks.
    lst_idx : ndarray of int64, shape (n_list,)
        x-index of every listed node (corners of uniform blocks, seam columns of periodic rings).
    lst_nbr : ndarray of int64, shape (n_list, 9)
        x-indices of their 3x3 neighbours, row-major from ``(di, dj) = (-1, -1)`` (neighbours outside the
        block: any in-bounds index, their coefficients are zero).
    lst_coef : ndarray, shape (n_list, 36)
        Their stencils [N m-1].
    tie_s : ndarray of int64, shape (n_tie,)
        x-index of every tied node of the model's mesh transitions (:class:`fivid.fe.model.Tie`).
    tie_m : ndarray of int64, shape (n_tie, 2)
        x-indices of its two masters.
    tie_w : ndarray, shape (n_tie, 2)
        Their interpolation weights [-].
    tie_j : ndarray of int64, shape (n_joint, 3)
        Ties that are whole halving joints, ``(s0, m0, n)``: x-indices ``s0 .. s0 + 2n`` tied to ``m0 .. m0 + n``
        (even ones on a master, odd ones half-way), not listed in ``tie_*`` (:func:`_tie_arrays`).
    """

    n_nodes: int
    pad: int
    npd: int
    blocks: np.ndarray
    c_uni: np.ndarray
    c_map: np.ndarray
    rot: np.ndarray
    lst_idx: np.ndarray
    lst_nbr: np.ndarray
    lst_coef: np.ndarray
    tie_s: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    tie_m: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    tie_w: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    tie_j: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), dtype=np.int64))

    @property
    def kernel_args(self):
        """The stencil argument of :func:`fivid.solver._stencil_kernels.block_forces` (a
        :class:`fivid.solver._stencil_kernels.StencilArrays`), with its own scratch array (one per call: runs
        sharing these stencils do not share scratch)."""
        from fivid.solver._stencil_kernels import StencilArrays  # lazy: pulls numba

        return StencilArrays(self.npd, self.blocks, self.c_uni, self.c_map, self.rot, np.zeros(2 * self.npd),
                             self.lst_idx, self.lst_nbr, self.lst_coef, self.tie_s, self.tie_m, self.tie_w, self.tie_j)

    def dof_index(self, dof) -> np.ndarray:
        """Flat kernel index of global dof(s) ``2*node + c``."""
        dof = np.asarray(dof, dtype=np.int64)
        return (dof % 2) * self.npd + self.pad + dof // 2

    def node_index(self, node) -> np.ndarray:
        """x-index of global node(s)."""
        return self.pad + np.asarray(node, dtype=np.int64)

    def to_kernel(self, vec: np.ndarray) -> np.ndarray:
        """A global dof vector (n_dofs,) in the kernel layout (2*npd,), zero padding."""
        out = np.zeros(2 * self.npd)
        out[self.dof_index(np.arange(2 * self.n_nodes))] = vec
        return out

    def to_global(self, vec: np.ndarray) -> np.ndarray:
        """A kernel-layout vector back in global dof order (n_dofs,)."""
        return np.asarray(vec)[self.dof_index(np.arange(2 * self.n_nodes))]


def _node_coefficients(ke: np.ndarray) -> np.ndarray:
    """Scatter element stiffnesses ``ke`` (ny, nx, 8, 8) into node stencils (ny+1, nx+1, 3, 3, 2, 2)."""
    ny, nx = ke.shape[:2]
    c = np.zeros((ny + 1, nx + 1, 3, 3, 2, 2))
    for A, (ia, ja) in enumerate(_CORNERS):
        for B, (ib, jb) in enumerate(_CORNERS):
            di, dj = ib - ia, jb - ja
            c[ja:ja + ny, ia:ia + nx, dj + 1, di + 1] += ke[:, :, 2 * A:2 * A + 2, 2 * B:2 * B + 2]
    return c


def _block_coefficients(block, ke: np.ndarray) -> np.ndarray:
    """Node stencils of a block, shape (ny+1, n_cols, 36); a periodic ring folds column nx onto column 0."""
    c = _node_coefficients(ke)
    if block.periodic:
        c[:, 0] += c[:, -1]
        c = c[:, :-1]
    return c.reshape(block.ny + 1, block.n_cols, 36)


def _neighbours(block, pad: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """x-indices of the 3x3 neighbours of local nodes (i, j), shape (n, 9); outside the block: the node itself."""
    out = np.empty((i.size, 9), dtype=np.int64)
    own = pad + block.node(i, j)
    for dj in (-1, 0, 1):
        for di in (-1, 0, 1):
            ii, jj = i + di, j + dj
            inside = (jj >= 0) & (jj <= block.ny)
            if not block.periodic:
                inside &= (ii >= 0) & (ii <= block.nx)
            nb = pad + block.node(np.where(inside, ii, i), np.where(inside, jj, j))
            out[:, (dj + 1) * 3 + di + 1] = np.where(inside, nb, own)
    return out


#: two stencils are one when they agree to this fraction of the block's largest coefficient: the float
#: resolution of the element integration (coordinates rounded to ~eps of the block's size, differenced over an
#: element: measured 3e-14 on the 360 x 20 ring of ``configs/models/ring_pressure.yaml``), ~10^4 below any
#: geometric difference between rows
SAME_STENCIL_RTOL = 1e-12


def _uniform_tolerance(block) -> float:
    """Relative tolerance [-] under which a block's element stiffnesses are one: :data:`SAME_STENCIL_RTOL`, or the
    round-off of a long block's coordinates if larger -- ``eps |x|`` with ``|x|`` up to the block's extent, differenced
    over one element, is ``eps`` times the elements along it (8x for the products of the integration): 1.2e-12
    measured on the 5 248-column rectangles of the 120 mm rough pair's transition levels, whose coordinates are
    multiples of a 22.9 um step."""
    return max(SAME_STENCIL_RTOL, 8.0 * np.finfo(float).eps * max(block.nx, block.ny))


def _column_angles(block) -> np.ndarray:
    """Angle of every node column of ``block`` against its first [rad]: the direction from its row-0 node to its
    last-row node (a ring's radial lines; 0 for the vertical columns of rectangles and profiled blocks)."""
    d = block.coords[-1, :block.n_cols] - block.coords[0, :block.n_cols]
    theta = np.arctan2(d[:, 1], d[:, 0])
    return theta - theta[0]


def _rotated_rows(block, c: np.ndarray, i0: int, i1: int, tol: float):
    """``(row stencils (ny+1, 36), cos and sin of the column angles (2, n_cols))`` when every row of the patch
    ``c[:, i0:i1]`` is one stencil seen from each node's column frame, else None.

    With ``R_k`` the rotation by column ``k``'s angle (:func:`_column_angles`), node ``i``'s 2x2 coupling with
    neighbour column ``i + di`` is ``C_i = R_i C' R_{i+di}^T``; the force is then ``R_i sum C' (R^T w)`` with one
    ``C'`` per row. ``C'`` is the row's mean of ``R_i^T C_i R_{i+di}`` over its nodes, accepted when no node
    differs from it by more than ``tol`` (so the forces change at the integration's round-off only)."""
    ny1, ncols = c.shape[:2]
    theta = _column_angles(block)
    cs, sn = np.cos(theta), np.sin(theta)
    r = np.stack([np.stack([cs, -sn], -1), np.stack([sn, cs], -1)], -2)  # (ncols, 2, 2)
    cols = np.arange(i0, i1)
    nb = cols[:, None] + np.array([-1, 0, 1])[None, :]
    nb = nb % ncols if block.periodic else np.clip(nb, 0, ncols - 1)  # outside a block: zero coefficients
    cc = c[:, i0:i1].reshape(ny1, i1 - i0, 3, 3, 2, 2)
    local = np.einsum("ica,jiyxce,ixeb->jiyxab", r[cols], cc, r[nb])
    ref = local.mean(axis=1)
    if np.abs(local - ref[:, None]).max() > tol:
        return None
    return ref.reshape(ny1, 36), np.stack([cs, sn])


def block_stencils(model, prestress=None, *, rotated: bool = True) -> BlockStencils:
    """Stencil coefficients of every block of ``model`` (springs and constraints not included; the model's ties
    are, as ``tie_*``: the kernel eliminates the tied nodes).

    ``prestress`` (n_dofs,), optional: a static state [m] whose initial-stress stiffness
    (:func:`fivid.fe.prestress.block_geometric_stiffness`) is added to each element's elastic stiffness, so the
    stencil applies ``K + K_sigma`` (folded into the coefficients: no cost per step; a block whose stress varies
    is not uniform, nor rotated unless the stress is, and takes the mapped path).

    A block is uniform when all its element stiffnesses agree to :data:`SAME_STENCIL_RTOL` of their largest
    entry (float resolution of the element integration; a long block's coordinate round-off if larger,
    :func:`_uniform_tolerance`): its interior nodes then share one coefficient set, and
    so do the nodes of each edge. Other blocks (and blocks with fewer than 3x3 nodes) are patches whose rows are
    rotations of one stencil (an annular ring's or arc's radial layers, :func:`_rotated_rows`, unless
    ``rotated`` is false; their first and last columns listed) or, failing that, mapped patches with per-node
    coefficients; periodic rings list their two seam columns with explicit neighbours.
    """
    pad = max(b.n_cols for b in model.blocks) + 1
    npd = model.n_nodes + 2 * pad
    rows, uni_coef, map_coef, n_map, rot, n_rot = [], [], [], 0, [], 0
    lst_idx, lst_nbr, lst_coef = [], [], []
    for block in model.blocks:
        ke = block_element_stiffness(block)
        if prestress is not None:
            ke = ke + block_geometric_stiffness(block, prestress)
        same = _uniform_tolerance(block)
        uniform = bool(np.allclose(ke, ke[0, 0], rtol=0.0, atol=same * np.abs(ke[0, 0]).max()))
        uniform = uniform and block.nx >= 2 and block.ny >= 2 and not block.periodic
        c = _block_coefficients(block, ke)
        o = pad + block.node_offset
        stride = block.n_cols
        listed = np.zeros((block.ny + 1, block.n_cols), dtype=bool)
        if uniform:
            nx, ny = block.nx, block.ny
            for (j, i), cols, nrows in (((1, 1), nx - 1, ny - 1), ((0, 1), nx - 1, 1), ((ny, 1), nx - 1, 1),
                                        ((1, 0), 1, ny - 1), ((1, nx), 1, ny - 1)):
                cc = c[j, i].reshape(9, 2, 2)
                # rectangular elements: no xy coupling with the axis neighbours and the node itself (exactly
                # zero up to the Gauss-sum round-off, ~1e-18 of the diagonal), the kernel skips those terms
                cross = np.abs(cc[[1, 3, 4, 5, 7]][:, [0, 1], [1, 0]])
                kind = PATCH_RECT if cross.max() <= same * np.abs(cc).max() else PATCH_UNIFORM
                rows.append((o + j * stride + i, cols, nrows, stride, kind, len(uni_coef), 0, 0))
                uni_coef.append(c[j, i])
            listed[[0, 0, -1, -1], [0, -1, 0, -1]] = True
        else:
            # rotated rows: the inner columns (an arc's end columns miss an element row, a ring's seam columns
            # reach across the seam: both listed)
            same_rows = (_rotated_rows(block, c, 1, stride - 1, SAME_STENCIL_RTOL * np.abs(c).max())
                         if rotated and stride >= 3 else None)
            if same_rows is not None:
                rows.append((o + 1, stride - 2, block.ny + 1, stride, PATCH_ROTATED, len(uni_coef), o, n_rot))
                uni_coef.extend(same_rows[0])
                rot.append(same_rows[1])
                n_rot += stride
                listed[:, [0, -1]] = True
            else:
                i0, i1 = (1, block.nx - 1) if block.periodic else (0, block.n_cols)
                rows.append((o + i0, i1 - i0, block.ny + 1, stride, PATCH_MAPPED, n_map, 0, 0))
                patch = c[:, i0:i1].reshape(-1, 36)
                map_coef.append(_difference_form(patch, block.name))
                n_map += patch.shape[0]
                if block.periodic:
                    listed[:, [0, -1]] = True
        j, i = np.nonzero(listed)
        lst_idx.append(pad + block.node(i, j))
        lst_nbr.append(_neighbours(block, pad, i, j))
        lst_coef.append(c[listed])
    return BlockStencils(
        n_nodes=model.n_nodes,
        pad=pad,
        npd=npd,
        blocks=np.array(rows, dtype=np.int64).reshape(-1, 8),
        c_uni=np.array(uni_coef, dtype=float).reshape(-1, 36),
        c_map=np.ascontiguousarray(np.concatenate(map_coef, axis=1) if map_coef else np.zeros((32, 0)),
                                   dtype=MAPPED_DTYPE),
        rot=np.ascontiguousarray(np.concatenate(rot, axis=1) if rot else np.zeros((2, 0))),
        lst_idx=np.concatenate(lst_idx).astype(np.int64),
        lst_nbr=np.ascontiguousarray(np.concatenate(lst_nbr), dtype=np.int64).reshape(-1, 9),
        lst_coef=np.ascontiguousarray(np.concatenate(lst_coef), dtype=float).reshape(-1, 36),
        **_tie_arrays(model, pad),
    )


def _difference_form(patch: np.ndarray, name: str) -> np.ndarray:
    """The mapped coefficients ``(32, n)`` in :data:`MAPPED_DTYPE` of node stencils ``patch`` (n, 36): the 8
    neighbours' 2x2 couplings, component-major, the node's own left out.

    ``K w`` at node ``m`` is ``sum_k C_k w_k``; a rigid translation gives no force, so ``C_m = -sum_(k != m) C_k``
    and ``K w = sum_(k != m) C_k (w_k - w_m)``. That identity holds to the element integration's round-off; it is
    checked here against float32's resolution: a block whose 2x2 row sums exceed ``2^-24`` of the sum of their
    absolute values (an element stiffness that is not translation-invariant) would lose more by leaving out its
    own coupling than the float32 rounding does, and is refused (``ValueError``; no element of fivid.fe does)."""
    own = np.abs(patch.reshape(-1, 9, 2, 2).sum(axis=1))
    scale = np.abs(patch.reshape(-1, 9, 2, 2)).sum(axis=1)
    if np.any(own > np.finfo(np.float32).eps / 2 * scale):
        worst = int(np.argmax((own / np.maximum(scale, 1e-300)).reshape(len(patch), -1).max(axis=1)))
        raise ValueError(f"block {name!r}: the stiffness stencil of its node {worst} does not vanish for a rigid "
                         f"translation (2x2 row sums up to {own.max():.3g} N/m against {scale.max():.3g}): the "
                         "difference form of the mapped stencil needs a translation-invariant element stiffness")
    return np.ascontiguousarray(np.delete(patch, np.r_[_OWN], axis=1).T, dtype=MAPPED_DTYPE)


def _halving_joint(tie):
    """``(s0, m0, n)`` when ``tie`` is a whole halving joint (:mod:`fivid.fe.transition`'s: slaves ``s0 .. s0 + 2n``
    in order, slave ``2i`` on master ``m0 + i`` with weights (1, 0) -- the last one (0, 1) on ``m0 + n`` -- and slave
    ``2i + 1`` half-way between ``m0 + i`` and ``m0 + i + 1``), else None."""
    s, m, w = np.asarray(tie.slave_nodes), np.asarray(tie.master_nodes), np.asarray(tie.weights, dtype=float)
    k = s.size
    if k < 3 or k % 2 == 0 or np.any(np.diff(s) != 1):
        return None
    n = (k - 1) // 2
    m0 = int(m[0, 0])
    i = np.arange(k) // 2
    i[-1] = n - 1  # the last slave's segment is the last one
    want_w = np.where((np.arange(k) % 2 == 1)[:, None], 0.5, [1.0, 0.0])
    want_w[-1] = (0.0, 1.0)
    if np.array_equal(m, np.stack([m0 + i, m0 + i + 1], axis=1)) and np.array_equal(w, want_w):
        return int(s[0]), m0, n
    return None


def _tie_arrays(model, pad: int) -> dict:
    """``tie_s``, ``tie_m``, ``tie_w`` and ``tie_j`` of :class:`BlockStencils` from the model's ties (x-indices:
    ``pad + node``): the whole halving joints as ``tie_j`` (:func:`_halving_joint`), the others listed. The joints
    are done after the listed ties, so a joint's masters may not be tied themselves (a chain of ties would need
    an order in both passes); then everything is listed."""
    ties = tuple(getattr(model, "ties", ()))
    if not ties:
        return {}
    joints = [_halving_joint(t) for t in ties]
    slaves = np.concatenate([t.slave_nodes for t in ties])
    masters = np.concatenate([np.ravel(t.master_nodes) for t in ties])
    if np.isin(masters, slaves).any():
        joints = [None] * len(ties)
    listed = [t for t, j in zip(ties, joints) if j is None]
    out = {"tie_j": np.array([(pad + s0, pad + m0, n) for s0, m0, n in filter(None, joints)],
                             dtype=np.int64).reshape(-1, 3)}
    if listed:
        out.update(tie_s=np.ascontiguousarray(pad + np.concatenate([t.slave_nodes for t in listed]), dtype=np.int64),
                   tie_m=np.ascontiguousarray(pad + np.concatenate([t.master_nodes for t in listed]), dtype=np.int64),
                   tie_w=np.ascontiguousarray(np.concatenate([t.weights for t in listed]), dtype=float))
    return out


def apply_stencils(stencils: BlockStencils, w: np.ndarray) -> np.ndarray:
    """``K_blocks @ w`` [N] by the stencil kernel, global dof order in and out; ``w`` [m] (n_dofs,)."""
    from fivid.solver._stencil_kernels import block_forces  # lazy: pulls numba

    s = stencils
    wk = s.to_kernel(np.asarray(w, dtype=float))
    f = np.zeros_like(wk)
    block_forces(wk, f, s.kernel_args)
    return s.to_global(f)
