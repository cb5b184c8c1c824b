"""The logged run: :class:`Run`, one run's validated table and its column accessors.

A :class:`Run` holds one logged run (docs/log_format.md) as read from a file or built in
memory: its table, validated on construction by :mod:`uvsim.log_columns`, the manifest
attributes ``dof``, ``weight`` and ``split`` (checked here, with :data:`DOFS`,
:data:`SPLITS` and :data:`MAX_RUN_WEIGHT`), the reader's notes, and properties that give
the columns as arrays (inputs, position, attitude as quaternion or Euler angles, depth,
velocities and rates, accelerometer, battery voltage) with NaN for what was not logged.
Everything the contract forbids raises :class:`uvsim.errors.LogFormatError`.

Reading and writing run files and datasets (``manifest.yaml``) is :mod:`uvsim.logs`,
which re-exports the names of this module.
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from uvsim.errors import LogFormatError
from uvsim.kinematics import euler_to_quat, quat_to_euler
from uvsim.log_columns import (
    ACCEL_COLUMNS, DEPTH_COLUMN, EULER_COLUMNS, FORMAT_COLUMNS, POSITION_COLUMNS, QUAT_COLUMNS, RATE_COLUMNS,
    VELOCITY_COLUMNS, VOLTAGE_COLUMN, _empty_column_notes, _extra_column_notes, _quaternion_notes, _validate)

DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw", "mixed")
SPLITS = ("train", "validation")


def _check_choice(value, allowed, what: str, source: str, none_ok: bool = True):
    if value is None and none_ok:
        return None
    if not isinstance(value, str) or value not in allowed:
        raise LogFormatError(f"{source}: {what} {value!r} is not one of {', '.join(allowed)}")
    return value


#: Largest run weight accepted (weights are relative): at a million to one the lighter runs already
#: count below 1e-12 of the cost (weights enter squared), and 1e300 overflowed the squared weighted
#: residuals to inf (numpy overflow warnings, a fit of nothing).
MAX_RUN_WEIGHT = 1e6


def _check_closed_loop(value, source: str) -> bool | None:
    """A run's ``closed_loop`` (manifest): true, false or absent (None: not said)."""
    if value is None or isinstance(value, (bool, np.bool_)):
        return None if value is None else bool(value)
    raise LogFormatError(f"{source}: closed_loop {value!r} must be true (flown under an autopilot that held some of "
                         "the vehicle's states: ArduSub STABILIZE, DEPTH HOLD, heading hold), false (manual) or absent")


def _check_weight(weight, source: str) -> float:
    ok = isinstance(weight, (int, float, np.integer, np.floating)) and not isinstance(weight, bool)
    if not ok or not math.isfinite(float(weight)) or float(weight) <= 0:
        raise LogFormatError(f"{source}: weight {weight!r} must be a positive finite number")
    if float(weight) > MAX_RUN_WEIGHT:
        raise LogFormatError(f"{source}: weight {weight!r} is above {MAX_RUN_WEIGHT:g}; weights are relative (1 is "
                             "every run alike): scale them down")
    return float(weight)


@dataclass
class Run:
    """One logged run, validated on construction.

    ``data`` holds every column as read (float64, index 0..n-1); columns that
    were entirely empty are removed and listed in ``empty_columns``.  NaN in a
    measured signal is a missing sample and is kept.
    """

    name: str
    path: Path | None
    data: pd.DataFrame = field(repr=False)
    dof: str | None = None
    weight: float = 1.0
    split: str = "train"
    #: Flown under an autopilot that held some of the vehicle's states (its logged inputs react to
    #: them): True, False, or None when the log does not say (the manifest's ``closed_loop``).
    closed_loop: bool | None = None
    empty_columns: list[str] = field(init=False, default_factory=list)
    #: What the reader changed in the data beyond the float64 conversion or did not use (e.g.
    #: quaternions renormalized by more than :data:`uvsim.log_columns.QUAT_NOTE_TOL`, columns not in the format,
    #: a run split at a gap: :mod:`uvsim.gaps`); commands print these.
    notes: list[str] = field(init=False, default_factory=list)
    #: Row 0 of this table is row ``row_offset`` of the file (a segment of a run split at a
    #: gap, :mod:`uvsim.gaps`), so that messages name the file's rows.
    row_offset: int = field(init=False, default=0)
    #: The name of the run this one was cut from at a gap (:mod:`uvsim.gaps`); None for a
    #: run as read.
    segment_of: str | None = field(init=False, default=None)
    #: How much later than their time stamps the inputs act in this copy of the run, s
    #: (:func:`uvsim.latency.delay_inputs`; 0: as logged), and the run as logged.
    input_delay: float = field(init=False, default=0.0)
    as_logged: "Run | None" = field(init=False, repr=False, default=None)
    _kind: str = field(init=False, repr=False, default="")
    _input_columns: list[str] = field(init=False, repr=False, default_factory=list)

    def __post_init__(self):
        src = str(self.path) if self.path is not None else f"run {self.name!r}"
        self.path = Path(self.path) if self.path is not None else None
        self.dof = _check_choice(self.dof, DOFS, "dof", src)
        self.split = _check_choice(self.split, SPLITS, "split", src, none_ok=False)
        self.weight = _check_weight(self.weight, src)
        self.closed_loop = _check_closed_loop(self.closed_loop, src)
        self.data, self.empty_columns, self._kind, self._input_columns = _validate(self.data, src)
        self.notes = (_quaternion_notes(self.data, src) + _extra_column_notes(self.data, self._input_columns, src)
                      + _empty_column_notes(self.empty_columns, src))

    def derived(self, data: pd.DataFrame, *, name: str | None = None) -> "Run":
        """A copy of this run with ``data`` in place of its table, not validated again: for
        tables derived from this run's own validated columns by the library (the inputs
        delayed by interpolation between logged values, :func:`uvsim.latency.delay_inputs`),
        whose columns, kind and finiteness are this run's.  ``name``: the copy's name."""
        if list(data.columns) != list(self.data.columns) or len(data) != len(self.data):
            raise ValueError(f"run {self.name}: a derived table must have this run's columns and length")
        out = copy.copy(self)
        out.data = data
        out.notes = list(self.notes)
        if name is not None:
            out.name = name
        return out

    def _column(self, c: str) -> np.ndarray | None:
        """Column ``c`` of :attr:`data` as a read-only float array (None when absent).  The fits
        read a run's columns thousands of times, and pandas' column lookup costs microseconds to a
        millisecond each, so the arrays are kept while :attr:`data` is the same table with the
        same column blocks: a column assigned or added (``run.data["z"] = ...``) or a new table
        is read again, and a value edited in place shows through (the arrays are views)."""
        blocks = getattr(getattr(self.data, "_mgr", None), "blocks", None)  # (pandas' column storage)
        kept = self.__dict__.get("_kept_columns")
        if kept is None or kept[0] is not self.data or kept[1] is not blocks:
            kept = (self.data, blocks, {})
            if blocks is not None:
                self.__dict__["_kept_columns"] = kept
        cols = kept[2]
        if c not in cols:
            a = None
            if c in self.data.columns:
                a = self.data[c].to_numpy()
                if a.flags.writeable:  # (pandas before copy-on-write: a view of the table)
                    a = a.view()
                    a.flags.writeable = False
            cols[c] = a
        return cols[c]

    def __getstate__(self):
        # the kept columns are not sent to worker processes (the table is)
        state = dict(self.__dict__)
        state.pop("_kept_columns", None)
        return state

    def _cols(self, names) -> np.ndarray:
        """(n, len(names)) array, NaN for absent columns."""
        out = np.full((len(self.data), len(names)), np.nan)
        for j, c in enumerate(names):
            a = self._column(c)
            if a is not None:
                out[:, j] = a
        return out

    def _has(self, names) -> bool:
        return any(c in self.data.columns for c in names)

    @property
    def t(self) -> np.ndarray:
        """Sample times, s, shape (n,)."""
        return self._column("t")

    @property
    def input_kind(self) -> str:
        """``"force"``, ``"thrust"`` or ``"pwm"``."""
        return self._kind

    @property
    def input_columns(self) -> list[str]:
        """Input column names in the order of :attr:`inputs`."""
        return list(self._input_columns)

    @property
    def inputs(self) -> np.ndarray:
        """Inputs, shape (n, k): X,Y,Z,K,M,N (N, N m) or thrust_i (N) or pwm_i (us)."""
        out = np.empty((len(self.data), len(self._input_columns)), order="F")  # (as pandas gives it)
        for j, c in enumerate(self._input_columns):
            out[:, j] = self._column(c)
        return out

    @property
    def n_thrusters(self) -> int | None:
        """Number of thrust/pwm columns; None for force inputs."""
        return None if self._kind == "force" else len(self._input_columns)

    @property
    def has_position(self) -> bool:
        return self._has(POSITION_COLUMNS)

    @property
    def position(self) -> np.ndarray:
        """NED position x, y, z (m), shape (n, 3); NaN columns for absent axes."""
        return self._cols(POSITION_COLUMNS)

    @property
    def has_quaternion(self) -> bool:
        return self._has(QUAT_COLUMNS)

    @property
    def has_euler(self) -> bool:
        return self._has(EULER_COLUMNS)

    @property
    def has_attitude(self) -> bool:
        """True when the run logs any attitude channel (quaternion or any Euler angle)."""
        return self.has_quaternion or self.has_euler

    @property
    def has_full_attitude(self) -> bool:
        """True when the run logs the whole attitude (a quaternion or roll, pitch and yaw)."""
        return self.has_quaternion or all(c in self.data.columns for c in EULER_COLUMNS)

    @property
    def euler_mask(self) -> np.ndarray:
        """(3,) bool: which of roll, pitch, yaw the run logs (all three for a quaternion)."""
        if self.has_quaternion:
            return np.ones(3, bool)
        return np.array([c in self.data.columns for c in EULER_COLUMNS])

    @property
    def has_depth(self) -> bool:
        return DEPTH_COLUMN in self.data.columns

    @property
    def depth(self) -> np.ndarray:
        """Pressure-sensor depth (m, NED z of the sensor), shape (n,); all NaN when absent."""
        return self._cols((DEPTH_COLUMN,))[:, 0]

    @property
    def has_acceleration(self) -> bool:
        return self._has(ACCEL_COLUMNS)

    @property
    def acceleration(self) -> np.ndarray:
        """Accelerometer specific force (m/s^2, body axes, at the IMU), shape (n, 3); NaN when absent."""
        return self._cols(ACCEL_COLUMNS)

    @property
    def quaternion(self) -> np.ndarray:
        """Unit quaternion body->NED (qw, qx, qy, qz), shape (n, 4).

        From the qw..qz columns (normalized, sign as logged) or else from
        roll/pitch/yaw via :func:`uvsim.kinematics.euler_to_quat`.  Rows with
        any component missing are all NaN; all NaN without a full attitude (a
        run with roll and pitch only has no quaternion: use :attr:`euler`)."""
        if self.has_quaternion:
            q = self._cols(QUAT_COLUMNS)
            return q / np.linalg.norm(q, axis=1, keepdims=True)
        if self.has_full_attitude:
            return euler_to_quat(self._cols(EULER_COLUMNS))
        return np.full((len(self.data), 4), np.nan)

    @property
    def euler(self) -> np.ndarray:
        """ZYX Euler angles roll, pitch, yaw (rad), shape (n, 3): the logged
        columns (NaN for angles not logged), or else from the quaternion via
        :func:`uvsim.kinematics.quat_to_euler`."""
        if self.has_euler:
            return self._cols(EULER_COLUMNS)
        if self.has_quaternion:
            return quat_to_euler(self.quaternion)
        return np.full((len(self.data), 3), np.nan)

    @property
    def has_voltage(self) -> bool:
        return VOLTAGE_COLUMN in self.data.columns

    @property
    def voltage(self) -> np.ndarray | None:
        """Battery voltage (V) per row, shape (n,), or None when not logged.  Empty cells
        (no new sample) hold the previous sample (zero-order hold, as inputs are held)."""
        if not self.has_voltage:
            return None
        return self.data[VOLTAGE_COLUMN].ffill().to_numpy()

    @property
    def has_velocity(self) -> bool:
        return self._has(VELOCITY_COLUMNS)

    @property
    def has_rates(self) -> bool:
        return self._has(RATE_COLUMNS)

    @property
    def velocity(self) -> np.ndarray:
        """Body velocities u, v, w (m/s) and rates p, q, r (rad/s), shape (n, 6);
        NaN columns for absent ones."""
        return self._cols(VELOCITY_COLUMNS + RATE_COLUMNS)

    @property
    def measured_columns(self) -> dict[str, list[str]]:
        """Measured columns present, by signal group, e.g. ``{"position": ["z"],
        "attitude": ["qw", "qx", "qy", "qz"], "rates": ["p", "q", "r"]}``."""
        groups = {
            "position": POSITION_COLUMNS,
            "depth": (DEPTH_COLUMN,),
            "attitude": QUAT_COLUMNS + EULER_COLUMNS,
            "velocity": VELOCITY_COLUMNS,
            "rates": RATE_COLUMNS,
            "acceleration": ACCEL_COLUMNS,
        }
        out = {g: [c for c in names if c in self.data.columns] for g, names in groups.items()}
        return {g: cols for g, cols in out.items() if cols}

    def signals(self) -> list[str]:
        """Measured signal groups present, in the order position, depth, attitude,
        velocity, rates, acceleration (the axes are in :attr:`measured_columns`)."""
        return list(self.measured_columns)

    @property
    def extra_columns(self) -> list[str]:
        """Columns that are not part of the log format (kept in ``data``, named in :attr:`notes`)."""
        known = set(FORMAT_COLUMNS) | set(self._input_columns)
        return [c for c in self.data.columns if c not in known]
