"""Small model configs (mappings for fivid.fe.load_model) shared by the solver tests. Synthetic geometry."""

STEEL = {"E": "210 GPa", "nu": 0.3, "rho": "7850 kg/m^3"}


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


def cantilever(*, nx=16, ny=3, v0=0.5, mapped=False, sheared=False, beta=0.0, spring=None):
    """A steel cantilever 32 x 6 mm clamped on the left, initial transverse velocity ``v0``; optionally a
    trapezoidal (mapped) or parallelogram (sheared: uniform, not rectangular) outline and a spring to ground
    at the tip."""
    top_right = ["32 mm", "5 mm"] if mapped else ["34 mm", "6 mm"] if sheared else ["32 mm", "6 mm"]
    top_left = ["2 mm", "6 mm"] if sheared else ["0 mm", "6 mm"]
    cfg = {
        "name": "cantilever",
        "plane": "stress",
        "materials": {"steel": STEEL},
        "bodies": {"beam": {"corners": [["0 mm", "0 mm"], ["32 mm", "0 mm"], top_right, top_left],
                            "divisions": [nx, ny], "material": "steel", "thickness": "5 mm", "clamp": ["left"],
                            "initial_velocity": ["0 m/s", f"{v0} m/s"]}},
        "damping": {"alpha": "0 s-1", "beta": f"{beta} s"},
        "sensors": [{"name": "tip", "body": "beam", "at": ["32 mm", "0 mm"], "direction": "y"}],
    }
    if spring:
        cfg["springs"] = [{"name": "tip_spring", "a": {"body": "beam", "at": ["32 mm", "0 mm"]}, "b": "ground",
                           "component": "y", "stiffness": f"{spring} N/m", "damping": "0.01 N s/m"}]
    return cfg
