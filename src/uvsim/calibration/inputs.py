"""What a calibration reads and how its settings are checked: the dataset (a directory, a
:class:`uvsim.logs.Dataset` or runs in memory), the starting vehicle, the channel weights
of the GA's fitness, how much a run moves (its weight among a DOF's runs) and the
``latency`` setting (:class:`uvsim.calibration.Calibrator`).
"""
from __future__ import annotations

from pathlib import Path
from typing import Mapping

import numpy as np

from uvsim.errors import CalibrationError, VehicleError
from uvsim.logs import MANIFEST, Dataset, read_dataset
from uvsim.signals import CHANNEL_GROUP, channel_weight
from uvsim.vehicle import check_latency, load_vehicle


def as_dataset(data) -> Dataset:
    """``data`` as a :class:`uvsim.logs.Dataset`: a dataset, its directory, or runs in memory."""
    if isinstance(data, Dataset):
        return data
    if isinstance(data, (str, Path)):
        return read_dataset(data)
    from uvsim.logged_run import Run

    runs = list(data) if isinstance(data, (list, tuple)) else None
    if runs is None or not all(isinstance(r, Run) for r in runs):
        raise CalibrationError(f"dataset: expected a dataset directory, a uvsim.logs.Dataset or a list of "
                               f"uvsim.logs.Run, got {type(data).__name__} {data!r}"[:300])
    if not runs:
        raise CalibrationError("no runs given")
    return Dataset(path=Path("."), vehicle=None, description="runs given in memory", runs=runs)


def resolve_vehicle(vehicle, ds: Dataset):
    """The starting vehicle: ``vehicle`` (a Vehicle, a file, a built-in name, or a name
    with ``NAME.yaml`` beside the manifest, which wins over a built-in as for the
    manifest's own ``vehicle:``) or else the manifest's."""
    if vehicle is None:
        if ds.vehicle is None:
            raise CalibrationError(f"{ds.path}: no vehicle given and the manifest names none")
        return load_vehicle(ds.vehicle_file or ds.vehicle)
    if isinstance(vehicle, (str, Path)) and not Path(vehicle).is_file() and (ds.path / MANIFEST).is_file():
        beside = Dataset(ds.path, str(vehicle), "", []).vehicle_file
        if beside is not None and beside.is_file():
            return load_vehicle(beside)
    return load_vehicle(vehicle)


def combine_weights(default: Mapping, user: Mapping | None) -> dict:
    """Channel weights default[c] x user[group(c)] x user[c] (:func:`uvsim.signals.channel_weight`)."""
    return {c: float(default.get(c, 1.0)) * channel_weight(user, g, c) for c, g in CHANNEL_GROUP.items()}


def run_amplitude(meas) -> float:
    """RMS over the used channels of (spread / noise): how much a run moves."""
    vals = []
    for g, grp in meas.groups.items():
        w = meas.channel_weights(g)
        for j in np.flatnonzero(grp.logged & (w > 0)):
            x = grp.values[grp.valid[:, j], j] if grp.mode != "quaternion" else None
            if x is not None and x.size > 1:
                vals.append(np.std(x) / grp.sigma[j])
    return float(np.sqrt(np.mean(np.square(vals)))) if vals else 1.0


def latency_setting(value):
    """``Calibrator(latency=...)`` checked: None, "auto", or a number of seconds (a numeric string
    too) returned as a float; anything else a CalibrationError."""
    if value is None or value == "auto":
        return value
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise CalibrationError(f"latency {value!r}: expected 'auto' or a latency in s (e.g. 0.03)") from None
    try:
        return check_latency(value, "latency")
    except VehicleError as e:  # the same message, as a calibration setting's error
        raise CalibrationError(str(e)) from None
