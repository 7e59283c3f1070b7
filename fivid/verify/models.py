"""The verification cases' models (mappings for :func:`fivid.fe.load_model`). Synthetic geometry.

The tests build the same models from here (tests/helpers/solver_models.py, tests/helpers/contact_models.py re-export them):
one home for each benchmark's model.
"""

import copy

__all__ = ["STEEL", "STEEL_NU0", "POLYCARBONATE", "FLOOR", "block_on_base", "impacting_bars", "block_on_line",
           "block_on_belt", "ring_on_shaft", "roller_on_flat"]

STEEL = {"E": "210 GPa", "nu": 0.3, "rho": "7850 kg/m^3"}
STEEL_NU0 = {"E": "210 GPa", "nu": 0.0, "rho": "7850 kg/m^3"}  # no Poisson expansion locked in by stick
POLYCARBONATE = {"E": "2.3 GPa", "nu": 0.37, "rho": "1200 kg/m^3"}

FLOOR = {"line": {"point": ["0 mm", "0 mm"], "normal": [0, 1]}}


def block_on_base(*, mu=0.3, spring=1.24e4, base_velocity=None, load=-2e-9, v0=0.0, beta=1e-8, load_ramp="0.2 ms",
                  base_ramp="0.5 ms"):
    """A 4 x 4 mm steel block (2x2 Q4) pressed by a roller clamp on its top edge onto a 40 x 4 mm base.

    The base's bottom edge is clamped (optionally driven in x: the belt); a spring of stiffness ``spring``
    [N/m] ties the block's centre to the ground in x; the block starts with x velocity ``v0`` [m/s].
    """
    motions = [{"name": "load", "body": "block", "edge": "top", "component": "y", "kind": "displacement",
                "amplitude": f"{load} m", "ramp_time": load_ramp, "role": "load"}]
    if base_velocity is not None:
        motions.append({"name": "belt", "body": "base", "edge": "bottom", "component": "x", "kind": "velocity",
                        "amplitude": f"{base_velocity} m/s", "ramp_time": base_ramp, "role": "base"})
    return {
        "name": "block_on_base",
        "plane": "stress",
        "materials": {"steel": STEEL},
        "bodies": {
            "base": {"corners": [["0 mm", "0 mm"], ["40 mm", "0 mm"], ["40 mm", "4 mm"], ["0 mm", "4 mm"]],
                     "divisions": [20, 2], "material": "steel", "thickness": "10 mm", "clamp": ["bottom"]},
            "block": {"corners": [["18 mm", "4 mm"], ["22 mm", "4 mm"], ["22 mm", "8 mm"], ["18 mm", "8 mm"]],
                      "divisions": [2, 2], "material": "steel", "thickness": "10 mm",
                      "initial_velocity": [f"{v0} m/s", "0 m/s"]},
        },
        "damping": {"alpha": "0 s-1", "beta": f"{beta} s"},
        "contacts": [{"name": "interface", "slave": {"body": "block", "edge": "bottom"},
                      "master": {"body": "base", "edge": "top"}, "mu": mu}],
        "motions": motions,
        "springs": [{"name": "holder", "a": {"body": "block", "at": ["20 mm", "6 mm"]}, "b": "ground",
                     "component": "x", "stiffness": f"{spring} N/m"}],
        "sensors": [{"name": "block_x", "body": "block", "at": ["20 mm", "6 mm"], "direction": "x"}],
    }


def impacting_bars(*, length=0.01, n=40, v0=1.0, gap=1e-5):
    """Two identical steel bars (nu = 0, 1 element high) moving at +v0 and -v0 towards each other."""
    mat = {"E": "210 GPa", "nu": 0.0, "rho": "7850 kg/m^3"}
    L = length
    return {
        "name": "bars",
        "plane": "stress",
        "materials": {"bar": mat},
        "bodies": {
            "left": {"corners": [[0, 0], [L, 0], [L, 1e-3], [0, 1e-3]], "divisions": [n, 1], "material": "bar",
                     "thickness": "1 mm", "initial_velocity": [f"{v0} m/s", "0 m/s"]},
            "right": {"corners": [[L + gap, 0], [2 * L + gap, 0], [2 * L + gap, 1e-3], [L + gap, 1e-3]],
                      "divisions": [n, 1], "material": "bar", "thickness": "1 mm",
                      "initial_velocity": [f"{-v0} m/s", "0 m/s"]},
        },
        "contacts": [{"name": "impact", "slave": {"body": "left", "edge": "right"},
                      "master": {"body": "right", "edge": "left"}, "mu": 0.0}],
        "sensors": [{"name": "left_end", "body": "left", "at": [0, 0], "direction": "x"},
                    {"name": "right_end", "body": "right", "at": [2 * L + gap, 0], "direction": "x"}],
    }


def block_on_line(*, law, pressure=1e6, kick=None, nx=10, ny=4):
    """A 10 x 2 mm steel block (thickness 10 mm) pressed by a uniform ``pressure`` [Pa] on its top edge onto the
    rigid line y = 0 with the normal ``law``, frictionless; optional ``kick`` [Pa], a second top pressure stepped
    on at 1 ms over 1 us (sets the contact ringing)."""
    loads = [{"name": "press", "body": "block", "edge": "top", "pressure": f"{pressure} Pa", "ramp_time": "0.5 ms"}]
    if kick:
        loads.append({"name": "kick", "body": "block", "edge": "top", "pressure": f"{kick} Pa", "ramp_time": "1 us",
                      "start": "1 ms"})
    return {
        "name": "block_on_line", "plane": "stress", "materials": {"steel": STEEL},
        "bodies": {"block": {"corners": [["0 mm", "0 mm"], ["10 mm", "0 mm"], ["10 mm", "2 mm"], ["0 mm", "2 mm"]],
                             "divisions": [nx, ny], "material": "steel", "thickness": "10 mm"}},
        "contacts": [{"name": "floor", "slave": {"body": "block", "edge": "bottom"}, "rigid": copy.deepcopy(FLOOR),
                      "mu": 0.0,
                      "normal": law}],
        "loads": loads,
        "sensors": [{"name": "top", "body": "block", "at": ["5 mm", "2 mm"], "direction": "y"}],
    }


def block_on_belt(*, mu=0.3, mu_static=0.5, belt=0.05, spring=1.24e4, normal=10.0, v0=0.0, stribeck=None,
                  viscous=None, alpha="0 s-1"):
    """A 4 x 4 mm steel block (nu = 0, 2 x 2 Q4, thickness 10 mm) on a rigid belt (the line y = 0 sliding at
    ``belt`` [m/s] in x, from 0.5 ms over 0.1 ms), pressed by ``normal`` [N] of uniform top pressure and held by
    a spring [N/m] to ground in x at its bottom centre. Friction acts at the bottom centre node only (pair
    "belt"); the bottom corners rest on the belt without friction (pairs "support*", they stop the block from
    tipping), so the friction is one point force in line with the spring: the block is the rigid oscillator of
    the closed forms."""
    w, t = 4e-3, 1e-2
    rigid = {**copy.deepcopy(FLOOR), "velocity": [f"{belt} m/s", "0 m/s"], "start": "0.5 ms", "ramp_time": "0.1 ms"}
    contacts = [{"name": "belt", "slave": {"body": "block", "edge": "bottom", "x": ["0 mm", "0 mm"]}, "rigid": rigid,
                 "mu": mu, "mu_static": mu_static}]
    if stribeck is not None:
        contacts[0]["stribeck_velocity"] = stribeck
    if viscous is not None:
        contacts[0]["viscous"] = viscous
    contacts += [{"name": f"support{i}", "slave": {"body": "block", "edge": "bottom", "x": [f"{x} mm", f"{x} mm"]},
                  "rigid": copy.deepcopy(rigid), "mu": 0.0} for i, x in enumerate((-2, 2))]
    return {
        "name": "block_on_belt", "plane": "stress", "materials": {"steel": STEEL_NU0},
        "bodies": {"block": {"corners": [["-2 mm", "0 mm"], ["2 mm", "0 mm"], ["2 mm", "4 mm"], ["-2 mm", "4 mm"]],
                             "divisions": [2, 2], "material": "steel", "thickness": "10 mm",
                             "initial_velocity": [f"{v0} m/s", "0 m/s"]}},
        "damping": {"alpha": alpha, "beta": "1e-8 s"},
        "contacts": contacts,
        "loads": [{"name": "press", "body": "block", "edge": "top", "pressure": f"{normal / (w * t)} Pa",
                   "ramp_time": "0.2 ms"}],
        "springs": [{"name": "holder", "a": {"body": "block", "at": ["0 mm", "0 mm"]}, "b": "ground",
                     "component": "x", "stiffness": f"{spring} N/m"}],
        "sensors": [{"name": "block_x", "body": "block", "at": ["0 mm", "0 mm"], "direction": "x"}],
    }


def ring_on_shaft(mu, *, speed="600 rpm", squeeze="1 MPa", holder=1e6, alpha="2000 s^-1", n=96, m=3):
    """A polycarbonate ring (radii 30/50 mm, thickness 10 mm) squeezed by an outer pressure onto a rigid shaft of
    radius 30 mm turning at ``speed`` (from 2 ms over 1 ms), held against turning by two springs [N/m] in x at
    (0, +-50 mm). Heavy mass damping ``alpha`` settles the holder's oscillation."""
    return {
        "name": "ring_on_shaft", "plane": "stress", "materials": {"pc": POLYCARBONATE},
        "bodies": {"ring": {"annulus": {"center": ["0 mm", "0 mm"], "inner_radius": "30 mm", "outer_radius": "50 mm"},
                            "divisions": [n, m], "material": "pc", "thickness": "10 mm"}},
        "damping": {"alpha": alpha, "beta": "4.5e-7 s"},
        "loads": [{"name": "squeeze", "body": "ring", "edge": "outer", "pressure": squeeze, "ramp_time": "1 ms"}],
        "contacts": [{"name": "bore", "slave": {"body": "ring", "edge": "inner"}, "mu": mu,
                      "rigid": {"circle": {"center": ["0 mm", "0 mm"], "radius": "30 mm"}, "speed": speed,
                                "start": "2 ms", "ramp_time": "1 ms"}}],
        "springs": [{"name": f"holder{i}", "a": {"body": "ring", "at": ["0 mm", f"{y} mm"]}, "b": "ground",
                     "component": "x", "stiffness": f"{holder} N/m"} for i, y in enumerate((50, -50))],
        "sensors": [{"name": "top", "body": "ring", "at": ["0 mm", "50 mm"], "direction": "x"}],
    }


def roller_on_flat(n, m):
    """The lower 60 deg sector of a steel roller of radius 10 mm (inner arc at 5 mm driven down by a clamp with a
    force cell) on the rigid flat y = 0, plane strain, n x m elements graded toward the contact (Hertz)."""
    return {
        "name": "roller_on_flat", "plane": "strain", "materials": {"steel": STEEL},
        "bodies": {"roller": {"annulus": {"center": ["0 mm", "10 mm"], "inner_radius": "5 mm",
                                          "outer_radius": "10 mm", "angles": ["240 deg", "300 deg"]},
                              "divisions": [n, m], "grading": {"edge": "outer", "ratio": 1.1 ** (10 / m)},
                              "material": "steel", "thickness": "10 mm"}},
        "contacts": [{"name": "flat", "slave": {"body": "roller", "edge": "outer"}, "mu": 0.0,
                      "rigid": copy.deepcopy(FLOOR)}],
        "motions": [{"name": "press", "body": "roller", "edge": "inner", "component": "y", "kind": "displacement",
                     "amplitude": "-1 um", "role": "load"},
                    {"name": "guide", "body": "roller", "edge": "inner", "component": "x", "kind": "displacement",
                     "amplitude": "0 m"}],
        "reactions": [{"name": "cell", "body": "roller", "edge": "inner", "tangential": "x", "normal": "y"}],
    }
