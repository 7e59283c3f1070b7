"""Model updating: named config parameters fitted to target modes (``fivid update``).

* :func:`load_targets` — the targets file (parameters with bounds, target modes, options).
* :func:`update_model` — least squares, confidence intervals, correlation, identifiability; the updated text.
* :class:`FEModes`, :class:`DamperPeaks` — what FE and damper models predict for the targets.
"""

from fivid.updating.fit import Parameter, UpdateResult, update_model
from fivid.updating.predict import DamperPeaks, FEModes, mac
from fivid.updating.targets import Targets, load_targets

__all__ = ["DamperPeaks", "FEModes", "Parameter", "Targets", "UpdateResult", "load_targets", "mac", "update_model"]
