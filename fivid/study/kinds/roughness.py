"""The roughness-noise kind (``kind: roughness``, seed 003): a rough sliding pair built at each point from
synthetic profiles of the point's Ra, its vibration level Lv, shocks and friction power
(:func:`fivid.study.roughness.evaluate_roughness_point`), and the fits of Lv = 20 n log Ra + 20 m log V + c.

Its section is ``points.roughness`` (:class:`RoughnessSettings`); the point's record length and sample rate are
``points.transient``'s."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from fivid.config_layer import ConfigModel, Number, Quantity
from fivid.study.fits import roughness_noise_fits
from fivid.study.kinds.sweep import FeSweep
from fivid.study.roughness import evaluate_roughness_point, roughness_settings
from fivid.study.roughness_report import roughness_section

__all__ = ["RoughnessSettings", "RoughnessNoise", "KIND", "ROUGHNESS_KEYS"]

#: per-point results of a roughness-noise point copied into summary.json
ROUGHNESS_KEYS = ("vibration_level", "velocity_rms", "band_vibration_level", "band_velocity_rms", "shock_rate",
                  "shock_impulse", "shock_count", "shock_energy", "friction_power", "vibratory_power", "impact_power",
                  "mean_normal_force", "mean_friction_force", "open_fraction", "friction_coefficient",
                  "friction_coefficient_rms", "profile_rsm_target", "profile_Ra", "profile_Rq",
                  "profile_Rz", "profile_Rsm", "simulation_seconds", "simulation_cpu_seconds", "mesh_step",
                  "dof_updates_per_second", "n_dof", "time_step", "added_mass_fraction")


class RoughnessSettings(ConfigModel):
    """seed 003's rough pair (:mod:`fivid.study.roughness`; defaults :data:`fivid.study.roughness.ROUGHNESS_TASK`)."""

    correlation_length: Quantity("m", positive=True, bare_is_si=True) = None
    profile_step: Quantity("m", positive=True, bare_is_si=True) = None
    seeds: Annotated[list[Annotated[int, Field(ge=0)]], Field(min_length=2, max_length=2,
                                                              description="lower, upper profile")] = None
    sensor_every: Annotated[int, Field(ge=1)] = None
    gs_tolerance: Annotated[Number, Field(gt=0, lt=1)] = None
    gs_max_iterations: Annotated[int, Field(ge=1)] = None
    settle_time: Quantity("s", positive=True, bare_is_si=True) = None
    surfaces: Literal["rsm_levels", "table1", "measured"] = Field(
        None, description="rsm_levels: Gaussian profiles at the replicate's Rsm level; table1: seed 003's Table 1 "
                          "surface of the point's Ra; measured: profile_files")
    nodes_per_rsm: Annotated[int, Field(ge=2)] = Field(None, description="re-divide the blocks at Rsm / this")
    sensor_spacing: Quantity("m", positive=True, bare_is_si=True) = None
    seat: bool = Field(None, description="start the upper block seated on its two supporting asperities")
    transition: bool = Field(None, description="with nodes_per_rsm: coarsen both blocks along x with depth "
                                               "(fivid.fe.transition; only the surface level at Rsm / nodes_per_rsm)")
    surface_added_mass: Annotated[Number, Field(ge=0, lt=1)] = Field(
        None, description="with transition: mass-scale each block's surface level, adding at most this fraction of "
                          "the body's mass (fivid.fe.mass_scaling; a longer stable step)")
    profile_files: Annotated[list[str], Field(min_length=2, max_length=2, description="lower, upper profile files "
                                                                                       "(surfaces: measured)")] = None


class RoughnessNoise(FeSweep):
    """Roughness noise of a rough pair (:class:`fivid.study.kind.StudyKind`)."""

    name = "roughness"
    description = ("roughness noise of a rough sliding pair (seed 003): Lv, shocks, vibratory and friction power, "
                   "their power laws")
    section = ("points", "roughness")
    config = RoughnessSettings
    point_keys = tuple((k, k) for k in ROUGHNESS_KEYS)

    def guess(self, data: dict) -> bool:
        """An FE study with a ``points.roughness`` section."""
        return "roughness" in (data.get("points") or {})

    def check(self, cfg) -> list[tuple[str, str]]:
        """A rough-pair point is a transient."""
        if cfg.points.transient is None:
            return [("points.roughness", "a rough-pair point is a transient: give points.transient (duration, "
                                         "sample_rate)")]
        return []

    def settings(self, section) -> dict:
        """The keys given (the rest from :data:`fivid.study.roughness.ROUGHNESS_TASK`), in SI."""
        return section.model_dump(exclude_unset=True) if section is not None else {}

    def system(self, study) -> dict:
        """The base model file (the point's profiles are put on it at the point)."""
        return {"model_path": str(study.model_path)}

    def evaluate(self, system: dict, tasks: dict, conditions: dict):
        """:func:`fivid.study.roughness.evaluate_roughness_point`."""
        import xarray as xr

        return xr.Dataset(evaluate_roughness_point(system["model_path"], tasks, conditions))

    def summarise(self, study, ds, points: list[dict]) -> dict:
        """``n``, ``m``, the fits of :func:`fivid.study.fits.roughness_noise_fits` and ``roughness_settings``."""
        if not any("vibration_level" in p for p in points):
            return {}
        rn = roughness_noise_fits(points)
        return {"fits": rn.pop("fits"), **rn, "roughness_settings": roughness_settings(study)}

    def report(self, page, ds, summary: dict) -> None:
        """:func:`fivid.study.roughness_report.roughness_section`."""
        roughness_section(page, ds, summary)


#: the registered instance
KIND = RoughnessNoise()
