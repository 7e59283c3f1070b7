"""The FE sweep kind (``kind: fe_sweep``): an FE model over the swept conditions; at each point the preloaded modes
(with the weak/strong coupling indicator on a model with contacts), a transient and its PSD; once for the study
a CEA over mu. The base of the FE kinds (ring, weak/strong, convergence, roughness), and the kind of a study
config with an FE model that no other kind claims."""

from __future__ import annotations

import numpy as np

from fivid.fe import load_model
from fivid.fe.cea import complex_eigenvalue_analysis
from fivid.study.fits import power_law_fit
from fivid.study.tasks import COUPLING_KEYS, TRANSIENT_KEYS, coupling_system, fe_point, refined_model

__all__ = ["FeSweep", "KIND"]


class FeSweep:
    """An FE model swept over conditions (:class:`fivid.study.kind.StudyKind`)."""

    name = "fe_sweep"
    description = "an FE model over the swept conditions: preloaded modes, transients, PSDs, a CEA over mu"
    lumped = False
    section = None
    config = None
    point_keys = TRANSIENT_KEYS[:8] + COUPLING_KEYS + TRANSIENT_KEYS[8:]

    def __repr__(self) -> str:
        return f"<study kind {self.name!r}: {type(self).__module__}.{type(self).__name__}>"

    def guess(self, data: dict) -> bool:
        """Any FE study (registered last: the kinds before it claim theirs first)."""
        return True

    def check(self, cfg) -> list[tuple[str, str]]:
        """Nothing beyond the generic checks of the study config."""
        return []

    def settings(self, section) -> dict:
        """No section of its own."""
        return {}

    def system(self, study) -> dict:
        """The model file, and the coupling bounds per mesh when modes are computed on a model with contacts."""
        out = {"model_path": str(study.model_path)}
        if "modes" in study.points:
            out.update(coupling_system(study.model_path, study.axes.get("mesh", [1.0]),
                                       study.points["modes"]["n_modes"]))
        return out

    def evaluate(self, system: dict, tasks: dict, conditions: dict):
        """:func:`fivid.study.tasks.fe_point`."""
        return fe_point(system, tasks, conditions)

    def cea(self, study, mu) -> dict:
        """:func:`fivid.fe.cea.complex_eigenvalue_analysis` about the preload ``cea.normal_load`` (on the swept mesh
        when one mesh is swept)."""
        meshes = np.unique(study.axes.get("mesh", [1.0]))  # one mesh swept: the CEA on it too
        model = refined_model(study.model_path, float(meshes[0])) if meshes.size == 1 else load_model(study.model_path)
        ds = complex_eigenvalue_analysis(model, mu, normal_load=study.cea.get("normal_load"))
        lam = ds["real_part"].transpose("mu", "mode").values + 2j * np.pi * ds["frequency"].transpose("mu", "mode").values
        p = ds["partner"].values  # mode numbers (1-based), -1 for none
        return {"eigenvalues": lam, "critical_mu": ds["critical_mu"].values, "partner": np.where(p > 0, p - 1, -1)}

    def summarise(self, study, ds, points: list[dict]) -> dict:
        """``fits.rms``: the response RMS as a power law of the varying load, velocity and roughness
        (:func:`fivid.study.fits.power_law_fit`), when there are enough points."""
        fit = power_law_fit(points, "rms")
        return {"fits": {"rms": fit}} if fit is not None else {}

    def report(self, page, ds, summary: dict) -> None:
        """Nothing beyond the generic section (points table, growth and level figures, CEA)."""


#: the registered instance
KIND = FeSweep()
