"""Small model configs (mappings for fivid.fe.load_model) shared by the solver tests. Synthetic geometry.

The benchmark models (impacting bars, block on a base) live once, with the verification cases that use them
(fivid/verify/models.py)."""

from fivid.verify.models import STEEL, block_on_base, impacting_bars

__all__ = ["STEEL", "block_on_base", "impacting_bars", "cantilever"]


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
