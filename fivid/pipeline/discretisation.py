"""Which mesh the pipeline simulated with and its estimated discretisation error in the scored band.

The estimate comes from a shipped *convergence table*: the ``convergence`` block of the summary of a mesh and
time-step study (``fivid study configs/studies/convergence.yaml``, :mod:`fivid.study.convergence`), with the
model files it covers. The calibration pipeline looks for ``convergence.json`` next to its run configuration
(``configs/runs/convergence.json`` for the shipped runs); the run configuration cannot name another file yet
(``discretisation.convergence`` is read from the parsed configuration with that default, see docs/pipeline.md).

For the pipeline's model (matched by file name, then checked by its largest element side ``h``) and scoring band
``[f1, f2]``:

- ``band_level_error_db``: ``|band_level_deviation_db|``, the model's mesh's level of the scoring band minus
  the Richardson-extrapolated level (the finest mesh's where the three levels do not converge monotonically),
  computed from the study's PSDs of the three meshes (at the solver's step) that the table carries, with the
  scores' bin weights (:func:`fivid.signal.levels.bin_weights`, as ``level_diff_db``);
  ``band_lsd_db``: the log-spectral distance between the model's mesh's PSD and the finest mesh's over the
  band's bins (the study's record: one realisation, the same seed on every mesh). A table without PSDs gives
  instead the largest error over the one-third-octave bands the scoring band overlaps: a band's power is the
  sum of its parts' powers, so if every part is off by a factor within ``[a, b]`` the band is too;
- ``third_octaves``: the breakdown, each one-third-octave band with its level error on the model's mesh, observed
  order and reference: from the PSDs, exactly the bands of the scores' ``band_level_error_db`` (IEC 61260-1
  base-10 bands inside the scoring band, :func:`fivid.signal.levels.third_octave_weights`); from a table without
  PSDs, its bands (the same IEC grid over the study's PSD range) that overlap the scoring band;
- ``peaks``: each prominent PSD peak inside the band, its frequency shift on the model's mesh [Hz] and that shift
  in Welch bins of the scoring (``sample_rate / nperseg``); ``peak_shift_bins`` the largest;
- ``time_step``: the largest PSD log-spectral distance [dB] between the solver's step and the smallest step of
  the study, on the model's mesh.

``python -m fivid.pipeline.discretisation configs/studies/convergence.yaml STUDY_OUT -o configs/runs/convergence.json
--model configs/models/triboair_coarse.yaml 0.25 --model configs/models/triboair.yaml 1`` writes the convergence
table from a finished study folder.
"""

from __future__ import annotations

import argparse
import json
import logging
from pathlib import Path

import numpy as np

from fivid.fe import load_model
from fivid.pipeline.cache import file_sha256
from fivid.signal.compare import band_distance, band_levels_db
from fivid.signal.levels import bin_weights, third_octave_weights
from fivid.storage import write_json
from fivid.study import load_study
from fivid.study.convergence import BAND_LEVEL_REFERENCE, observed_order
from fivid.study.tasks import element_size, refined_model

__all__ = ["DEFAULT_TABLE", "discretisation_estimate", "model_mesh", "write_convergence_table"]

log = logging.getLogger("fivid")

#: the convergence table the pipeline looks for next to its run configuration
DEFAULT_TABLE = "convergence.json"
#: relative tolerance on the element size when a model is matched to a mesh of the study
H_TOLERANCE = 1e-6


def model_mesh(model_path) -> dict:
    """The model the pipeline simulates with: name, path, sha256, largest element side [m], dofs."""
    model = load_model(model_path)
    name = model.config.get("name") if isinstance(model.config, dict) else None
    return {"name": name or Path(model_path).stem, "path": str(model_path), "sha256": file_sha256(model_path),
            "element_size": element_size(model), "dofs": int(model.n_dofs),
            "damping": "band-limited Rayleigh" if np.isfinite(model.damping_cutoff) else "Rayleigh"}


def _pick(deviation, h_list, h) -> float | None:
    for k, hk in enumerate(h_list):
        if abs(hk - h) <= H_TOLERANCE * h:
            return float(deviation[k])
    return None


def _part(band, oo, h) -> dict:
    """One one-third-octave band of the breakdown: its level's deviation on the model's mesh [dB], order, reference."""
    return {"band": [float(band[0]), float(band[1])], "deviation_db": _pick(oo["deviation"], oo["h"], h),
            "order": oo["order"], "reference": "extrapolated" if oo["order"] is not None else "finest mesh"}


def _from_spectra(spectra: dict, h: float, lo: float, hi: float) -> tuple[dict, list[dict]]:
    """Band level error, its order and the LSD to the finest mesh in ``[lo, hi]`` [Hz], and the breakdown over the
    scores' one-third-octave bands, from the table's PSDs of the meshes (the scores' band grid and bin weights:
    :func:`fivid.signal.levels.third_octave_weights`, :func:`fivid.signal.compare.band_distance`)."""
    f = np.asarray(spectra["frequency"], float)
    psd = np.asarray(spectra["psd"], float)  # (mesh, frequency)
    hs = [float(x) for x in spectra["element_size"]]
    k_model = next(k for k, x in enumerate(hs) if abs(x - h) <= H_TOLERANCE * h)
    # Richardson needs three meshes: the three finest, the model's among them (else the two finest and it)
    three = [int(k) for k in np.argsort(hs)[:3]]
    if k_model not in three:
        three = three[:2] + [k_model]
    h3 = [hs[k] for k in three]
    oo = observed_order(h3, band_levels_db(psd[three], bin_weights(f, lo, hi), reference=BAND_LEVEL_REFERENCE))
    dev = _pick(oo["deviation"], oo["h"], h)
    lsd, _ = band_distance(f, psd[int(np.argmin(hs))], psd[k_model], (lo, hi))
    thirds, weights = third_octave_weights(f, lo, hi, min_bins=1.0)
    levels = band_levels_db(psd[three], weights, reference=BAND_LEVEL_REFERENCE)  # (3, band)
    parts = [_part(band, observed_order(h3, levels[:, b]), h)
             for b, band in enumerate(zip(thirds["lower"], thirds["upper"]))]
    return ({"band_level_error_db": abs(dev), "band_level_deviation_db": dev, "band_level_order": oo["order"],
             "band_lsd_db": lsd if np.isfinite(lsd) else None}, parts)


def discretisation_estimate(model_path, band, table_path, *, bin_width: float) -> dict:
    """The model's mesh and its estimated discretisation error in ``band`` [Hz] (module docstring).

    Parameters
    ----------
    model_path : path-like
        The pipeline's model file.
    band : (float, float)
        Scoring band [Hz].
    table_path : path-like or None
        Convergence table (JSON, :func:`write_convergence_table`); None or a missing file: no estimate.
    bin_width : float
        Welch bin of the scoring [Hz] (sample rate / nperseg).

    Returns
    -------
    dict
        ``model`` (:func:`model_mesh`), ``band`` [Hz], ``covered`` (the table has this model's mesh), ``table``
        (path, sha256, source), and when covered ``band_level_error_db``, ``band_level_deviation_db``,
        ``band_level_order``, ``band_lsd_db``, ``third_octaves``, ``peaks``, ``peak_shift_bins``,
        ``time_step_lsd_db``, ``reference`` (what the errors are measured against).
    """
    mesh = model_mesh(model_path)
    out = {"model": mesh, "band": [float(band[0]), float(band[1])], "covered": False, "table": None}
    if table_path is None or not Path(table_path).is_file():
        out["reason"] = "no convergence table" + (f" ({table_path})" if table_path else "")
        return out
    table = json.loads(Path(table_path).read_text(encoding="utf-8"))
    out["table"] = {"path": str(table_path), "sha256": file_sha256(table_path), "source": table.get("source")}
    entry = table.get("models", {}).get(Path(model_path).name)
    h = mesh["element_size"]
    if entry is None or abs(float(entry["element_size"]) - h) > H_TOLERANCE * h:
        out["reason"] = (f"model {Path(model_path).name} (element size {h * 1e3:.4g} mm) is not a mesh of the "
                         f"convergence table")
        return out
    conv = table["convergence"]
    # the solver's own step: the largest time step of the study (mesh entries are per step)
    meshes = sorted(conv.get("mesh", []), key=lambda e: -float(e["conditions"].get("time_step", 1.0)))
    m = next((e for e in meshes if _pick(e["element_size"], e["element_size"], h) is not None), None)
    if m is None:
        out["reason"] = f"element size {h * 1e3:.4g} mm is not among the study's meshes"
        return out
    lo, hi = band
    parts = []
    for b in m.get("band_level_db", [])[:-1]:  # the last entry is the whole PSD range
        if b["band"][1] > lo and b["band"][0] < hi:
            parts.append(_part(b["band"], b, h))
    level = {"band_level_error_db": max((abs(o["deviation_db"]) for o in parts), default=None),
             "band_level_deviation_db": None, "band_level_order": None, "band_lsd_db": None}
    spectra = table.get("psd")
    if spectra and _pick(spectra["element_size"], spectra["element_size"], h) is not None:
        level, parts = _from_spectra(spectra, h, lo, hi)
    peaks = []
    for p in m.get("psd_peak_frequency", []):
        if lo <= p["peak"] <= hi:
            d = _pick(p["deviation"], p["h"], h)
            peaks.append({"frequency": p["extrapolated"] if p["order"] is not None else p["values"][0],
                          "shift_hz": d, "shift_bins": abs(d) / bin_width, "order": p["order"]})
    lsd = [s["lsd_db"] for s in conv.get("time_step", [])
           if abs(float(s["conditions"].get("mesh", 0.0)) - float(entry.get("mesh", np.nan))) < 1e-12]
    out.update(
        covered=True, element_sizes=m["element_size"], conditions=m["conditions"], third_octaves=parts, **level,
        peaks=peaks, peak_shift_bins=max((p["shift_bins"] for p in peaks), default=0.0),
        time_step_lsd_db=max(lsd, default=None),
        reference="Richardson extrapolation over the study's three meshes where they converge monotonically, "
                  "else the finest mesh", note=entry.get("note"))
    return out


def write_convergence_table(study_dir, out, models: dict[str, dict]) -> Path:
    """Write a convergence table from a finished study folder (its ``summary.json``).

    ``models``: ``{model file name: {"element_size": h [m], "mesh": study mesh factor, "note": str}}``.
    """
    import xarray as xr

    summary = json.loads((Path(study_dir) / "summary.json").read_text(encoding="utf-8"))
    if "convergence" not in summary:
        raise ValueError(f"{study_dir}/summary.json has no 'convergence' block: not a mesh or time-step study")
    source = {k: summary.get(k) for k in ("study", "description", "source", "fivid_version", "quick", "n_points", "n_done")
              if summary.get(k) is not None}
    table = {"fivid-convergence": 1, "source": source, "models": models, "convergence": summary["convergence"]}
    with xr.open_dataset(Path(study_dir) / "study.nc") as ds:
        if "psd" in ds and "time_step" in ds.coords and "mesh" in ds.coords:
            step = float(ds["time_step"].max())  # the solver's step: the largest of the study
            idx = np.flatnonzero(ds["time_step"].values == step)
            h = ds["element_size"].values[idx]
            if np.unique(h).size == idx.size:  # one point per mesh (no other swept condition): PSDs by mesh
                idx = idx[np.argsort(h)]
                table["psd"] = {"time_step": step, "element_size": ds["element_size"].values[idx].tolist(),
                                "frequency": ds["frequency"].values.tolist(), "units": ds["psd"].attrs.get("units"),
                                "psd": ds["psd"].values[idx].tolist()}
    return write_json(out, table)


def main(argv=None) -> Path:
    """``python -m fivid.pipeline.discretisation``: write the convergence table; returns its path (logged)."""
    p = argparse.ArgumentParser(prog="python -m fivid.pipeline.discretisation",
                                description="Write the pipeline's convergence table from a finished mesh/time-step study.")
    p.add_argument("study", help="the study config, e.g. configs/studies/convergence.yaml")
    p.add_argument("study_dir", help="its output folder (fivid study STUDY -o STUDY_DIR, finished)")
    p.add_argument("-o", "--output", required=True, help="the table, e.g. configs/runs/convergence.json")
    p.add_argument("--model", action="append", nargs=2, metavar=("MODEL.yaml", "MESH_FACTOR"), default=[],
                   help="a model file the table covers and the study's mesh factor whose element size it has")
    p.add_argument("--note", action="append", nargs=2, metavar=("MODEL.yaml", "TEXT"), default=[],
                   help="what differs between that model and the study's mesh (shown in the report)")
    args = p.parse_args(argv)
    notes = {Path(path).name: text for path, text in args.note}
    study_model = load_study(args.study).model_path
    models = {}
    for path, factor in args.model:
        h = element_size(load_model(path))
        h_study = element_size(refined_model(study_model, float(factor)))
        if abs(h_study - h) > H_TOLERANCE * h:
            p.error(f"{path}: element size {h:g} m differs from the study's mesh x{factor} ({h_study:g} m)")
        models[Path(path).name] = {"element_size": h, "mesh": float(factor), "note": notes.get(Path(path).name)}
    path = write_convergence_table(args.study_dir, args.output, models)
    log.info("wrote the convergence table %s", path)
    return path


if __name__ == "__main__":
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    main()
