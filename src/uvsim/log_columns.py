"""The log format's columns and their checks (docs/log_format.md): the column names, the
accepted ranges and tolerances, and the validation of one run's table (numeric columns, one
kind of inputs, time strictly increasing, quaternions of unit norm, attitude columns that
agree).  Every check raises :class:`uvsim.errors.LogFormatError` naming the file, the column
and the row; :mod:`uvsim.logs` reads and writes runs and datasets with them.
"""
from __future__ import annotations

import re

import numpy as np
import pandas as pd

from uvsim.constants import PWM_RANGE_US  # noqa: F401 (re-exported: the log format's PWM range)
from uvsim.errors import LogFormatError
from uvsim.kinematics import attitude_error_angle, euler_to_quat
from uvsim.log_aliases import check_aliases

INPUT_KINDS = ("force", "thrust", "pwm")
FORCE_COLUMNS = ("X", "Y", "Z", "K", "M", "N")
POSITION_COLUMNS = ("x", "y", "z")
QUAT_COLUMNS = ("qw", "qx", "qy", "qz")
EULER_COLUMNS = ("roll", "pitch", "yaw")
VELOCITY_COLUMNS = ("u", "v", "w")
RATE_COLUMNS = ("p", "q", "r")
#: Depth (m, NED z, positive down) measured by a pressure sensor at its own position on the
#: body (vehicle file ``sensors.pressure.position``; default the body origin).
DEPTH_COLUMN = "depth"
#: Accelerometer specific force (m/s^2, body axes) at the IMU position (``sensors.imu.position``):
#: ``f = R^T (a - g e_3)``, so a vehicle at rest and level reads (0, 0, -g).
ACCEL_COLUMNS = ("acc_x", "acc_y", "acc_z")
#: Battery voltage (V) per sample, an optional auxiliary input of PWM thrust curves.
VOLTAGE_COLUMN = "voltage"
MEASURED_COLUMNS = (POSITION_COLUMNS + (DEPTH_COLUMN,) + QUAT_COLUMNS + EULER_COLUMNS + VELOCITY_COLUMNS
                    + RATE_COLUMNS + ACCEL_COLUMNS)

#: Highest ``voltage`` accepted, V: the column feeds the thrust curves of PWM-driven ESCs (1000-2000 us),
#: rated up to 12S LiPo (50.4 V) for hobby ESCs and 7-20 V for the Blue Robotics T200; 100 V leaves
#: room, and a voltage logged in millivolts (16000) is refused instead of read as 16 kV.
MAX_BATTERY_VOLTAGE = 100.0
#: Tolerance on |q| - 1 for logged quaternions: beyond it a run is rejected.
QUAT_NORM_TOL = 1e-2
#: Quaternions are divided by their norm; when |q| - 1 exceeds this in some row (more
#: than the rounding of a log written with 4+ decimals) the run records a note
#: (:attr:`Run.notes`) that the commands print and put in their reports.
QUAT_NOTE_TOL = 1e-3
#: Largest disagreement (rad) allowed between quaternion and Euler columns
#: when a run logs both.
ATTITUDE_CONSISTENCY_TOL = 1e-2
#: The format's own names (exact, case-sensitive) besides ``thrust_i`` / ``pwm_i``.
FORMAT_COLUMNS = ("t", VOLTAGE_COLUMN) + MEASURED_COLUMNS + FORCE_COLUMNS
_ACTUATOR_RE = re.compile(r"^(thrust|pwm)_([1-9][0-9]*)$")
# a thruster name and a number, nothing between but a separator (``pwm_0``, ``thruster-3``);
# ``thrust_lag_1`` (a simulation's term state) is another quantity and an extra column
_ACTUATOR_LIKE_RE = re.compile(r"^(thrust|pwm|thruster)[\s_-]*\d+$", re.IGNORECASE)


def _row(i: int, source: str) -> str:
    """``"row i (line i+2)"`` for CSV files, ``"row i"`` otherwise."""
    if source.lower().endswith(".csv"):
        return f"row {i} (line {i + 2} of the file)"
    return f"row {i}"


def _clean(df: pd.DataFrame, source: str) -> tuple[pd.DataFrame, list[str]]:
    """Numeric float64 copy of ``df`` with entirely empty columns removed.

    Returns the frame and the names of the removed (empty) columns."""
    df = df.copy()
    df.columns = [str(c).strip() for c in df.columns]
    dup = df.columns[df.columns.duplicated()]
    if len(dup):
        raise LogFormatError(f"{source}: column {dup[0]!r} appears more than once")
    df = df.reset_index(drop=True)
    if len(df) < 2:
        raise LogFormatError(f"{source}: needs at least 2 samples, found {len(df)}")
    all_nan = df.isna().all().to_numpy()
    empty = [c for c, e in zip(df.columns, all_nan) if e]
    df = df.drop(columns=empty)
    # float64 columns (what a numeric CSV reads as) need only the infinity check: done for all of
    # them at once; the others are converted one by one, in column order as the errors are
    floats = [c for c, d in zip(df.columns, df.dtypes) if d == np.float64]
    has_inf = dict(zip(floats, np.isinf(df[floats].to_numpy()).any(axis=0))) if floats else {}
    for c in df.columns:
        if not has_inf.get(c, True):
            continue
        col = df[c]
        if pd.api.types.is_bool_dtype(col):
            bad = col.notna().to_numpy()
        elif not pd.api.types.is_numeric_dtype(col):
            num = pd.to_numeric(col, errors="coerce")
            bad = (col.notna() & num.isna()).to_numpy()
            col = num
        else:
            bad = np.zeros(len(col), dtype=bool)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise LogFormatError(
                f"{source}: column {c!r}, {_row(i, source)}: {df[c].iloc[i]!r} is not a number "
                "(expected a numeric value, or an empty cell for a missing sample)"
            )
        df[c] = col.astype("float64")
        inf = np.isinf(df[c].to_numpy())
        if inf.any():
            i = int(np.flatnonzero(inf)[0])
            raise LogFormatError(
                f"{source}: column {c!r}, {_row(i, source)} is infinite (expected a finite number "
                "or an empty cell for a missing sample)"
            )
    return df, empty


def _actuator_columns(cols, source: str) -> tuple[str | None, list[str]]:
    """Input kind and input column names in order; raises on mixed or gappy inputs."""
    found: dict[str, list[str]] = {"force": [c for c in FORCE_COLUMNS if c in cols]}
    numbered: dict[str, dict[int, str]] = {"thrust": {}, "pwm": {}}
    for c in cols:
        m = _ACTUATOR_RE.match(c)
        if m:
            numbered[m.group(1)][int(m.group(2))] = c
        elif _ACTUATOR_LIKE_RE.match(c):
            raise LogFormatError(
                f"{source}: column {c!r} looks like an actuator column; expected thrust_1..thrust_n "
                "or pwm_1..pwm_n (lower case, underscore, numbered from 1)"
            )
    for kind, cols_by_index in numbered.items():
        found[kind] = [cols_by_index[i] for i in sorted(cols_by_index)]
        if cols_by_index and sorted(cols_by_index) != list(range(1, len(cols_by_index) + 1)):
            missing = sorted(set(range(1, max(cols_by_index) + 1)) - set(cols_by_index))
            raise LogFormatError(
                f"{source}: {kind} columns must be numbered 1..n without gaps; "
                f"found {found[kind]}, missing {[f'{kind}_{i}' for i in missing]}"
            )
    kinds = [k for k in INPUT_KINDS if found[k]]
    if not kinds:
        raise LogFormatError(
            f"{source}: no input columns; expected all of X,Y,Z,K,M,N, or thrust_1..thrust_n, "
            "or pwm_1..pwm_n"
        )
    if len(kinds) > 1:
        raise LogFormatError(
            f"{source}: mixed input kinds {kinds} ({', '.join(c for k in kinds for c in found[k])}); "
            "a run must use exactly one of force (X..N), thrust_i or pwm_i"
        )
    kind = kinds[0]
    if kind == "force" and len(found["force"]) != 6:
        missing = [c for c in FORCE_COLUMNS if c not in cols]
        raise LogFormatError(
            f"{source}: force inputs need all six columns X,Y,Z,K,M,N; missing {missing}"
        )
    return kind, found[kind]


def _validate(df: pd.DataFrame, source: str) -> tuple[pd.DataFrame, list[str], str, list[str]]:
    """Check a run frame against the contract; returns (clean frame, empty
    columns, input kind, input columns)."""
    check_aliases(df, FORMAT_COLUMNS, source)  # ax, time, phi, ...: named so that they are read
    df, empty = _clean(df, source)
    cols = list(df.columns)
    if "t" not in cols:
        raise LogFormatError(f"{source}: missing time column 't' (columns found: {cols})")
    t = df["t"].to_numpy()
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise LogFormatError(
            f"{source}: column 't', {_row(int(bad[0]), source)} is empty/NaN; time must be given in every row"
        )
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        i = int(bad[0]) + 1
        raise LogFormatError(
            f"{source}: column 't' must be strictly increasing; {_row(i, source)} has t = {float(t[i])!r} "
            f"after t = {float(t[i - 1])!r}"
        )
    # a quaternion is all-or-nothing; Euler angles may be any subset (an IMU without a
    # magnetometer logs roll and pitch only, a compass yaw only)
    for group, names in (("quaternion", QUAT_COLUMNS), ("acceleration", ACCEL_COLUMNS)):
        present = [c for c in names if c in cols]
        if present and len(present) != len(names):
            raise LogFormatError(
                f"{source}: partial {group} columns {present}; expected all of {list(names)} "
                "(an entirely empty column counts as absent)"
            )
    if not any(c in cols for c in MEASURED_COLUMNS):
        raise LogFormatError(
            f"{source}: no measured columns; a run needs at least one of position (x, y, z), depth, "
            "attitude (qw..qz or any of roll, pitch, yaw), velocity (u, v, w), rates (p, q, r) or "
            "acceleration (acc_x, acc_y, acc_z)"
        )
    if VOLTAGE_COLUMN in cols:
        _check_voltage_column(df[VOLTAGE_COLUMN].to_numpy(), source)
    kind, in_cols = _actuator_columns(cols, source)
    for c in in_cols:
        v = df[c].to_numpy()
        nan = np.flatnonzero(np.isnan(v))
        if nan.size:
            raise LogFormatError(
                f"{source}: input column {c!r}, {_row(int(nan[0]), source)} is empty/NaN; "
                "inputs must be given in every row"
            )
        if kind == "pwm":
            lo, hi = PWM_RANGE_US
            out = np.flatnonzero((v < lo) | (v > hi))
            if out.size:
                i = int(out[0])
                raise LogFormatError(
                    f"{source}: column {c!r}, {_row(i, source)}: PWM {float(v[i])!r} us outside the accepted "
                    f"{lo:g}..{hi:g} us (standard ESC pulse range, 1500 us neutral; values must be in "
                    "microseconds)"
                )
    if all(c in cols for c in QUAT_COLUMNS):
        q = df[list(QUAT_COLUMNS)].to_numpy()
        norm = np.linalg.norm(q, axis=1)
        far = np.flatnonzero(np.abs(norm - 1.0) > QUAT_NORM_TOL)  # NaN rows compare False
        if far.size:
            i = int(far[0])
            raise LogFormatError(
                f"{source}: quaternion qw..qz in {_row(i, source)} has norm {norm[i]:.6g}; expected a unit "
                f"quaternion (|q| within {QUAT_NORM_TOL:g} of 1)"
            )
        if all(c in cols for c in EULER_COLUMNS):
            qe = euler_to_quat(df[list(EULER_COLUMNS)].to_numpy())
            err = attitude_error_angle(q / norm[:, None], qe)
            off = np.flatnonzero(err > ATTITUDE_CONSISTENCY_TOL)
            if off.size:
                i = int(off[0])
                raise LogFormatError(
                    f"{source}: quaternion and roll/pitch/yaw columns disagree by {err[i]:.4g} rad in "
                    f"{_row(i, source)}; expected the same attitude (within {ATTITUDE_CONSISTENCY_TOL:g} rad)"
                )
    return df, empty, kind, in_cols


def _check_voltage_column(v: np.ndarray, source: str) -> None:
    """``voltage``: positive where logged; NaN = no new sample (held, see :attr:`Run.voltage`),
    so the first row must carry a value."""
    if np.isnan(v[0]):
        raise LogFormatError(
            f"{source}: column 'voltage', {_row(0, source)} is empty; the battery voltage is held from one "
            "sample to the next (empty cells = no new sample), so the first row must have a value"
        )
    bad = np.flatnonzero(~np.isnan(v) & ~(v > 0))
    if bad.size:
        i = int(bad[0])
        raise LogFormatError(
            f"{source}: column 'voltage', {_row(i, source)}: {float(v[i])!r} V is not a positive battery voltage"
        )
    high = np.flatnonzero(v > MAX_BATTERY_VOLTAGE)  # NaN compares False
    if high.size:
        i = int(high[0])
        raise LogFormatError(
            f"{source}: column 'voltage', {_row(i, source)}: {float(v[i]):g} V is above {MAX_BATTERY_VOLTAGE:g} V, "
            "more than any PWM thruster's battery; expected volts (a value in millivolts is 1000 x too large)"
        )


def _extra_column_notes(df: pd.DataFrame, input_columns, source: str) -> list[str]:
    """A note naming the columns that are not part of the log format: they are kept in the
    run's table (:attr:`uvsim.logs.Run.extra_columns`) and no method uses them, which the
    commands say (docs/log_format.md)."""
    known = set(FORMAT_COLUMNS) | set(input_columns)
    extra = [c for c in df.columns if c not in known]
    if not extra:
        return []
    return [f"{source}: column{'s' if len(extra) > 1 else ''} not in the log format, not used: {', '.join(extra)}"]


def _empty_column_notes(empty, source: str) -> list[str]:
    """A note naming the named columns that are entirely empty and so count as absent (removed
    from the run's table): a column the user logged and meant to be read is not dropped without a
    word.  The nameless ``Unnamed: N`` column of a trailing comma holds nothing and is not named."""
    named = [str(c) for c in empty if not str(c).startswith("Unnamed:")]
    if not named:
        return []
    return [f"{source}: column{'s' if len(named) > 1 else ''} {', '.join(named)} entirely empty, not used "
            "(counts as absent)"]


def _quaternion_notes(df: pd.DataFrame, source: str) -> list[str]:
    """A note when the logged quaternions are renormalized by more than QUAT_NOTE_TOL."""
    if not all(c in df.columns for c in QUAT_COLUMNS):
        return []
    dev = np.abs(np.linalg.norm(df[list(QUAT_COLUMNS)].to_numpy(), axis=1) - 1.0)
    if not np.any(dev > QUAT_NOTE_TOL):  # NaN rows compare False
        return []
    i = int(np.nanargmax(dev))
    n = int(np.sum(dev > QUAT_NOTE_TOL))
    return [f"{source}: quaternion qw..qz renormalized to unit norm; |q| deviates from 1 by up to "
            f"{dev[i]:.3g} ({_row(i, source)}; {n} of {len(dev)} rows beyond {QUAT_NOTE_TOL:g})"]
