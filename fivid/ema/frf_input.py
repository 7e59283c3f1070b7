"""FRFs for experimental modal analysis, from the three inputs ``fivid ema`` takes.

* **UFF58** (``.uff``, ``.unv``; read with pyuff): every dataset 58 of function type 4 (FRF). Each record's
  response node and direction name the measured DOF; its reference node and direction the input. The FRF
  form comes from the ordinate's specific data type (8 displacement, 11 velocity, 12 acceleration) or, when
  that is 0 (unknown, as ``fivid export`` writes), from the ordinate's unit label over N.
* **FRF netCDF** (``.nc`` with a ``frequency`` dimension): every complex variable along ``frequency``, or every
  pair ``NAME_real``/``NAME_imag``; a second dimension (``sensor``, ``dof``) gives one FRF per label. The
  FRF form comes from the variable's ``units``. Optional attributes ``node``, ``direction`` (and on the
  dataset ``reference_node``, ``reference_direction``) name the DOFs.
* **Run dataset** (``.nc`` with a ``time`` dimension, a RunDataset): H1 FRFs (:func:`fivid.signal.frf`) of
  each response channel (``acceleration`` per sensor by default) to a force channel, with their coherence.

All FRFs of one analysis share one reference (SIMO) and one frequency axis.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fivid.errors import FividError, SchemaError, UnitError
from fivid.io.daq.channels import require
from fivid.signal import frf
from fivid.units import is_compatible

__all__ = ["FRFSet", "read_frfs", "frf_form_of_units"]

_DIRECTIONS = {1: "+x", 2: "+y", 3: "+z", -1: "-x", -2: "-y", -3: "-z", 0: "?"}
_FORM_OF_TYPE = {8: "receptance", 11: "mobility", 12: "accelerance"}


@dataclass(frozen=True)
class FRFSet:
    """FRFs of several measured DOFs to one reference.

    Attributes
    ----------
    frequency : ndarray, shape (n_f,)
        [Hz].
    frf : ndarray of complex, shape (n_dofs, n_f)
    node : list of int
        Response node of each DOF.
    direction : list of str
        Response direction of each DOF (``+x``, ``-z``, ``y`` for a sensor direction ...).
    name : list of str
        Channel names.
    form : str
        ``receptance``, ``mobility`` or ``accelerance``.
    units : str
        Units of the FRFs.
    reference : tuple
        ``(node, direction)`` of the input, when known.
    coherence : ndarray or None, shape (n_dofs, n_f)
        Ordinary coherence (run datasets).
    sources : list of str
        The files read.
    """

    frequency: np.ndarray
    frf: np.ndarray
    node: list
    direction: list
    name: list
    form: str
    units: str
    reference: tuple = (None, None)
    coherence: np.ndarray | None = None
    sources: list = field(default_factory=list)

    @property
    def driving_point(self) -> int | None:
        """Index of the DOF measured at the reference, if any."""
        for k, (n, d) in enumerate(zip(self.node, self.direction)):
            if self.reference[0] is not None and n == self.reference[0] and d == self.reference[1]:
                return k
        return None


def frf_form_of_units(units: str, *, file=None, what: str = "FRF") -> str:
    """``receptance`` (length/force), ``mobility`` (velocity/force) or ``accelerance`` (acceleration/force)."""
    for form, si in (("receptance", "m N-1"), ("mobility", "m s-1 N-1"), ("accelerance", "m s-2 N-1")):
        if units and is_compatible(units, si):
            return form
    raise UnitError(f"the {what}'s unit {units!r} is not a displacement, velocity or acceleration per force "
                    "(m/N, m/s/N, m/s^2/N); give --form", file=file)


def read_frfs(paths, *, form: str | None = None, force: str = "friction_force", response: str = "acceleration",
              nperseg: int | None = None) -> FRFSet:
    """Read FRFs from UFF58 files, FRF netCDF files or run datasets (see the module docstring).

    Parameters
    ----------
    paths : sequence of path-like
        One or more files of one kind; their FRFs are stacked (same frequency axis required).
    form : str, optional
        Override the FRF form.
    force, response : str
        Run datasets: the input variable and the response variable (one FRF per sensor).
    nperseg : int, optional
        Run datasets: Welch segment length (default: :func:`fivid.signal.welch.default_nperseg`).
    """
    sets = []
    for p in paths:
        path = Path(p)
        if not path.is_file():
            raise FividError(f"cannot read {str(path)!r}: no such file", file=path)
        suffix = path.suffix.lower()
        if suffix in (".uff", ".unv", ".uf"):
            sets.append(_read_uff(path, form))
        elif suffix in (".nc", ".nc4", ".netcdf"):
            sets.append(_read_netcdf(path, form, force, response, nperseg))
        else:
            raise FividError(f"unknown FRF file type {path.suffix!r}; give UFF58 (.uff, .unv) or netCDF (.nc: an FRF "
                             "dataset or a run dataset)", file=path)
    if form is not None and form not in ("receptance", "mobility", "accelerance"):
        raise FividError(f"--form must be receptance, mobility or accelerance, got {form!r}")
    first = sets[0]
    for s in sets[1:]:
        if s.frequency.shape != first.frequency.shape or not np.allclose(s.frequency, first.frequency, rtol=1e-9):
            raise FividError(f"{s.sources[0]} has another frequency axis than {first.sources[0]}; all FRFs of one "
                             "analysis need the same lines", file=s.sources[0])
        if s.form != first.form:
            raise FividError(f"{s.sources[0]} holds {s.form} FRFs, {first.sources[0]} {first.form}", file=s.sources[0])
        if s.reference != first.reference:
            raise FividError(f"{s.sources[0]} has reference {s.reference}, {first.sources[0]} {first.reference}: "
                             "one analysis takes FRFs of one reference", file=s.sources[0])
    coh = None
    if all(s.coherence is not None for s in sets):
        coh = np.concatenate([s.coherence for s in sets])
    out = FRFSet(first.frequency, np.concatenate([s.frf for s in sets]), sum((s.node for s in sets), []),
                 sum((s.direction for s in sets), []), sum((s.name for s in sets), []), first.form,
                 first.units, first.reference, coh, sum((s.sources for s in sets), []))
    return out


def _read_uff(path: Path, form) -> FRFSet:
    pyuff = require("pyuff", "pyuff", "UFF58 input")
    try:
        raw = pyuff.UFF(str(path)).read_sets()
    except Exception as exc:  # pyuff raises assorted types on malformed files
        raise FividError(f"cannot read UFF file: {type(exc).__name__}: {exc}", file=path) from None
    records = raw if isinstance(raw, list) else [raw]
    frfs = [r for r in records if r.get("type") == 58 and int(r.get("func_type", 0)) == 4]
    if not frfs:
        raise FividError("no FRF record (UFF dataset 58 with function type 4) in the file", file=path)
    x = np.asarray(frfs[0]["x"], dtype=float)
    rows, nodes, dirs, names, forms = [], [], [], [], set()
    refs = {(int(r.get("ref_node", 0)), _DIRECTIONS.get(int(r.get("ref_dir", 0)), "?")) for r in frfs}
    if len(refs) > 1:
        raise FividError(f"the file holds FRFs of {len(refs)} references {sorted(refs)}; EMA here takes one "
                         "reference (SIMO)", file=path)
    units = ""
    for k, r in enumerate(frfs):
        xr_ = np.asarray(r["x"], dtype=float)
        if xr_.shape != x.shape or not np.allclose(xr_, x, rtol=1e-9):
            raise FividError(f"record {k + 1} ('{r.get('id1', '')}') has another frequency axis than record 1",
                             file=path)
        units = str(r.get("ordinate_axis_units_lab", ""))
        spec = int(r.get("ordinate_spec_data_type", 0))
        if form is not None:
            forms.add(form)
        elif spec in _FORM_OF_TYPE:
            forms.add(_FORM_OF_TYPE[spec])
        else:
            forms.add(frf_form_of_units(_uff_units(units), file=path, what=f"record {k + 1}"))
        rows.append(np.asarray(r["data"], dtype=complex))
        nodes.append(int(r.get("rsp_node", k + 1)))
        dirs.append(_DIRECTIONS.get(int(r.get("rsp_dir", 0)), "?"))
        names.append(str(r.get("id1", f"frf{k + 1}")).strip() or f"frf{k + 1}")
    if len(forms) > 1:
        raise FividError(f"the file mixes FRF forms {sorted(forms)}", file=path)
    ref = refs.pop()
    return FRFSet(x, np.array(rows), nodes, dirs, names, forms.pop(), units, ref if ref[0] else (None, None),
                  None, [str(path)])


def _uff_units(label: str) -> str:
    """A UFF ordinate label, which may omit the force: ``m/s^2`` over an FRF is per newton only when said."""
    text = label.strip()
    return text if "N" in text else f"({text})/N" if text else "1"


def _read_netcdf(path: Path, form, force: str, response: str, nperseg) -> FRFSet:
    import xarray as xr

    try:
        ds = xr.open_dataset(path)
    except Exception as exc:
        raise FividError(f"cannot open as netCDF: {type(exc).__name__}: {exc}", file=path) from None
    with ds:
        ds.load()
    if "time" in ds.dims:
        return _run_frfs(ds, path, form, force, response, nperseg)
    if "frequency" not in ds.dims:
        raise SchemaError(f"the netCDF has dimensions {dict(ds.sizes)}: expected an FRF dataset (frequency) or a run "
                          "dataset (time)", file=path)
    f = ds["frequency"].values.astype(float)
    chans = []
    for name, var in ds.data_vars.items():
        if "frequency" not in var.dims or var.ndim > 2:
            continue
        if np.iscomplexobj(var.values):
            chans.append((str(name), var))
        elif str(name).endswith("_real") and f"{str(name)[:-5]}_imag" in ds:
            base = str(name)[:-5]
            chans.append((base, (var + 1j * ds[f"{base}_imag"]).assign_attrs(var.attrs)))
    if not chans:
        raise SchemaError("no FRF in the file: expected complex variables along 'frequency' or NAME_real/NAME_imag "
                          "pairs", file=path)
    rows, nodes, dirs, names, forms, units = [], [], [], [], set(), ""
    for name, var in chans:
        units = str(var.attrs.get("units", ""))
        forms.add(form or frf_form_of_units(units, file=path, what=f"variable {name!r}"))
        if var.ndim == 1:
            items = [(name, var)]
        else:
            other = next(d for d in var.dims if d != "frequency")
            items = [(f"{name}:{lab}", var.sel({other: lab})) for lab in var[other].values]
        for label, v in items:
            rows.append(v.transpose("frequency").values.astype(complex))
            nodes.append(int(v.attrs.get("node", len(nodes) + 1)))
            dirs.append(str(v.attrs.get("direction", "?")))
            names.append(label)
    if len(forms) > 1:
        raise SchemaError(f"the file mixes FRF forms {sorted(forms)}", file=path)
    ref = (ds.attrs.get("reference_node"), ds.attrs.get("reference_direction"))
    ref = (int(ref[0]), str(ref[1])) if ref[0] is not None else (None, None)
    return FRFSet(f, np.array(rows), nodes, dirs, names, forms.pop(), units, ref, None, [str(path)])


def _run_frfs(ds, path, form, force: str, response: str, nperseg) -> FRFSet:
    for var, what in ((force, "force"), (response, "response")):
        if var not in ds:
            raise SchemaError(f"the run dataset has no {what} variable {var!r}; its variables: "
                              f"{', '.join(map(str, ds.data_vars))} (choose with --{what})", file=path)
    x = ds[force]
    if x.ndim != 1:
        raise SchemaError(f"the force {force!r} must be one channel along time, it has dims {x.dims}", file=path)
    y = ds[response]
    items = ([(f"{response}:{s}", y.sel(sensor=s), str(s)) for s in y["sensor"].values] if "sensor" in y.dims
             else [(response, y, "?")])
    rows, coh, names, dirs = [], [], [], []
    freq = units = None
    for name, yy, sensor in items:
        h = frf(x, yy.rename(name), nperseg=nperseg, estimator="H1")
        freq, units = h["frequency"].values, h.attrs["units"]
        rows.append(h.values)
        coh.append(h["coherence"].values)
        names.append(name)
        dirs.append(sensor)
    keep = freq > 0  # the DC line carries the means, not the dynamics
    return FRFSet(freq[keep], np.array(rows)[:, keep], list(range(1, len(rows) + 1)), dirs, names,
                  form or frf_form_of_units(units, file=path), units, (None, None), np.array(coh)[:, keep], [str(path)])
