"""What a model predicts for the targets of ``fivid update``: paired modal frequencies (FE models) or FRF
peak frequencies (damper models), from a config mapping.

* :class:`FEModes` — ``fivid modes`` on the config (:func:`fivid.fe.modal.modal_analysis`, same preload and
  contact options), mode shapes read at the model's sensors, targets paired by MAC or by order.
* :class:`DamperPeaks` — harmonic-balance FRF peak per target normal load (:func:`fivid.damper.peaks.frf_peak`).
* :func:`pair_critical_mu` — the critical friction coefficient of a CEA mode pair (``critical_mu`` targets of an
  FE model, :func:`fivid.fe.cea.complex_eigenvalue_analysis`).

Each is called with a config mapping and returns one predicted frequency [Hz] per target mode, plus what
the report needs (paired model mode, MAC).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fivid.damper.model import damper_model_from_dict
from fivid.damper.peaks import frf_peak
from fivid.errors import ConfigError
from fivid.fe.cea import Linearisation, complex_eigenvalue_analysis
from fivid.fe.modal import modal_analysis
from fivid.fe.build import load_model

__all__ = ["Prediction", "FEModes", "DamperPeaks", "mac", "pair_critical_mu", "is_damper_config", "predictor_for"]

#: a shape target pairs with a model mode only at or above this MAC
PAIRING_MAC = 0.6
#: factor on the contact's normal springs of an ``interface: rigid`` target: the frequency's deficit from the
#: rigid limit falls as 1 / factor (seed 002's ring: 5 % at its interface stiffness, so ~5e-6 here)
RIGID_INTERFACE_SCALE = 1e4


def mac(a, b) -> float:
    """Modal assurance criterion ``|a^H b|^2 / ((a^H a)(b^H b))`` of two (complex) shape vectors [1]."""
    a = np.asarray(a, dtype=complex)
    b = np.asarray(b, dtype=complex)
    den = np.real(np.vdot(a, a) * np.vdot(b, b))
    return float(abs(np.vdot(a, b)) ** 2 / den) if den > 0 else 0.0


@dataclass(frozen=True)
class Prediction:
    """Model values paired with the target modes.

    Attributes
    ----------
    frequency : ndarray
        Predicted frequency per target [Hz].
    model_mode : list of int or None
        1-based elastic model mode paired with each target (None for FRF peaks).
    mac : list of float or None
        MAC of the paired shapes (None where the target has no shape).
    all_frequencies : ndarray
        Every computed model frequency [Hz] (for ``count_below``; empty for damper models).
    critical_mu : ndarray
        Predicted critical friction coefficient per ``critical_mu`` target [1] (empty without such targets).
    critical_detail : list of dict
        Per ``critical_mu`` target: ``mode``, ``partner`` (1-based CEA modes), ``frequency_hz`` (of the mode at
        the first μ) and ``extrapolated`` (True when the pair stays stable over the sweep).
    """

    frequency: np.ndarray
    model_mode: list
    mac: list
    all_frequencies: np.ndarray
    critical_mu: np.ndarray = field(default_factory=lambda: np.zeros(0))
    critical_detail: list = field(default_factory=list)


def pair_critical_mu(ds, mode: int) -> tuple[float, dict]:
    """The critical friction coefficient of the pair containing CEA mode ``mode`` (1-based).

    The pair is the mode and its nearest mode in frequency at the first μ (a doublet's twin: which of the two
    turns unstable depends on the arbitrary basis of a degenerate pair), plus the mode the CEA names as its
    partner; the value is the smallest finite ``critical_mu`` among them. When the pair stays stable over the
    sweep, it is extrapolated linearly from the last two sweep points of the larger real part of the mode and
    its nearest mode (10 x the last μ when that real part does not grow), so that a fit started far from the
    instability still sees a slope.

    Parameters
    ----------
    ds : xarray.Dataset
        :func:`fivid.fe.cea.complex_eigenvalue_analysis` output.
    mode : int

    Returns
    -------
    mu_c : float
        [1].
    detail : dict
        ``mode``, ``partner`` (1-based, None if unknown), ``frequency_hz`` (the mode's frequency at the first
        μ), ``extrapolated``.
    """
    n = ds.sizes["mode"]
    if not 1 <= mode <= n:
        raise ConfigError(f"critical_mu: CEA mode {mode} is not among the {n} modes reported; raise n_modes",
                          key="critical_mu")
    i = mode - 1
    crit = ds["critical_mu"].values
    f0 = ds["frequency"].values[0]
    dist = np.abs(f0 - f0[i])
    dist[i] = np.inf
    near = int(np.argmin(dist)) if n > 1 else i  # its doublet twin / nearest mode
    partner = int(ds["partner"].values[i])
    pair = {i, near} | ({partner - 1} if partner > 0 else set())
    finite = sorted((float(crit[k]), k) for k in pair if np.isfinite(crit[k]))
    if finite:
        value, k = finite[0]
        other = int(ds["partner"].values[k]) if k != i else partner
        detail = {"mode": mode, "partner": (k + 1) if k != i else (other if other > 0 else near + 1),
                  "frequency_hz": float(f0[i]), "extrapolated": False}
        return value, detail
    detail = {"mode": mode, "partner": near + 1, "frequency_hz": float(f0[i]), "extrapolated": True}
    mu = ds["mu"].values
    re = np.maximum(ds["real_part"].values[:, i], ds["real_part"].values[:, near])
    slope = (re[-1] - re[-2]) / (mu[-1] - mu[-2])
    return (float(mu[-1] - re[-1] / slope) if slope > 0 else float(10 * mu[-1])), detail


def is_damper_config(data) -> bool:
    """A damper model config (``configs/dampers``: a ``beam`` with a ``contact``) rather than an FE model."""
    return isinstance(data, dict) and "beam" in data and "bodies" not in data


def predictor_for(data, targets):
    """The predictor for this kind of model config."""
    return DamperPeaks(targets) if is_damper_config(data) else FEModes(targets)


class FEModes:
    """Modal frequencies of an FE model config paired with target modes (see the module docstring)."""

    #: relative finite-difference step of the sensitivities (eigenvalues are exact to ~1e-12)
    diff_step = 1e-6

    def __init__(self, targets):
        self.targets = targets
        self.n_modes = targets.n_modes or max(10, 2 * len(targets.modes))
        for t in targets.modes:
            if t.normal_load is not None:
                raise targets.source.error(f"{t.key}.normal_load", "normal_load is for damper models (FRF peak "
                                                                    "per normal load); an FE model's preload is "
                                                                    "the top-level 'load'")

    def __call__(self, data) -> Prediction:
        """Predictions for the config mapping ``data``."""
        model = load_model(data)
        sets = {}
        for interface in dict.fromkeys(t.interface for t in self.targets.modes) | {"model": None}:
            ds = modal_analysis(model, self.n_modes, mass=self.targets.mass, include_contact=self.targets.contact,
                                normal_load=self.targets.load, prestress=self.targets.prestress,
                                interface_scale=RIGID_INTERFACE_SCALE if interface == "rigid" else 1.0)
            f = ds["frequency"].values
            sets[interface] = (f, np.flatnonzero(f > 1e-6 * max(f.max(), 1e-300)), ds["mode_shape"].values)
        sensors = {s.name: s for s in model.sensors}
        used, out_f, out_mode, out_mac = set(), [], [], []
        order_k = 0
        src = self.targets.source
        for t in self.targets.modes:
            freq, elastic, shapes = sets[t.interface]
            if t.shape is not None:
                missing = [s for s in t.sensors if s not in sensors]
                if missing:
                    raise src.error(f"{t.key}.shape.sensors", f"no sensor {missing[0]!r} in the model; its sensors: "
                                                              f"{', '.join(sensors) or '(none)'}")
                phi = np.array([[shapes[j, sensors[s].node] @ sensors[s].direction for s in t.sensors]
                                for j in elastic])
                macs = np.array([mac(t.shape, p) if (t.interface, j) not in used else -1.0
                                 for j, p in zip(elastic, phi)])
                best = int(np.argmax(macs))
                if macs[best] < PAIRING_MAC:
                    raise src.error(f"{t.key}.shape", f"no model mode pairs with this shape: the best unpaired MAC "
                                                      f"among {elastic.size} elastic modes is {max(macs[best], 0):.2f}"
                                                      f" (< {PAIRING_MAC}); compute more modes (n_modes) or check "
                                                      "the sensors' order")
                j = int(elastic[best])
                out_mac.append(float(macs[best]))
            else:
                idx = (t.model_mode - 1) if t.model_mode is not None else order_k
                order_k += 1
                if idx >= elastic.size:
                    raise src.error(t.key, f"cannot pair this target: the model has {elastic.size} elastic modes among "
                                           f"the {self.n_modes} computed and the target is number {idx + 1} by order; "
                                           "raise n_modes or give 'mode: N'")
                j = int(elastic[idx])
                out_mac.append(None)
            used.add((t.interface, j))
            out_f.append(freq[j])
            out_mode.append(int(np.searchsorted(elastic, j)) + 1)
        crit, detail = self.critical(model)
        return Prediction(np.array(out_f), out_mode, out_mac, sets["model"][0], crit, detail)

    def critical(self, model) -> tuple[np.ndarray, list]:
        """The ``critical_mu`` targets' predictions (:func:`pair_critical_mu`), one CEA per distinct μ sweep."""
        out, detail, sweeps = [], [], {}
        n_report = max([t.mode for t in self.targets.critical_mu], default=0) + 2
        for t in self.targets.critical_mu:
            k = tuple(t.mu)
            if k not in sweeps:
                sweeps[k] = complex_eigenvalue_analysis(
                    model, t.mu, normal_load=self.targets.load, n_modes=max(20, n_report),
                    linearisation=Linearisation(prestress=self.targets.prestress))
            value, d = pair_critical_mu(sweeps[k], t.mode)
            out.append(value)
            detail.append(d)
        return np.array(out), detail


class DamperPeaks:
    """FRF peak frequencies of a damper model config at the targets' normal loads."""

    #: relative finite-difference step: the peak is refined to 1e-7 Hz, the step moves it by ~1e-3 Hz
    diff_step = 1e-4

    def __init__(self, targets):
        self.targets = targets
        for t in targets.modes:
            if t.normal_load is None:
                raise targets.source.error(t.key, "a damper model's target is the FRF peak at a normal load: add "
                                                  "'normal_load: 40 N'")
            if t.shape is not None:
                raise targets.source.error(f"{t.key}.shape", "a damper model has one sensor: no shape to pair")
            if t.interface != "model":
                raise targets.source.error(f"{t.key}.interface", "'interface' is for FE models with a contact")
        if targets.count_below:
            raise targets.source.error(targets.count_below[0].key, "count_below is for FE models (modal analysis)")
        if targets.critical_mu:
            raise targets.source.error(targets.critical_mu[0].key, "critical_mu is for FE models with a contact (CEA)")

    def __call__(self, data) -> Prediction:
        """Predictions for the config mapping ``data``."""
        model = damper_model_from_dict(data)
        peaks = {}
        for t in self.targets.modes:
            if t.normal_load not in peaks:
                p = frf_peak(model, t.normal_load, xatol=1e-7)
                if p.on_edge:
                    raise ConfigError(f"the FRF peak at {t.normal_load:g} N is at the edge of the model's "
                                      f"frequency_range ({p.frequency:.4g} Hz): widen frequency_range",
                                      key="frequency_range")
                peaks[t.normal_load] = p.frequency
        f = np.array([peaks[t.normal_load] for t in self.targets.modes])
        return Prediction(f, [None] * f.size, [None] * f.size, np.zeros(0))
