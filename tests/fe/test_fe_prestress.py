"""Prestress (initial-stress) stiffness against closed forms: a tensioned strip and an Euler column.

Both use a slender plane Q4 strip of length L, depth h (L/h = 50) with a uniform axial stress ``s`` from dead
end pressures (exact for Q4: a uniform stress is in the element's span). Under the "Navier" support
(``v = 0`` on both end faces, ``u`` free there, one axial pin) the 2D continuum has separable modes
``(U(y) cos kx, V(y) sin kx)``, ``k = n pi / L``, and on each such subspace the initial-stress energy
``s int (u_x^2 + v_x^2) dV`` equals ``s k^2 int (u^2 + v^2) dV``, i.e. ``K_sigma = (s k^2 / rho) M`` exactly,
whatever the depth profile. Hence two exact facts of the continuum that the FE must reproduce in the limit:

* tension adds exactly ``s k^2 / rho`` to every omega^2 of the n-th half-wave (the string's term);
* the compressive buckling stress of the n = 1 half-wave is ``rho omega_1^2 / k^2`` of the unstressed strip.

Tolerances come from the observed convergence (order fitted on >= 3 meshes by tests.helpers.convergence.assert_order,
its tolerance from the fit's residual; Richardson extrapolation), as in
tests/fe/test_fe_modal.py.
"""

import numpy as np
import pytest

from fivid.fe import load_model, static_response
from fivid.fe.modal import constrained_matrices, lowest_modes, modal_analysis
from fivid.fe.prestress import (
    buckling_load_factors,
    element_geometric_stiffness_q4,
    gauss_point_stress_q4,
    geometric_stiffness_matrix,
)
from tests.helpers.convergence import assert_order

E, NU, RHO = 210e9, 0.3, 7850.0
L, H, T = 0.5, 0.01, 0.01  # length, depth, thickness [m]


def _strip(ny, *, plane="stress", pressure=0.0, support="pins"):
    """The strip with ``ny`` square elements through the depth; end pressures ``pressure`` [Pa] (negative: tension).

    support "pins": mid-depth node of the left end fixed in x and y, of the right end in y (statically determinate,
    the self-equilibrated end pressures leave the stress uniform). "navier": y fixed on both end faces, the left
    mid-depth node in x (for vibration/buckling; the end faces would restrain the Poisson contraction of a preload)."""
    def motion(edge, component, mid=True):
        ref = {"body": "s", "edge": edge, **({"y": [H / 2, H / 2]} if mid else {})}
        return {"name": f"{edge}_{component}_{mid}", **ref, "component": component, "kind": "displacement",
                "amplitude": 0.0}

    motions = ([motion("left", "x"), motion("left", "y"), motion("right", "y")] if support == "pins" else
               [motion("left", "x"), motion("left", "y", mid=False), motion("right", "y", mid=False)])
    loads = [{"name": f"end_{e}", "body": "s", "edge": e, "pressure": pressure} for e in ("left", "right")]
    return load_model({
        "plane": plane,
        "bodies": {"s": {"corners": [[0, 0], [L, 0], [L, H], [0, H]], "divisions": [int(round(ny * L / H)), ny],
                         "material": {"E": E, "nu": NU, "rho": RHO}, "thickness": T}},
        "motions": motions, **({"loads": loads} if pressure else {})})


def _fit_and_extrapolate(h, values, order=2.0):
    """Observed order ``p`` (least-squares slope of log|successive differences| vs log h, over >= 3 meshes), the
    Richardson limit with the asymptotic ``order`` (Q4: 2 for eigenvalues and stress-driven terms) from the finest
    pair, and its uncertainty: the change of the limit when extrapolating from the next-coarser pair instead (an
    estimate, and a bound, of the finest extrapolation's remainder) plus the change when the observed ``p`` replaces
    ``order``. The tolerance is thus read off the meshes, not tuned."""
    values = np.asarray(values, dtype=float)
    h = np.asarray(h, dtype=float)
    d = np.abs(np.diff(values, axis=0))
    p = np.polyfit(np.log(h[:-1]), np.log(d), 1)[0]

    def limit(q, k):
        r = h[k - 1] / h[k]
        return values[k] + (values[k] - values[k - 1]) / (r**q - 1)

    best = limit(order, -1)
    return p, best, np.abs(best - limit(order, -2)) + np.abs(limit(p, -1) - best)


def test_element_geometric_stiffness_is_the_string_energy_of_a_uniform_tension():
    """A uniform stress s_xx on a rectangle a x b: w^T K_sigma w = s t int (w_x,x^2 + w_y,x^2) dA, exact for the
    bilinear field w (Gauss 2x2 integrates its quadratic gradient products exactly); and a rigid translation has
    zero initial-stress energy."""
    a, b, s = 0.3, 0.2, 7e6
    xy = np.array([[0, 0], [a, 0], [a, b], [0, b]], dtype=float)
    stress = np.tile([s, 0.0, 0.0], (4, 1))
    Ke = element_geometric_stiffness_q4(xy, stress, T)
    w = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0])  # w_y = x / a: w_y,x = 1/a everywhere
    assert w @ Ke @ w == pytest.approx(s * T * a * b / a**2, rel=1e-13)
    assert np.abs(Ke @ np.tile([1.0, 0.0], 4)).max() < 1e-9 * np.abs(Ke).max()
    np.testing.assert_allclose(Ke, Ke.T, atol=0)


def test_static_end_pressure_gives_the_exact_uniform_stress():
    """Q4 reproduces a uniform stress exactly: s_xx = -p at every Gauss point, s_yy = s_xy = 0 (float resolution
    of the sparse solve)."""
    p = -50e6
    model = _strip(2, pressure=p)
    u = static_response(model)
    b = model.blocks[0]
    s = gauss_point_stress_q4(b.element_corners(), u[b.element_dofs()], b.material.elasticity_matrix("stress"))
    np.testing.assert_allclose(s[..., 0], -p, rtol=1e-9)
    assert np.abs(s[..., 1:]).max() < 1e-9 * abs(p)


@pytest.mark.parametrize("plane", ["stress", "strain"])
def test_tension_adds_the_string_term_to_every_half_wave(plane):
    """Tensioned strip (s = 200 MPa, Navier-supported ends): omega_n^2(s) - omega_n^2(0) -> s (n pi/L)^2 / rho,
    the string's term, for the first three transverse modes, with the observed order 2 (fitted on three meshes, the
    tolerance from the fit's residual: tests.helpers.convergence) and the
    Richardson limit inside the next-order remainder (+ 1e-9 relative for the eigen solver's omega^2 differences).

    And the full frequencies against the closed form of a beam in tension: Euler-Bernoulli
    ``omega^2 = (EI k^4 + s A k^2) / (rho A)`` (``E`` -> ``E/(1 - nu^2)`` in plane strain) misses the shear and
    rotary-inertia corrections, Timoshenko's (``kappa`` Cowper's, rotary inertia ``rho I``, the tension's rotary part
    ``s I k^2`` cancelling against it) includes them; the FE limit must be at least 3x closer to Timoshenko."""
    s = 200e6
    k = np.arange(1, 4) * np.pi / L
    h, inc, full = [], [], []
    for ny in (4, 8, 16):
        tension = static_response(_strip(ny, plane=plane, pressure=-s))
        navier = _strip(ny, plane=plane, support="navier")
        lam0 = lowest_modes(*constrained_matrices(navier)[:2], 3)[0]
        lam = lowest_modes(*constrained_matrices(navier, prestress=tension)[:2], 3)[0]
        h.append(H / ny), inc.append((lam - lam0) / (s * k**2 / RHO)), full.append(np.sqrt(lam) / (2 * np.pi))
    h = np.array(h)
    err = np.array(inc) - 1.0  # a known reference: fit the errors themselves
    for mode in range(3):
        assert_order(h, np.abs(err[:, mode]), 2.0)
    _, limit, spread = _fit_and_extrapolate(h, inc)
    assert np.all(np.abs(limit - 1.0) <= spread + 1e-9), (limit - 1, spread)

    _, f_fe, f_spread = _fit_and_extrapolate(h, full)
    Ep = E if plane == "stress" else E / (1 - NU**2)
    A, I, r2, G, kappa = H * T, T * H**3 / 12, H**2 / 12, E / (2 * (1 + NU)), 10 * (1 + NU) / (12 + 11 * NU)
    f_eb = np.sqrt((Ep * I * k**4 + s * A * k**2) / (RHO * A)) / (2 * np.pi)
    f_t = np.sqrt((Ep * I * k**4 / (1 + Ep * I * k**2 / (kappa * G * A)) + s * A * k**2 * (1 + r2 * k**2))
                  / (RHO * A * (1 + r2 * k**2))) / (2 * np.pi)
    assert np.all(np.abs(f_fe - f_t) + f_spread < np.abs(f_eb - f_t) / 3), (f_fe, f_t, f_eb)


def test_string_limit_of_modal_analysis_with_prestress():
    """modal_analysis(prestress=True) on the pinned strip (the static state of its own end tensions) vs the string
    f_n = n/(2L) sqrt(s/rho) in the string limit: at s = 2 GPa (a linear model: only the ratio s L^2 / (E h^2)
    matters, here 24) the bending share of omega_1^2 is pi^2 E h^2 / (12 s L^2) = 0.035, so
    f_1 / f_string - 1 ~ share/2, positive and below the share (the coarse mesh's stiffer bending adds a few per cent
    of the share)."""
    s = 2e9
    ds = modal_analysis(_strip(2, pressure=-s), 1, prestress=True)
    f_string = 1 / (2 * L) * np.sqrt(s / RHO)
    share = np.pi**2 * E * H**2 / (12 * s * L**2)
    rel = ds["frequency"].values[0] / f_string - 1
    assert 0 < rel < share, (rel, share)
    assert ds.attrs["prestress"] == 1
    # without the prestress the strip is the bare pinned beam: sqrt(share) = 0.19 of the string's (+ mesh error)
    bare = modal_analysis(_strip(2, pressure=-s), 1)["frequency"].values[0]
    assert np.sqrt(share) < bare / f_string < 1.1 * np.sqrt(share), (bare / f_string, np.sqrt(share))


def test_euler_column_buckling_load():
    """Pinned-pinned column (L/h = 50) in compression: the lowest load factor where K + lambda K_sigma is singular,
    against Euler's pi^2 EI / L^2 with the Engesser shear correction (kappa Cowper's) and the 2D continuum's exact
    initial-stress factor of the axial displacements 1 + (k r)^2 (``P_cr = P_E / (1 + P_E/(kappa G A)) /
    (1 + (pi r / L)^2)``, r^2 = h^2/12: the module docstring's identity). Observed order 2 of the successive
    differences on 4 meshes (tolerance from the fit's residual); the
    Richardson limit must be 3x closer to this than to Euler's bare value (which is 1.3e-3 above it), with the
    extrapolation's fitted uncertainty added."""
    P = 1e6 * H * T  # reference load of a 1 MPa end pressure [N]
    h, pcr = [], []
    for ny in (2, 4, 8, 16):
        model = _strip(ny, pressure=1e6)
        h.append(H / ny), pcr.append(buckling_load_factors(model, static_response(model), 1)[0] * P)
    assert_order(h[:-1], np.abs(np.diff(pcr)), 2.0)
    _, limit, spread = _fit_and_extrapolate(np.array(h), pcr)
    A, I, G, kappa = H * T, T * H**3 / 12, E / (2 * (1 + NU)), 10 * (1 + NU) / (12 + 11 * NU)
    p_euler = np.pi**2 * E * I / L**2
    p_ref = p_euler / (1 + p_euler / (kappa * G * A)) / (1 + (np.pi / L) ** 2 * H**2 / 12)
    assert abs(limit - p_ref) + spread < abs(p_euler - p_ref) / 3, (limit, p_ref, p_euler)


def test_buckling_stress_equals_the_unstressed_frequency_identity():
    """The continuum identity s_cr = rho omega_1^2 / k^2 (module docstring) holds for the FE up to the discretisation
    error of K_sigma against the consistent M (both bending errors cancel: the same K): the relative difference
    converges with order 2 over ny = 2, 4, 8 (tolerance from the fit's residual) and is below 1e-4 already at ny = 2
    (measured 8.2e-5)."""
    rel = []
    for ny in (2, 4, 8):
        navier = _strip(ny, support="navier")
        s_cr = 1e6 * buckling_load_factors(navier, static_response(_strip(ny, pressure=1e6)), 1)[0]  # same dofs
        w2 = lowest_modes(*constrained_matrices(navier)[:2], 1)[0][0]
        rel.append(abs(s_cr / (RHO * w2 / (np.pi / L) ** 2) - 1))
    assert rel[0] < 1e-4, rel
    assert_order(H / np.array([2.0, 4.0, 8.0]), rel, 2.0)


def test_prestress_rejects_a_state_of_the_wrong_size():
    from fivid.errors import ConfigError

    model = _strip(2)
    with pytest.raises(ConfigError, match="prestress state"):
        geometric_stiffness_matrix(model, np.zeros(5))


def test_prestressed_cea_at_zero_friction_equals_the_prestressed_modal_analysis(capsys):
    """The rig's CEA about the prestressed preload (5 N) at mu = 0 without damping is the prestressed coupled modal
    analysis (the basis modes are its eigenvectors: dense-solver rounding, 1e-9), and `fivid modes --prestress`
    reports the same; the preload's K_sigma moves the frequencies by far more than that rounding."""
    import json
    from pathlib import Path

    from fivid.cli import main
    from fivid.fe.cea import Linearisation, complex_eigenvalue_analysis

    coarse = Path(__file__).resolve().parents[2] / "configs" / "models" / "triboair_coarse.yaml"
    model = load_model(coarse)
    cea = complex_eigenvalue_analysis(model, [0.0, 0.5], normal_load=5.0, n_modes=6,
                                      linearisation=Linearisation(damping=False, prestress=True))
    modes = modal_analysis(model, 6, include_contact=True, normal_load=5.0, prestress=True)
    bare = modal_analysis(model, 6, include_contact=True, normal_load=5.0)
    np.testing.assert_allclose(cea["frequency"].values[0], modes["frequency"].values, rtol=1e-9)
    assert np.abs(modes["frequency"].values / bare["frequency"].values - 1).max() > 1e-7
    assert cea.attrs["prestress"] == 1 and bare.attrs["prestress"] == 0
    assert main(["modes", str(coarse), "-n", "6", "--load", "5 N", "--prestress", "--json"]) == 0
    j = json.loads(capsys.readouterr().out)
    assert j["prestress"] is True
    np.testing.assert_allclose(j["frequencies_hz"], modes["frequency"].values, rtol=1e-9)


def test_an_imposed_stretch_is_the_prestress_state_of_modal_analysis():
    """A strip stretched by an imposed end displacement delta (displacement motions on the x of both end faces,
    Poisson contraction free): static_state gives the uniform s_xx = E delta / L at every Gauss point (exact for Q4),
    and modal_analysis(prestress=True) equals the same supports prestressed by that stress from end pressures
    (identical K_sigma: float rounding) and lies above the Rayleigh bound below."""
    from fivid.fe.prestress import static_state

    delta = 1e-4  # [m]: s = E delta / L = 42 MPa
    motions = [{"name": "pin_y", "body": "s", "edge": "left", "y": [H / 2, H / 2], "component": "y",
                "kind": "displacement", "amplitude": 0.0},
               {"name": "pin_ry", "body": "s", "edge": "right", "y": [H / 2, H / 2], "component": "y",
                "kind": "displacement", "amplitude": 0.0},
               {"name": "hold", "body": "s", "edge": "left", "component": "x", "kind": "displacement", "amplitude": 0.0},
               {"name": "stretch", "body": "s", "edge": "right", "component": "x", "kind": "displacement",
                "amplitude": delta, "role": "load"}]
    stretched = load_model({
        "bodies": {"s": {"corners": [[0, 0], [L, 0], [L, H], [0, H]], "divisions": [100, 2],
                         "material": {"E": E, "nu": NU, "rho": RHO}, "thickness": T}},
        "motions": motions})
    u = static_state(stretched)
    b = stretched.blocks[0]
    s = gauss_point_stress_q4(b.element_corners(), u[b.element_dofs()], b.material.elasticity_matrix("stress"))
    np.testing.assert_allclose(s[..., 0], E * delta / L, rtol=1e-9)
    assert np.abs(s[..., 1:]).max() < 1e-9 * E * delta / L
    ds = modal_analysis(stretched, 3, prestress=True)
    tension = static_response(_strip(2, pressure=-E * delta / L))  # same mesh and dofs
    lam = lowest_modes(*constrained_matrices(stretched, prestress=tension)[:2], 3)[0]
    np.testing.assert_allclose(ds["frequency"].values, np.sqrt(lam) / (2 * np.pi), rtol=1e-9)
    # Rayleigh + Wirtinger: omega_1^2(s) >= omega_1^2(0) + s min(int |w_x|^2 / int |w|^2) / rho, and for a beam
    # whose axis deflection vanishes at both pins that minimum is (pi/L)^2 (the 2D strip departs from the beam's
    # kinematics by O((h/L)^2) = 4e-4 relative; measured ratio of the two sides 1.24: the clamped ends' shape)
    w0 = 2 * np.pi * modal_analysis(stretched, 1)["frequency"].values[0]
    w1 = 2 * np.pi * ds["frequency"].values[0]
    assert w1**2 - w0**2 >= E * delta / L * (np.pi / L) ** 2 / RHO, (w1**2 - w0**2, E * delta / L * (np.pi / L) ** 2 / RHO)
