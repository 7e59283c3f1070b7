"""A DAQ file as named channels, read through a rig profile like a rig CSV.

Every format reader (:mod:`fivid.io.daq.tdms`, ``uff``, ``mat``, ``lvm``, ``mdf``) returns a
:class:`ChannelFile`: channels by name with the unit the file states (if any), the file's metadata
as ``key -> text``, and an implicit time axis when the format has one (a waveform's start and
increment, an MDF master channel). From there everything is the rig-CSV path: the profile's
``columns`` name the channels, its ``metadata.in_file.keys`` the metadata keys, the file name and
``metadata.values`` add the rest (:func:`~fivid.io.rig_header.resolve_metadata`), and the columns
go through the same conversion, checks and assembly (:func:`~fivid.io.run_assembly.assemble_run`).
"""

from __future__ import annotations

import hashlib
import importlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fivid.errors import FividError, SchemaError, UnitError
from fivid.io.rig_header import RigHead, metadata_attribute, resolve_metadata, rig_csv_columns, table_columns
from fivid.io.rig_profile import RigProfile
from fivid.io.run_assembly import assemble_run, by_variable
from fivid.schema import registry
from fivid.units import conversion

__all__ = ["ChannelFile", "channel_head", "run_from_channels", "require"]


@dataclass
class ChannelFile:
    """What a DAQ file holds, before any profile is applied.

    Attributes
    ----------
    format : str
        Short name of the format (``"tdms"``, ``"uff58"``, ``"mat"``, ``"lvm"``, ``"mdf4"``).
    channels : dict
        ``name -> 1-D ndarray`` of the raw values, as the profile names them.
    units : dict
        ``name -> unit string`` for the channels whose unit the file states.
    metadata : dict
        ``key -> (text value, where)``: the file's properties and where each is (``"file property 'Run'"``).
    time : ndarray or None
        The time axis [s] the format implies (waveform start + increment, a master channel), used
        when the profile's time column is not a channel of the file.
    """

    format: str
    channels: dict = field(default_factory=dict)
    units: dict = field(default_factory=dict)
    metadata: dict = field(default_factory=dict)
    time: np.ndarray | None = None


def require(module: str, package: str, what: str):
    """Import optional ``module`` or raise a :class:`FividError` saying how to install it."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise FividError(f"reading {what} needs the {package} package, which is not installed: "
                         f"pip install 'fivid[daq]' (or pip install {package})") from None


def _time_name(profile: RigProfile) -> str:
    spec = profile.column("time")
    return "time" if spec is None else spec.name


def _fields(path: Path, profile: RigProfile, data: ChannelFile) -> tuple[list[str], dict]:
    """The channel names as header fields, and ``field -> channel``; the implicit time added as needed."""
    names = list(data.channels)
    if profile.format == "fivid-rig-csv":  # channels named by canonical names, units from the file
        fields = {}
        for name in names:
            if data.units.get(name):
                fields[f"{name} [{data.units[name]}]"] = name
            elif name.partition(":")[0] in registry().variables:
                raise UnitError(f"channel {name!r} states no unit; the fivid-rig-csv format takes units from the "
                                "file: give a rig profile with the channel's unit (--rig, format: table)",
                                file=path, column=name)
        if data.time is not None and not any(n.partition(":")[0] == "time" for n in names):
            fields["time [s]"] = None
        return list(fields), fields
    fields = {name: name for name in names}
    time_name = _time_name(profile)
    if time_name not in fields and data.time is not None:
        fields[time_name] = None
    return list(fields), fields


def _check_units(path: Path, head_columns, data: ChannelFile, fields: dict) -> None:
    """A unit stated in the file must be the profile's (the same scale), so no value is silently rescaled."""
    for index, spec in head_columns:
        channel = list(fields.values())[index]
        stated = None if channel is None else data.units.get(channel)
        if not stated or stated == spec.units:
            continue
        try:
            factor, offset = conversion(stated, spec.units)
        except UnitError as exc:
            raise UnitError(f"the file states the unit {stated!r} for this channel, which does not convert to the "
                            f"profile's {spec.units!r}: {exc.message}", file=path, column=spec.name) from None
        if abs(factor - 1) > 1e-12 or offset:
            raise UnitError(f"the file states the unit {stated!r} for this channel but the profile says "
                            f"{spec.units!r} ({factor:g} x apart); correct 'units' in the profile",
                            file=path, column=spec.name)


def channel_head(path, profile: RigProfile, data: ChannelFile) -> RigHead:
    """The :class:`RigHead` of a DAQ file: its channels mapped by ``profile``, its metadata resolved.

    Raises
    ------
    SchemaError, UnitError
        A required channel is missing, a unit the file states disagrees with the profile, a
        required metadata value is missing or invalid; the message names the file and channel or key.
    """
    path = Path(path)
    names, fields = _fields(path, profile, data)
    if profile.format == "fivid-rig-csv":
        columns, ignored = rig_csv_columns(path, names, None)
        missing = [n for n, v in registry().variables.items()
                   if (v.required or n == "time") and n not in {s.variable for _, s in columns}]
        if missing:
            raise SchemaError(f"required channel(s) {', '.join(repr(m) for m in missing)} missing; the file's "
                              f"channels are {', '.join(repr(n) for n in data.channels)}", file=path,
                              column=missing[0])
        found = {k.replace("-", "_"): v for k, v in data.metadata.items()}
    else:
        columns, ignored = table_columns(path, profile, names, None, what="channel")
        _check_units(path, columns, data, fields)
        found = {}
        for key, (value, where) in data.metadata.items():
            attr = metadata_attribute(profile, key)
            if attr is None:
                continue
            if attr in found:
                raise SchemaError(f"metadata {attr!r} is given twice ({found[attr][1]} and {where})",
                                  file=path, key=attr)
            found[attr] = (value, where)
    attrs, origin = resolve_metadata(path, profile, found)
    return RigHead(path, profile, columns, len(names), None, 0, attrs, origin, ignored)


def _no_line(row: int) -> None:
    return None


def run_from_channels(path, profile: RigProfile, data: ChannelFile, *, allow_implausible: bool = False):
    """Convert, check and assemble a DAQ file's channels into a RunDataset (see :func:`read_daq_file`)."""
    path = Path(path)
    head = channel_head(path, profile, data)
    names, fields = _fields(path, profile, data)
    channel_of = list(fields.values())
    arrays, n = {}, None
    for variable, members in by_variable(head).items():
        raw = [data.time if channel_of[i] is None else data.channels[channel_of[i]] for i, _ in members]
        for (_, spec), values in zip(members, raw, strict=True):
            if values.ndim != 1:
                raise SchemaError(f"channel holds an array of shape {values.shape}; expected one value per sample",
                                  file=path, column=spec.name)
            if n is not None and values.size != n:
                raise SchemaError(f"channel has {values.size} samples but the time channel has {n}; every mapped "
                                  "channel must have one value per time sample", file=path, column=spec.name)
            n = values.size
        stacked = np.stack([np.asarray(v, dtype=np.float64) for v in raw], axis=1)
        for k, (_, spec) in enumerate(members):
            stacked[:, k] = stacked[:, k] * spec.factor + spec.offset
        values = stacked[:, 0].copy() if members[0][1].sensor is None else stacked
        arrays[variable] = (values, [spec for _, spec in members])
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    return assemble_run(head, _no_line, arrays, digest, file_format=data.format, allow_implausible=allow_implausible)
