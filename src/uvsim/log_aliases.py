"""Column names other tools write for the log format's columns, and their refusal.

A run file whose accelerometer columns are named ``ax, ay, az`` (as some converters write
them) follows the format in every other respect: before this check it was read, the three
columns were kept as extra columns and every method ran without the accelerometer, silently.
:func:`check_aliases` refuses such columns with a :class:`uvsim.errors.LogFormatError` that
names the file, the columns and the format's names for them.

The table :data:`COLUMN_ALIASES` is deliberately conservative: it holds names that
unambiguously mean one format column (``phi`` is roll in every vehicle convention;
``mag_x``, ``voltage_raw`` or ``temperature`` mean nothing in the format and stay allowed as
extra columns, which the reader reports in :attr:`uvsim.logs.Run.notes`).  A name is looked
up case-insensitively, after removing one unit suffix (:data:`UNIT_SUFFIXES`: ``depth_m``,
``acc_x_mps2``, ``roll_deg``); a trailing number is a thruster index (``thrust1``,
``motor_3``).  A column is not refused when the file also has the format column it stands
for (``timestamp`` beside ``t`` is an extra column, e.g. a second clock), nor when it is
entirely empty (it counts as absent, docs/log_format.md).
"""
from __future__ import annotations

import re

import pandas as pd

from uvsim.errors import LogFormatError

#: Another tool's name (lower case; ``#`` stands for a thruster number from 1) -> the log
#: format's column (docs/log_format.md).  Sources of the names: MAVLink ATTITUDE (rollspeed..),
#: SCALED_IMU (xacc..) and ROS sensor_msgs/Imu (angular_velocity.x, linear_acceleration.x,
#: orientation.w) field names, ArduPilot's IMU.GyrX / AccX, the usual phi/theta/psi of
#: Fossen 2021 (sec. 2.2.1) and the q0..q3 of scalar-first quaternions.  Case variants of the
#: format's own multi-letter names (``Roll``, ``ACC_X``, ``PWM_1``) map to themselves.
COLUMN_ALIASES = {
    # time
    "time": "t", "timestamp": "t", "times": "t", "time_sec": "t", "seconds": "t",
    # NED position of the body origin
    "pos_x": "x", "pos_y": "y", "pos_z": "z", "position_x": "x", "position_y": "y", "position_z": "z",
    "position.x": "x", "position.y": "y", "position.z": "z", "north": "x", "east": "y", "down": "z",
    # pressure-sensor depth
    "depth": "depth", "pressure_depth": "depth", "baro_depth": "depth", "depth_pressure": "depth",
    # quaternion body->NED, scalar first
    "qw": "qw", "qx": "qx", "qy": "qy", "qz": "qz",
    "q0": "qw", "q1": "qx", "q2": "qy", "q3": "qz",
    "quat_w": "qw", "quat_x": "qx", "quat_y": "qy", "quat_z": "qz",
    "quatw": "qw", "quatx": "qx", "quaty": "qy", "quatz": "qz",
    "quaternion_w": "qw", "quaternion_x": "qx", "quaternion_y": "qy", "quaternion_z": "qz",
    "orientation_w": "qw", "orientation_x": "qx", "orientation_y": "qy", "orientation_z": "qz",
    "orientation.w": "qw", "orientation.x": "qx", "orientation.y": "qy", "orientation.z": "qz",
    # ZYX Euler angles
    "roll": "roll", "pitch": "pitch", "yaw": "yaw", "phi": "roll", "theta": "pitch", "psi": "yaw",
    "heading": "yaw",
    # body-frame velocity (DVL)
    "vx": "u", "vy": "v", "vz": "w", "vel_x": "u", "vel_y": "v", "vel_z": "w",
    "velocity_x": "u", "velocity_y": "v", "velocity_z": "w",
    # body rates (gyro)
    "gx": "p", "gy": "q", "gz": "r", "wx": "p", "wy": "q", "wz": "r",
    "gyro_x": "p", "gyro_y": "q", "gyro_z": "r", "gyrox": "p", "gyroy": "q", "gyroz": "r",
    "gyr_x": "p", "gyr_y": "q", "gyr_z": "r", "gyrx": "p", "gyry": "q", "gyrz": "r",
    "omega_x": "p", "omega_y": "q", "omega_z": "r",
    "angular_velocity_x": "p", "angular_velocity_y": "q", "angular_velocity_z": "r",
    "angular_velocity.x": "p", "angular_velocity.y": "q", "angular_velocity.z": "r",
    "rollspeed": "p", "pitchspeed": "q", "yawspeed": "r",
    "roll_rate": "p", "pitch_rate": "q", "yaw_rate": "r", "rollrate": "p", "pitchrate": "q", "yawrate": "r",
    # accelerometer specific force
    "acc_x": "acc_x", "acc_y": "acc_y", "acc_z": "acc_z",
    "ax": "acc_x", "ay": "acc_y", "az": "acc_z", "accx": "acc_x", "accy": "acc_y", "accz": "acc_z",
    "accel_x": "acc_x", "accel_y": "acc_y", "accel_z": "acc_z",
    "accelx": "acc_x", "accely": "acc_y", "accelz": "acc_z",
    "acceleration_x": "acc_x", "acceleration_y": "acc_y", "acceleration_z": "acc_z",
    "xacc": "acc_x", "yacc": "acc_y", "zacc": "acc_z",
    "linear_acceleration_x": "acc_x", "linear_acceleration_y": "acc_y", "linear_acceleration_z": "acc_z",
    "linear_acceleration.x": "acc_x", "linear_acceleration.y": "acc_y", "linear_acceleration.z": "acc_z",
    # battery voltage
    "voltage": "voltage", "volt": "voltage", "volts": "voltage", "vbat": "voltage",
    "battery_voltage": "voltage", "batt_voltage": "voltage", "bat_volt": "voltage",
    # thruster inputs (# = thruster number); a motor or ESC channel is a command or a thrust
    "thrust_#": "thrust_#", "pwm_#": "pwm_#", "thrust#": "thrust_#", "pwm#": "pwm_#",
    "thruster#": "thrust_# or pwm_#", "thruster_#": "thrust_# or pwm_#",
    "motor#": "pwm_# or thrust_#", "motor_#": "pwm_# or thrust_#",
    "esc#": "pwm_#", "esc_#": "pwm_#", "servo#": "pwm_#", "servo_#": "pwm_#",
}

#: Unit suffixes removed before the look-up (one, at the end): ``depth_m`` is ``depth``.
UNIT_SUFFIXES = ("m", "mm", "cm", "s", "ms", "us", "rad", "deg", "mps", "m_s", "mps2", "m_s2", "ms2", "rads",
                 "rad_s", "radps", "degs", "deg_s", "dps", "g", "n", "nm", "v", "mv")
_SUFFIX_RE = re.compile(r"^(.+?)_(" + "|".join(sorted(UNIT_SUFFIXES, key=len, reverse=True)) + r")$",
                        re.IGNORECASE)
_NUMBER_RE = re.compile(r"^(.*?)(\d+)$")
_FORMAT_ACTUATOR_RE = re.compile(r"^(thrust|pwm)_[1-9][0-9]*$")

#: What a format column holds (for the message): the unit and, where a look-alike is often
#: something else, the difference.
_MEANING = {
    "t": "s", "x": "m, NED position of the body origin", "depth": "m, NED depth of the pressure sensor",
    "qw": "unit quaternion body->NED, scalar first", "roll": "rad, ZYX Euler angles",
    "u": "m/s, body-frame velocity; a velocity in NED has no column in the format",
    "p": "rad/s, body rates", "acc_x": "m/s^2, accelerometer specific force in body axes",
    "voltage": "V, battery voltage",
    "thrust_#": "thrust_1..thrust_n in N or pwm_1..pwm_n in us, lower case, numbered from 1",
}
_GROUP = {**{c: "x" for c in "xyz"}, **{c: "qw" for c in ("qw", "qx", "qy", "qz")},
          **{c: "roll" for c in ("roll", "pitch", "yaw")}, **{c: "u" for c in "uvw"}, **{c: "p" for c in "pqr"},
          **{c: "acc_x" for c in ("acc_x", "acc_y", "acc_z")}}


def format_name(name: str, format_columns) -> str | None:
    """The format column(s) that column ``name`` stands for, or None when it is no alias.

    Parameters
    ----------
    name : a column name of a run file (stripped of surrounding spaces).
    format_columns : the names of the log format (exact, case-sensitive); a name among them,
        or matching ``thrust_i`` / ``pwm_i``, is the format's own and never an alias.

    Returns
    -------
    str or None
        e.g. ``"acc_x"`` for ``ax`` or ``Acc_X_mps2``, ``"pwm_3 or thrust_3"`` for ``motor_3``.
    """
    if name in format_columns or _FORMAT_ACTUATOR_RE.match(name):
        return None
    key = name.lower()
    hit = _look_up(key)
    if hit is not None:
        return hit
    m = _SUFFIX_RE.match(name)
    if m is None:
        return None
    if m.group(1) in format_columns:  # x_m, t_s, X_N: a format name with its unit appended
        return m.group(1)
    return _look_up(m.group(1).lower())


def _look_up(key: str) -> str | None:
    """:data:`COLUMN_ALIASES` for a lower-case key, with a trailing thruster number."""
    if key in COLUMN_ALIASES:
        return COLUMN_ALIASES[key]
    m = _NUMBER_RE.match(key)
    if m is None or int(m.group(2)) < 1 or f"{m.group(1)}#" not in COLUMN_ALIASES:
        return None
    return COLUMN_ALIASES[f"{m.group(1)}#"].replace("#", str(int(m.group(2))))


def _meaning(target: str) -> str:
    first = target.split(" or ")[0]
    if _FORMAT_ACTUATOR_RE.match(first):
        return _MEANING["thrust_#"]
    return _MEANING.get(_GROUP.get(first, first), "")


def check_aliases(df: pd.DataFrame, format_columns, source: str) -> None:
    """Raise :class:`LogFormatError` when columns of ``df`` are aliases of format columns.

    Parameters
    ----------
    df : the run's table as read (names may carry surrounding spaces).
    format_columns : the log format's column names (see :func:`format_name`).
    source : the file (or run) named in the message.

    Notes
    -----
    A column that is entirely empty counts as absent and is not refused; nor is an alias
    whose format column is present in the file too (it is then an extra column).
    """
    names = [str(c).strip() for c in df.columns]
    found = []
    for raw, name in zip(df.columns, names):
        target = format_name(name, format_columns)
        if target is None or set(target.split(" or ")) & set(names) or df[raw].isna().all():
            continue
        found.append((name, target))
    if not found:
        return
    cols = ", ".join(repr(n) for n, _ in found)
    targets = list(dict.fromkeys(t for _, t in found))
    hints = {}
    for t in targets:
        if _meaning(t):
            hints.setdefault(_meaning(t), []).append(t)
    what = "; ".join(f"{', '.join(ts)}: {h}" for h, ts in hints.items())
    raise LogFormatError(
        f"{source}: column{'s' if len(found) > 1 else ''} {cols} {'are' if len(found) > 1 else 'is'} not in the "
        f"log format; did you mean {', '.join(targets)}? Rename {'them' if len(found) > 1 else 'it'} to the "
        f"format's name{'s' if len(targets) > 1 else ''} ({what}; docs/log_format.md); a column under another "
        "name is not read, so the methods would silently run without it")
