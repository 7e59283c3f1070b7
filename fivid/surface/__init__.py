"""Surface metrology of stylus profiles (layer L2): readers, form removal, ISO filters and parameters, synthesis.

* Readers (:mod:`fivid.surface.readers`): :func:`read_profile` picks :func:`read_dektak_csv`
  (Bruker Dektak CSV export), :func:`read_profile_columns` (``x [um], z [um]`` text) or
  :func:`read_x3p` (ISO 25178-72 X3P, needs the optional ``x3pio``). A profile is an
  ``xarray.DataArray`` of heights [m] over ``x`` [m] (:func:`make_profile`).
* Metrology: :func:`evaluate_profile` (window, form removal, ISO 16610-21 Gaussian filter,
  ISO 4287 / ISO 21920-2 parameters keyed by ISO symbol in SI units).
* Synthesis and statistics: :func:`gaussian_random_profile`, :func:`profile_from_psd`,
  :func:`height_distribution`, :func:`profile_psd`, :func:`autocorrelation`, :func:`correlation_length`.

See docs/surface.md.
"""

from fivid.surface.dektak import instrument_results, read_dektak_csv
from fivid.surface.columns import read_profile_columns
from fivid.surface.form import form_degree, remove_form
from fivid.surface.gaussian_filter import gaussian_mean_line, gaussian_weights, mean_line_transmission
from fivid.surface.metrology import PARAMETER_UNITS, Evaluation, evaluate_profile
from fivid.surface.profile import make_profile, sampling_step
from fivid.surface.readers import read_profile
from fivid.surface.statistics import autocorrelation, correlation_length, height_distribution, profile_psd
from fivid.surface.synthesis import gaussian_random_profile, profile_from_psd
from fivid.surface.x3p import read_x3p

__all__ = [
    "read_profile",
    "read_dektak_csv",
    "read_profile_columns",
    "read_x3p",
    "instrument_results",
    "make_profile",
    "sampling_step",
    "form_degree",
    "remove_form",
    "gaussian_weights",
    "gaussian_mean_line",
    "mean_line_transmission",
    "evaluate_profile",
    "Evaluation",
    "PARAMETER_UNITS",
    "gaussian_random_profile",
    "profile_from_psd",
    "height_distribution",
    "profile_psd",
    "autocorrelation",
    "correlation_length",
]
