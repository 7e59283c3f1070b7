"""A rough sliding pair's model config (seed 003): a rough_pair-style config with two height profiles on its facing
edges, the upper body lifted to first touch, sensors on the lower body's back face and the dead load set."""

from __future__ import annotations

import copy

import numpy as np

from fivid.config_layer import quantity_at
from fivid.errors import ConfigError
from fivid.fe.config import read_config
from fivid.fe.transition import surface_rows_for, transition_columns

__all__ = ["rough_pair_config", "profiled_length", "graded_divisions", "seating_line"]


def _si(ctx, value, key, units="m") -> float:
    return quantity_at(ctx, value, key, units)


def graded_divisions(length: float, depth: float, step: float, ratio: float) -> list[int]:
    """Divisions ``[columns, layers]`` of a block ``length`` x ``depth`` [m] with columns of ``step`` [m] and layers
    growing by ``ratio`` from its profiled edge, as many as make the first (surface) layer closest to ``step``
    (``depth (r - 1) / (r^n - 1) ~ step``; ``n = depth / step`` rounded when ``ratio`` is 1)."""
    cols = max(1, int(round(length / step)))
    if ratio <= 1.0:
        return [cols, max(1, int(round(depth / step)))]
    return [cols, max(1, int(round(np.log1p(depth * (ratio - 1.0) / step) / np.log(ratio))))]


def seating_line(x, gap, centre: float) -> tuple[float, float]:
    """``(a, b)``: the line ``a + b x`` [m] on which a rigid block with gap ``gap`` [m] at its contact nodes ``x``
    [m] rests under a dead load through ``centre`` [m]: the lower convex hull's edge of the points ``(x, gap)``
    spanning ``centre`` (its two supporting asperities; one, with ``b = 0``, when ``centre`` is off the hull's
    span). ``gap - (a + b x) >= 0`` everywhere, zero at the supports."""
    x, g = np.asarray(x, float), np.asarray(gap, float)
    hull: list[int] = []
    for i in np.argsort(x, kind="stable"):  # Andrew's monotone chain, lower hull
        while len(hull) >= 2:
            o, a = hull[-2], hull[-1]
            if (x[a] - x[o]) * (g[i] - g[o]) - (g[a] - g[o]) * (x[i] - x[o]) <= 0:
                hull.pop()
            else:
                break
        hull.append(int(i))
    for a, b in zip(hull[:-1], hull[1:]):
        if x[a] <= centre <= x[b] and x[b] > x[a]:
            slope = (g[b] - g[a]) / (x[b] - x[a])
            return float(g[a] - slope * x[a]), float(slope)
    return float(np.min(g)), 0.0


def rough_pair_config(base, lower, upper, *, sensor_every: int = 1, normal_load: float | None = None,
                      mesh_step: float | None = None, seat: bool = False, transition: bool = False):
    """A rough-pair model config: ``base`` (path or mapping of a rough_pair-style config) with the profiles.

    Parameters
    ----------
    base : path-like or mapping
        A model config with two rectangular bodies whose facing edges carry ``profile:`` keys (the one with a
        ``top`` profile is the lower body, the ``bottom`` one the upper body) and one contact pair.
    lower, upper : xarray.DataArray
        Height profiles [m] over ``x`` [m] from the bodies' left ends (a reader's or a synthesis's output),
        covering the body length.
    sensor_every : int
        A velocity sensor (direction y) on every ``sensor_every``-th node of the lower body's back face
        (``bottom`` edge), both end nodes included when the division count allows; replaces the config's sensors.
    normal_load : float, optional
        Dead load [N] on the upper body: its ``top``-edge pressure loads are scaled to sum to it (pressure x
        length x thickness). None: as configured.
    mesh_step : float, optional
        Re-divide both profiled blocks (:func:`graded_divisions`): columns of ``mesh_step`` [m] along x and as many
        layers (the config's grading ratio, default 1) as make the surface layer about ``mesh_step`` thick.
        None: the config's divisions.
    transition : bool
        With ``mesh_step``: divide the profiled edges for a coarsening stack instead (:mod:`fivid.fe.transition`):
        columns of at most ``mesh_step`` whose number divides by ``2^K`` (:func:`fivid.fe.transition.transition_columns`)
        and one layer; build the model with :func:`fivid.fe.load_model` and re-mesh both bodies with
        :func:`fivid.fe.transition.transition_model` (the record's ``transition`` lists them).
    seat : bool
        Seat the upper block on the lower one instead of lifting it to first touch: its profile is lowered by the
        :func:`seating_line` of the gap under its centre, so it starts resting on its two supporting asperities
        (a rigid rotation of a few 1e-4 rad taken as a shear of the profile, exact to its square). A light dead
        load would otherwise take milliseconds of free fall to seat a 120 mm block (13 m/s2 at 1 N).

    Returns
    -------
    (dict, dict)
        The config mapping, and a record: ``lift`` [m] (the upper body is lifted by ``max(z_lower - z_upper)``
        over the contact's slave nodes, so the highest asperity pair touches with zero gap), the profiled bodies'
        ``divisions``, the bodies' names,
        ``back_face_sensors``, ``sensor_every`` and the base config's source.
    """
    data, ctx, origin = read_config(base)
    data = copy.deepcopy(data)
    bodies = data["bodies"]
    edges = {b["profile"]["edge"]: name for name, b in bodies.items() if isinstance(b.get("profile"), dict)}
    if set(edges) != {"top", "bottom"}:
        raise ConfigError(f"{origin}: a rough pair needs one body with a 'top' profile and one with a 'bottom' "
                          f"profile; profiled edges found: {sorted(edges) or 'none'}", key="bodies")
    lo_name, up_name = edges["top"], edges["bottom"]
    lo, up = bodies[lo_name], bodies[up_name]
    lc = np.array([[_si(ctx, v, f"bodies.{lo_name}.corners") for v in c] for c in lo["corners"]])
    uc = np.array([[_si(ctx, v, f"bodies.{up_name}.corners") for v in c] for c in up["corners"]])
    length = lc[1, 0] - lc[0, 0]
    if mesh_step is not None:
        for body, c, prof in ((lo, lc, lower), (up, uc, upper)):
            ratio = float((body.get("grading") or {}).get("ratio", 1.0))
            body["divisions"] = graded_divisions(c[1, 0] - c[0, 0], c[2, 1] - c[1, 1], float(mesh_step), ratio)
            if transition:
                rows = surface_rows_for(prof.values, float(mesh_step))
                body["divisions"] = [transition_columns(c[1, 0] - c[0, 0], float(mesh_step), c[2, 1] - c[1, 1],
                                                        surface_rows=rows), 1]
    nx = int(lo["divisions"][0])
    xn = np.linspace(0.0, length, nx + 1)  # back-face nodes (uniform along x; grading is through the depth)
    nu = int(up["divisions"][0])
    xs = np.linspace(uc[0, 0], uc[1, 0], nu + 1)[1:-1]  # the interface's slave nodes, end nodes excluded (below)
    zl = np.interp(xs - lc[0, 0], lower["x"].values, lower.values)
    zu = np.interp(xs - uc[0, 0], upper["x"].values, upper.values)
    lift = float(np.max(zl - zu))
    if seat:
        a, b = seating_line(xs, lift + zu - zl, 0.5 * (uc[0, 0] + uc[1, 0]))
        xu = np.asarray(upper["x"].values, float)
        upper = upper.copy(data=np.asarray(upper.values, float) - (a + b * (xu + uc[0, 0])))
    top = lc[2, 1]
    up_corners_y0 = up["corners"][0][1]
    depth_up = uc[2, 1] - uc[1, 1]
    uc[:, 1] = [top + lift, top + lift, top + lift + depth_up, top + lift + depth_up]
    for body, prof, edge in ((lo, lower, "top"), (up, upper, "bottom")):
        body["profile"] = {"edge": edge, "x": np.asarray(prof["x"].values, float),
                           "z": np.asarray(prof.values, float)}
    up["corners"] = [[f"{float(x)!r} m", f"{float(y)!r} m"] for x, y in uc]
    # whatever rides with the upper body (a carriage block, transducer springs, point masses) rises with it
    dy = top + lift - _si(ctx, up_corners_y0, f"bodies.{up_name}.corners")
    for name, b in bodies.items():
        if name not in (lo_name, up_name) and "corners" in b:
            b["corners"] = [[c[0], f"{float(_si(ctx, c[1], f'bodies.{name}.corners') + dy)!r} m"] for c in b["corners"]]
    for group in ("springs", "point_masses"):
        for item in data.get(group) or []:
            for end in ("a", "b", None):
                ref = item if end is None else item.get(end)
                if isinstance(ref, dict) and ref.get("body") not in (None, lo_name) and "at" in ref:
                    y = _si(ctx, ref["at"][1], f"{group}.{item.get('name')}.at") + dy
                    ref["at"] = [ref["at"][0], f"{float(y)!r} m"]
    # the slave edge without its two end nodes: the carriage-held one (prescribed dofs) and the one facing the lower
    # body's clamped corner would tie prescribed dofs through the rigid contact (a flat pair diverges with them)
    h = (uc[1, 0] - uc[0, 0]) / nu
    for c in data["contacts"]:
        if c["slave"]["body"] == up_name:
            c["slave"] = {**c["slave"], "x": [f"{float(uc[0, 0] + h / 2)!r} m", f"{float(uc[1, 0] - h / 2)!r} m"]}
    if normal_load is not None:
        weights = [ld for ld in data.get("loads") or [] if ld.get("body") == up_name and ld.get("edge") == "top"]
        if not weights:
            raise ConfigError(f"{origin}: normal_load needs a pressure load on the top edge of {up_name!r}",
                              key="loads")
        area = (uc[1, 0] - uc[0, 0]) * _si(ctx, up["thickness"], f"bodies.{up_name}.thickness")
        total = sum(_si(ctx, ld["pressure"], "loads.pressure", "Pa") for ld in weights)
        for ld in weights:
            p = _si(ctx, ld["pressure"], "loads.pressure", "Pa") / total * normal_load / area
            ld["pressure"] = f"{float(p)!r} Pa"
    k = max(1, int(sensor_every))
    y0 = lc[0, 1]
    data["sensors"] = [{"name": f"back_{i:04d}", "body": lo_name, "direction": "y",
                        "at": [f"{float(xn[i] + lc[0, 0])!r} m", f"{float(y0)!r} m"]} for i in range(0, nx + 1, k)]
    data["name"] = f"{data.get('name', 'rough_pair')} (profiles: {lower.attrs.get('source', 'given')})"
    return data, {"lift": lift, "seated": bool(seat),
                  "transition": [lo_name, up_name] if (transition and mesh_step is not None) else [], "divisions": {lo_name: list(lo["divisions"]), up_name: list(up["divisions"])},
                  "lower_body": lo_name, "upper_body": up_name,
                  "back_face_sensors": len(data["sensors"]), "sensor_every": k, "base": origin}


def profiled_length(base) -> float:
    """Length [m] of the lower (``top``-profiled) body of a rough_pair-style config (path or mapping): the span its
    profiles must cover."""
    data, ctx, origin = read_config(base)
    corners = next((b["corners"] for b in data["bodies"].values()
                    if isinstance(b.get("profile"), dict) and b["profile"].get("edge") == "top"), None)
    if corners is None:
        raise ConfigError(f"{origin}: no body with a 'top' profile (the lower body of a rough pair)", key="bodies")
    return _si(ctx, corners[1][0], "corners") - _si(ctx, corners[0][0], "corners")
