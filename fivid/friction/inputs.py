"""What a simulation's friction sees: the operating condition and the friction chosen for the contact pairs.

The first two groups of :func:`fivid.solver.simulate` (``simulate(model, condition, friction, ...)``); they live
here because the friction table (:func:`fivid.friction.friction_table`) and the laws consume them. Plain frozen
records in SI units: the solver's driver validates them (:func:`fivid.solver.driver.prepare_run`).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["OperatingCondition", "FrictionInput"]


@dataclass(frozen=True)
class OperatingCondition:
    """The test condition of a run (each None: as the model is configured).

    Attributes
    ----------
    sliding_velocity : float or None
        Velocity of the "base" motion after its ramp [m s-1], >= 0; the sign of the configured amplitude gives the
        direction. None: the configured amplitude.
    normal_load : float or None
        Target normal force at the transducer [N], > 0, set by the "load" clamp's displacement (static preload
        solve, :mod:`fivid.fe.static`). None: the configured clamp displacement.
    roughness_ra : float or None
        Roughness Ra [m], >= 0, passed to the friction law and recorded. None: recorded as 0.

    Examples
    --------
    >>> OperatingCondition(sliding_velocity=0.01, normal_load=5.0)  # 10 mm/s, 5 N
    OperatingCondition(sliding_velocity=0.01, normal_load=5.0, roughness_ra=None)
    """

    sliding_velocity: float | None = None
    normal_load: float | None = None
    roughness_ra: float | None = None


@dataclass(frozen=True)
class FrictionInput:
    """The friction of the contact pairs: a friction law, a constant coefficient, or each pair's own ``mu``.

    Attributes
    ----------
    law : friction-law object or None
        ``mu_k(t) = mu0 + mu_p,k(t)`` (the :class:`fivid.friction.FrictionLaw` interface). Not with ``mu``.
    mu : float or None
        Constant Coulomb friction coefficient [-] of every pair. Not with ``law``. Both None: each contact pair's
        configured ``mu``.
    seed : int
        Seed (>= 0) of the law's synthesis of ``mu_p(t)``; the run is otherwise deterministic.

    Examples
    --------
    >>> FrictionInput(mu=0.3)
    FrictionInput(law=None, mu=0.3, seed=0)
    """

    law: object = None
    mu: float | None = None
    seed: int = 0
