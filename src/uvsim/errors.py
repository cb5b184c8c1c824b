"""Exception types.  Every error a user can cause names the file, field or
parameter at fault and what was expected."""
from __future__ import annotations


class UvsimError(Exception):
    """Base class of all errors uvsim raises on purpose."""


class VehicleError(UvsimError, ValueError):
    """A vehicle file or parameter set is malformed or non-physical."""


class LogFormatError(UvsimError, ValueError):
    """A logged run or dataset breaks the contract of docs/log_format.md."""


class SimulationError(UvsimError, RuntimeError):
    """An integration blew up (non-finite state) or was asked something impossible."""


class HydroError(UvsimError, ValueError):
    """Bad geometry or a malformed coefficient table."""


class CalibrationError(UvsimError, RuntimeError):
    """A calibration could not be set up or run."""


class PlausibilityError(LogFormatError):
    """A run's values make no physical sense for the vehicle (wrong units, a sample
    interval the integrator cannot follow, PWM outside the thrust curve):
    :mod:`uvsim.plausibility`, ``--allow NAME`` on the commands."""


class ResultCheckError(UvsimError, RuntimeError):
    """A fit finished but its result fails the sanity checks (non-finite or exploding
    RMSE, every parameter on a search bound) and is not reported as a success."""


class CheckpointError(CalibrationError):
    """A checkpoint cannot be written or read, or belongs to another problem."""
