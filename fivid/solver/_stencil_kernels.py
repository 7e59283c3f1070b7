"""Internal forces of the explicit solver (layer L0): the per-block 3x3 stencils ``f = K w`` (with the tied
nodes of mesh transitions eliminated, ``f = T^T K T w``) and the discrete springs and dashpots. Layout and indexing: :mod:`fivid.solver._kernels`."""

from collections import namedtuple

from numba import uint64

from fivid.solver._kernels import fma_kernel, kernel

__all__ = ["StencilArrays", "block_forces", "spring_forces"]

#: the stencil argument of :func:`block_forces` (``block_forces(w, f, stencil)``), built by
#: :attr:`fivid.solver.stencil.BlockStencils.kernel_args`
StencilArrays = namedtuple("StencilArrays", ["npd", "blocks", "c_uni", "c_map", "rot", "wr", "lst_idx", "lst_nbr",
                                             "lst_coef", "tie_s", "tie_m", "tie_w", "tie_j"])


@fma_kernel
def _uniform_component(wx, wy, fo, c, a, first, ncols, nrows, stride):
    """Force component ``a`` on a rectangular patch of nodes sharing one stencil ``c`` (unsigned indices: no
    negative-index wraparound, so the row loop vectorises)."""
    st = uint64(stride)
    one = uint64(1)
    k = 2 * a
    c0 = c[k]
    c1 = c[k + 1]
    c4 = c[k + 4]
    c5 = c[k + 5]
    c8 = c[k + 8]
    c9 = c[k + 9]
    c12 = c[k + 12]
    c13 = c[k + 13]
    c16 = c[k + 16]
    c17 = c[k + 17]
    c20 = c[k + 20]
    c21 = c[k + 21]
    c24 = c[k + 24]
    c25 = c[k + 25]
    c28 = c[k + 28]
    c29 = c[k + 29]
    c32 = c[k + 32]
    c33 = c[k + 33]
    for j in range(nrows):
        b = uint64(first + j * stride)
        for i in range(ncols):
            m = b + uint64(i)
            s = m - st
            n = m + st
            fo[m] = (c0 * wx[s - one] + c1 * wy[s - one] + c4 * wx[s] + c5 * wy[s] + c8 * wx[s + one]
                     + c9 * wy[s + one] + c12 * wx[m - one] + c13 * wy[m - one] + c16 * wx[m] + c17 * wy[m]
                     + c20 * wx[m + one] + c21 * wy[m + one] + c24 * wx[n - one] + c25 * wy[n - one]
                     + c28 * wx[n] + c29 * wy[n] + c32 * wx[n + one] + c33 * wy[n + one])


@fma_kernel
def _rect_component(wx, wy, fo, c, a, first, ncols, nrows, stride):
    """As :func:`_uniform_component` for a patch of rectangular elements, whose cross-coupling (xy) with the
    axis neighbours and the node itself vanishes: 13 terms instead of 18."""
    st = uint64(stride)
    one = uint64(1)
    # own-component coefficient of neighbour position p (0..8, row-major from (-1, -1)): c[4p + 3a];
    # cross-component: c[4p + a + 1], non-zero only at the four corners
    s0 = c[3 * a]
    s1 = c[4 + 3 * a]
    s2 = c[8 + 3 * a]
    s3 = c[12 + 3 * a]
    s4 = c[16 + 3 * a]
    s5 = c[20 + 3 * a]
    s6 = c[24 + 3 * a]
    s7 = c[28 + 3 * a]
    s8 = c[32 + 3 * a]
    x0 = c[a + 1]
    x2 = c[8 + a + 1]
    x6 = c[24 + a + 1]
    x8 = c[32 + a + 1]
    if a == 0:
        ws = wx
        wo = wy
    else:
        ws = wy
        wo = wx
    for j in range(nrows):
        b = uint64(first + j * stride)
        for i in range(ncols):
            m = b + uint64(i)
            s = m - st
            n = m + st
            fo[m] = (s0 * ws[s - one] + x0 * wo[s - one] + s1 * ws[s] + s2 * ws[s + one] + x2 * wo[s + one]
                     + s3 * ws[m - one] + s4 * ws[m] + s5 * ws[m + one]
                     + s6 * ws[n - one] + x6 * wo[n - one] + s7 * ws[n] + s8 * ws[n + one] + x8 * wo[n + one])


@fma_kernel
def _mapped_component(wx, wy, fo, cm, col0, a, first, ncols, nrows, stride):
    """Force component ``a`` on a patch of nodes with per-node stencils in difference form,
    ``cm[:, col0 + row*ncols + column]`` (float32, :data:`fivid.solver.stencil.MAPPED_DTYPE`): ``f_m = sum_k
    C_mk (w_k - w_m)`` over the 8 neighbours ``k``, the node's own coupling being minus the sum of the others
    (rigid translations exact); the products and sums in float64.

    Component-major storage: each coefficient is contiguous over a row of nodes; taking the 16 row slices
    first (views, no copy) lets the row loop vectorise (indexing ``cm[k, q]`` inside it measured 2.8x slower:
    the coefficient loads were not recognised as unit-stride). Neighbour position ``p`` (0..8 row-major from
    ``(-1, -1)``, 4 the node itself) holds ``cm[4 p' + 2 a + b]`` with ``p' = p`` below 4 and ``p - 1`` above.

    The patch is a whole block, so its first node row has no neighbours below and its last none above: their
    coefficients are exactly zero and are not read (the thin surface level of a rough block is mostly such rows:
    2 of Ra 1's 3)."""
    st = uint64(stride)
    k = 2 * a
    for j in range(nrows):
        b = uint64(first + j * stride)
        q0 = col0 + j * ncols
        q1 = q0 + ncols
        c0 = cm[k, q0:q1]
        c1 = cm[k + 1, q0:q1]
        c4 = cm[k + 4, q0:q1]
        c5 = cm[k + 5, q0:q1]
        c8 = cm[k + 8, q0:q1]
        c9 = cm[k + 9, q0:q1]
        c12 = cm[k + 12, q0:q1]
        c13 = cm[k + 13, q0:q1]
        c16 = cm[k + 16, q0:q1]
        c17 = cm[k + 17, q0:q1]
        c20 = cm[k + 20, q0:q1]
        c21 = cm[k + 21, q0:q1]
        c24 = cm[k + 24, q0:q1]
        c25 = cm[k + 25, q0:q1]
        c28 = cm[k + 28, q0:q1]
        c29 = cm[k + 29, q0:q1]
        if j == 0:  # no row below: c0..c9 are zero
            for i in range(ncols):
                m = b + uint64(i)
                x = wx[m]
                y = wy[m]
                fo[m] = (_sides(wx, wy, c12[i], c13[i], c16[i], c17[i], m, x, y)
                         + _row(wx, wy, c20[i], c21[i], c24[i], c25[i], c28[i], c29[i], m + st, x, y))
        elif j == nrows - 1:  # no row above: c20..c29 are zero
            for i in range(ncols):
                m = b + uint64(i)
                x = wx[m]
                y = wy[m]
                fo[m] = (_row(wx, wy, c0[i], c1[i], c4[i], c5[i], c8[i], c9[i], m - st, x, y)
                         + _sides(wx, wy, c12[i], c13[i], c16[i], c17[i], m, x, y))
        else:
            for i in range(ncols):
                m = b + uint64(i)
                x = wx[m]
                y = wy[m]
                fo[m] = (_row(wx, wy, c0[i], c1[i], c4[i], c5[i], c8[i], c9[i], m - st, x, y)
                         + _sides(wx, wy, c12[i], c13[i], c16[i], c17[i], m, x, y)
                         + _row(wx, wy, c20[i], c21[i], c24[i], c25[i], c28[i], c29[i], m + st, x, y))


@fma_kernel
def _row(wx, wy, a0, b0, a1, b1, a2, b2, p, x, y):
    """A mapped node's coupling with the three neighbours ``p - 1, p, p + 1`` of the row below or above it, in
    difference form (:func:`_mapped_component`): coefficients ``a`` on x, ``b`` on y; ``(x, y)`` the node's own."""
    one = uint64(1)
    return (a0 * (wx[p - one] - x) + b0 * (wy[p - one] - y) + a1 * (wx[p] - x) + b1 * (wy[p] - y)
            + a2 * (wx[p + one] - x) + b2 * (wy[p + one] - y))


@fma_kernel
def _sides(wx, wy, a0, b0, a2, b2, m, x, y):
    """A mapped node's coupling with its left and right neighbours ``m - 1, m + 1`` (as :func:`_row`)."""
    one = uint64(1)
    return a0 * (wx[m - one] - x) + b0 * (wy[m - one] - y) + a2 * (wx[m + one] - x) + b2 * (wy[m + one] - y)


@fma_kernel
def _rotate(wx, wy, rx, ry, rot, t0, first, ncols, nrows):
    """``(rx, ry) = R_k^T (wx, wy)`` on a block of ``nrows`` rows of ``ncols`` nodes (row stride ``ncols``) from
    x-index ``first``: each node's components in its column's frame, ``R_k`` the rotation by column ``k``'s
    angle, cosine ``rot[0, t0 + k]`` and sine ``rot[1, t0 + k]``."""
    cs = rot[0, t0:t0 + ncols]
    sn = rot[1, t0:t0 + ncols]
    for j in range(nrows):
        b = uint64(first + j * ncols)
        for k in range(ncols):
            m = b + uint64(k)
            x = wx[m]
            y = wy[m]
            rx[m] = cs[k] * x + sn[k] * y
            ry[m] = cs[k] * y - sn[k] * x


@fma_kernel
def _rotated_row(rx, ry, fx, fy, c, cs, sn, first, ncols, stride):
    """Both force components of a row of ``ncols`` nodes from x-index ``first`` with one stencil ``c`` in the
    column frames (displacements ``rx, ry`` in those frames), turned back to x, y by the columns' cosines ``cs``
    and sines ``sn``: one pass, the 18 neighbour values loaded once for both components."""
    st = uint64(stride)
    one = uint64(1)
    b = uint64(first)
    for i in range(ncols):
        m = b + uint64(i)
        s = m - st
        n = m + st
        # both components from the same 18 neighbour values (LLVM loads each once)
        gx = (c[0] * rx[s - one] + c[1] * ry[s - one] + c[4] * rx[s] + c[5] * ry[s] + c[8] * rx[s + one]
              + c[9] * ry[s + one] + c[12] * rx[m - one] + c[13] * ry[m - one] + c[16] * rx[m] + c[17] * ry[m]
              + c[20] * rx[m + one] + c[21] * ry[m + one] + c[24] * rx[n - one] + c[25] * ry[n - one]
              + c[28] * rx[n] + c[29] * ry[n] + c[32] * rx[n + one] + c[33] * ry[n + one])
        gy = (c[2] * rx[s - one] + c[3] * ry[s - one] + c[6] * rx[s] + c[7] * ry[s] + c[10] * rx[s + one]
              + c[11] * ry[s + one] + c[14] * rx[m - one] + c[15] * ry[m - one] + c[18] * rx[m] + c[19] * ry[m]
              + c[22] * rx[m + one] + c[23] * ry[m + one] + c[26] * rx[n - one] + c[27] * ry[n - one]
              + c[30] * rx[n] + c[31] * ry[n] + c[34] * rx[n + one] + c[35] * ry[n + one])
        fx[m] = cs[i] * gx - sn[i] * gy
        fy[m] = sn[i] * gx + cs[i] * gy


@fma_kernel
def _rotated_patch(wx, wy, fx, fy, rx, ry, c_uni, rot, blk):
    """Forces on a patch whose rows are rotations of one stencil (a ring's or an arc's radial layers): the
    displacements turned into each column's frame (:func:`_rotate` over the whole block, the patch's
    neighbours included), then per row its stencil ``c_uni[blk[5] + row]`` in those frames and the turn back
    (:func:`_rotated_row`). ``blk``: the patch's row of ``blocks``."""
    first = blk[0]
    ncols = blk[1]
    nrows = blk[2]
    stride = blk[3]
    start = blk[6]
    t0 = blk[7]
    _rotate(wx, wy, rx, ry, rot, t0, start, stride, nrows)
    t1 = t0 + first - start
    cs = rot[0, t1:t1 + ncols]
    sn = rot[1, t1:t1 + ncols]
    for j in range(nrows):
        _rotated_row(rx, ry, fx, fy, c_uni[blk[5] + j], cs, sn, first + j * stride, ncols, stride)


@fma_kernel
def _joint_displacements(w, s0, m0, n):
    """A halving joint's tied row (:func:`block_forces`, ``tie_j``): node ``s0 + 2i`` takes ``w`` of master
    ``m0 + i``, node ``s0 + 2i + 1`` the mean of masters ``m0 + i`` and ``m0 + i + 1`` (one component)."""
    s = uint64(s0)
    m = uint64(m0)
    two = uint64(2)
    for i in range(n):
        a = w[m + uint64(i)]
        b = w[m + uint64(i + 1)]
        w[s + two * uint64(i)] = a
        w[s + two * uint64(i) + uint64(1)] = 0.5 * a + 0.5 * b
    w[s + two * uint64(n)] = w[m + uint64(n)]


@fma_kernel
def _joint_forces(f, s0, m0, n):
    """The transpose of :func:`_joint_displacements`: the tied row's forces moved onto the masters (in the order
    of the listed ties: ``f_m + f_(2i-1) / 2 + f_(2i) + f_(2i+1) / 2``), the tied row's zeroed (one component)."""
    s = uint64(s0)
    m = uint64(m0)
    two = uint64(2)
    f[m] += f[s]
    for i in range(n):
        q = s + two * uint64(i)
        h = 0.5 * f[q + uint64(1)]
        f[m + uint64(i)] += h
        g = f[m + uint64(i + 1)] + h
        f[m + uint64(i + 1)] = g + f[q + two]
    for i in range(2 * n + 1):
        f[s + uint64(i)] = 0.0


@fma_kernel
def block_forces(w, f, stencil):
    """``f = K_blocks w`` by the per-block 3x3 stencils (every node of every block is written).

    Parameters
    ----------
    w : ndarray (2*npd,)
        Generalised displacement ``u + beta v`` [m], x part then y part, node ``p`` at ``pad + p``.
    f : ndarray (2*npd,)
        Output forces [N] (same layout).
    stencil : StencilArrays
        ``(npd, blocks, c_uni, c_map, rot, wr, lst_idx, lst_nbr, lst_coef)``:

    npd : int
        Length of one component (nodes plus padding on both sides).
    blocks : int64 ndarray (n_patch, 8)
        Patches: ``first x-index, columns, rows, row stride, kind, coefficients, block start, angles``; kind 0:
        one shared stencil ``c_uni[coefficients]`` (18 terms per force), 1: the same for rectangular elements
        (the xy couplings with the axis neighbours vanish and are skipped: 13 terms), 2: per-node stencils
        ``c_map[:, coefficients + row*columns + column]`` in difference form (:func:`_mapped_component`), 3: rows
        that are rotations of one stencil, in the column frames ``c_uni[coefficients + row]``, the block's column
        angles at ``rot[:, angles + column]`` from its first x-index ``block start`` (:func:`_rotated_patch`).
        Neighbours outside a block have zero coefficients (the padding keeps their indices in bounds).
    c_uni : ndarray (n_uniform, 36)
        Shared stencils [N m-1].
    c_map : float32 ndarray (32, n_mapped)
        Per-node stencils of mapped patches in difference form (the 8 neighbours' couplings) [N m-1].
    rot : ndarray (2, n_angles)
        Cosine and sine of the column angles of rotated patches' blocks.
    wr : ndarray (2*npd,)
        Scratch: the displacements of rotated blocks in their column frames [m].
    lst_idx : int64 ndarray (n_list,)
        Listed nodes (block corners, seam columns of periodic rings): x-index.
    lst_nbr : int64 ndarray (n_list, 9)
        x-indices of their 3x3 neighbours, row-major from ``(-1, -1)``.
    lst_coef : ndarray (n_list, 36)
        Their stencils [N m-1].
    tie_s, tie_m, tie_w : int64 ndarray (n_tie,), int64 ndarray (n_tie, 2), ndarray (n_tie, 2)
        Tied nodes of mesh transitions (:class:`fivid.fe.model.Tie`): x-index, masters' x-indices, weights.
        Their ``w`` is first set from the masters' (``w_s = sum weights w_m``, written into ``w``), and their
        forces are finally moved to the masters (``f_m += weights f_s``, ``f_s = 0``): ``f = T^T K T w``.
    tie_j : int64 ndarray (n_joint, 3)
        Halving joints, the same for a whole tied row at once: ``(s0, m0, n)``, nodes ``s0 .. s0 + 2n`` tied to
        masters ``m0 .. m0 + n`` (node ``s0 + 2i`` on master ``m0 + i``, node ``s0 + 2i + 1`` half-way): contiguous
        loops instead of the listed ties' gathers and scatters (:func:`_joint_displacements`, :func:`_joint_forces`).
    """
    npd, blocks, c_uni, c_map, rot, wr, lst_idx, lst_nbr, lst_coef, tie_s, tie_m, tie_w, tie_j = stencil
    wx = w[:npd]
    wy = w[npd:]
    fx = f[:npd]
    fy = f[npd:]
    for r in range(tie_j.shape[0]):
        _joint_displacements(wx, tie_j[r, 0], tie_j[r, 1], tie_j[r, 2])
        _joint_displacements(wy, tie_j[r, 0], tie_j[r, 1], tie_j[r, 2])
    for r in range(tie_s.shape[0]):
        s = tie_s[r]
        a = tie_m[r, 0]
        b = tie_m[r, 1]
        wx[s] = tie_w[r, 0] * wx[a] + tie_w[r, 1] * wx[b]
        wy[s] = tie_w[r, 0] * wy[a] + tie_w[r, 1] * wy[b]
    for b in range(blocks.shape[0]):
        kind = blocks[b, 4]
        if kind == 3:
            _rotated_patch(wx, wy, fx, fy, wr[:npd], wr[npd:], c_uni, rot, blocks[b])
            continue
        if kind == 2:
            _mapped_component(wx, wy, fx, c_map, blocks[b, 5], 0, blocks[b, 0], blocks[b, 1], blocks[b, 2],
                              blocks[b, 3])
            _mapped_component(wx, wy, fy, c_map, blocks[b, 5], 1, blocks[b, 0], blocks[b, 1], blocks[b, 2],
                              blocks[b, 3])
            continue
        c = c_uni[blocks[b, 5]]
        if kind == 1:
            _rect_component(wx, wy, fx, c, 0, blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3])
            _rect_component(wx, wy, fy, c, 1, blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3])
        else:
            _uniform_component(wx, wy, fx, c, 0, blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3])
            _uniform_component(wx, wy, fy, c, 1, blocks[b, 0], blocks[b, 1], blocks[b, 2], blocks[b, 3])
    for r in range(lst_idx.shape[0]):
        p = lst_idx[r]
        sx = 0.0
        sy = 0.0
        for e in range(9):
            q = lst_nbr[r, e]
            k = 4 * e
            ax = wx[q]
            ay = wy[q]
            sx += lst_coef[r, k] * ax + lst_coef[r, k + 1] * ay
            sy += lst_coef[r, k + 2] * ax + lst_coef[r, k + 3] * ay
        fx[p] = sx
        fy[p] = sy
    for r in range(tie_s.shape[0]):
        s = tie_s[r]
        for k in range(2):
            q = tie_m[r, k]
            fx[q] += tie_w[r, k] * fx[s]
            fy[q] += tie_w[r, k] * fy[s]
        fx[s] = 0.0
        fy[s] = 0.0
    for r in range(tie_j.shape[0]):
        _joint_forces(fx, tie_j[r, 0], tie_j[r, 1], tie_j[r, 2])
        _joint_forces(fy, tie_j[r, 0], tie_j[r, 1], tie_j[r, 2])


@kernel
def spring_forces(u, v, f, spr_dof, spr_kc, with_damping):
    """Add discrete spring (and dashpot) forces to ``f``; ``spr_dof[s] = (dof_a, dof_b or -1)``, ``spr_kc = (k, c)``."""
    for s in range(spr_dof.shape[0]):
        a = spr_dof[s, 0]
        b = spr_dof[s, 1]
        du = u[a]
        dv = v[a]
        if b >= 0:
            du -= u[b]
            dv -= v[b]
        fs = spr_kc[s, 0] * du
        if with_damping:
            fs += spr_kc[s, 1] * dv
        f[a] += fs
        if b >= 0:
            f[b] -= fs
