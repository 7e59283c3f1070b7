"""SYNTHETIC friction-law files with a stated coefficient covariance and domain, for the Monte-Carlo tests.

Not identified from data: the law of tests/helpers/synthetic_friction_runs.py (μ0 = 0.3, a 4th-order roll-off at
1.5 kHz) with a power-law amplitude A = 0.002 (Ra/1 µm)^0.5 (V/1 mm/s)^0.6 and standard errors of the size
an 8-run identification gives (0.15 on ln A at the reference, 0.05 on each exponent, uncorrelated), and the
domain V 5-20 mm/s, Ra 0.5-2 µm at Fn 5 N (convex hull of a 2 x 2 grid).
"""

from __future__ import annotations

import numpy as np
from tests.helpers.synthetic_friction_runs import MU0, SHAPE, SHAPE_F

from fivid.friction import AmplitudeModel, ConditionDomain, PerturbedCoulombLaw, law_dataset, write_law

STDERR = np.array([0.15, 0.05, 0.05])  # ln A at the reference, roughness and velocity exponents
DOMAIN = np.array([[0.005, 0.5e-6, 5.0], [0.02, 0.5e-6, 5.0], [0.005, 2e-6, 5.0], [0.02, 2e-6, 5.0]])


def uncertain_law(stderr=STDERR) -> PerturbedCoulombLaw:
    """The law above with covariance diag(stderr²)."""
    stderr = np.asarray(stderr, float)
    model = AmplitudeModel("power_law", np.array([np.log(0.002), 0.5, 0.6]),
                           ("log_prefactor", "roughness_exponent", "velocity_exponent"), stderr, np.diag(stderr**2),
                           terms=("roughness_ra", "sliding_velocity"), residual_variance=0.01, df_resid=5.0)
    return PerturbedCoulombLaw(MU0, SHAPE_F, SHAPE, model, (SHAPE_F[0], SHAPE_F[-1]))


def write_uncertain_law(path, stderr=STDERR):
    """Write :func:`uncertain_law` with its domain to ``path`` (a law file, version 2); returns the law."""
    law = uncertain_law(stderr)
    write_law(law_dataset(law, domain=ConditionDomain(DOMAIN)), path, overwrite=True)
    return law
