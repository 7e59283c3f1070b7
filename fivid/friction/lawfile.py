"""The FrictionLaw file (netCDF4): write a law object and read it back.

Layout (``law_file_version`` 2; version 1 files are read too)::

    coords   frequency [Hz]            grid of the normalised shape (inside the valid band)
             coefficient, coefficient_b amplitude-model coefficient names
             roughness_level            index of the roughness levels of the linear forms
    vars     mu0 () [1]                 attrs ci_lower, ci_upper, confidence
             shape (frequency) [Hz-1]   ∫ shape d(frequency) = 1
             amplitude_coefficient (coefficient), amplitude_stderr (coefficient),
             amplitude_covariance (coefficient, coefficient_b)
             roughness_levels (roughness_level) [m]
    attrs    law ("perturbed_coulomb" | "coulomb"), amplitude_form, amplitude_terms, band_lower,
             band_upper [Hz], injection, reference_velocity [m s-1], reference scales, history, source

Added in version 2 (absent from version-1 files, which read as before; what is missing is then said):

    vars     amplitude_coefficient_units (coefficient)        CF units of each coefficient
             domain_sliding_velocity, domain_roughness_ra, domain_normal_load (domain_condition)
                                               the conditions the law was fitted on (its domain)
             shape_condition (shape_condition_index, frequency), shape_condition_sliding_velocity,
             shape_condition_roughness_ra, shape_condition_normal_load (shape_condition_index)
                                               per-condition shapes, when the shape depends on the condition
    attrs    amplitude_residual_variance, amplitude_residual_relative, amplitude_df_resid
                                               for prediction intervals (fivid.friction.prediction)
             shape_dependence                  "one shape" or "per condition" (and the test's p-value,
                                               written by fivid.identify)

Version-1 files have no domain variables: :func:`domain_from_dataset` then takes the conditions of
the used runs of the per-run table, when there is one.

:mod:`fivid.identify` adds the per-run table (dim ``run``) and the candidate-form table (dim ``form``)
to the same dataset; :func:`load_law` ignores what it does not need.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from fivid import __version__
from fivid.errors import FividError, SchemaError
from fivid.friction.amplitude import REFERENCE_SCALES, AmplitudeModel, coefficient_units
from fivid.friction.domain import ConditionDomain
from fivid.friction.laws import CoulombLaw, PerturbedCoulombLaw
from fivid.storage import check_writable, write_netcdf

__all__ = ["LAW_FILE_VERSION", "READABLE_VERSIONS", "law_dataset", "law_from_dataset", "load_law", "write_law",
           "domain_from_dataset"]

LAW_FILE_VERSION = 2
#: versions :func:`law_from_dataset` reads
READABLE_VERSIONS = (1, 2)


def law_dataset(law, *, mu0_ci=None, confidence: float = 0.95, attrs: dict | None = None, domain=None):
    """The law-file content of a law object, as an xarray Dataset.

    Parameters
    ----------
    law : CoulombLaw or PerturbedCoulombLaw
    mu0_ci : (float, float), optional
        Confidence interval of μ0 [-].
    confidence : float, default 0.95
        Level of ``mu0_ci``.
    attrs : dict, optional
        Extra global attributes (provenance, settings).
    domain : ConditionDomain, optional
        The conditions the amplitude law was identified at.
    """
    import xarray as xr

    mu0_attrs = {"units": "1", "long_name": "mean friction coefficient", "confidence": confidence}
    if mu0_ci is not None:
        mu0_attrs["ci_lower"], mu0_attrs["ci_upper"] = (float(x) for x in mu0_ci)
    base = {
        "title": "fivid friction law",
        "law_file_version": LAW_FILE_VERSION,
        "fivid_version": __version__,
        "injection": law.injection,
        "law_sha256": law.sha256,
        "Conventions": "CF-1.8",
    }
    if isinstance(law, CoulombLaw):
        ds = xr.Dataset({"mu0": ((), law.mu0, mu0_attrs)}, attrs={**base, "law": "coulomb"})
    elif isinstance(law, PerturbedCoulombLaw):
        m = law.amplitude_model
        names = list(m.names)
        ds = xr.Dataset(
            {
                "mu0": ((), law.mu0, mu0_attrs),
                "shape": (
                    "frequency",
                    law.shape,
                    {"units": "Hz-1", "long_name": "normalised one-sided PSD shape of the friction perturbation"},
                ),
                "amplitude_coefficient": (
                    "coefficient",
                    np.asarray(m.coefficients, float),
                    {"long_name": f"coefficients of the amplitude law ({m.form})", "units": "1",
                     "comment": "units per coefficient: see fivid.friction.amplitude (SI: s m-1 for "
                     "velocity_slope, N-1 for load_slope, 1 otherwise)"},
                ),
                "amplitude_stderr": ("coefficient", np.asarray(m.stderr, float), {"long_name": "standard errors"}),
                "amplitude_covariance": (
                    ("coefficient", "coefficient_b"),
                    np.asarray(m.covariance, float).reshape(len(names), len(names)),
                    {"long_name": "covariance of the amplitude-law coefficients"},
                ),
                "amplitude_coefficient_units": ("coefficient", np.array([coefficient_units(n) for n in names],
                                                                          dtype=object)),
                "roughness_levels": (
                    "roughness_level",
                    np.asarray(m.roughness_levels, float),
                    {"units": "m", "long_name": "roughness levels of the linear amplitude forms"},
                ),
            },
            coords={
                "frequency": ("frequency", law.shape_frequency, {"units": "Hz", "long_name": "frequency"}),
                "coefficient": ("coefficient", np.array(names, dtype=object)),
                "coefficient_b": ("coefficient_b", np.array(names, dtype=object)),
            },
            attrs={
                **base,
                "law": "perturbed_coulomb",
                "amplitude_form": m.form,
                "amplitude_terms": ",".join(m.terms),
                "band_lower": law.band[0],
                "band_upper": law.band[1],
                "band_units": "Hz",
                "reference_velocity": np.nan if law.reference_velocity is None else law.reference_velocity,
                "reference_velocity_units": "m s-1",
                **{f"reference_{k}": v for k, v in REFERENCE_SCALES.items()},
                "amplitude_residual_variance": float(m.residual_variance),
                "amplitude_residual_relative": int(m.residual_relative),
                "amplitude_df_resid": float(m.df_resid),
                "shape_dependence": "one shape" if law.condition_shapes is None else "per condition",
            },
        )
        if law.condition_shapes is not None:
            points, shapes = law.condition_shapes
            ds["shape_condition"] = (("shape_condition_index", "frequency"), shapes,
                                     {"units": "Hz-1", "long_name": "normalised shape at each test condition"})
            for j, (name, units) in enumerate(_CONDITIONS):
                ds[f"shape_condition_{name}"] = ("shape_condition_index", points[:, j], {"units": units})
    else:
        raise FividError(f"cannot write a law of type {type(law).__name__}; expected CoulombLaw or PerturbedCoulombLaw")
    if domain is not None:
        for j, (name, units) in enumerate(_CONDITIONS):
            ds[f"domain_{name}"] = ("domain_condition", domain.points[:, j],
                                    {"units": units, "long_name": f"{name} of the conditions the law was fitted on"})
    if attrs:
        ds.attrs.update(attrs)
    return ds


_CONDITIONS = (("sliding_velocity", "m s-1"), ("roughness_ra", "m"), ("normal_load", "N"))


def domain_from_dataset(ds):
    """The :class:`~fivid.friction.domain.ConditionDomain` of a law file, or None when it holds none.

    Version 2: the ``domain_*`` variables; version 1: the conditions of the used runs of the per-run
    table (``run_*``), when the file has one.
    """
    if "domain_sliding_velocity" in ds:
        cols = [ds[f"domain_{name}"].values for name, _ in _CONDITIONS]
    elif "run_sliding_velocity" in ds:
        used = ds["run_used"].values.astype(bool) if "run_used" in ds else np.ones(ds.sizes["run"], bool)
        cols = [ds[f"run_{name}"].values[used] for name, _ in _CONDITIONS]
    else:
        return None
    points = np.column_stack([np.asarray(c, float) for c in cols])
    if points.size == 0 or not np.all(np.isfinite(points) & (points > 0)):
        return None
    return ConditionDomain(points)


def _what_it_is(ds) -> str:
    """What a Dataset that is no law file looks like it is, for the error message."""
    if "run_id" in ds.attrs and "time" in ds.dims:
        return (f"a RunDataset (run {str(ds.attrs['run_id'])!r}: time series as written by 'fivid ingest' or "
                "'fivid simulate')")
    names = ", ".join(list(map(str, ds.data_vars))[:6]) or "none"
    return f"a netCDF file with variables {names} and no law attributes"


def law_from_dataset(ds, *, source: str = "", file=None):
    """The law object described by a law-file Dataset (see the module docstring).

    Errors are :class:`~fivid.errors.SchemaError` located at ``file`` when given, else prefixed by
    ``source``.
    """
    where = source or "law dataset"

    def error(text: str) -> SchemaError:
        return SchemaError(text, file=file) if file is not None else SchemaError(f"{where}: {text}")

    kind = ds.attrs.get("law")
    version = ds.attrs.get("law_file_version")
    if version is None:
        raise error(f"not a fivid friction-law file: it has no 'law_file_version' attribute and is "
                    f"{_what_it_is(ds)}; give the law file written by 'fivid identify ... -o LAW.nc'")
    if version not in READABLE_VERSIONS:
        raise error(f"law_file_version {version!r}; this fivid reads versions "
                    f"{', '.join(map(str, READABLE_VERSIONS))}")
    if "mu0" not in ds:
        raise error("variable 'mu0' is missing")
    mu0 = float(ds["mu0"].values)
    injection = ds.attrs.get("injection", "uniform")
    if kind == "coulomb":
        return CoulombLaw(mu0, injection=injection)
    if kind != "perturbed_coulomb":
        raise error(f"attribute law = {kind!r}; expected 'coulomb' or 'perturbed_coulomb'")
    missing = [v for v in ("shape", "amplitude_coefficient", "amplitude_stderr", "amplitude_covariance") if v not in ds]
    missing += [a for a in ("amplitude_form", "band_lower", "band_upper") if a not in ds.attrs]
    if missing:
        raise error(f"missing {', '.join(missing)} (not a fivid law file?)")
    terms = tuple(t for t in str(ds.attrs.get("amplitude_terms", "")).split(",") if t)
    model = AmplitudeModel(
        form=str(ds.attrs["amplitude_form"]),
        coefficients=np.asarray(ds["amplitude_coefficient"].values, float),
        names=tuple(str(n) for n in ds["coefficient"].values),
        stderr=np.asarray(ds["amplitude_stderr"].values, float),
        covariance=np.asarray(ds["amplitude_covariance"].values, float),
        terms=terms,
        roughness_levels=tuple(float(r) for r in ds["roughness_levels"].values) if "roughness_levels" in ds else (),
        residual_variance=float(ds.attrs.get("amplitude_residual_variance", np.nan)),
        residual_relative=bool(ds.attrs.get("amplitude_residual_relative", 0)),
        df_resid=float(ds.attrs.get("amplitude_df_resid", np.nan)),
    )
    condition_shapes = None
    if "shape_condition" in ds:
        condition_shapes = (np.column_stack([ds[f"shape_condition_{name}"].values for name, _ in _CONDITIONS]),
                            ds["shape_condition"].values)
    ref = ds.attrs.get("reference_velocity")
    ref = None if ref is None or not np.isfinite(ref) else float(ref)
    return PerturbedCoulombLaw(
        mu0,
        ds["frequency"].values,
        ds["shape"].values,
        model,
        (float(ds.attrs["band_lower"]), float(ds.attrs["band_upper"])),
        injection=injection,
        reference_velocity=ref,
        source=source,
        condition_shapes=condition_shapes,
    )


def load_law(path: str | os.PathLike):
    """Read a law file written by ``fivid identify`` (or :func:`write_law`).

    Returns
    -------
    CoulombLaw or PerturbedCoulombLaw

    Raises
    ------
    FividError
        The file does not exist.
    SchemaError
        It is not a readable fivid law file.
    """
    import hashlib

    from fivid.io.netcdf import read_run  # lazy: pulls pydantic

    path = Path(path)
    ds = read_run(path, validate=False)  # the same opening and error messages as a run file
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    return law_from_dataset(ds, source=f"{path.name} sha256:{digest}", file=path)


def write_law(law_or_dataset, path: str | os.PathLike, *, overwrite: bool = False) -> Path:
    """Write a law (object or law-file Dataset) to ``path`` atomically; returns the path.

    The Dataset is read back into a law object first, so nothing unloadable is ever written.
    """
    ds = law_or_dataset if hasattr(law_or_dataset, "data_vars") else law_dataset(law_or_dataset)
    law_from_dataset(ds, source=str(path))
    check_writable(path, overwrite=overwrite)
    return write_netcdf(ds, path, overwrite=overwrite)
