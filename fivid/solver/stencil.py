"""Per-block stencil coefficients of the Q4 stiffness (DESIGN §7): ``K u`` as a 3x3-neighbourhood stencil.

Node ``p = (i, j)`` of a structured block couples with its 3x3 neighbourhood through 2x2 blocks of
``K``; the coefficient of dof ``a`` of ``p`` on dof ``b`` of ``p + dj*(nx+1) + di`` is the sum, over the
(up to four) elements holding both nodes, of the element stiffness entries
(:func:`fivid.fe.assembly.element_stiffness_q4`). When every element of a block has the same stiffness
(rectangles and parallelograms of equal size), all interior nodes share one coefficient set
(``uniform``); boundary nodes and the nodes of mapped blocks use per-node coefficients.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BlockStencils", "block_stencils", "stencil_index", "apply_stencils"]

# local corner offsets (i, j) of a Q4 element, counter-clockwise from its (i, j) node
_CORNERS = ((0, 0), (1, 0), (1, 1), (0, 1))


def stencil_index(dj: int, di: int, a: int, b: int) -> int:
    """Position in a node's 36 coefficients of the coupling of its dof ``a`` with dof ``b`` of neighbour ``(di, dj)``."""
    return ((dj + 1) * 3 + (di + 1)) * 4 + 2 * a + b


@dataclass(frozen=True)
class BlockStencils:
    """Stencil data and dof layout of a model for :mod:`fivid.solver._kernels`.

    Attributes
    ----------
    n_nodes : int
    pad : int
        Zero entries before node 0 (and after the last node) in each component half.
    npd : int
        Length of one component half, ``n_nodes + 2*pad``.
    blocks : ndarray of int64, shape (n_patch, 5)
        Patches of nodes sharing one stencil, ``first x-index, columns, rows, row stride, rectangular``:
        the interior and each edge (corners excluded) of every uniform block; ``rectangular`` = 1 when the
        xy couplings with the axis neighbours vanish (rectangular elements: 13 terms per force instead of 18).
    c_uni : ndarray, shape (n_patch, 36)
        Patch coefficients [N m-1].
    lst_idx, lst_stride : ndarray of int64, shape (n_list,)
        x-index and row stride of every other node (corners of uniform blocks, all nodes of mapped blocks).
    lst_coef : ndarray, shape (n_list, 36)
        Their coefficients [N m-1].
    """

    n_nodes: int
    pad: int
    npd: int
    blocks: np.ndarray
    c_uni: np.ndarray
    lst_idx: np.ndarray
    lst_stride: np.ndarray
    lst_coef: np.ndarray

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


def block_stencils(model) -> BlockStencils:
    """Stencil coefficients of every block of ``model`` (springs and constraints not included).

    A block is uniform when all its element stiffnesses agree to ``1e-12`` of their largest entry
    (float resolution of the element integration, ~10 ulp): its interior nodes then share one coefficient
    set, and so do the nodes of each edge (neighbours outside the block get zero coefficients; the padding
    keeps their indices in bounds). Blocks with fewer than 3x3 nodes are listed node by node.
    """
    from fivid.fe.assembly import block_element_stiffness

    pad = max(b.nx + 1 for b in model.blocks) + 1
    npd = model.n_nodes + 2 * pad
    uni_rows, uni_coef, lst_idx, lst_stride, lst_coef = [], [], [], [], []
    for block in model.blocks:
        ke = block_element_stiffness(block)
        uniform = bool(np.allclose(ke, ke[0, 0], rtol=0.0, atol=1e-12 * np.abs(ke[0, 0]).max()))
        uniform = uniform and block.nx >= 2 and block.ny >= 2
        c = _node_coefficients(ke).reshape(block.ny + 1, block.nx + 1, 36)
        listed = np.ones((block.ny + 1, block.nx + 1), dtype=bool)
        if uniform:
            nx, ny, stride = block.nx, block.ny, block.nx + 1
            o = pad + block.node_offset
            for (j, i), cols, rows in (((1, 1), nx - 1, ny - 1), ((0, 1), nx - 1, 1), ((ny, 1), nx - 1, 1),
                                       ((1, 0), 1, ny - 1), ((1, nx), 1, ny - 1)):
                cc = c[j, i].reshape(9, 2, 2)
                # rectangular elements: no xy coupling with the axis neighbours and the node itself (exactly
                # zero up to the Gauss-sum round-off, ~1e-18 of the diagonal), the kernel skips those terms
                cross = np.abs(cc[[1, 3, 4, 5, 7]][:, [0, 1], [1, 0]])
                rect = int(cross.max() <= 1e-12 * np.abs(cc).max())
                uni_rows.append((o + j * stride + i, cols, rows, stride, rect))
                uni_coef.append(c[j, i])
            listed[:, :] = False
            listed[[0, 0, -1, -1], [0, -1, 0, -1]] = True
        nodes = block.node_numbers()[listed]
        lst_idx.append(pad + nodes)
        lst_stride.append(np.full(nodes.size, block.nx + 1))
        lst_coef.append(c[listed])
    return BlockStencils(
        n_nodes=model.n_nodes,
        pad=pad,
        npd=npd,
        blocks=np.array(uni_rows, dtype=np.int64).reshape(-1, 5),
        c_uni=np.array(uni_coef, dtype=float).reshape(-1, 36),
        lst_idx=np.concatenate(lst_idx).astype(np.int64),
        lst_stride=np.concatenate(lst_stride).astype(np.int64),
        lst_coef=np.ascontiguousarray(np.concatenate(lst_coef), dtype=float),
    )


def apply_stencils(stencils: BlockStencils, w: np.ndarray) -> np.ndarray:
    """``K_blocks @ w`` [N] by the stencil kernel, global dof order in and out; ``w`` [m] (n_dofs,)."""
    from fivid.solver._kernels import block_forces

    s = stencils
    wk = s.to_kernel(np.asarray(w, dtype=float))
    f = np.zeros_like(wk)
    block_forces(wk, f, s.npd, s.blocks, s.c_uni, s.lst_idx, s.lst_stride, s.lst_coef)
    return s.to_global(f)
