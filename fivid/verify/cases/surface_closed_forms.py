"""Roughness of a sampled sine and the ISO 16610-21 Gaussian filter's transmission at the cut-off."""

from __future__ import annotations

import numpy as np

from fivid.surface import evaluate_profile, gaussian_mean_line, make_profile, mean_line_transmission
from fivid.verify.case import Case, Curve, Outcome, Plot

__all__ = ["CASES", "sine_profile", "filter_transmission"]

UM = 1e-6


def sine_profile(amplitude, wavelength, periods, per_period, phase=0.3):
    """A sine profile z = A sin(2πx/λ + φ) of ``periods`` whole periods at ``per_period`` samples each."""
    x = np.arange(periods * per_period) * (wavelength / per_period)
    return make_profile(x, amplitude * np.sin(2 * np.pi * x / wavelength + phase))


def filter_transmission(wavelength, cutoff, dx=0.5 * UM) -> float:
    """Amplitude of the Gaussian mean line of a unit sine of ``wavelength`` [m] (cut-off ``cutoff`` [m]), by a
    least-squares sine fit in the interior (one cut-off away from the ends)."""
    x = np.arange(int(round(20 * cutoff / dx))) * dx
    m = gaussian_mean_line(np.sin(2 * np.pi * x / wavelength), dx, cutoff)
    inner = (x > cutoff) & (x < x[-1] - cutoff)
    basis = np.column_stack([np.sin(2 * np.pi * x[inner] / wavelength), np.cos(2 * np.pi * x[inner] / wavelength)])
    coef, *_ = np.linalg.lstsq(basis, m[inner], rcond=None)
    return float(np.hypot(*coef))


def _sine_ra(quick: bool, data) -> Outcome:
    a, lam, n = 1 * UM, 100 * UM, 1000
    prof = sine_profile(a, lam, 40, n)
    p = evaluate_profile(prof, form="none").parameters
    x = prof["x"].values[:2 * n]
    plot = Plot("x [µm]", "height [µm]", (Curve(x * 1e6, prof.values[:2 * n] * 1e6, "sine profile (2 of 40 periods)"),
                                          Curve(x[[0, -1]] * 1e6, np.full(2, p["Ra"] * 1e6), "fivid Ra"),
                                          Curve(x[[0, -1]] * 1e6, np.full(2, 2 / np.pi), "2A/π", "dashed")))
    return Outcome(float(p["Ra"]), 2 * a / np.pi, (2 * np.pi / n) ** 2, plot,
                   {"Rq / (A/√2)": float(p["Rq"] / (a / np.sqrt(2))), "Rsk": float(p["Rsk"]), "Rku": float(p["Rku"])})


def _gaussian_cutoff(quick: bool, data) -> Outcome:
    lc = 80 * UM
    ratios = np.array([0.5, 0.75, 1.0, 1.5, 2.0])
    measured = np.array([filter_transmission(r * lc, lc) for r in ratios])
    closed = np.asarray(mean_line_transmission(ratios * lc, lc), float)
    i = int(np.flatnonzero(ratios == 1.0)[0])
    plot = Plot("wavelength / cut-off [-]", "mean-line transmission [-]",
                (Curve(ratios, measured, "fivid", "points"),
                 Curve(np.linspace(0.4, 2.2, 100), np.exp(-np.pi * (0.4697 / np.linspace(0.4, 2.2, 100)) ** 2),
                       "exp(-π(αλc/λ)²)", "dashed")))
    return Outcome(float(measured[i]), 0.5, 1e-6, plot,
                   {"largest |measured - closed form| over λ/λc = 0.5-2": float(np.abs(measured - closed).max())})


CASES = (
    Case(name="sine_roughness_ra", title="Roughness of a sine profile", quantity="Ra of a sine of amplitude 1 µm",
         unit="m", reference="Ra = 2A/π of a sine over whole periods",
         source="closed form; parameter definitions ISO 21920-2:2021 (ISO 4287)",
         method="fivid.surface.evaluate_profile(form='none') of 40 periods (λ = 100 µm) at 1000 samples each; same "
                "for --quick",
         tolerance_basis="(2π/1000)²: |sin| has kinks, so the rectangle rule over the samples errs by O((2πΔx/λ)²)",
         compute=_sine_ra),
    Case(name="gaussian_filter_cutoff", title="ISO 16610-21 Gaussian filter at its cut-off",
         quantity="amplitude transmission of the mean line at λ = λc", unit="",
         reference="0.5: the Gaussian weighting function passes exp(-π(αλc/λ)²) of a sine, α = √(ln 2/π)",
         source="ISO 16610-21:2011, Geometrical product specifications — Filtration — Linear profile filters: "
                "Gaussian filters",
         method="fivid.surface.gaussian_mean_line (λc = 80 µm, Δx = 0.5 µm) of unit sines at λ/λc = 0.5-2; the "
                "amplitude by a least-squares sine fit one cut-off away from the ends; same for --quick",
         tolerance_basis="1e-6 absolute: the weights truncated at ±λc lose erfc(√π/α) = 1.3e-7 of their mass; the "
                         "rectangle rule of a Gaussian sampled 160 times per λc errs exponentially little",
         compute=_gaussian_cutoff, error="absolute"),
)
