"""Node coordinates of structured blocks: bilinear quadrilaterals, annular sectors/rings, profiled rectangles.

Pure geometry (numpy only): each function returns the ``(ny+1, n_cols, 2)`` coordinate grid that
:class:`fivid.fe.model.Block` stores, ``coords[j, i]`` being local node ``(i, j)``. Divisions may be
graded: :func:`graded_fractions` gives the node positions along one direction.

Units: SI (m, rad).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "graded_fractions",
    "bilinear_coords",
    "annulus_coords",
    "profile_coords",
    "sine_profile",
    "gaussian_profile",
]


def graded_fractions(n: int, ratio: float = 1.0, *, toward_end: bool = True) -> np.ndarray:
    """Node positions ``0 = s_0 < ... < s_n = 1`` of ``n`` divisions in geometric progression.

    Each division is ``ratio`` times the next one toward the graded end (``ratio > 1`` refines toward
    it): sizes ``h_k`` proportional to ``ratio**(n-1-k)`` when ``toward_end`` (refined at s = 1), to
    ``ratio**k`` otherwise (refined at s = 0). ``ratio = 1`` gives equal divisions.

    Parameters
    ----------
    n : int
        Number of divisions, >= 1.
    ratio : float
        Size ratio of neighbouring divisions [-], > 0.
    toward_end : bool
        Refine toward ``s = 1`` (True) or ``s = 0``.

    Returns
    -------
    ndarray, shape (n+1,)
        Fractions [-] (exactly 0 and 1 at the ends).

    Examples
    --------
    >>> graded_fractions(3, 2.0).round(4).tolist()
    [0.0, 0.5714, 0.8571, 1.0]
    """
    if ratio == 1.0:  # exactly the equal divisions (and node coordinates) of ungraded blocks
        return np.linspace(0.0, 1.0, n + 1)
    k = np.arange(n)
    h = float(ratio) ** ((n - 1 - k) if toward_end else k)
    s = np.concatenate([[0.0], np.cumsum(h)])
    s /= s[-1]
    s[-1] = 1.0
    return s


def bilinear_coords(corners: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Bilinear map of 4 corners (counter-clockwise from bottom-left) at fractions ``s`` (along c0->c1) and
    ``t`` (along c0->c3) [m], shape (len(t), len(s), 2)."""
    s = np.asarray(s, float)[None, :, None]
    t = np.asarray(t, float)[:, None, None]
    c0, c1, c2, c3 = np.asarray(corners, float)
    return (1 - s) * (1 - t) * c0 + s * (1 - t) * c1 + s * t * c2 + (1 - s) * t * c3


def annulus_coords(center, inner_radius: float, outer_radius: float, angle_start: float, angle_end: float,
                   nx: int, t: np.ndarray, *, periodic: bool) -> np.ndarray:
    """Nodes of an annular sector: ``i`` clockwise from ``angle_end`` to ``angle_start``, ``j`` outward.

    Parameters
    ----------
    center : array_like, shape (2,)
        Centre [m].
    inner_radius, outer_radius : float
        Radii [m], ``0 < inner < outer``.
    angle_start, angle_end : float
        Angle range [rad], counter-clockwise from +x; a full ring has ``angle_end = angle_start + 2 pi``.
    nx : int
        Divisions around.
    t : ndarray, shape (ny+1,)
        Radial fractions from inner (0) to outer (1) radius.
    periodic : bool
        Full ring: ``nx`` node columns (the column at ``angle_start`` is the one at ``angle_end``).

    Returns
    -------
    ndarray, shape (ny+1, nx or nx+1, 2) [m]
    """
    cols = nx if periodic else nx + 1
    theta = angle_end - (angle_end - angle_start) * np.arange(cols) / nx
    r = inner_radius + (outer_radius - inner_radius) * np.asarray(t, float)
    xy = np.stack([np.cos(theta)[None, :] * r[:, None], np.sin(theta)[None, :] * r[:, None]], axis=-1)
    return xy + np.asarray(center, float)


def profile_coords(corners: np.ndarray, edge: str, heights: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Nodes of an axis-aligned rectangle whose ``edge`` ("bottom" or "top") is displaced by ``heights``.

    The nodes are the bilinear map of the rectangle (:func:`bilinear_coords`) moved vertically by
    ``h(x_i)`` times the node's share: 1 on the profiled edge, decaying linearly to 0 on the opposite
    (straight) edge, so a column stays vertical and a flat profile gives exactly the rectangle's nodes.

    Parameters
    ----------
    corners : ndarray, shape (4, 2)
        The rectangle [m] (axis-aligned, counter-clockwise from bottom-left).
    edge : {"bottom", "top"}
    heights : ndarray, shape (len(s),)
        Profile heights at the node columns [m], positive along +y.
    s, t : ndarray
        Fractions along x (len nx+1) and from bottom to top (len ny+1).

    Returns
    -------
    ndarray, shape (len(t), len(s), 2) [m]
    """
    xy = bilinear_coords(corners, s, t)
    share = np.asarray(t, float) if edge == "top" else 1.0 - np.asarray(t, float)
    xy[..., 1] += share[:, None] * np.asarray(heights, float)[None, :]
    return xy


def sine_profile(x: np.ndarray, amplitude: float, wavelength: float, phase: float = 0.0) -> np.ndarray:
    """``h(x) = amplitude sin(2 pi x / wavelength + phase)`` [m] at ``x`` [m]."""
    return amplitude * np.sin(2.0 * np.pi * np.asarray(x, float) / wavelength + phase)


def gaussian_profile(x: np.ndarray, amplitude: float, width: float, center: float) -> np.ndarray:
    """A Gaussian bump ``h(x) = amplitude exp(-(x - center)^2 / (2 width^2))`` [m] at ``x`` [m]."""
    return amplitude * np.exp(-0.5 * ((np.asarray(x, float) - center) / width) ** 2)
