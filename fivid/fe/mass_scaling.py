"""Conventional mass scaling of a coarsening stack's surface level: a longer stable step for a documented added mass.

In a rough block re-meshed as a stack of levels (:mod:`fivid.fe.transition`) the explicit step is set by the
profiled surface level: its elements are ``h`` wide and, faded across by the profile, thinned and sheared by it
(Ra 1 um: 0.74 h thinnest; Ra 10-26 um: sheared by the asperity slopes, element steps 0.5-0.65 of an ``h``
square's), while every deeper element is at least ``2h`` square. Multiplying the surface level's density by ``f``
(its stiffness unchanged) multiplies its elements' steps by ``sqrt f`` (``omega_e^2`` of ``M_e^-1 K_e`` scales as
``1/f``), until the next level's elements set the step.

:func:`surface_mass_scaling` chooses, per profiled block, ``f = min((dt_1 / dt_0)^2, 1 + a M_body / M_0)``: up to
the next level's element step ``dt_1`` (more would not lengthen the step), and no more mass than the fraction
``a`` of the block's body (all its levels) -- the cap is what keeps the physics: the bodies' modes in the scored
band drop by about ``a / 2`` in frequency (the added mass moves with the bending and axial modes, whose
wavelengths are 10^3 times the level's depth). What it does not keep is the surface nodes' own inertia in an
impact (the contact's Lagrange step uses the nodes' masses): that enters the shocks at the time scale of a few
steps, MHz, far above the band; docs/roughness.md gives the measured change of Lv and of the back face's PSD.

Element steps ``2 / omega_e`` with ``omega_e^2`` the largest eigenvalue of ``M_e^-1 K_e`` (lumped ``M_e``): the
model's ``omega_max`` is at most the largest ``omega_e`` (Irons' element eigenvalue theorem; with ties the tied
system's too, a restriction of the same quadratic forms), so the smallest element step is a lower bound of the
model's undamped stable step.

Units: SI.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from fivid.fe.assembly import block_element_mass, block_element_stiffness

__all__ = ["element_time_steps", "surface_mass_scaling"]


def element_time_steps(block) -> np.ndarray:
    """Undamped element steps ``2 / omega_e`` of every element of ``block`` [s], shape (ny, nx): ``omega_e^2`` the
    largest eigenvalue of ``M_e^-1 K_e`` with the lumped element mass (its ``mass_scale`` in)."""
    ke = block_element_stiffness(block).reshape(-1, 8, 8)
    me = np.diagonal(block_element_mass(block, lumped=True).reshape(-1, 8, 8), axis1=1, axis2=2)
    s = 1.0 / np.sqrt(me)
    w2 = np.linalg.eigvalsh(ke * s[:, :, None] * s[:, None, :])[:, -1]
    return (2.0 / np.sqrt(w2)).reshape(block.ny, block.nx)


def _block_mass(block) -> float:
    """Mass of a block [kg] (its ``mass_scale`` in)."""
    return float(block_element_mass(block, lumped=True).reshape(-1, 8, 8).diagonal(axis1=1, axis2=2).sum() / 2.0)


def surface_mass_scaling(model, *, max_added_mass: float):
    """``(model, record)``: ``model`` with the density of every profiled surface level of a coarsening stack
    (a ``shape == "profile"`` block named ``B`` whose next level ``B~1`` exists, :mod:`fivid.fe.transition`) scaled
    by ``f = min((dt_1 / dt_0)^2, 1 + max_added_mass M_body / M_0)``, at least 1 (module docstring).

    Parameters
    ----------
    model : Model
        A transition model (:func:`fivid.fe.transition.transition_model`); blocks without a next level are left.
    max_added_mass : float
        Largest added mass per body as a fraction of the body's mass [-] (>= 0; 0: nothing scaled).

    Returns
    -------
    model : Model
        The same model with the scaled blocks' ``mass_scale`` set (stiffness, nodes, ties unchanged).
    record : dict
        Per scaled block name: ``factor`` (``f``), ``added_mass_fraction`` (of its body's mass), ``added_mass`` [kg],
        ``element_step`` (smallest, before) [s], ``element_step_scaled`` [s], ``next_level_element_step`` [s].

    Raises
    ------
    ValueError
        ``max_added_mass`` negative or not finite.
    """
    a = float(max_added_mass)
    if not np.isfinite(a) or a < 0.0:
        raise ValueError(f"max_added_mass must be a finite fraction >= 0 of a body's mass, got {max_added_mass!r}")
    by_name = {b.name: b for b in model.blocks}
    record, blocks = {}, list(model.blocks)
    for k, block in enumerate(model.blocks):
        nxt = by_name.get(f"{block.name}~1")
        if block.shape != "profile" or nxt is None or a == 0.0:
            continue
        body = sum(_block_mass(b) for b in model.blocks if b.name == block.name or b.name.startswith(f"{block.name}~"))
        m0 = _block_mass(block)
        dt0 = float(element_time_steps(block).min())
        dt1 = float(element_time_steps(nxt).min())
        f = max(1.0, min((dt1 / dt0) ** 2, 1.0 + a * body / m0))
        blocks[k] = dataclasses.replace(block, mass_scale=block.mass_scale * f)
        record[block.name] = {"factor": f, "added_mass_fraction": (f - 1.0) * m0 / body, "added_mass": (f - 1.0) * m0,
                              "element_step": dt0, "element_step_scaled": dt0 * float(np.sqrt(f)),
                              "next_level_element_step": dt1}
    return dataclasses.replace(model, blocks=tuple(blocks) if isinstance(model.blocks, tuple) else blocks), record
