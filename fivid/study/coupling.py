"""How strongly a contact couples the bodies it joins: weak (two structures that barely touch) or strong (one).

Seed 001 separates weak contact, where each beam vibrates in its own modes excited by the friction noise, from
strong contact, where the beams vibrate as one structure. A contact enters the linearised model as normal
springs ``K_n`` (the tangent stiffness of the contact law at the preload, :mod:`fivid.fe.contact`). Adding a
positive semi-definite stiffness raises every ordered eigenvalue (Rayleigh's monotonicity theorem), so each
natural frequency ``f_i`` of the preloaded system lies between

- ``f_i^0``, the bodies without any contact spring (uncoupled: each on its own supports), and
- ``f_i^inf``, every slave node tied normally to its master (the whole interface closed and rigid; sliding
  tangentially, as in the CEA's linearisation),

and the **coupling indicator**

``kappa = sum_i (f_i - f_i^0) / sum_i (f_i^inf - f_i^0)``  over the lowest ``n`` modes,

is 0 for uncoupled bodies, 1 for a rigidly closed interface, and rises with the contact stiffness in between.
``kappa < 0.5`` is called weak, otherwise strong; modes whose two bounds coincide (a body's mode the interface
does not touch) drop out of both sums. The rigid bound is the limit of a normal penalty ``k -> inf``, taken by
Richardson extrapolation of two large penalties (``f(k) = f^inf - c/k + O(1/k^2)``).
"""

from __future__ import annotations

import numpy as np

from fivid.fe.contact import linearise_contact
from fivid.fe.modal import constrained_matrices, lowest_modes
from fivid.fe.static import contact_geometry, preload_state

__all__ = ["coupling_bounds", "coupling_indicator", "reference_frequencies", "peak_positions", "response_coupling",
           "WEAK_STRONG_THRESHOLD"]

#: kappa below which a contact is called weak
WEAK_STRONG_THRESHOLD = 0.5


def _frequencies(K, M, n_modes):
    lam = lowest_modes(K, M, n_modes)[0]
    return np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi)


def coupling_bounds(model, n_modes: int, *, penalty: float = 1e4, closed=None):
    """``(f0, f_inf)`` [Hz], the lowest ``n_modes`` frequencies uncoupled and with the interface tied normally.

    ``penalty`` scales each pair's modal penalty ``normal_stiffness x area`` at every slave node (the operators of
    :func:`fivid.fe.contact.linearise_contact`) for the tie; ``f_inf = 2 f(2 penalty) - f(penalty)``. ``closed``
    (bool per slave node, e.g. ``preload_state(model, load).active``): tie only these (default: every slave node).
    """
    from dataclasses import replace

    K0, M, free = constrained_matrices(model)
    f0 = _frequencies(K0, M, n_modes)
    lin = linearise_contact(model, closed=closed)  # default: every slave node closed
    # the tie: each pair's modal penalty (normal_stiffness x tributary area), whatever its law (a compliant law's
    # tangent at zero penetration is no tie)
    area = contact_geometry(model).area[lin.slave]
    k_tie = np.array([model.contacts[p].normal_stiffness for p in lin.pair]) * area
    tied = []
    for scale in (penalty, 2.0 * penalty):
        lk = replace(lin, stiffness=k_tie * scale)
        Kt = K0 + lk.normal_stiffness_matrix()[free][:, free]
        tied.append(_frequencies(Kt, M, n_modes))
    return f0, 2.0 * tied[1] - tied[0]


def coupling_indicator(frequencies, f0, f_inf) -> float:
    """``kappa`` in [0, 1] of a preloaded system's lowest frequencies [Hz] between its bounds (module docstring)."""
    f = np.asarray(frequencies, dtype=float)
    n = min(f.size, len(f0), len(f_inf))
    f, f0, fi = f[:n], np.asarray(f0, dtype=float)[:n], np.asarray(f_inf, dtype=float)[:n]
    span = fi - f0
    use = span > 1e-9 * fi
    if not use.any():
        return float("nan")
    return float(np.sum(f[use] - f0[use]) / np.sum(span[use]))


def reference_frequencies(model, n_modes: int, normal_load: float) -> tuple[np.ndarray, np.ndarray]:
    """The response criterion's two reference sets [Hz], the lowest ``n_modes`` of each.

    *Uncoupled*: the bodies without any contact spring, each on its own supports (``f0`` of
    :func:`coupling_bounds`). *Coupled*: the slave nodes closed under ``normal_load`` [N] (the static preload,
    :func:`fivid.fe.static.preload_state`; take the sweep's heaviest load, where the contact set has settled)
    tied rigidly, normal direction (the rigid limit of the preloaded interface). Tying every slave node instead
    would over-constrain a beam end that touches only along part of the nominal interface: on the two-beam rig
    the rigid limit of the preloaded modes is 1445 Hz, the all-tied bound 2147 Hz.
    """
    closed = preload_state(model, float(normal_load)).active
    f0, f_tied = coupling_bounds(model, n_modes, closed=closed)
    return f0, f_tied


def peak_positions(peaks, uncoupled, coupled) -> np.ndarray:
    """Each peak's position between the two reference sets: ``d_u / (d_u + d_c)``, 0 on an uncoupled frequency,
    1 on a coupled one.

    ``d_u`` and ``d_c`` are the peak's relative distances ``|f - f_ref| / f_ref`` to the nearest frequency of each
    set [Hz]. A frequency in both sets (a mode the interface does not touch) gives 0/0: NaN, the peak tells
    nothing; so does a peak above both sets' highest frequency by more than 5 % (no reference there).
    """
    f = np.asarray(peaks, dtype=float)[:, None]
    u, c = np.asarray(uncoupled, dtype=float), np.asarray(coupled, dtype=float)
    du = np.min(np.abs(f - u) / u, axis=1)
    dc = np.min(np.abs(f - c) / c, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        pos = du / (du + dc)
    pos[(du + dc) < 1e-3] = np.nan  # a shared frequency (within 0.1 %)
    pos[f[:, 0] > 1.05 * max(u.max(), c.max())] = np.nan
    return pos


def response_coupling(peak_frequency, peak_power, uncoupled, coupled) -> float:
    """``coupling_response`` in [0, 1]: the peaks' :func:`peak_positions` averaged with their power as weights
    (NaN positions left out); NaN when no peak tells."""
    pos = peak_positions(peak_frequency, uncoupled, coupled)
    w = np.asarray(peak_power, dtype=float)
    use = np.isfinite(pos) & (w > 0)
    if not use.any():
        return float("nan")
    return float(np.sum(w[use] * pos[use]) / np.sum(w[use]))
