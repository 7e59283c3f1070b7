"""The friction home: the kinetic curve, the perturbation μp(t) and their compiled form for the solver.

- :class:`CoulombLaw` — μ = μ0.
- :class:`PerturbedCoulombLaw` — μ = μ0 + μp(t), μp with one-sided PSD A(V, Ra, Fn)^2 s(f) (DESIGN §3).
- :func:`load_law` / :func:`write_law` — the law file written by ``fivid identify``.
- :func:`synthesise_perturbation` — random-phase / Gaussian spectral synthesis (pyfftw, seeded).
- :class:`AmplitudeModel` — the amplitude forms A(V, Ra, Fn); :func:`predict_amplitude` — A with its
  prediction interval, checked against the identified domain (:class:`ConditionDomain`).
- :class:`FrictionCurve` — the kinetic curve over μk: static excess μs − μk, Stribeck decay, viscous term;
  :func:`slave_coefficients` — μk of every contact node (static preload and solver).
- :func:`friction_table` (:class:`FrictionTable`) — μ0 + μp(t) per contact node on the solver's time grid, the
  injection modes (uniform, per node, convected); the kernels (:mod:`fivid.friction._curve_kernels`) evaluate the
  curve and the table, reading the curve's parameters from a pair's record (:mod:`fivid.contact._layout_kernels`).
- :class:`OperatingCondition`, :class:`FrictionInput` — the condition (V, Fn, Ra) and the friction (law or constant
  μ, seed) of a simulation, the first groups of :func:`fivid.solver.simulate`.
- :mod:`fivid.friction.jenkins` — Jenkins (Masing) and Iwan elements for friction dampers (seed 004).
"""

from fivid.friction.jenkins import (iwan_energy_per_cycle, iwan_force, iwan_uniform_elements, jenkins_energy_per_cycle,
                                    jenkins_force, jenkins_periodic_force, loop_energy)
from fivid.friction.amplitude import (AMPLITUDE_FORMS, CATEGORICAL_FORMS, CONTINUOUS_FORMS, INTERACTION_FORMS,
                                      AmplitudeModel, amplitude_design_matrix, coefficient_units)
from fivid.friction.domain import ConditionDomain
from fivid.friction.lawfile import domain_from_dataset, law_dataset, law_from_dataset, load_law, write_law
from fivid.friction.prediction import AmplitudePrediction, ExtrapolationWarning, predict_amplitude
from fivid.friction.laws import INJECTION_MODES, CoulombLaw, FrictionLaw, PerturbedCoulombLaw
from fivid.friction.curve import FrictionCurve, slave_coefficients
from fivid.friction.injection import FrictionTable, friction_table
from fivid.friction.inputs import FrictionInput, OperatingCondition
from fivid.friction.synthesis import synthesise_perturbation

__all__ = [
    "AMPLITUDE_FORMS",
    "CONTINUOUS_FORMS",
    "INTERACTION_FORMS",
    "CATEGORICAL_FORMS",
    "AmplitudeModel",
    "coefficient_units",
    "ConditionDomain",
    "domain_from_dataset",
    "predict_amplitude",
    "AmplitudePrediction",
    "ExtrapolationWarning",
    "amplitude_design_matrix",
    "CoulombLaw",
    "FrictionLaw",
    "PerturbedCoulombLaw",
    "INJECTION_MODES",
    "FrictionCurve",
    "slave_coefficients",
    "FrictionTable",
    "FrictionInput",
    "OperatingCondition",
    "friction_table",
    "load_law",
    "write_law",
    "law_dataset",
    "law_from_dataset",
    "synthesise_perturbation",
    "jenkins_force",
    "jenkins_periodic_force",
    "jenkins_energy_per_cycle",
    "loop_energy",
    "iwan_force",
    "iwan_uniform_elements",
    "iwan_energy_per_cycle",
]
