"""``evaluate_profile``: roughness and waviness parameters of a profile over an evaluation window.

Steps, in this order (each recorded in the result's ``settings``):

1. **Window** ``[start, end]`` [m], both ends included, like the R and M cursors of a profilometer
   (default: the whole profile).
2. **Form removal** over the window: least-squares line (default) or polynomial
   (:mod:`fivid.surface.form`).
3. **Filters** (optional): λs short-wave Gaussian filter (the primary profile is its mean line),
   then the λc Gaussian filter: roughness = primary − mean line, waviness = mean line
   (:mod:`fivid.surface.gaussian_filter`). With ``ends="trim"`` (default) λc/2 is dropped at each end
   of the window before parameters are computed; ``ends="keep"`` keeps them (the mean line is then
   end-corrected there but biased). Without λc the roughness profile is the form-removed primary
   profile (what a Dektak reports as R parameters with its filters off).
4. **Parameters** (:mod:`fivid.surface.parameters`) over the evaluation length ``L`` that is left:

   * Rz: with λc, the sampling length is ``lr = λc`` and Rz is the mean of the peak-to-valley heights
     of the ``floor(L / λc)`` whole sampling lengths from the start (5 for the standard evaluation
     length); without λc, or when ``L < λc``, Rz is the peak-to-valley of the whole evaluation length
     (= Rt). ``settings["Rz_sampling_lengths"]`` says which.
   * Rsm: height discrimination 10 % of Rz, width discrimination 1 % of the sampling length (λc, or
     ``L`` without a cut-off), ISO 4287 3.2.4 defaults.
   * Wa, Wq: arithmetic mean and rms of the waviness profile (mean line, its own mean removed) over
     the same evaluation length; only with λc.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError, DataQualityError
from fivid.surface.form import form_degree, remove_form
from fivid.surface.gaussian_filter import gaussian_mean_line
from fivid.surface.parameters import amplitude_parameters, mean_element_width, peak_to_valley_mean, slope_parameters
from fivid.surface.profile import MIN_POINTS, sampling_step

__all__ = ["evaluate_profile", "Evaluation", "PARAMETER_UNITS", "PARAMETER_NAMES"]

PARAMETER_UNITS = {"Ra": "m", "Rq": "m", "Rz": "m", "RzDIN": "m", "Rt": "m", "Rp": "m", "Rv": "m", "Rsk": "1",
                   "Rku": "1", "Rsm": "m", "Rdq": "rad", "attack_angle": "rad", "Wa": "m", "Wq": "m"}
PARAMETER_NAMES = {
    "Ra": "arithmetic mean deviation of the roughness profile (ISO 4287 4.2.1)",
    "Rq": "root mean square deviation of the roughness profile (ISO 4287 4.2.2)",
    "Rz": "maximum height of the roughness profile, mean over sampling lengths (ISO 4287 4.1.3)",
    "RzDIN": "mean peak-to-valley height of 5 equal segments (DIN 4768)",
    "Rt": "total height of the roughness profile (ISO 4287 4.1.6)",
    "Rp": "maximum profile peak height (ISO 4287 4.1.1)",
    "Rv": "maximum profile valley depth (ISO 4287 4.1.2)",
    "Rsk": "skewness of the roughness profile (ISO 4287 4.2.3)",
    "Rku": "kurtosis of the roughness profile (ISO 4287 4.2.4)",
    "Rsm": "mean width of the profile elements (ISO 4287 4.3.1)",
    "Rdq": "root mean square slope of the roughness profile (ISO 4287 4.4.1)",
    "attack_angle": "mean absolute flank angle, mean of |atan(dz/dx)|",
    "Wa": "arithmetic mean deviation of the waviness profile (ISO 4287 4.2.1)",
    "Wq": "root mean square deviation of the waviness profile (ISO 4287 4.2.2)",
}
RZ_SEGMENTS_DIN = 5
HEIGHT_DISCRIMINATION = 0.10  # of Rz
WIDTH_DISCRIMINATION = 0.01  # of the sampling length


@dataclass
class Evaluation:
    """Result of :func:`evaluate_profile`.

    Attributes
    ----------
    parameters : dict
        ISO symbol → value in SI (m; Rsk, Rku: 1; Rdq, attack_angle: rad).
    settings : dict
        Window [m], form, cut-offs [m], end handling, step [m], number of points, evaluation length [m],
        Rz sampling lengths, discrimination thresholds [m].
    x : ndarray [m]
        Positions of the evaluated samples.
    roughness : ndarray [m]
        Roughness profile over ``x``.
    waviness : ndarray [m] or None
        Mean line over ``x`` (only with a cut-off).
    """

    parameters: dict
    settings: dict
    x: np.ndarray
    roughness: np.ndarray
    waviness: np.ndarray | None = None


def _window(profile, window, label):
    x = np.asarray(profile["x"].values, dtype=np.float64)
    z = np.asarray(profile.values, dtype=np.float64)
    if window is None:
        return x, z, (float(x[0]), float(x[-1]))
    start, end = (float(v) for v in window)
    if not start < end:
        raise ConfigError(f"window start {start:g} m must be less than its end {end:g} m", key="window")
    if start > x[-1] or end < x[0]:
        raise ConfigError(f"window [{start:g}, {end:g}] m is outside the profile [{x[0]:g}, {x[-1]:g}] m",
                          key="window")
    keep = (x >= start) & (x <= end)
    if keep.sum() < MIN_POINTS:
        raise DataQualityError(f"{label}: window [{start:g}, {end:g}] m holds {int(keep.sum())} point(s); "
                               f"need at least {MIN_POINTS}")
    return x[keep], z[keep], (start, end)


def _check_cutoffs(cutoff, short_cutoff, step, length):
    if cutoff is not None:
        if not cutoff > 0 or not math.isfinite(cutoff):
            raise ConfigError(f"cut-off λc must be a positive length, got {cutoff!r} m", key="cutoff")
        if cutoff > length:
            raise ConfigError(f"cut-off λc = {cutoff:g} m is longer than the window ({length:g} m); choose a "
                              "shorter cut-off or a longer window", key="cutoff")
        if cutoff < 10 * step:
            raise ConfigError(f"cut-off λc = {cutoff:g} m is under 10 sampling steps ({step:g} m each)",
                              key="cutoff")
    if short_cutoff is not None:
        if not short_cutoff > 0:
            raise ConfigError(f"short cut-off λs must be a positive length, got {short_cutoff!r} m",
                              key="short_cutoff")
        if cutoff is not None and not short_cutoff < cutoff:
            raise ConfigError(f"short cut-off λs = {short_cutoff:g} m must be less than λc = {cutoff:g} m",
                              key="short_cutoff")
        if short_cutoff < 2 * step:
            raise ConfigError(f"short cut-off λs = {short_cutoff:g} m is under 2 sampling steps ({step:g} m)",
                              key="short_cutoff")


def evaluate_profile(profile, *, window=None, form="line", cutoff=None, short_cutoff=None, ends="trim"):
    """Roughness (and waviness) parameters of a profile, as a profilometer computes them between its cursors.

    Parameters
    ----------
    profile : xarray.DataArray
        Heights [m] over ``x`` [m], uniformly sampled (:func:`fivid.surface.read_profile`).
    window : (float, float), optional
        Evaluation window ``(start, end)`` [m], ends included; default the whole profile.
    form : {"line", "poly:N", "none"} or int, default "line"
        Form removed over the window by least squares.
    cutoff : float, optional
        λc [m] of the Gaussian roughness filter; default no filter.
    short_cutoff : float, optional
        λs [m] of the Gaussian short-wave filter; default none.
    ends : {"trim", "keep"}, default "trim"
        With a cut-off, drop λc/2 at each end of the window, or keep the end-corrected mean line there.

    Returns
    -------
    Evaluation
        ``parameters`` keyed by ISO symbols in SI units, and everything needed to reproduce them.

    Raises
    ------
    ConfigError
        Bad window, form, cut-offs or ends (naming the value and what is allowed).
    DataQualityError
        Non-uniform sampling, or too few points in the window.

    Examples
    --------
    A sine of amplitude 1 µm has Ra = 2A/π:

    >>> import numpy as np
    >>> from fivid.surface import make_profile
    >>> x = np.arange(100_000) * 1e-7
    >>> p = make_profile(x, 1e-6 * np.sin(2 * np.pi * x / 1e-4))
    >>> round(evaluate_profile(p, form="none").parameters["Ra"] / (2e-6 / np.pi), 4)
    1.0
    """
    label = str(profile.attrs.get("source", "profile"))
    if ends not in ("trim", "keep"):
        raise ConfigError(f"unknown end handling {ends!r}; choose 'trim' or 'keep'", key="ends")
    degree = form_degree(form)
    step = sampling_step(profile, label=label)
    x, z, (start, end) = _window(profile, window, label)
    _check_cutoffs(cutoff, short_cutoff, step, x[-1] - x[0])
    primary, _ = remove_form(x, z, degree)
    if short_cutoff is not None:
        primary = gaussian_mean_line(primary, step, short_cutoff)
    waviness = None
    roughness = primary
    if cutoff is not None:
        waviness = gaussian_mean_line(primary, step, cutoff)
        roughness = primary - waviness
        if ends == "trim":
            keep = (x >= x[0] + cutoff / 2) & (x <= x[-1] - cutoff / 2)
            if keep.sum() < MIN_POINTS:
                raise DataQualityError(f"{label}: {int(keep.sum())} point(s) left after dropping λc/2 at each end "
                                       f"of the window; need {MIN_POINTS}: use a longer window or ends='keep'")
            x, roughness, waviness = x[keep], roughness[keep], waviness[keep]
    length = x.size * step
    params = amplitude_parameters(roughness)
    n_sampling = int(math.floor(length / cutoff + 1e-9)) if cutoff is not None else 0
    if n_sampling >= 1:  # whole sampling lengths of round(cutoff / step) samples (rounding up may leave one less)
        n_sampling = min(n_sampling, x.size // int(round(cutoff / step)))
    if n_sampling >= 1:
        params["Rz"] = peak_to_valley_mean(roughness, n_sampling, segment_points=int(round(cutoff / step)))
        sampling_length = cutoff
    else:
        params["Rz"] = params["Rt"]
        n_sampling, sampling_length = 1, length
    params["RzDIN"] = peak_to_valley_mean(roughness, RZ_SEGMENTS_DIN)
    height_threshold = HEIGHT_DISCRIMINATION * params["Rz"]
    width_threshold = WIDTH_DISCRIMINATION * sampling_length
    params["Rsm"] = mean_element_width(roughness, step, height_threshold=height_threshold,
                                       width_threshold=width_threshold)
    params.update(slope_parameters(roughness, step))
    if waviness is not None:
        w = waviness - waviness.mean()
        params["Wa"], params["Wq"] = float(np.mean(np.abs(w))), float(np.sqrt(np.mean(w**2)))
    settings = {
        "window_start": start, "window_end": end, "form": "none" if degree is None else
        ("line" if degree == 1 else f"poly:{degree}"),
        "cutoff": cutoff, "short_cutoff": short_cutoff, "ends": ends if cutoff is not None else "n/a",
        "step": step, "n_points": int(x.size), "evaluation_length": length,
        "Rz_sampling_lengths": n_sampling, "sampling_length": sampling_length,
        "Rsm_height_discrimination": height_threshold, "Rsm_width_discrimination": width_threshold,
    }
    ordered = {k: params[k] for k in PARAMETER_UNITS if k in params}
    return Evaluation(ordered, settings, x, roughness, waviness)
