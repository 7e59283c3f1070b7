"""Time-step halving (DESIGN §5: friction needs it): the same run at dt and dt/2, PSDs compared.

A check of one simulation's step, not a parametric study (those are :mod:`fivid.study`); the PSDs and their
distance come from :mod:`fivid.signal.compare`.
"""

from __future__ import annotations

import math
from dataclasses import replace

from fivid.fe.build import load_model
from fivid.fe.model import Model
from fivid.signal.compare import band_distance, steady_psds
from fivid.friction.inputs import FrictionInput, OperatingCondition
from fivid.solver.driver import simulate
from fivid.solver.options import IntegrationOptions, OutputOptions, RunSchedule
from fivid.solver.timestep import stable_step
from fivid.units import power_units

__all__ = ["time_step_halving"]


def time_step_halving(model, condition: OperatingCondition = OperatingCondition(),
                      friction: FrictionInput = FrictionInput(), *, schedule: RunSchedule,
                      integration: IntegrationOptions = IntegrationOptions(), output: OutputOptions = OutputOptions(),
                      variable="acceleration", band=None, nperseg=None):
    """Run :func:`fivid.solver.simulate` at ``dt`` and ``dt/2`` and report how the PSD changes.

    Parameters
    ----------
    model : Model or path
    condition, friction, schedule, integration, output
        As :func:`fivid.solver.simulate`. ``integration.time_step`` is the coarser step [s] (None: the solver's
        default step, ``integration.safety`` x critical), rounded down to fit a whole number of steps in a
        recording interval; the finer run uses exactly half of it.
    variable : str
        Variable whose PSD is compared (first sensor if it has a sensor dim).
    band : (float, float), optional
        Frequency band [Hz] of the comparison (default: 0 to 0.8 x Nyquist).
    nperseg : int, optional
        Welch segment length [samples] (Hann window, 50 % overlap, constant detrend, density scaling); default
        :func:`fivid.signal.welch.default_nperseg` of the steady part. The result's ``welch`` attr states it.

    Returns
    -------
    xarray.Dataset
        ``psd_coarse``, ``psd_fine`` [unit2 Hz-1] on ``frequency`` [Hz]; attrs ``time_step_coarse``,
        ``time_step_fine`` [s], ``lsd_db`` (RMS of 10 log10(P_fine/P_coarse) over the band [dB]),
        ``level_diff_db`` (10 log10 of the ratio of band powers [dB]; :func:`fivid.signal.compare.band_distance`), ``band`` [Hz] and the Welch settings.
        Only the steady-sliding part (time >= ``transient_end``) is analysed.
    """
    import xarray as xr

    if not isinstance(model, Model):
        model = load_model(model)
    time_step = integration.time_step
    if time_step is None:
        time_step = float(integration.safety) * stable_step(model).critical_time_step
    # the solver fits a whole number of steps in each recording interval: take that step and exactly half of it
    t_int = 1.0 / (float(schedule.sample_rate) * int(output.oversample))
    n_sub = max(1, math.ceil(t_int / time_step * (1.0 - 1e-12)))
    coarse = t_int / n_sub
    runs = [simulate(model, condition, friction, schedule=schedule, integration=replace(integration, time_step=dt),
                     output=output) for dt in (coarse, t_int / (2 * n_sub))]
    f, psds, n = steady_psds(runs, variable=variable, nperseg=nperseg)
    fs = float(runs[0].attrs["sample_rate"])
    lo, hi = band if band is not None else (0.0, 0.8 * fs / 2)
    lsd, level = band_distance(f, psds[0], psds[1], (lo, hi))
    units = power_units(runs[0][variable].attrs.get("units", "1"))
    out = xr.Dataset(
        {"psd_coarse": (("frequency",), psds[0], {"units": units}),
         "psd_fine": (("frequency",), psds[1], {"units": units})},
        coords={"frequency": ("frequency", f, {"units": "Hz"})},
    )
    out.attrs.update({
        "variable": variable,
        "time_step_coarse": runs[0].attrs["time_step"],
        "time_step_fine": runs[1].attrs["time_step"],
        "lsd_db": lsd,
        "level_diff_db": level,
        "band": [float(lo), float(hi)],
        "welch": f"hann, nperseg {n}, noverlap {n // 2}, detrend constant, density",
    })
    return out
