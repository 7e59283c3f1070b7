"""Modal parameters from FRFs: sdypy-EMA's LSCF poles, an automatic stabilisation diagram, LSFD shapes.

The numerical core is sdypy-EMA (:class:`sdypy.EMA.Model`, the field's reference implementation):

1. **LSCF** (least-squares complex frequency domain, Guillaume et al. 2003): a common-denominator rational
   model of all FRFs in the band, solved for model orders ``2, 4, ..., 2 max_order``; each order gives a
   set of poles ``lambda = -zeta omega + i omega sqrt(1 - zeta^2)``.
2. **Stabilisation** (here, instead of sdypy's interactive picking): a pole of order ``n`` is *stable* when
   a pole of order ``n - 1`` lies within ``frequency_tolerance`` (relative) in frequency and
   ``damping_tolerance`` (relative) in damping ratio, with ``0 < zeta < max_damping`` and its frequency
   in the band. Stable poles are grouped by frequency (neighbours closer than ``frequency_tolerance``
   relative); a group seen at many orders is a physical mode, spurious poles wander. The ``n_modes``
   largest groups are kept (without ``n_modes``: every group present at ``min_fraction`` of the orders);
   each mode's pole is the group member closest to the group's median frequency and damping.
3. **LSFD** (sdypy's ``get_constants``): the modal constants ``A_r`` of every FRF with those poles, with
   lower and upper residuals; the complex mode shape at the measured DOFs is
   ``A_r sqrt(2 i omega_d / A_r,dp)`` with ``dp`` the driving point (a response at the reference DOF): for
   FRFs in SI (m/N, m/s/N, m/s2/N) the shapes are then mass-normalised [kg^-1/2], rotated so the largest
   component is real positive; without a driving point, ``A_r`` scaled to unit largest component.
"""

from __future__ import annotations

import logging
import warnings
from dataclasses import dataclass

import numpy as np

from fivid.errors import FividError

__all__ = ["StabilisationDiagram", "EMAResult", "StabilityCriteria", "identify_modes"]

log = logging.getLogger("fivid")


@dataclass(frozen=True)
class StabilisationDiagram:
    """Poles per model order.

    Attributes
    ----------
    order : ndarray of int
        Model order of each pole.
    frequency : ndarray
        [Hz].
    damping_ratio : ndarray
        [1].
    stable : ndarray of bool
        Stable in frequency and damping against the previous order.
    selected_frequency : ndarray
        Frequencies of the modes kept [Hz].
    """

    order: np.ndarray
    frequency: np.ndarray
    damping_ratio: np.ndarray
    stable: np.ndarray
    selected_frequency: np.ndarray


@dataclass(frozen=True)
class EMAResult:
    """Identified modes.

    Attributes
    ----------
    frequency : ndarray, shape (n_modes,)
        Damped-pole natural frequencies ``|lambda| / 2 pi`` [Hz].
    damping_ratio : ndarray, shape (n_modes,)
        ``-Re(lambda) / |lambda|`` [1].
    shape : ndarray of complex, shape (n_modes, n_dofs)
        Mode shapes at the measured DOFs (see the module docstring for their scaling).
    mass_normalised : bool
        Whether ``shape`` is scaled by a driving point (receptance: mass-normalised).
    poles : ndarray of complex
        The selected poles [rad/s].
    n_orders : ndarray of int
        Orders at which each mode was stable.
    reconstruction_error : float
        ``||H_model - H|| / ||H||`` over the band [1].
    diagram : StabilisationDiagram
    settings : dict
    """

    frequency: np.ndarray
    damping_ratio: np.ndarray
    shape: np.ndarray
    mass_normalised: bool
    poles: np.ndarray
    n_orders: np.ndarray
    reconstruction_error: float
    diagram: StabilisationDiagram
    settings: dict


@dataclass(frozen=True)
class StabilityCriteria:
    """When a pole of the stabilisation diagram is a stable physical mode.

    Attributes
    ----------
    frequency_tolerance, damping_tolerance : float
        Relative change [-] of a pole's frequency and damping ratio from one model order to the next (default
        0.005 and 0.1).
    max_damping : float
        Poles with a larger damping ratio [-] are not physical modes here (default 0.2).
    min_fraction : float
        Without a number of modes: fraction [-] of the model orders a mode must be stable at (default 0.3).
    """

    frequency_tolerance: float = 0.005
    damping_tolerance: float = 0.1
    max_damping: float = 0.2
    min_fraction: float = 0.3


def identify_modes(frequency, frf, *, band=None, n_modes: int | None = None, max_order: int = 40,
                   form: str = "receptance", driving_point: int | None = None,
                   stability: StabilityCriteria = StabilityCriteria()) -> EMAResult:
    """Identify modes from FRFs of one reference (SIMO) by LSCF + LSFD (see the module docstring).

    Parameters
    ----------
    frequency : array_like, shape (n_f,)
        Uniformly spaced frequencies [Hz].
    frf : array_like of complex, shape (n_dofs, n_f)
        FRFs of each measured DOF to the one reference.
    band : (float, float), optional
        Frequency band [Hz] (default: the whole axis above its first non-zero line).
    n_modes : int, optional
        Modes to keep (the best-stabilised); default: every mode stable at ``min_fraction`` of the orders.
    max_order : int
        Highest LSCF model order / 2 (sdypy's ``pol_order_high``).
    form : {"receptance", "mobility", "accelerance"}
        What the FRFs are (displacement, velocity or acceleration per force).
    driving_point : int, optional
        Index of the DOF measured at the reference (scales the shapes).
    stability : StabilityCriteria
        Relative stability tolerances of frequency and damping, the largest damping ratio of a physical mode and,
        without ``n_modes``, the fraction of the orders a mode must be stable at.

    Returns
    -------
    EMAResult
    """
    try:
        from sdypy.EMA import Model
    except ImportError:
        raise FividError("experimental modal analysis needs the sdypy-ema package, which is not installed: "
                         "pip install 'fivid[ema]' (or pip install sdypy-ema)") from None

    frequency_tolerance, damping_tolerance = stability.frequency_tolerance, stability.damping_tolerance
    max_damping, min_fraction = stability.max_damping, stability.min_fraction
    f = np.asarray(frequency, dtype=float)
    h = np.atleast_2d(np.asarray(frf, dtype=complex))
    if h.shape[1] != f.size:
        raise FividError(f"FRFs have {h.shape[1]} lines but the frequency axis has {f.size}")
    if f.size < 16:
        raise FividError(f"EMA needs at least 16 frequency lines, got {f.size}")
    step = np.diff(f)
    if not np.allclose(step, step[0], rtol=1e-6, atol=0) or step[0] <= 0:
        raise FividError("EMA (LSCF) needs uniformly spaced, increasing frequency lines")
    lo, hi = (max(f[0], step[0]), f[-1]) if band is None else (float(band[0]), float(band[1]))
    if not (f[0] <= lo < hi <= f[-1] + 0.5 * step[0]):
        raise FividError(f"band {[lo, hi]!r} Hz is not within the FRFs' {f[0]:g}..{f[-1]:g} Hz")
    inside = (f >= lo) & (f <= hi)
    if not np.all(np.isfinite(h[:, inside])):
        raise FividError("FRFs contain NaN or infinite values in the band (a zero input spectrum?); cut the band to "
                         "where the input has energy")
    h = np.where(np.isfinite(h), h, 0.0)  # lines outside the band do not enter the fit
    if form not in ("receptance", "mobility", "accelerance"):
        raise FividError(f"FRF form must be receptance, mobility or accelerance, got {form!r}")
    if max_order < 2:
        raise FividError(f"max_order must be >= 2, got {max_order}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        model = Model(frf=h, freq=f, lower=lo, upper=hi, pol_order_high=int(max_order), frf_form=form,
                      driving_point=driving_point)
        model.get_poles(method="lscf", show_progress=False)
    diagram, groups = _stabilise(model.all_poles, lo, hi, frequency_tolerance, damping_tolerance, max_damping)
    n_orders = len(model.all_poles)
    groups.sort(key=lambda g: -len(g))
    if n_modes is not None:
        if len(groups) < n_modes:
            raise FividError(f"only {len(groups)} stable mode(s) found in {lo:g}..{hi:g} Hz, {n_modes} asked for; "
                             "raise --max-order, widen the band or ask for fewer modes")
        groups = groups[:n_modes]
    else:
        groups = [g for g in groups if len(g) >= min_fraction * n_orders]
        if not groups:
            raise FividError(f"no mode is stable at {min_fraction:.0%} of the {n_orders} model orders in "
                             f"{lo:g}..{hi:g} Hz; raise --max-order or give --modes N")
    picks = sorted((_representative(g) + (len(g),) for g in groups), key=lambda p: p[2])
    model.pole_ind = np.array([[p[0], p[1]] for p in picks], dtype=int)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        h_rec, a = model.get_constants(method="lsfd", whose_poles="own", f_lower=lo, f_upper=hi)
    poles = np.array([model.all_poles[p[0]][p[1]] for p in picks])
    wn = np.abs(poles)
    band_mask = (model.freq >= lo) & (model.freq <= hi)
    err = float(np.linalg.norm((h_rec - model.frf)[:, band_mask]) / np.linalg.norm(model.frf[:, band_mask]))
    shape, normalised = _shapes(a, driving_point, poles)
    sel = wn / (2 * np.pi)
    diagram = StabilisationDiagram(*diagram, selected_frequency=sel)
    settings = {"method": "LSCF poles + LSFD constants (sdypy-EMA)", "band_hz": [lo, hi], "max_order": int(max_order),
                "n_modes": n_modes, "frf_form": form, "frequency_tolerance": frequency_tolerance,
                "damping_tolerance": damping_tolerance, "max_damping": max_damping, "min_fraction": min_fraction,
                "driving_point": driving_point}
    log.info("EMA: %d modes in %.4g..%.4g Hz, reconstruction error %.3g", sel.size, lo, hi, err)
    return EMAResult(frequency=sel, damping_ratio=-poles.real / wn, shape=shape, mass_normalised=normalised,
                     poles=poles, n_orders=np.array([p[3] for p in picks], dtype=int),
                     reconstruction_error=err, diagram=diagram, settings=settings)


def _stabilise(all_poles, lo, hi, ftol, ztol, zmax):
    """Poles of every order with their stability flag, and the stable poles grouped by frequency."""
    rows, prev = [], None
    for k, p in enumerate(all_poles):
        p = np.asarray(p)
        wn = np.abs(p)
        with np.errstate(invalid="ignore", divide="ignore"):
            fr, zeta = wn / (2 * np.pi), -p.real / wn
        keep = (p.imag > 0) & np.isfinite(fr) & (fr >= lo) & (fr <= hi) & (zeta > 0) & (zeta < zmax)
        idx = np.flatnonzero(keep)
        stable = np.zeros(idx.size, bool)
        if prev is not None and prev[0].size:
            for n, i in enumerate(idx):
                df = np.abs(prev[0] - fr[i]) / fr[i]
                dz = np.abs(prev[1] - zeta[i]) / zeta[i]
                stable[n] = np.any((df < ftol) & (dz < ztol))
        for n, i in enumerate(idx):
            rows.append((2 * (k + 1), fr[i], zeta[i], stable[n], k, i))
        prev = (fr[idx], zeta[idx])
    if not rows:
        empty = np.zeros(0)
        return (empty.astype(int), empty, empty, empty.astype(bool)), []
    order, fr, zeta, stable, k, i = (np.array(c) for c in zip(*rows))
    st = np.flatnonzero(stable)
    st = st[np.argsort(fr[st])]
    groups, current = [], []
    for s in st:
        if current and (fr[s] - fr[current[-1]]) / fr[s] >= ftol:
            groups.append(current)
            current = []
        current.append(s)
    if current:
        groups.append(current)
    members = [[(int(k[s]), int(i[s]), float(fr[s]), float(zeta[s])) for s in g] for g in groups]
    # one pole per order in a group: a group with two poles of one order holds two modes the tolerance merged
    members = [_one_per_order(g) for g in members]
    return (order.astype(int), fr.astype(float), zeta.astype(float), stable.astype(bool)), members


def _one_per_order(group):
    best = {}
    med = np.median([m[2] for m in group])
    for m in group:
        if m[0] not in best or abs(m[2] - med) < abs(best[m[0]][2] - med):
            best[m[0]] = m
    return list(best.values())


def _representative(group):
    """``(order index, pole index, frequency)`` of the member closest to the group's median (f, zeta)."""
    f = np.array([m[2] for m in group])
    z = np.array([m[3] for m in group])
    fm, zm = np.median(f), np.median(z)
    j = int(np.argmin(((f - fm) / fm) ** 2 + ((z - zm) / zm) ** 2 * 1e-2))
    return group[j][0], group[j][1], group[j][2]


def _shapes(a, driving_point, poles):
    """Complex shapes (n_modes, n_dofs) from the modal constants ``a`` (n_dofs, n_modes).

    The receptance residue of a mass-normalised mode is ``A_r = psi psi^T / (2 i omega_d)``, so with a driving
    point ``psi = A_r sqrt(2 i omega_d / A_r,dp)``.
    """
    a = np.asarray(a, dtype=complex).T
    if driving_point is not None:
        scale = np.sqrt(a[:, driving_point] / (2j * poles.imag))
        with np.errstate(invalid="ignore", divide="ignore"):
            shape = a / scale[:, None]
        if np.all(np.isfinite(shape)):
            return _rotate(shape), True
    mag = np.abs(a)
    big = a[np.arange(a.shape[0]), np.argmax(mag, axis=1)]
    return a / big[:, None], False


def _rotate(shape):
    """Each shape multiplied by the unit phase that makes its largest component real positive."""
    big = shape[np.arange(shape.shape[0]), np.argmax(np.abs(shape), axis=1)]
    return shape * (np.abs(big) / big)[:, None]
