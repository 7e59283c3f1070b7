"""Identification from measured runs: the friction law (forward route) and damping.

- :func:`identify_friction_law` — μ0, the perturbation spectrum s(f), the amplitude law A(V, Ra, Fn)
  in every candidate form with statistics and the chosen form (DESIGN §3, seeds 000/001); its settings in groups
  (:class:`RunAnalysisSettings`, :class:`ShapeSettings`, :class:`AmplitudeSettings`).
- :func:`identify_damping` — modal damping ratios from PSD/FRF peaks and a Rayleigh (α, β) fit.
- :func:`inverse_amplitude_scale` — the inverse route of seed 001: the amplitude scale that makes the
  simulated acceleration level match the measured one in a band.
"""

from fivid.identify.damping import DampingIdentification, RayleighFit, identify_damping
from fivid.identify.inverse import InverseAmplitude, inverse_amplitude_scale
from fivid.identify.amplitude_fit import (SELECTION_RULE, FormFit, akaike_weights, candidate_forms, choose_form,
                                          fit_amplitude_forms)
from fivid.identify.friction import (AmplitudeSettings, FrictionIdentification, ShapeSettings,
                                     identification_arguments, identify_friction_law)
from fivid.identify.runs import RunAnalysis, RunAnalysisSettings, analyse_run

__all__ = [
    "identify_friction_law",
    "identification_arguments",
    "ShapeSettings",
    "AmplitudeSettings",
    "identify_damping",
    "inverse_amplitude_scale",
    "InverseAmplitude",
    "DampingIdentification",
    "RayleighFit",
    "FrictionIdentification",
    "fit_amplitude_forms",
    "choose_form",
    "akaike_weights",
    "candidate_forms",
    "FormFit",
    "SELECTION_RULE",
    "RunAnalysis",
    "RunAnalysisSettings",
    "analyse_run",
]
