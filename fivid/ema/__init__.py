"""Experimental modal analysis: natural frequencies, damping ratios and complex mode shapes from measured FRFs.

* :func:`experimental_modal_analysis` — FRF files (UFF58, FRF netCDF, run datasets) to a MODES.nc Dataset.
* :func:`identify_modes` — LSCF poles (sdypy-EMA) + automatic stabilisation + LSFD shapes on arrays.
* :func:`read_frfs` — the three inputs as one :class:`FRFSet`.
* :func:`read_modes`, :func:`modes_json` — MODES.nc and its JSON summary.
"""

from fivid.ema.analysis import experimental_modal_analysis
from fivid.ema.frf_input import FRFSet, read_frfs
from fivid.ema.lscf import EMAResult, StabilisationDiagram, identify_modes
from fivid.ema.modes_file import modes_json, read_modes

__all__ = ["EMAResult", "FRFSet", "StabilisationDiagram", "experimental_modal_analysis", "identify_modes",
           "modes_json", "read_frfs", "read_modes"]
