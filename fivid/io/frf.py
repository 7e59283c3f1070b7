"""Reader for measured frequency response functions (CSV with units in the header).

Layout::

    # fivid-frf-csv: 1
    # normal_load: 2 N
    # excitation_amplitude: 2 N
    frequency [Hz],amplitude [m],phase [deg]
    15.0,1.2e-5,-3.1

The response is given either as ``amplitude`` (and optionally ``phase`` in deg or rad) or as
``real`` and ``imag``. Its unit says what it is: a displacement (``m``, ``mm``...) or a receptance
(``m/N``, ``m N-1``...). Both are returned in SI with their kind.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fivid.errors import DataQualityError, FividError, SchemaError, UnitError
from fivid.io.hysteresis import numeric_columns, read_units_csv
from fivid.units import conversion, is_compatible, parse_quantity

__all__ = ["MeasuredFRF", "read_frf_csv"]



@dataclass(frozen=True)
class MeasuredFRF:
    """A measured FRF in SI units.

    Attributes
    ----------
    frequency : ndarray
        [Hz], strictly increasing.
    response : ndarray of complex
        Displacement [m] or receptance [m/N]; real (zero phase) when only amplitudes were given.
    kind : str
        ``'displacement'`` or ``'receptance'``.
    normal_load : float or None
        [N], from the ``# normal_load:`` line.
    excitation_amplitude : float or None
        [N], from the ``# excitation_amplitude:`` line.
    metadata : dict
    has_phase : bool
        False when the file gave amplitudes only.
    """

    frequency: np.ndarray
    response: np.ndarray
    kind: str
    normal_load: float | None = None
    excitation_amplitude: float | None = None
    metadata: dict = field(default_factory=dict)
    has_phase: bool = True

    def displacement_amplitude(self, excitation_amplitude: float | None = None) -> np.ndarray:
        """``|response|`` as a displacement amplitude [m] (receptance times the force amplitude [N])."""
        amp = np.abs(self.response)
        if self.kind == "displacement":
            return amp
        p = excitation_amplitude if excitation_amplitude is not None else self.excitation_amplitude
        if p is None:
            raise FividError("a receptance FRF needs the excitation amplitude to give displacements")
        return amp * p


def read_frf_csv(path) -> MeasuredFRF:
    """Read a measured FRF CSV (see the module docstring)."""
    path = Path(path)
    if not path.is_file():
        raise FividError("no such file", file=path)
    meta, hline, header, body = read_units_csv(path, "frequency [Hz],amplitude [m],phase [deg]")
    cols = {name: j for name, (j, _) in header.items()}
    units = {name: unit for name, (_, unit) in header.items()}
    if "frequency" not in cols:
        raise SchemaError("missing column 'frequency [Hz]'", file=path, line=hline)
    if "amplitude" in cols:
        value_cols = ["amplitude"] + (["phase"] if "phase" in cols else [])
    elif "real" in cols and "imag" in cols:
        value_cols = ["real", "imag"]
    else:
        raise SchemaError("need 'amplitude' (optionally 'phase') or 'real' and 'imag' columns", file=path, line=hline)
    resp_unit = units[value_cols[0]]
    if is_compatible(resp_unit, "m"):
        kind, si = "displacement", "m"
    elif is_compatible(resp_unit, "m N-1"):
        kind, si = "receptance", "m N-1"
    else:
        raise UnitError(f"response unit {resp_unit!r} is neither a displacement (m) nor a receptance (m/N)",
                        file=path, line=hline, column=value_cols[0])
    scale = conversion(resp_unit, si)[0]
    f_scale = _scale(units["frequency"], "Hz", path, hline, "frequency")
    arr = numeric_columns(path, body, [cols[c] for c in ["frequency"] + value_cols])
    if arr.shape[0] < 2:
        raise DataQualityError(f"only {arr.shape[0]} frequency rows", file=path)
    freq = arr[:, 0] * f_scale
    if np.any(np.diff(freq) <= 0):
        raise DataQualityError("frequencies must be strictly increasing", file=path, column="frequency")
    if value_cols[0] == "real":
        if units["imag"] != resp_unit:
            raise UnitError(f"'real' and 'imag' must have the same unit ({resp_unit!r} vs {units['imag']!r})",
                            file=path, line=hline, column="imag")
        resp = (arr[:, 1] + 1j * arr[:, 2]) * scale
    else:
        amp = arr[:, 1] * scale
        if np.any(amp < 0):
            raise DataQualityError("negative amplitudes", file=path, column="amplitude")
        phase = arr[:, 2] * _scale(units["phase"], "rad", path, hline, "phase") if "phase" in value_cols else 0.0
        resp = amp * np.exp(1j * phase)
    if not np.all(np.isfinite(freq)) or not np.all(np.isfinite(np.abs(resp))):
        raise DataQualityError("non-finite values in the FRF", file=path)

    def load(key):
        if key not in meta:
            return None
        try:
            return parse_quantity(meta[key], "N")
        except FividError as exc:
            raise UnitError(exc.message, file=path, key=key) from None

    return MeasuredFRF(frequency=freq, response=resp, kind=kind, normal_load=load("normal_load"),
                       excitation_amplitude=load("excitation_amplitude"), metadata=meta,
                       has_phase=value_cols != ["amplitude"])


def _scale(unit: str, to: str, path, line, column) -> float:
    try:
        return conversion(unit, to)[0]
    except FividError as exc:
        raise UnitError(exc.message, file=path, line=line, column=column) from None
