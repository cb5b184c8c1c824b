"""The SAM vehicle with a selectable hull data set, and its command vector.

``load_sam("jorgensen")`` is the built-in ``sam`` vehicle (src/uvsim/vehicles/sam.yaml) with
the hull table built by Jorgensen's method only; ``"datcom"`` DATCOM only;
``"multifidelity"`` (default) seed 003 Algorithm 1.
"""
from __future__ import annotations

import copy

import numpy as np

from uvsim.errors import VehicleError
from uvsim.sam.buildup import DATASETS

#: Command columns (input_kind="thrust"), in order, with units.
SAM_INPUTS = ("rpm_1", "rpm_2", "tv_pitch", "tv_yaw", "vbs", "lcg", "tcg")
SAM_INPUT_UNITS = ("rev/min", "rev/min", "rad", "rad", "%", "%", "rad")
#: Commands holding SAM neutral: propellers off, nozzle centred, VBS and LCG at 50 %, TCG down.
NEUTRAL = np.array([0.0, 0.0, 0.0, 0.0, 50.0, 50.0, 0.0])


def load_sam(dataset: str = "multifidelity", vehicle="sam"):
    """The SAM vehicle (or another vehicle file using ``component_buildup``) with the body
    tables of ``dataset`` (``multifidelity``, ``jorgensen`` or ``datcom``)."""
    from uvsim.vehicle import load_vehicle

    if dataset not in DATASETS:
        raise VehicleError(f"SAM data set {dataset!r} not one of {DATASETS}")
    veh = load_vehicle(vehicle)
    if getattr(veh.damping, "kind", None) != "component_buildup":
        raise VehicleError(f"{veh.source}: damping is {veh.damping.kind!r}, not component_buildup")
    if veh.damping.dataset == dataset:
        return veh
    new = copy.copy(veh)
    new.damping = veh.damping.with_dataset(dataset)
    new.name = f"{veh.name}_{dataset}"
    return new


def commands(n: int, **columns) -> np.ndarray:
    """A command array (n, 7) at :data:`NEUTRAL` with some columns replaced, e.g.
    ``commands(100, rpm_1=rpm, rpm_2=rpm, tv_yaw=0.12)`` (arrays of length n or scalars)."""
    u = np.tile(NEUTRAL, (n, 1))
    for k, v in columns.items():
        if k not in SAM_INPUTS:
            raise VehicleError(f"unknown SAM command {k!r}; expected one of {SAM_INPUTS}")
        u[:, SAM_INPUTS.index(k)] = v
    return u
