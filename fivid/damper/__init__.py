"""Friction dampers (seed 004): a beam with a Jenkins contact, FRFs by harmonic balance, identification.

* :func:`load_damper_model` — beam + contact + excitation + sensor from a YAML config.
* :class:`HarmonicBalance` — AFT harmonic balance at fixed frequencies (``sweep``);
  :func:`continue_frequency_response` — pseudo-arclength continuation with Floquet stability.
* :func:`steady_state_response` — Newmark/Newton-Raphson time-domain reference.
* :func:`fit_jenkins_loop` — slip force and stiffness from a measured hysteresis loop.
* :func:`update_contact_parameters` — mu and k_d from FRFs at several normal loads.
* :func:`frf_peak` — the FRF peak frequency at a normal load (the target ``fivid update`` fits damper models to).
"""

from fivid.damper.continuation import FrequencyResponseCurve, continue_frequency_response
from fivid.damper.hbm import HarmonicBalance, PeriodicSolution
from fivid.damper.loop_fit import JenkinsLoopFit, fit_jenkins_loop
from fivid.damper.modal import ModalModel
from fivid.damper.model import DamperModel, damper_model_from_dict, load_damper_model
from fivid.damper.peaks import FRFPeak, frf_peak
from fivid.damper.stability import floquet_multipliers
from fivid.damper.timedomain import SteadyStateResponse, steady_state_response
from fivid.damper.updating import ContactUpdate, update_contact_parameters

__all__ = [
    "ContactUpdate",
    "DamperModel",
    "FRFPeak",
    "FrequencyResponseCurve",
    "HarmonicBalance",
    "JenkinsLoopFit",
    "ModalModel",
    "PeriodicSolution",
    "SteadyStateResponse",
    "continue_frequency_response",
    "damper_model_from_dict",
    "fit_jenkins_loop",
    "frf_peak",
    "floquet_multipliers",
    "load_damper_model",
    "steady_state_response",
    "update_contact_parameters",
]
