"""The minimal mode-coupling model (Hoffmann et al. 2002): CEA's critical friction coefficient in closed form."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from fivid.fe.cea import complex_eigenvalue_sweep, project_on_modes
from fivid.fe.contact import ContactLinearisation
from fivid.verify.case import Case, Curve, Outcome, Plot

__all__ = ["CASES", "hoffmann_model", "hoffmann_sweep"]

#: mass [kg], springs at +45 and 135 deg and the contact spring [N/m], mass-proportional damping [N s/m]
M, K1, K2, K3, C = 1.0, 1.0e6, 1.6e6, 0.8e6, 20.0


def hoffmann_model(m=M, k1=K1, k2=K2, k3=K3, c=C):
    """A mass on a belt moving in +x, held by springs k1 at +45° and k2 at 135°, pressed on the belt by the contact
    spring k3 (normal y): k11 = k22s = (k1 + k2)/2, k12 = (k1 - k2)/2, k22 = k22s + k3; friction adds μ k3 at
    (x, y). Undamped, the eigenvalues coalesce (flutter) when (k11 - k22)² + 4k12² + 4μk3k12 < 0:
    μc = -[(k11 - k22)² + 4k12²]/(4k3k12) (k12 < 0); with mass-proportional damping c the threshold moves to
    μc = -[(k11 - k22)² + 4k12² + 2c²(k11 + k22)/m]/(4k3k12).

    Returns K_s (springs), the contact linearisation (G_n = [0, 1], G_t = [1, 0], rigid belt), M, C and the two
    closed-form thresholds.
    """
    k11, k12, k22s = (k1 + k2) / 2, (k1 - k2) / 2, (k1 + k2) / 2
    K_s = np.array([[k11, k12], [k12, k22s]])
    contact = ContactLinearisation(sp.csr_matrix([[0.0, 1.0]]), sp.csr_matrix([[1.0, 0.0]]),
                                   np.array([k3]), np.array([1.0]), np.array([0]))
    k22 = k22s + k3
    mu_c = -((k11 - k22) ** 2 + 4 * k12 ** 2) / (4 * k3 * k12)
    mu_c_damped = -((k11 - k22) ** 2 + 4 * k12 ** 2 + 2 * c ** 2 * (k11 + k22) / m) / (4 * k3 * k12)
    return K_s, contact, m * np.eye(2), c * np.eye(2), mu_c, mu_c_damped


def hoffmann_sweep(damped: bool, mu=None, contact=None):
    """fivid's CEA sweep of the model over ``mu`` (default 0-2 in 41 steps); returns ``(result, closed form μc)``.
    ``contact`` replaces the model's linearisation (the mirrored belt of the tests)."""
    K_s, lin, Mm, Cm, mu_c, mu_c_damped = hoffmann_model()
    lin = lin if contact is None else contact
    K = K_s + lin.normal_stiffness_matrix().toarray()
    Kf = lin.friction_stiffness_matrix().toarray()
    proj = project_on_modes(K, Mm, Cm if damped else 0 * Cm, Kf)
    mu = np.linspace(0.0, 2.0, 41) if mu is None else mu
    return complex_eigenvalue_sweep(proj, mu), (mu_c_damped if damped else mu_c)


def _make(damped: bool):
    def compute(quick: bool, data) -> Outcome:
        mu = np.linspace(0.0, 2.0, 41)
        res, expected = hoffmann_sweep(damped, mu)
        crit = res["critical_mu"]
        finite = np.flatnonzero(np.isfinite(crit))
        value = float(crit[finite[0]]) if finite.size == 1 else float("nan")
        lam = res["eigenvalues"]
        plot = Plot("friction coefficient μ [-]", "Re(λ) [1/s]",
                    (Curve(mu, lam[:, 0].real, "fivid CEA, mode 1"), Curve(mu, lam[:, 1].real, "fivid CEA, mode 2"),
                     Curve(np.array([expected, expected]), np.array([lam.real.min(), lam.real.max()]),
                           "closed-form μc", "dashed")))
        return Outcome(value, float(expected), 1e-6 if damped else 1e-9, plot,
                       {"modes destabilised": int(finite.size), "Re tolerance of the bisection [1/s]":
                        float(res["tolerance"])})
    compute.__name__ = compute.__qualname__ = "compute_damped" if damped else "compute_undamped"
    return compute


compute_undamped = _make(False)
compute_damped = _make(True)

_SOURCE = ("N. Hoffmann, M. Fischer, R. Allgaier, L. Gaul, A minimal model for studying properties of the "
           "mode-coupling type instability in friction induced oscillations, Mech. Res. Commun. 29 (2002) 197-205; "
           "N. Hoffmann, L. Gaul, Effects of damping on mode-coupling instability in friction induced "
           "oscillations, ZAMM 83 (2003) 524-534")
_METHOD = ("fivid.fe.cea.project_on_modes and complex_eigenvalue_sweep over μ = 0-2 (41 values, bisection to the "
           "threshold) of the 2-DOF model m = 1 kg, k1 = 1e6, k2 = 1.6e6, k3 = 0.8e6 N/m; same for --quick")

CASES = (
    Case(name="hoffmann_threshold", title="Mode-coupling threshold of the minimal 2-DOF model",
         quantity="critical friction coefficient μc (undamped)", unit="",
         reference="μc = -[(k11 - k22)² + 4k12²]/(4k3k12)", source=_SOURCE, method=_METHOD,
         tolerance_basis="1e-9: the bisection runs to machine precision on Re(λ) ~ ω√(μ - μc); what is left is the "
                         "threshold tolerance √eps|λ|max on Re, ~eps on μ, with margin",
         compute=compute_undamped),
    Case(name="hoffmann_threshold_damped", title="Mode-coupling threshold with mass-proportional damping",
         quantity="critical friction coefficient μc (damping c = 20 N s/m)", unit="",
         reference="μc = -[(k11 - k22)² + 4k12² + 2c²(k11 + k22)/m]/(4k3k12)", source=_SOURCE, method=_METHOD,
         tolerance_basis="1e-6: damped, Re(λ) ~ ω(μ - μc) is linear at the threshold, so the Re tolerance √eps|λ| "
                         "maps to ~1.5e-8 on μ; with margin",
         compute=compute_damped),
)
