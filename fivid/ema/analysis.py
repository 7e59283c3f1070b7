"""``fivid ema`` as a function: FRF files -> identified modes (MODES.nc Dataset) and Rayleigh coefficients."""

from __future__ import annotations

import logging

from fivid.ema.frf_input import read_frfs
from fivid.ema.lscf import identify_modes
from fivid.ema.modes_file import modes_dataset
from fivid.errors import FividError
from fivid.fe.damping import fit_rayleigh_least_squares

__all__ = ["experimental_modal_analysis"]

log = logging.getLogger("fivid")


def experimental_modal_analysis(paths, *, band=None, n_modes=None, max_order: int = 40, form=None,
                                force: str = "friction_force", response: str = "acceleration", nperseg=None):
    """Identify modes from FRF files (UFF58, FRF netCDF, run datasets; :mod:`fivid.ema.frf_input`).

    Parameters
    ----------
    paths : sequence of path-like
    band : (float, float), optional
        [Hz].
    n_modes : int, optional
    max_order : int
        LSCF ``pol_order_high``.
    form : str, optional
        FRF form override.
    force, response, nperseg
        Run datasets: H1 input/output variables and Welch segment length.

    Returns
    -------
    ds : xarray.Dataset
        MODES.nc content (:mod:`fivid.ema.modes_file`), with Rayleigh alpha [s-1], beta [s] fitted to the
        identified damping ratios (:func:`fivid.fe.damping.fit_rayleigh_least_squares`) when two modes or more
        are found.
    frfs : FRFSet
    """
    frfs = read_frfs(paths, form=form, force=force, response=response, nperseg=nperseg)
    result = identify_modes(frfs.frequency, frfs.frf, band=band, n_modes=n_modes, max_order=max_order,
                            form=frfs.form, driving_point=frfs.driving_point)
    rayleigh = None
    if result.frequency.size >= 2:
        try:
            rayleigh = fit_rayleigh_least_squares(result.frequency, result.damping_ratio)
        except FividError as exc:  # e.g. two identical frequencies
            log.warning("no Rayleigh fit: %s", exc.message)
    return modes_dataset(result, frfs, rayleigh), frfs
