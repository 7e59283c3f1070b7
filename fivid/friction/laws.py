"""Friction law objects used by the solver: Coulomb and perturbed Coulomb (DESIGN §3).

μ_k(t) = μ0 + μp_k(t), clipped at 0 by the solver. μp is a zero-mean stationary random process with
one-sided PSD ``S(f; V, Ra, Fn) = A(V, Ra, Fn)^2 s(f)``, ``∫ s df = 1`` over the valid band, so A is
the RMS of μp. Every law object has ``mu0``, ``amplitude(...)``, ``psd(...)``, ``sample(...)``,
``injection``, ``describe()`` and ``sha256``.

Injection modes: ``uniform`` (one signal for the whole contact: the solver asks for ``n_signals=1``),
``per_node`` (independent signals, one per contact node), ``convected`` (a spatial field frozen on
the moving surface, μp(x − V t)). For ``convected`` the law's shape is the temporal shape at the
reference velocity ``V_ref``; at velocity V a frozen field gives
``S(f; V) = A^2 (V_ref / V) s(f V_ref / V)``, which keeps ``∫ S df = A^2``.
"""

from __future__ import annotations

import hashlib
import json
import logging
from typing import Protocol, runtime_checkable

import numpy as np

from fivid.errors import FividError
from fivid.friction.amplitude import AmplitudeModel
from fivid.friction.domain import ConditionDomain
from fivid.friction.synthesis import check_sampling, fft_frequencies, synthesise_perturbation

__all__ = ["FrictionLaw", "FRICTION_LAW_MEMBERS", "CoulombLaw", "PerturbedCoulombLaw", "INJECTION_MODES"]

INJECTION_MODES = ("uniform", "per_node", "convected")
_log = logging.getLogger("fivid")


@runtime_checkable
class FrictionLaw(Protocol):
    """What the solver asks of a friction law: μ0, the injection mode, samples of μp(t), a description, a hash.

    :class:`CoulombLaw` and :class:`PerturbedCoulombLaw` implement it; any object with these members can be
    simulated (``isinstance(obj, FrictionLaw)`` checks that they exist).
    """

    mu0: float
    injection: str

    @property
    def sha256(self) -> str:
        """Content hash of the law (recorded in the simulation's provenance)."""

    def amplitude(self, velocity, roughness, normal_load=None):
        """RMS of μp [-] at sliding velocity [m s-1], roughness Ra [m], normal load [N]."""

    def sample(self, duration, sample_rate, velocity, roughness, seed, n_signals=1, normal_load=None):
        """μp(t) [-], shape (n_signals, round(duration * sample_rate)), reproducible from ``seed``."""

    def describe(self) -> str:
        """One line saying what the law is."""


#: members of :class:`FrictionLaw`, for error messages that name what an object lacks
FRICTION_LAW_MEMBERS = ("mu0", "injection", "sha256", "amplitude", "sample", "describe")


def _sha256_of(content: dict, *arrays: np.ndarray) -> str:
    h = hashlib.sha256(json.dumps(content, sort_keys=True).encode())
    for a in arrays:
        h.update(np.ascontiguousarray(a, dtype="<f8").tobytes())
    return h.hexdigest()


class CoulombLaw:
    """Coulomb friction, μ = μ0 [-]: no perturbation (amplitude 0).

    Parameters
    ----------
    mu0 : float
        Friction coefficient [-], >= 0.
    injection : str, default "uniform"
    """

    def __init__(self, mu0: float, *, injection: str = "uniform"):
        mu0 = float(mu0)
        if not (np.isfinite(mu0) and mu0 >= 0):
            raise FividError(f"mu0 = {mu0!r}; a friction coefficient must be finite and >= 0")
        if injection not in INJECTION_MODES:
            raise FividError(f"injection {injection!r} is not one of {', '.join(INJECTION_MODES)}")
        self.mu0 = mu0
        self.injection = injection

    def amplitude(self, velocity, roughness, normal_load=None):
        """RMS of μp [-]: 0 for Coulomb friction (same shape as the broadcast inputs)."""
        return np.zeros(np.broadcast(np.asarray(velocity), np.asarray(roughness)).shape)

    def psd(self, frequency, velocity, roughness, normal_load=None):
        """One-sided PSD of μp [Hz-1]: 0."""
        return np.zeros(np.shape(frequency))

    def sample(self, duration, sample_rate, velocity, roughness, seed, n_signals=1, normal_load=None):
        """μp(t) [-]: zeros, shape ``(n_signals, round(duration * sample_rate))``."""
        n = check_sampling(duration, sample_rate, n_signals)
        return np.zeros((int(n_signals), n))

    def describe(self) -> str:
        """One line: the law and its parameter."""
        return f"Coulomb friction, mu0 = {self.mu0:.6g}"

    @property
    def sha256(self) -> str:
        """Hash of the law's content, for provenance."""
        return _sha256_of({"law": "coulomb", "mu0": self.mu0, "injection": self.injection})

    def __repr__(self):
        return f"CoulombLaw(mu0={self.mu0!r})"


class PerturbedCoulombLaw:
    """Coulomb friction with a stochastic perturbation, μ = μ0 + μp(t) (DESIGN §3).

    Parameters
    ----------
    mu0 : float
        Mean friction coefficient [-].
    shape_frequency : array_like
        Frequencies [Hz] of the normalised shape, increasing, within the valid band.
    shape : array_like
        Normalised one-sided spectral shape s(f) [Hz-1], ``∫ s df = 1`` (trapezoid rule; renormalised).
    amplitude_model : AmplitudeModel
        A(V, Ra, Fn), the RMS of μp [-].
    band : (float, float)
        Valid band [Hz]; the PSD is 0 outside it.
    injection : {"uniform", "per_node", "convected"}
    reference_velocity : float, optional
        V_ref [m s-1] of the shape; required for ``convected``.
    source : str, optional
        Where the law came from (law file path and sha256), for ``describe``.
    condition_shapes : (ndarray (m, 3), ndarray (m, len(shape_frequency))), optional
        Shapes per test condition (V [m s-1], Ra [m], Fn [N]) on ``shape_frequency``, when the
        identification found that the shape depends on the condition: :meth:`normalised_shape` then
        interpolates between them (:meth:`fivid.friction.domain.ConditionDomain.interpolate`), and
        ``shape`` is their average, used where no condition is given.
    """

    def __init__(
        self,
        mu0,
        shape_frequency,
        shape,
        amplitude_model: AmplitudeModel,
        band,
        *,
        injection: str = "uniform",
        reference_velocity: float | None = None,
        source: str = "",
        condition_shapes=None,
    ):
        mu0 = float(mu0)
        if not (np.isfinite(mu0) and mu0 >= 0):
            raise FividError(f"mu0 = {mu0!r}; a friction coefficient must be finite and >= 0")
        if injection not in INJECTION_MODES:
            raise FividError(f"injection {injection!r} is not one of {', '.join(INJECTION_MODES)}")
        f = np.asarray(shape_frequency, dtype=float)
        s = np.asarray(shape, dtype=float)
        if f.ndim != 1 or f.shape != s.shape or f.size < 2:
            raise FividError(f"shape_frequency {f.shape} and shape {s.shape} must be 1-D of one length >= 2")
        if not np.all(np.diff(f) > 0) or not np.all(np.isfinite(s)) or np.any(s < 0):
            raise FividError("the spectral shape must have increasing frequencies and finite values >= 0")
        lo, hi = (float(b) for b in band)
        if not (0 <= lo < hi):
            raise FividError(f"band = ({lo}, {hi}) Hz; need 0 <= f_lo < f_hi")
        area = np.trapezoid(s, f)
        if not area > 0:
            raise FividError("the spectral shape integrates to 0 over its frequencies")
        if injection == "convected" and not (reference_velocity is not None and reference_velocity > 0):
            raise FividError(f"injection 'convected' needs reference_velocity > 0 [m s-1], got {reference_velocity!r}")
        self.mu0 = mu0
        self.shape_frequency = f
        # a shape normalised already (to float rounding, e.g. read back from a law file) is kept
        # bit-identical, so that the law's sha256 survives a write/read round trip
        self.shape = s if abs(area - 1.0) < 1e-12 else s / area
        self.amplitude_model = amplitude_model
        self.band = (lo, hi)
        self.injection = injection
        self.reference_velocity = None if reference_velocity is None else float(reference_velocity)
        self.source = source
        self.condition_shapes = None
        if condition_shapes is not None:
            points, shapes = (np.asarray(x, dtype=float) for x in condition_shapes)
            if points.ndim != 2 or points.shape[1] != 3 or shapes.shape != (points.shape[0], f.size):
                raise FividError(f"condition_shapes: conditions {points.shape} and shapes {shapes.shape} must be "
                                 f"(m, 3) and (m, {f.size})")
            if not np.all(np.isfinite(shapes)) or np.any(shapes < 0):
                raise FividError("condition_shapes: every shape must be finite and >= 0")
            self.condition_shapes = (points, shapes)

    def _shape_at(self, velocity, roughness, normal_load):
        """The shape on ``shape_frequency`` at a condition (interpolated between conditions, renormalised)."""
        if self.condition_shapes is None or roughness is None:
            return self.shape

        points, shapes = self.condition_shapes
        s = ConditionDomain(points).interpolate(
            shapes, *(np.nan if x is None else float(np.asarray(x).reshape(-1)[0])
                      for x in (velocity, roughness, normal_load)))
        s = np.maximum(s, 0.0)
        return s / np.trapezoid(s, self.shape_frequency)

    def amplitude(self, velocity, roughness, normal_load=None):
        """RMS A of μp [-] over the band at sliding velocity [m s-1], roughness Ra [m], normal load [N]."""
        a = self.amplitude_model(velocity, roughness, normal_load)
        if np.ndim(velocity) == 0 and np.ndim(roughness) == 0 and np.ndim(normal_load) == 0:
            return float(a[0])
        return a

    def normalised_shape(self, frequency, velocity=None, roughness=None, normal_load=None) -> np.ndarray:
        """s(f) [Hz-1] at ``frequency`` [Hz] (linear interpolation, 0 outside the band), scaled for convection.

        With per-condition shapes, the shape at (velocity, roughness, normal_load) when ``roughness`` is given.
        """
        f = np.asarray(frequency, dtype=float)
        scale = 1.0
        if self.injection == "convected":
            if velocity is None or not float(velocity) > 0:
                raise FividError(f"a convected law needs a sliding velocity > 0 [m s-1], got {velocity!r}")
            scale = self.reference_velocity / float(velocity)
        fr = f * scale
        inside = (fr >= max(self.band[0], self.shape_frequency[0])) & (fr <= min(self.band[1], self.shape_frequency[-1]))
        shape = self._shape_at(velocity, roughness, normal_load)
        return np.where(inside, np.interp(fr, self.shape_frequency, shape) * scale, 0.0)

    def psd(self, frequency, velocity, roughness, normal_load=None):
        """One-sided PSD of μp [Hz-1]: ``A(V, Ra, Fn)^2 s(f)``."""
        a = float(np.asarray(self.amplitude_model(velocity, roughness, normal_load)).reshape(-1)[0])
        return a**2 * self.normalised_shape(frequency, velocity, roughness, normal_load)

    def sample(self, duration, sample_rate, velocity, roughness, seed, n_signals=1, normal_load=None):
        """Zero-mean μp(t) [-] with the law's PSD at (V, Ra, Fn), reproducible from ``seed``.

        The discrete shape on the synthesis grid (bins ``k fs / n``) is renormalised to unit sum
        ``Σ s_k Δf = 1`` so that the expected mean square is exactly A^2 whatever the record length.

        Returns
        -------
        ndarray, shape (n_signals, round(duration * sample_rate))
        """
        n = check_sampling(duration, sample_rate, n_signals)
        f = fft_frequencies(n, sample_rate)
        s = self.normalised_shape(f, velocity, roughness, normal_load)
        s[0] = 0.0
        if n % 2 == 0:
            s[-1] = 0.0
        total = s.sum() * (f[1] - f[0])
        if not total > 0:
            raise FividError(
                f"a record of {duration} s at {sample_rate} Hz has no frequency bin inside the law's band "
                f"{self.band[0]:g}-{self.band[1]:g} Hz (bin spacing {f[1] - f[0]:g} Hz, Nyquist {f[-1]:g} Hz)"
            )
        if f[-1] < self.band[1] and np.trapezoid(self.normalised_shape(f, velocity, roughness, normal_load), f) < 0.99:
            _log.warning(
                "sample rate %g Hz: Nyquist %g Hz is below the law's band edge %g Hz and more than 1 %% of "
                "the spectral shape lies above it; the shape is renormalised over the bins below Nyquist",
                sample_rate, f[-1], self.band[1],
            )
        a = float(np.asarray(self.amplitude_model(velocity, roughness, normal_load)).reshape(-1)[0])
        target = a**2 * s / total
        return synthesise_perturbation(lambda _f: target, n / float(sample_rate), sample_rate, seed, n_signals=n_signals)

    def scaled(self, factor: float) -> "PerturbedCoulombLaw":
        """The same law with the amplitude multiplied by ``factor`` (> 0) at every (V, Ra, Fn).

        Linear forms scale every coefficient; power laws add ``ln factor`` to ``log_prefactor``.
        Standard errors and covariance are scaled alike (relative errors unchanged).
        """
        factor = float(factor)
        if not (np.isfinite(factor) and factor > 0):
            raise FividError(f"amplitude scale factor {factor!r} must be finite and > 0")
        model = self.amplitude_model.scaled(factor)
        return PerturbedCoulombLaw(self.mu0, self.shape_frequency, self.shape, model, self.band,
                                   injection=self.injection, reference_velocity=self.reference_velocity,
                                   source=f"{self.source} scaled by {factor:.6g}".strip(),
                                   condition_shapes=self.condition_shapes)

    def describe(self) -> str:
        """A few lines: μ0, the amplitude form and coefficients, the band, the injection mode."""
        m = self.amplitude_model
        coeffs = ", ".join(f"{n} = {c:.4g} ± {s:.2g}" for n, c, s in zip(m.names, m.coefficients, m.stderr))
        lines = [
            f"perturbed Coulomb friction, mu0 = {self.mu0:.6g}",
            f"  amplitude (RMS of mu_p) form {m.form}: {coeffs}",
            f"  spectral shape on {self.shape_frequency.size} frequencies, valid band "
            f"{self.band[0]:g}-{self.band[1]:g} Hz, injection {self.injection}",
        ]
        if self.condition_shapes is not None:
            lines.append(f"  the shape depends on the condition: {self.condition_shapes[0].shape[0]} shapes, "
                         "interpolated between conditions")
        if self.source:
            lines.append(f"  source: {self.source}")
        return "\n".join(lines)

    @property
    def sha256(self) -> str:
        """Hash of the law's content (μ0, shape, amplitude model, band, injection), for provenance."""
        content = {
            "law": "perturbed_coulomb",
            "mu0": self.mu0,
            "band": list(self.band),
            "injection": self.injection,
            "reference_velocity": self.reference_velocity,
            "amplitude_model": self.amplitude_model.to_dict(),
        }
        if self.condition_shapes is None:
            return _sha256_of(content, self.shape_frequency, self.shape)
        content["condition_shapes"] = True
        return _sha256_of(content, self.shape_frequency, self.shape, *self.condition_shapes)

    def __repr__(self):
        return f"PerturbedCoulombLaw(mu0={self.mu0!r}, form={self.amplitude_model.form!r}, band={self.band!r})"
