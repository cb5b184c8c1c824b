"""Flight modes -> whether a run was flown under an autopilot (the manifest's ``closed_loop``).

Both importers read the autopilot's flight mode over time (``uvsim import ardusub``: the mode
number of ``HEARTBEAT.custom_mode`` or DataFlash ``MODE.ModeNum``; ``uvsim import bag``: the
mode name of a ``mavros_msgs/State`` topic) and write ``closed_loop`` on each run:

* ``True`` where every mode over the run holds some state (attitude, rates, depth, position);
* ``False`` where the run was flown in MANUAL throughout;
* nothing (None) where no mode is known at the run's start, or the run mixes both kinds, or a
  mode of neither kind (MOTOR_DETECT, a mode this table does not know) is among them.

docs/log_format.md says what ``closed_loop`` changes (the judging of closed-loop runs).
"""
from __future__ import annotations

import re

#: ArduSub flight modes (HEARTBEAT.custom_mode, DataFlash MODE.ModeNum): MAVLink ardupilotmega.xml,
#: enum SUB_MODE; a bag's ``mavros_msgs/State.mode`` carries a mode's name, or ``CMODE(n)`` for a
#: number mavros has no name for, which :func:`mode_name` reads as ArduSub's mode ``n`` (for another
#: autopilot it then matches none of its names, so such a run is "not known").  MANUAL passes the
#: pilot's sticks to the motors; every other mode holds some state (attitude, rates, depth, position) in closed loop, except
#: MOTOR_DETECT, a test of the motors (ArduPilot wiki, "Sub Modes").
SUB_MODES = {0: "STABILIZE", 1: "ACRO", 2: "ALT_HOLD", 3: "AUTO", 4: "GUIDED", 7: "CIRCLE", 9: "SURFACE",
             16: "POSHOLD", 19: "MANUAL", 20: "MOTOR_DETECT", 21: "SURFTRAK"}
OPEN_LOOP_MODES = {19}
CLOSED_LOOP_MODES = {0, 1, 2, 3, 4, 7, 9, 16, 21}
#: The same sets by name (the defaults of a bag map's mode stream).
OPEN_LOOP_NAMES = sorted(SUB_MODES[m] for m in OPEN_LOOP_MODES)
CLOSED_LOOP_NAMES = sorted(SUB_MODES[m] for m in CLOSED_LOOP_MODES)
_CMODE = re.compile(r"^CMODE\((\d+)\)$")


def closed_loop_over(modes, start: float, end: float, closed=CLOSED_LOOP_MODES, open_=OPEN_LOOP_MODES,
                     lead: float = 0.0):
    """Whether the vehicle flew ``start..end`` (s) under modes that hold some state (True), under
    open-loop modes only (False), or not known (None).

    Parameters
    ----------
    modes : ``[(t_s, mode)]`` in time order, the mode from ``t_s`` on.
    closed, open_ : the modes of each kind (numbers or names, as ``modes`` has them).
    lead : s; a report up to ``lead`` after ``start`` stands for the mode at ``start`` (a topic that
        reports the mode periodically, as mavros' State does at 1 Hz, reports it at most one
        interval late); 0: only a report at or before ``start`` does.
    """
    before = [m for t, m in modes if t <= start + lead]
    if not before:  # no mode logged, or none yet when the segment starts
        return None
    first = [m for t, m in modes if t <= start] or before[:1]
    inside = {first[-1]} | {m for t, m in modes if start < t < end}
    if inside <= set(closed):
        return True
    if inside <= set(open_):
        return False
    return None


def mode_changes(modes) -> list:
    """``[(t_s, mode)]`` where the mode changes (the first sample included)."""
    return [(t, m) for k, (t, m) in enumerate(modes) if k == 0 or m != modes[k - 1][1]]


def mode_record(modes, *, source: str, rule: str, name=str, **extra) -> dict:
    """An import record's ``flight_modes``: ``source`` (what the modes were read from), ``extra``
    entries, ``changes`` (:func:`mode_changes`, each mode shown by ``name``) and ``closed_loop``
    (``rule``: how a run's closed_loop was taken from them)."""
    return {"source": source, **extra,
            "changes": [{"t_s": round(t, 3), "mode": name(m)} for t, m in mode_changes(modes)],
            "closed_loop": rule}


def mode_name(value) -> str:
    """The name of a mode as a bag carries it: ``CMODE(n)`` (mavros, a mode without a name) becomes
    ArduSub's name for ``n`` where it has one; anything else is kept, stripped."""
    name = str(value).strip()
    m = _CMODE.match(name)
    if m and int(m.group(1)) in SUB_MODES:
        return SUB_MODES[int(m.group(1))]
    return name


__all__ = ["SUB_MODES", "OPEN_LOOP_MODES", "CLOSED_LOOP_MODES", "OPEN_LOOP_NAMES", "CLOSED_LOOP_NAMES",
           "closed_loop_over", "mode_changes", "mode_name", "mode_record"]
