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
