"""Shared definitions of the explicit solver's numba kernels (layer L0): arrays and scalars only.

The kernels are split by concern: :mod:`fivid.solver._stencil_kernels` (internal forces: block stencils,
springs), :mod:`fivid.solver._contact_kernels` (the contact correction and its bookkeeping) and
:mod:`fivid.solver._loop_kernels` (the time loop, records, guards); :mod:`fivid.solver._reduced_kernels` is the
reduced system's loop. This module holds what they share: the one compilation setting of every kernel, the
slots of the energy accumulator and of the output records, the status codes, and the smooth ramp of the
imposed motions.

Data layout (prepared by :mod:`fivid.solver.stencil` and the driver; float64 / int64, C-contiguous; the mapped
stencil coefficients ``c_map`` float32):

- dof vectors ``u, v, w, f`` have ``2*npd`` entries: the x components of all nodes, then the y
  components (structure of arrays, so the stencil loops vectorise); node ``p`` sits at index
  ``pad + p`` of each half, with ``pad`` zero entries on both sides so that every 3x3 neighbour index of
  every node is in bounds. Nodes are passed to kernels by their x-index ``pad + p`` (y-index
  ``+ npd``), springs and constraints by flat dof index.
- ``w = u + beta*v`` is kept up to date by the update pass, so one stencil pass gives
  ``f = K (u + beta v)`` (stiffness-proportional damping folded in).
- Stencil coefficient ``((dj+1)*3 + (di+1))*4 + 2*a + b`` couples dof ``a`` of node ``p`` with dof ``b`` of
  node ``p + dj*stride + di``; in a uniform block the interior nodes share one set and so do the nodes of
  each edge (corners excluded): five patches; a ring or arc is one patch with one stencil per row in the
  columns' frames (``rot``: the columns' angles; the displacements turned into those frames in the scratch
  ``wr``); another mapped block is one patch with per-node coefficients (component-major, ``c_map[k, node]``, float32,
  in difference form: the 8 neighbours' couplings applied to ``w_k - w_m``);
  block corners and the end or seam columns of rings and arcs are listed node by node with explicit
  neighbour indices.
- pressure loads: dofs ``ld_dof`` carry the full nodal forces ``ld_force``, ramped per load
  ``ld_grp`` with ``ld_par[g] = (t_start, ramp_time)`` by the smooth ramp, evaluated at the step start.
- Hot loops index with unsigned integers: numba then emits no negative-index wraparound, which
  otherwise blocks vectorisation (measured: 6x slower stencil).
- constrained dofs ``con_dof`` belong to motion groups ``con_grp``; ``grp_par[g] = (kind, amplitude, t_start,
  ramp_time)`` with kind 0 fixed, 1 displacement ramp, 2 velocity ramp (one velocity evaluation per group
  and step, not per dof); the smooth ramp is ``r(s) = s - sin(2 pi s)/(2 pi)``.

Nothing is allocated inside the time loop.

On-disk cache (``cache=True``): every kernel of the package is cached in a folder keyed on all ``_*kernels.py``
sources (:mod:`fivid._cache_kernels`, imported here so that its cache locator is registered before the first
kernel is decorated): a kernel whose callee lives in another file is recompiled when that file changes.
"""

import math

from numba import njit

import fivid._cache_kernels  # noqa: F401  (registers the kernel-sources cache locator before the decorations)

__all__ = [
    "PARALLEL",
    "kernel",
    "fma_kernel",
    "reassociating_kernel",
    "ramp",
    "constrained_velocity",
    "OK",
    "NAN",
    "RUNAWAY",
    "N_ACC",
    "N_REC",
]

# ---- the one compilation setting of the solver's kernels
#: numba's threads do not pay at the rig's sizes on the 2-core machines it runs on (bench_solver:
#: ``parallel_efficiency_2_cores`` 0.08 for the prange stencil), so every kernel is serial
PARALLEL = False
#: every kernel: compiled once and cached on disk (``cache=True``; the argument types never vary, so the cache is
#: reused), strict IEEE arithmetic -- the contact solve and the bookkeeping are bit-for-bit reproducible
kernel = njit(cache=True, parallel=PARALLEL)
#: stencil loops: fused multiply-add only (``contract``), which vectorises the 13/18-term sums; no reordering
fma_kernel = njit(cache=True, parallel=PARALLEL, fastmath={"contract"})
#: reductions over all dofs (energy sums of the predictor): reassociation lets the sums vectorise; no NaN/inf
#: assumptions (the guards still see them)
reassociating_kernel = njit(cache=True, parallel=PARALLEL, fastmath={"contract", "reassoc"})

# energy accumulator slots (acc array)
W_INT = 0  # work of internal (stencil + spring/dashpot) forces: strain energy + stiffness-damping loss
D_ALPHA = 1  # mass-proportional damping dissipation
W_EXT = 2  # work of the constraint reactions (imposed motions)
W_CN = 3  # work of the normal contact forces (<= 0: impact losses)
W_CT = 4  # work of the tangential contact forces (<= 0: friction dissipation)
GS_SWEEPS = 5  # total Gauss-Seidel sweeps
GS_MAX = 6  # largest number of sweeps in one step
GS_CAPPED = 7  # steps that reached the sweep limit
W_LOAD = 8  # work of the applied (pressure) loads
W_DRIVE = 9  # work of the rigid masters' surface motion on the slaves (rotation / belt drive)
N_ACC = 10

# output record columns (rec array, one row per output interval)
R_FT = 0  # reaction, tangential sum, interval average [N]
R_FN = 1  # reaction, normal sum, interval average [N]
R_KE = 2  # kinetic energy at the interval end [J]
R_U = 3  # strain energy at the interval end [J]
R_WINT = 4
R_DA = 5
R_WEXT = 6
R_WCN = 7
R_WCT = 8
R_WLOAD = 9
R_WDRIVE = 10  # work of the moving rigid surfaces [J]
R_EPEN = 11  # energy stored in the compliant contact laws at the interval end [J]
N_REC = 12

# status codes
OK = 0
NAN = 1
RUNAWAY = 2


@kernel
def ramp(s):
    """Smooth ramp ``r(s)`` from 0 (s <= 0) to 1 (s >= 1), ``r' = 1 - cos(2 pi s)`` vanishing at both ends."""
    if s <= 0.0:
        return 0.0
    if s >= 1.0:
        return 1.0
    return s - math.sin(2.0 * math.pi * s) / (2.0 * math.pi)


@kernel
def constrained_velocity(kind, amp, t0, tr, t, dt):
    """Velocity of a constrained dof over the step ``[t, t + dt]`` [m s-1] (half-step value)."""
    if kind == 0:
        return 0.0
    if kind == 1:  # displacement history: exact increment over the step
        d1 = amp * (ramp((t + dt - t0) / tr) if tr > 0.0 else (1.0 if t + dt >= t0 else 0.0))
        d0 = amp * (ramp((t - t0) / tr) if tr > 0.0 else (1.0 if t >= t0 else 0.0))
        return (d1 - d0) / dt
    th = t + 0.5 * dt
    if tr > 0.0:
        return amp * ramp((th - t0) / tr)
    return amp if th >= t0 else 0.0
