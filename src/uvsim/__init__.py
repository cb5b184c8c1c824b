"""uvsim: underwater vehicle simulation (Fossen 6-DOF, quaternion kinematics) and
model calibration against logged runs.

Quick use::

    import uvsim
    veh = uvsim.load_vehicle("bluerov2_heavy")
    res = uvsim.simulate(veh, t, inputs, input_kind="force")
    df = res.to_pandas()

Where things live: ``model.py`` (equations of motion), ``forces/`` (force-term
plug-ins: restoring, damping, actuators), ``vehicle.py`` + ``vehicles/*.yaml``
(vehicle definitions), ``logs.py`` (logged runs and datasets; the run class in
``logged_run.py``), ``simulate.py`` (integrators).
"""
from __future__ import annotations

__version__ = "0.1.0"

from uvsim.errors import (  # noqa: F401
    CalibrationError,
    HydroError,
    LogFormatError,
    SimulationError,
    UvsimError,
    VehicleError,
)
from uvsim.vehicle import Vehicle, builtin_vehicles, load_vehicle, save_vehicle  # noqa: F401
from uvsim.model import Model  # noqa: F401
from uvsim.simulate import SimulationResult, simulate, simulate_batch, simulate_run  # noqa: F401
