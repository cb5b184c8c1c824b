"""ArduSub thruster layouts and the check of a log's frame against a vehicle file.

ArduSub mixes the pilot's six commands into motor outputs with per-motor factors
(ArduPilot ``libraries/AP_Motors/AP_Motors6DOF.cpp``, ``AP_Motors6DOF::setup_motors``,
columns roll, pitch, yaw, throttle, forward, lateral) and then multiplies each motor's
output by its ``MOT_n_DIRECTION`` (+1 / -1; ``output_armed_stabilizing*``:
``_thrust_rpyt_out[i] = _motor_reverse[i] * (...)``), and sends ``1500 + 400 * out`` us
(``calc_thrust_to_pwm``).  So a command above 1500 us on motor n pushes the vehicle
along ``MOT_n_DIRECTION x factors_n``.  In uvsim axes (NED / FRD, docs/model.md):

============  ==========================  ==================================
ArduSub axis  uvsim generalized force     why
============  ==========================  ==================================
forward       +X                          surge forward
lateral       +Y                          starboard ("right")
throttle      -Z                          ascend; the roll/pitch factors of the
                                          vertical motors fix this sign (below)
roll          +K                          starboard side down
pitch         +M                          nose up
yaw           +N                          clockwise seen from above
============  ==========================  ==================================

The signs are checked against each other in the table itself: VECTORED_6DOF motor 5
(front right, vertical) has roll +1, pitch -1, throttle -1.  A downward force at a
point forward and to starboard gives +K and -M, so +output pushes down, and throttle
(+1 = up) then has factor -1, as in the table.  The horizontal motors agree the same
way (motor 1, front right: forward -1, lateral +1, yaw +1 = force backward-starboard
at the front right, which turns the vehicle clockwise).

**The check.**  A vehicle file lists its thrusters in ArduSub motor order (unit i is
Motor i, whose command the importer writes to ``pwm_i``).  For every motor and every
axis where its factor is non-zero, the sign of the vehicle's allocation column
(``B[:, i]``, the generalized force of +1 N on thruster i) must equal
``MOT_i_DIRECTION x factor``.  Axes with a zero factor are not compared (the factors
are a control mixing, not the geometry).  Any disagreement is an error naming the log,
its parameters and the vehicle file's thruster.  ``adapt=True`` instead flips the
direction of a thruster whose compared signs are *all* opposite (the situation a
``MOT_n_DIRECTION = -1`` describes: a reversed propeller or wiring) and reports it; a
thruster that agrees on some axes and not on others has a different geometry and
stays an error.
"""
from __future__ import annotations

import copy

import numpy as np

from uvsim.errors import LogFormatError

AXES = ("roll", "pitch", "yaw", "throttle", "forward", "lateral")
#: ArduSub command axis -> (index in uvsim's [X, Y, Z, K, M, N], sign)
AXIS_TO_TAU = {"forward": (0, 1), "lateral": (1, 1), "throttle": (2, -1),
               "roll": (3, 1), "pitch": (4, 1), "yaw": (5, 1)}
TAU_NAMES = ("X", "Y", "Z", "K", "M", "N")

#: FRAME_CONFIG -> (name, {motor: (roll, pitch, yaw, throttle, forward, lateral)}),
#: AP_Motors6DOF.cpp setup_motors (ArduPilot, commit 0fd5fbf2 in the code index).
FRAMES = {
    0: ("BLUEROV1", {1: (0, 0, -1, 0, 1, 0), 2: (0, 0, 1, 0, 1, 0), 3: (-0.5, 0.5, 0, 0.45, 0, 0),
                     4: (0.5, 0.5, 0, 0.45, 0, 0), 5: (0, -1, 0, 1, 0, 0), 6: (-0.25, 0, 0, 0, 0, 1)}),
    1: ("VECTORED", {1: (0, 0, 1, 0, -1, 1), 2: (0, 0, -1, 0, -1, -1), 3: (0, 0, -1, 0, 1, 1),
                     4: (0, 0, 1, 0, 1, -1), 5: (1, 0, 0, -1, 0, 0), 6: (-1, 0, 0, -1, 0, 0)}),
    2: ("VECTORED_6DOF", {1: (0, 0, 1, 0, -1, 1), 2: (0, 0, -1, 0, -1, -1), 3: (0, 0, -1, 0, 1, 1),
                          4: (0, 0, 1, 0, 1, -1), 5: (1, -1, 0, -1, 0, 0), 6: (-1, -1, 0, -1, 0, 0),
                          7: (1, 1, 0, -1, 0, 0), 8: (-1, 1, 0, -1, 0, 0)}),
    3: ("VECTORED_6DOF_90DEG", {1: (1, 1, 0, 1, 0, 0), 2: (0, 0, 1, 0, 1, 0), 3: (1, -1, 0, 1, 0, 0),
                                4: (0, 0, 0, 0, 0, 1), 5: (0, 0, 0, 0, 0, 1), 6: (-1, 1, 0, 1, 0, 0),
                                7: (0, 0, -1, 0, 1, 0), 8: (-1, -1, 0, 1, 0, 0)}),
}
_SIMPLE = ("SIMPLEROV", {1: (0, 0, -1, 0, 1, 0), 2: (0, 0, 1, 0, 1, 0), 3: (0, 0, 0, -1, 0, 0),
                         4: (0, 0, 0, -1, 0, 0), 5: (0, 0, 0, 0, 0, 1)})
for _k in (4, 5, 6):  # SIMPLEROV_3/4/5 share the default table
    FRAMES[_k] = _SIMPLE


def motor_function(servo_function: int) -> int | None:
    """Motor number of an output's ``SERVOn_FUNCTION`` (33..40 -> Motor1..8, 82..85 ->
    Motor9..12, ArduPilot ``SRV_Channel::Aux_servo_function_t``), else None."""
    f = int(servo_function)
    if 33 <= f <= 40:
        return f - 32
    if 82 <= f <= 85:
        return f - 73
    return None


def motor_outputs(params: dict, where: str) -> dict[int, int]:
    """{motor: servo output channel} from the log's ``SERVOn_FUNCTION`` parameters."""
    out = {}
    for n in range(1, 33):
        v = params.get(f"SERVO{n}_FUNCTION")
        if v is None:
            continue
        m = motor_function(v)
        if m is not None:
            if m in out:
                raise LogFormatError(f"{where}: SERVO{out[m]}_FUNCTION and SERVO{n}_FUNCTION both drive Motor{m}")
            out[m] = n
    if not out:
        raise LogFormatError(f"{where}: no SERVOn_FUNCTION parameter assigns a motor (33..40 = Motor1..8); "
                             "the log carries no usable parameter list")
    return out


def expected_signs(frame_config: int, directions: dict[int, float], where: str) -> dict[int, np.ndarray]:
    """Per motor, the expected sign (+1/-1, 0 = not compared) of [X, Y, Z, K, M, N] for a
    command above neutral: ``MOT_n_DIRECTION x factor`` mapped with :data:`AXIS_TO_TAU`."""
    if frame_config not in FRAMES:
        raise LogFormatError(f"{where}: FRAME_CONFIG = {frame_config} has no built-in motor table "
                             f"(known: {', '.join(f'{k} {v[0]}' for k, v in FRAMES.items())})")
    out = {}
    for motor, fac in FRAMES[frame_config][1].items():
        d = float(directions.get(motor, 1.0))
        s = np.zeros(6)
        for a, f in zip(AXES, fac):
            i, sign = AXIS_TO_TAU[a]
            s[i] = np.sign(f) * sign * np.sign(d)
        out[motor] = s
    return out


def check_frame(matrix: np.ndarray, names: list[str], frame_config: int, directions: dict[int, float], *,
                log: str, vehicle: str) -> tuple[list[dict], list[dict]]:
    """Compare a vehicle allocation ``matrix`` (6, n) with the log's frame.

    Returns ``(table, mismatches)``: one row per thruster (motor, direction, expected and
    vehicle signs) and the thrusters that disagree, each with ``flippable`` (all compared
    signs opposite).  Raises LogFormatError when the thruster counts differ."""
    name = FRAMES.get(frame_config, (f"FRAME_CONFIG {frame_config}",))[0]
    exp = expected_signs(frame_config, directions, log)
    n = matrix.shape[1]
    if n != len(exp):
        raise LogFormatError(f"{log}: frame {name} (FRAME_CONFIG={frame_config}) has {len(exp)} motors but vehicle "
                             f"{vehicle} has {n} thrusters; choose a vehicle file for this frame (--vehicle)")
    scale = np.abs(matrix).max(axis=0)
    table, bad = [], []
    for j in range(n):
        motor = j + 1
        s = exp[motor]
        axes = np.flatnonzero(s)
        b = matrix[:, j]
        got = np.where(np.abs(b) > 1e-6 * max(scale[j], 1e-12), np.sign(b), 0.0)
        agree = got[axes] == s[axes]
        row = {"thruster": names[j], "motor": motor, "MOT_DIRECTION": float(directions.get(motor, 1.0)),
               "expected": {TAU_NAMES[i]: int(s[i]) for i in axes},
               "vehicle": {TAU_NAMES[i]: round(float(b[i]), 6) for i in axes}}
        table.append(row)
        if not agree.all():
            row = dict(row, flippable=bool(np.all(got[axes] == -s[axes])),
                       disagree=[TAU_NAMES[i] for i in axes[~agree]])
            bad.append(row)
    return table, bad


def mismatch_message(bad: list[dict], frame_config: int, *, log: str, vehicle: str) -> str:
    name = FRAMES[frame_config][0]
    parts = []
    for r in bad:
        exp = ", ".join(f"{k}{'+' if v > 0 else '-'}" for k, v in r["expected"].items())
        got = ", ".join(f"{k}={v:+.3g}" for k, v in r["vehicle"].items())
        parts.append(f"{r['thruster']} (Motor{r['motor']}, MOT_{r['motor']}_DIRECTION={r['MOT_DIRECTION']:+g}): "
                     f"log expects {exp} for PWM > 1500 us, vehicle gives {got}")
    hint = (" All listed thrusters are exactly reversed (a MOT_n_DIRECTION = -1 propeller/wiring): "
            "pass --adapt-vehicle to write a copy of the vehicle file with their directions flipped."
            if all(r["flippable"] for r in bad) else " Some thrusters differ in geometry, not only in direction.")
    return (f"{log}: thruster layout of frame {name} (FRAME_CONFIG={frame_config}) does not match vehicle "
            f"{vehicle}: " + "; ".join(parts) + "." + hint)


def adapted_vehicle_dict(vdict: dict, bad: list[dict]) -> dict:
    """A copy of a vehicle-file dict with the direction (or matrix column) of each
    thruster in ``bad`` negated."""
    d = copy.deepcopy(vdict)
    th = d["thrusters"]
    for r in bad:
        j = r["motor"] - 1
        if "units" in th:
            th["units"][j]["direction"] = [-float(x) for x in th["units"][j]["direction"]]
        else:
            for row in th["configuration_matrix"]:
                row[j] = -float(row[j])
    return d
