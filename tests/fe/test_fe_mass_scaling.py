"""Conventional mass scaling of a coarsening stack's surface level (fivid.fe.mass_scaling): the density factor's
exact scaling laws, the added mass against its cap, Irons' element bound of the stable step, and the low modes'
shift against first-order perturbation theory."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fivid.fe import load_model as build_model
from fivid.fe.assembly import lumped_mass
from fivid.fe.mass_scaling import element_time_steps, surface_mass_scaling
from fivid.fe.modal import constrained_matrices, lowest_modes
from fivid.fe.transition import transition_model
from fivid.solver.timestep import max_angular_frequency

E, NU, RHO = 210e9, 0.3, 7800.0
LENGTH, DEPTH, WIDTH = 12e-3, 2e-3, 0.01


@pytest.fixture(scope="module")
def stack():
    """A clamped-clamped 12 x 2 mm steel block, its top edge a 20 um sine of 1 mm wavelength (steep enough to shear
    the surface elements), 96 surface columns, coarsened with depth (:func:`fivid.fe.transition.transition_model`)."""
    body = {"corners": [[0.0, 0.0], [LENGTH, 0.0], [LENGTH, DEPTH], [0.0, DEPTH]], "divisions": [96, 1],
            "material": "steel", "thickness": WIDTH, "clamp": ["left", "right"],
            "profile": {"edge": "top", "sine": {"amplitude": 20e-6, "wavelength": 1e-3}}}
    model = build_model({"name": "block", "plane": "strain", "materials": {"steel": {"E": E, "nu": NU, "rho": RHO}},
                         "bodies": {"lower": body}})
    return transition_model(model, ["lower"], max_width=1e-3)


def _scaled(model, f):
    return dataclasses.replace(model, blocks=tuple(dataclasses.replace(b, mass_scale=f) for b in model.blocks))


def _lowest(model, n=3, mass="lumped"):
    K, M, _ = constrained_matrices(model, mass=mass)
    return lowest_modes(K, M, n)


def test_a_density_factor_scales_mass_frequencies_and_step_exactly(stack):
    """``M -> f M`` with ``K`` unchanged: the mass by ``f``, every frequency and ``omega_max`` by ``1/sqrt f`` (the
    generalised eigenproblem's closed form), in the lumped and the consistent mass alike."""
    f = 2.7
    big = _scaled(stack, f)
    assert lumped_mass(big).sum() == pytest.approx(f * lumped_mass(stack).sum(), rel=1e-12)
    assert lumped_mass(stack).sum() == pytest.approx(2 * RHO * LENGTH * DEPTH * WIDTH, rel=1e-12)  # two dofs per node
    for mass in ("lumped", "consistent"):
        w0 = np.sqrt(_lowest(stack, mass=mass)[0])
        w1 = np.sqrt(_lowest(big, mass=mass)[0])
        np.testing.assert_allclose(w1, w0 / np.sqrt(f), rtol=1e-8)
    assert max_angular_frequency(big) == pytest.approx(max_angular_frequency(stack) / np.sqrt(f), rel=1e-8)


def test_the_added_mass_is_the_cap_and_the_step_grows(stack):
    """The surface level's density rises until the body has gained the cap's fraction of its mass (lumped mass
    summed, exact to round-off), not beyond the next level's element step; the model's undamped step stays
    above its smallest element step (Irons: ``omega_max <= max omega_e``) and grows."""
    body = lumped_mass(stack).sum() / 2  # per dof pair: the block's mass
    w_before = max_angular_frequency(stack)
    for cap in (0.002, 0.01):
        scaled, rec = surface_mass_scaling(stack, max_added_mass=cap)
        (name, r), = rec.items()
        assert name == "lower"
        dt1 = r["next_level_element_step"]
        if r["factor"] < (dt1 / r["element_step"]) ** 2:  # the cap binds
            assert lumped_mass(scaled).sum() / 2 - body == pytest.approx(cap * body, rel=1e-9)
            assert r["added_mass_fraction"] == pytest.approx(cap, rel=1e-12)
        surf = next(b for b in scaled.blocks if b.name == "lower")
        assert element_time_steps(surf).min() == pytest.approx(r["element_step_scaled"], rel=1e-12)
        steps = min(element_time_steps(b).min() for b in scaled.blocks)
        w_after = max_angular_frequency(scaled)
        assert 2.0 / w_after >= steps * (1 - 1e-9)
        assert w_after < w_before
    # no cap: the surface level's element step is lifted to the next level's exactly, and no further
    scaled, rec = surface_mass_scaling(stack, max_added_mass=0.99)
    r = rec["lower"]
    assert r["factor"] == pytest.approx((r["next_level_element_step"] / r["element_step"]) ** 2, rel=1e-12)
    assert r["element_step_scaled"] == pytest.approx(r["next_level_element_step"], rel=1e-12)
    assert surface_mass_scaling(stack, max_added_mass=0.0)[1] == {}
    with pytest.raises(ValueError, match="max_added_mass"):
        surface_mass_scaling(stack, max_added_mass=-0.1)


def test_low_modes_shift_as_first_order_perturbation_theory_says(stack):
    """Adding ``dM`` lowers ``omega_i`` by ``-1/2 phi^T dM phi / phi^T M phi`` to first order (Rayleigh quotient);
    the remainder is second order in the added mass fraction. For the block's bending modes, whose motion is
    nearly uniform through the depth, that first-order drop is close to half the added mass fraction."""
    cap = 0.01
    scaled, rec = surface_mass_scaling(stack, max_added_mass=cap)
    delta = rec["lower"]["added_mass_fraction"]
    K, M, free = constrained_matrices(stack, mass="lumped")
    _, M1, _ = constrained_matrices(scaled, mass="lumped")
    lam0, phi = lowest_modes(K, M, 3)
    lam1, _ = lowest_modes(K, M1, 3)
    dM = M1 - M
    first = np.array([-0.5 * (p @ (dM @ p)) / (p @ (M @ p)) for p in phi.T])
    drop = np.sqrt(lam1 / lam0) - 1.0
    assert np.all(drop < 0)
    np.testing.assert_allclose(drop, first, rtol=0, atol=2 * delta ** 2)
    # the surface level's share of these modes' kinetic energy is its share of the mass to within 10 % (the
    # shapes vary little through the 2 mm depth at these 67-228 kHz wavelengths; the 120 mm blocks' band modes far less)
    np.testing.assert_allclose(first, -0.5 * delta, rtol=0.1)
