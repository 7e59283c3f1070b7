"""The Hoffmann kind (``system: {lumped: hoffmann, parameters: ...}``): the minimal 2-DOF mode-coupling model
(:class:`fivid.study.lumped.HoffmannSystem`) swept over mu; its CEA in closed form, its nonlinear transient
classified as the FE transients are. A check of the study machinery against a closed form."""

from __future__ import annotations

from fivid.config_layer import ConfigModel, Quantity
from fivid.study.lumped import HoffmannSystem
from fivid.study.tasks import TRANSIENT_KEYS, transient_variables

__all__ = ["HoffmannParameters", "HoffmannKind", "KIND"]


class HoffmannParameters(ConfigModel):
    """Parameters of the 2-DOF mode-coupling model (:class:`fivid.study.lumped.HoffmannSystem`)."""

    mass: Quantity("kg", bare_is_si=True) = None
    k1: Quantity("N m-1", bare_is_si=True) = None
    k2: Quantity("N m-1", bare_is_si=True) = None
    k3: Quantity("N m-1", bare_is_si=True) = None
    damping: Quantity("N s m-1", bare_is_si=True) = None
    preload: Quantity("N", bare_is_si=True) = None
    belt_velocity: Quantity("m s-1", bare_is_si=True) = None


class HoffmannKind:
    """The lumped 2-DOF model as a study kind (:class:`fivid.study.kind.StudyKind`)."""

    name = "hoffmann"
    description = "2-DOF mass on a moving belt (Hoffmann et al. 2002): closed-form CEA, nonlinear transients over mu"
    lumped = True
    section = ("system", "parameters")
    config = HoffmannParameters
    point_keys = TRANSIENT_KEYS

    def __repr__(self) -> str:
        return f"<study kind {self.name!r}: {type(self).__module__}.{type(self).__name__}>"

    def guess(self, data: dict) -> bool:
        """Named by ``system.lumped``, never guessed."""
        return False

    def check(self, cfg) -> list[tuple[str, str]]:
        """No modes or law (closed form, mu from the sweep), no mesh or time-step axes, a mu axis for a transient."""
        pts, out = cfg.points, []
        if pts.modes is not None:
            out.append(("points.modes", "modes are computed for FE models (a lumped model has its closed form)"))
        if pts.transient is not None and pts.transient.law is not None:
            out.append(("points.transient.law", "a lumped model takes mu from the sweep, not a law file"))
        if {"mesh", "time_step"} & cfg.sweep.model_fields_set:
            out.append(("sweep", "mesh and time_step axes refine an FE model, not a lumped one"))
        if pts.transient is not None and cfg.sweep.mu is None:
            out.append(("sweep", "a lumped model's transient takes its friction coefficient from a 'mu' axis"))
        return out

    def settings(self, section) -> dict:
        """The parameters given, in SI; checked by building the system."""
        si = section.model_dump(exclude_unset=True) if section is not None else {}
        HoffmannSystem(**si)  # ConfigError naming the parameter
        return si

    def system(self, study) -> dict:
        """``{"lumped": {"kind": "hoffmann", "parameters": {...SI}}}``."""
        return {"lumped": study.lumped}

    def evaluate(self, system: dict, tasks: dict, conditions: dict):
        """The transient at the point's mu (and mu_static): the normal displacement ``y`` [m], analysed by
        :func:`fivid.study.tasks.transient_variables`."""
        import xarray as xr

        data, coords = {}, {}
        if "transient" in tasks:
            sys_ = HoffmannSystem(**system["lumped"]["parameters"])
            tr = tasks["transient"]
            ds = sys_.transient(float(conditions["mu"]), duration=tr["duration"], sample_rate=tr["sample_rate"],
                                perturbation=tr.get("perturbation", 1e-7), mu_static=conditions.get("mu_static"))
            st = ds["contact_state"].values
            state = {"sliding": st == 2, "stick": (st == 1).astype(float)}
            transient_variables(ds["time"].values, ds["y"].values, "m", state, tasks, data, coords)
        return xr.Dataset(data, coords=coords)

    def cea(self, study, mu) -> dict:
        """:meth:`fivid.study.lumped.HoffmannSystem.cea`."""
        res = HoffmannSystem(**study.lumped["parameters"]).cea(mu)
        return {k: res[k] for k in ("eigenvalues", "critical_mu", "partner")}

    def summarise(self, study, ds, points: list[dict]) -> dict:
        """Nothing beyond the generic summary (the CEA's critical mu and each point's CEA comparison)."""
        return {}

    def report(self, page, ds, summary: dict) -> None:
        """Nothing beyond the generic section (growth rates against the CEA's largest real part)."""


#: the registered instance
KIND = HoffmannKind()
