"""Form removal: subtract the least-squares line or polynomial from a profile (ISO 21920-2 §3.1.3 "form").

The nominal form of a stylus trace (tilt of the part, curvature of a cylinder) is removed by a
least-squares fit of a polynomial of degree 1 (line) or N; the residual is the primary profile
the filters and parameters work on.
"""

from __future__ import annotations

import numpy as np

from fivid.errors import ConfigError

__all__ = ["form_degree", "remove_form", "FORM_CHOICES"]

FORM_CHOICES = "'line', 'poly:N' (N = 0 ... 9) or 'none'"


def form_degree(spec) -> int | None:
    """The polynomial degree named by a form spec: ``"line"`` → 1, ``"poly:N"`` → N, ``"none"`` → None.

    An int is taken as the degree. Raises :class:`~fivid.errors.ConfigError` naming the choices.
    """
    if spec is None or spec == "none":
        return None
    if isinstance(spec, (int, np.integer)) and not isinstance(spec, bool):
        degree = int(spec)
    elif spec == "line":
        return 1
    elif isinstance(spec, str) and spec.startswith("poly:") and spec[5:].isdigit():
        degree = int(spec[5:])
    else:
        raise ConfigError(f"unknown form {spec!r}; choose {FORM_CHOICES}", key="form")
    if not 0 <= degree <= 9:
        raise ConfigError(f"form polynomial degree {degree} is out of range; choose {FORM_CHOICES}", key="form")
    return degree


def remove_form(x, z, degree: int | None):
    """Residual of ``z`` after the least-squares polynomial of ``degree`` in ``x``, and that polynomial.

    Parameters
    ----------
    x, z : ndarray [m]
        Positions and heights.
    degree : int or None
        Polynomial degree (1 = line); None removes nothing.

    Returns
    -------
    residual : ndarray [m]
        ``z - form``.
    form : ndarray [m]
        The fitted form at ``x`` (zeros when ``degree`` is None).

    Notes
    -----
    The fit is done in a scaled variable (:meth:`numpy.polynomial.Polynomial.fit` maps x onto
    [-1, 1]), so a polynomial of degree 9 over metre-scale x stays well conditioned.
    """
    x = np.asarray(x, dtype=np.float64)
    z = np.asarray(z, dtype=np.float64)
    if degree is None:
        return z.copy(), np.zeros_like(z)
    if x.size <= degree:
        raise ConfigError(f"a polynomial form of degree {degree} needs more than {degree} points; got {x.size}",
                          key="form")
    form = np.polynomial.Polynomial.fit(x, z, degree)(x)
    return z - form, form
