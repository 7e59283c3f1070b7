"""Node coordinates of structured blocks: bilinear quadrilaterals, annular sectors/rings, profiled rectangles.

Geometry (numpy only): each function returns the ``(ny+1, n_cols, 2)`` coordinate grid that
:class:`fivid.fe.model.Block` stores, ``coords[j, i]`` being local node ``(i, j)``. Divisions may be
graded: :func:`graded_fractions` gives the node positions along one direction. :func:`block_coords` is the
grid of a validated ``bodies`` entry of a model file (:class:`fivid.fe.config.BodyConfig`), a measured
profile read from its file by :func:`read_profile_table`.

Units: SI (m, rad).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = [
    "block_coords",
    "read_profile_table",
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


def _fractions(n: int, graded: str | None, ratio: float, axis: str) -> np.ndarray:
    """Node fractions along ``axis`` ("s": c0->c1, bottom-to-top "t") with the grading toward ``graded``."""
    ends = {"s": ("left", "right"), "t": ("bottom", "top")}[axis]
    if graded not in ends:
        return graded_fractions(n)
    return graded_fractions(n, ratio, toward_end=graded == ends[1])


def block_coords(body, source, key: str) -> tuple[np.ndarray, str, bool]:
    """``(coords (ny+1, n_cols, 2) [m], shape, periodic)`` of a validated body (:class:`fivid.fe.config.BodyConfig`).

    ``source`` (:class:`fivid.config_layer.ConfigSource`) and ``key`` (``bodies.upper``) name the file and key of
    an error found only here: a profile file that cannot be read, a profile that does not cover the edge or folds
    the body.
    """
    nx, ny = body.divisions
    graded = body.graded_edge
    ratio = body.grading.ratio if body.grading is not None else 1.0
    if body.annulus is not None:
        a = body.annulus
        a0, a1 = a.angle_range
        t = _fractions(ny, graded, ratio, "t")
        return annulus_coords(a.center, a.inner_radius, a.outer_radius, a0, a0 + 2.0 * np.pi if a.periodic else a1,
                              nx, t, periodic=a.periodic), "annulus", a.periodic
    corners = np.array(body.corners, dtype=float)
    s, t = _fractions(nx, graded, ratio, "s"), _fractions(ny, graded, ratio, "t")
    if body.profile is None:
        return bilinear_coords(corners, s, t), "quad", False
    heights = _profile_heights(body.profile, corners, s, source, f"{key}.profile")
    return profile_coords(corners, body.profile.edge, heights, s, t), "profile", False


def _profile_heights(p, corners: np.ndarray, s: np.ndarray, source, key: str) -> np.ndarray:
    """Heights [m] of profile ``p`` (:class:`fivid.fe.config.ProfileConfig`) at the node columns of the rectangle."""
    length = corners[1, 0] - corners[0, 0]
    xs = length * s  # node x measured from the left end
    if p.sine is not None:
        h = sine_profile(xs, p.sine.amplitude, p.sine.wavelength, p.sine.phase)
    elif p.gaussian is not None:
        h = gaussian_profile(xs, p.gaussian.amplitude, p.gaussian.width, p.gaussian.center)
    else:
        if p.file is not None:
            path = Path(p.file)
            if not path.is_absolute() and source.file is not None:
                path = Path(source.file).parent / path
            try:
                x, z = read_profile_table(path)
            except ValueError as exc:
                raise source.error(f"{key}.file", str(exc)) from None
        else:
            x, z = np.array(p.x, dtype=float), np.array(p.z, dtype=float)
        x, z = x * p.units.scale("x"), z * p.units.scale("z")
        tol = 1e-9 * length
        if x[0] > tol or x[-1] < length - tol:
            raise source.error(f"{key}.x", f"the profile covers x = [{x[0]:.6g}, {x[-1]:.6g}] m from the body's left "
                                           f"end; it must cover the whole edge [0, {length:.6g}] m")
        h = np.interp(xs, x, z)
    depth = corners[3, 1] - corners[0, 1]
    if (p.edge == "bottom" and h.max() >= depth) or (p.edge == "top" and -h.min() >= depth):
        raise source.error(key, f"profile heights [{h.min():.3g}, {h.max():.3g}] m fold the body (depth {depth:.3g} m)")
    return h


def read_profile_table(path) -> tuple[np.ndarray, np.ndarray]:
    """``(x, z)`` of a two-column text table (comma, semicolon or blank separated; ``#`` comments and one header
    line allowed), in the file's units; x strictly increasing.

    Raises
    ------
    ValueError
        The file cannot be read, is not a table of numbers, has fewer than 2 rows or x does not increase.
    """
    path = Path(path)
    try:
        text = path.read_text().replace(",", " ").replace(";", " ")
    except OSError as exc:
        raise ValueError(f"cannot read the profile file {str(path)!r}: {exc.strerror}") from None
    rows = [r for r in (ln.split() for ln in text.splitlines()) if r and not r[0].startswith("#")]
    if rows and not _is_number(rows[0][0]):
        rows = rows[1:]  # a header line
    try:
        table = np.array([[float(v) for v in r[:2]] for r in rows])
    except (ValueError, IndexError):
        raise ValueError(f"{str(path)!r} is not a two-column table of numbers (x, z)") from None
    if table.ndim != 2 or table.shape[0] < 2 or table.shape[1] != 2:
        raise ValueError(f"{str(path)!r} needs at least 2 rows of (x, z)")
    if not np.all(np.isfinite(table)):
        raise ValueError(f"{str(path)!r} contains values that are not finite")
    if not np.all(np.diff(table[:, 0]) > 0):
        raise ValueError(f"{str(path)!r}: profile x must increase strictly")
    return table[:, 0], table[:, 1]


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
