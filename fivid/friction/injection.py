"""The kinetic friction coefficient per contact node and time, from a constant or a friction-law object (DESIGN §3):
the table the solver's kernel :func:`fivid.friction._curve_kernels.friction_now` interpolates.

``mu_k(t) = mu0 + mu_p,k(t)``, clipped at 0 by the kernel. The law object has the interface of
:mod:`fivid.friction` (``mu0``, ``injection``, ``sample(duration, sample_rate, velocity, roughness, seed,
n_signals=1, normal_load=None) -> (n_signals, n)``, ``describe()``, ``sha256``); any object with it works.

Sampling rate: the law is sampled at ``rate = min(8 * sample_rate, 1/dt)`` and the kernel interpolates
linearly at every step. Linear interpolation of samples at ``rate`` multiplies the spectrum by
``sinc^2(f / rate)``: at the top of the analysis band (20 kHz at 51.2 kHz sampling, ``rate`` 409.6 kHz)
that is 0.992 (-0.07 dB), well inside the PSD estimation uncertainty, while the table is 20-60x smaller
than one value per solver step (dt ~ 10-30 ns).

Injection modes: ``uniform`` one signal for all contact nodes; ``per_node`` independent signals;
``convected`` a field frozen on the moving master surface, ``mu_p(x - V t)``: node ``k`` at ``x_k`` reads
one long signal delayed by ``x_k / V``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fivid.errors import ConfigError
from fivid.friction.curve import slave_coefficients
from fivid.friction.inputs import FrictionInput, OperatingCondition
from fivid.friction.laws import FRICTION_LAW_MEMBERS, INJECTION_MODES, FrictionLaw

__all__ = ["FrictionTable", "friction_table"]


@dataclass(frozen=True)
class FrictionTable:
    """``mu`` [-] per solver input sample (rows, at ``rate`` [Hz], first row at t = 0) and slave node (columns).

    A single row means constant in time. ``description`` and ``sha256`` record the provenance.
    """

    mu: np.ndarray
    rate: float
    description: str
    sha256: str
    injection: str


def friction_table(model, slave_pair: np.ndarray, slave_x: np.ndarray, friction: FrictionInput,
                   condition: OperatingCondition, *, total_time: float, dt: float, sample_rate: float) -> FrictionTable:
    """Build the friction table of the slave nodes (see the module docstring).

    Parameters
    ----------
    model : Model
    slave_pair : ndarray of int (n_slave,)
        Contact-pair index of each slave node.
    slave_x : ndarray (n_slave,)
        Reference position of each slave node along the sliding direction [m] (for ``convected``).
    friction : FrictionInput
        The law (or constant ``mu``, overriding the pairs' ``mu``; not both) and the seed of the law's synthesis.
    condition : OperatingCondition
        ``sliding_velocity`` [m s-1] as run, signed along the base motion; ``roughness_ra`` [m] and
        ``normal_load`` [N] (or None), passed to the law.
    total_time, dt, sample_rate : float
        Simulated time [s], solver step [s], output sample rate [Hz].
    """
    law, mu, seed = friction.law, friction.mu, friction.seed
    sliding_velocity, roughness_ra, normal_load = condition.sliding_velocity, condition.roughness_ra, \
        condition.normal_load
    ns = slave_pair.size
    if law is not None and mu is not None:
        raise ConfigError("give either a friction law or a constant mu, not both")
    if law is None:
        if mu is not None:
            if not (np.isfinite(mu) and mu >= 0.0):
                raise ConfigError(f"mu must be a finite number >= 0, got {mu!r}")
            values = np.full((1, ns), float(mu))
            desc = f"Coulomb, constant mu = {float(mu):g} (all contact pairs)"
        else:
            values = slave_coefficients(model)[None, :]  # one per-node mu builder (preload and solver)
            if values.shape != (1, ns):
                raise ValueError(f"slave_pair ({ns} nodes) does not match the model's slave nodes ({values.size})")
            desc = "Coulomb, mu of each contact pair from the model: " + ", ".join(
                f"{c.name} {c.mu:g}" for c in model.contacts)
        return FrictionTable(values, 1.0, desc, "", "constant")
    if not isinstance(law, FrictionLaw):
        missing = [m for m in FRICTION_LAW_MEMBERS if not hasattr(law, m)]
        raise ConfigError(f"the friction law object ({type(law).__name__}) lacks {', '.join(map(repr, missing))}; "
                          "expected the fivid.friction.FrictionLaw interface")
    mode = str(law.injection)
    if mode not in INJECTION_MODES:
        raise ConfigError(f"friction law injection {mode!r} is not one of {', '.join(INJECTION_MODES)}")
    rate = float(min(8.0 * sample_rate, 1.0 / dt))
    n_rows = int(np.ceil(total_time * rate)) + 2
    kwargs = dict(velocity=abs(sliding_velocity), roughness=roughness_ra, seed=int(seed), normal_load=normal_load)
    if mode == "uniform":
        sig = _sample(law, n_rows, rate, 1, kwargs)
        mup = np.repeat(sig[0][:, None], ns, axis=1)
    elif mode == "per_node":
        mup = _sample(law, n_rows, rate, ns, kwargs).T
    else:
        if sliding_velocity == 0.0:
            raise ConfigError("the 'convected' friction injection needs a non-zero sliding velocity")
        # surface moving along +sign(V): node k sees the field that passed x_min at t - (x_k - x_min)/V
        xs = np.asarray(slave_x, dtype=float) * np.sign(sliding_velocity)
        lag = (xs.max() - xs) / abs(sliding_velocity)  # >= 0 [s]
        extra = int(np.ceil(lag.max() * rate)) + 2
        sig = _sample(law, n_rows + extra, rate, 1, kwargs)[0]
        t = np.arange(n_rows) / rate
        grid = np.arange(sig.size) / rate
        mup = np.stack([np.interp(t + lag[k], grid, sig) for k in range(ns)], axis=1)
    mu0 = float(law.mu0)
    desc = law.describe()
    sha = str(law.sha256)
    return FrictionTable(np.ascontiguousarray(mu0 + mup), rate, f"{desc}; injection {mode}", sha, mode)


def _sample(law, n_rows: int, rate: float, n_signals: int, kwargs) -> np.ndarray:
    sig = np.asarray(law.sample(n_rows / rate, rate, n_signals=n_signals, **kwargs), dtype=float)
    sig = sig.reshape(n_signals, -1) if sig.ndim == 1 else sig
    if sig.shape[0] != n_signals or sig.shape[1] < n_rows - 1:
        raise ConfigError(
            f"the friction law returned samples of shape {sig.shape}; expected ({n_signals}, {n_rows})")
    if sig.shape[1] < n_rows:
        sig = np.concatenate([sig, sig[:, -1:]], axis=1)
    if not np.all(np.isfinite(sig)):
        raise ConfigError("the friction law returned NaN or infinite samples")
    return sig[:, :n_rows]
