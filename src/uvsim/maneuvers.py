"""SAM hydrobatic maneuvers (seed 003 sec. V-C and V-D) as command sequences, with the
quantities the paper states about them.

Each maneuver is a function of time returning SAM's command vector (columns
:data:`uvsim.sam.vehicle.SAM_INPUTS`: rpm_1, rpm_2 [rev/min], tv_pitch, tv_yaw [rad],
vbs, lcg [%], tcg [rad]) and an initial state.  :func:`run_maneuver` simulates it with
fixed-step RK4 (quaternion kinematics, so any attitude) and returns a
:class:`ManeuverResult` whose ``frame`` has the LOG_FORMAT columns (t, x, y, z, qw..qz,
roll, pitch, yaw, u..r), the commands as ``thrust_1..thrust_7`` (LOG_FORMAT's per-actuator
input columns; here the SAM command vector, so the file replays with
``uvsim.simulate_run(load_sam(), read_run(file))``) and the actuator states ``*_act``.

Maneuvers (command parameters from seed 003 where it gives them, otherwise stated):

* ``tight_loop`` - vertical turbo-turn: both propellers and the vertical thrust vector
  cycled together between +-1525 rpm (the rpm limit) and +-7 deg (sec. V-C-1, Fig. 18),
  square wave of period 1 s [assumed: the same cycle as the horizontal turbo-turn];
* ``turbo_turn`` - horizontal turbo-turn as in the field test (sec. V-D): +-1000 rpm and
  +-5 deg rudder, VBS and LCG at 50 %, square wave of period 1 s (Fig. 30 shows a yaw-rate
  oscillation close to 1 Hz; the period is therefore taken from the paper, and the test
  checks that the vehicle follows it);
* ``helix`` - the loop cycle plus a constant +7 deg horizontal thrust vector (sec. V-C-3
  "the horizontal thrust vector is also used"; our reading, Fig. 24 is not available), meant
  to make the loop precess in yaw; with a near-symmetric reverse thrust its yaw moment
  nearly cancels over a cycle (docs/sam.md);
* ``lcg_sweep`` - propellers off, VBS neutral, LCG all the way forward at 5 s and all
  the way back at 45 s (sec. V-C-4, Fig. 27);
* ``accelerating_turn`` - rpm ramped from 0 to 1525 over 30 s with the horizontal thrust
  vector at 7 deg (sec. V-C, the performance check of Table V).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from uvsim.errors import SimulationError
from uvsim.sam.subsystems import servo_time_constants
from uvsim.sam.vehicle import NEUTRAL, SAM_INPUTS, load_sam

#: Most samples a maneuver may have (50 Hz for 55 h), refused before anything is allocated; a
#: sample costs up to BYTES_PER_SAMPLE at peak (states, inputs, actuator states and the output
#: frame with their copies: 650-790 bytes measured with tracemalloc on tight_loop, 30-600 s).
MAX_SAMPLES = 10_000_000
BYTES_PER_SAMPLE = 1000
RPM_MAX = 1525.0                 # rev/min, smarc_modelling SAM.py
TV_MAX = np.radians(7.0)         # rad, seed 003 sec. V-A-1 / SAM.py


def _square(t, period):
    """+1 on the first half of each period, -1 on the second."""
    return np.where((np.asarray(t) % period) < 0.5 * period, 1.0, -1.0)


@dataclass
class Maneuver:
    """A command sequence and initial state.

    Attributes
    ----------
    name, description : str
    duration : float, s
    dt : float, s (RK4 step and output sample interval)
    commands : callable ``t (n_t,) -> (n_t, 7)`` command array
    nu0 : (6,) initial body velocity
    """

    name: str
    description: str
    duration: float
    dt: float
    commands: Callable[[np.ndarray], np.ndarray]
    nu0: np.ndarray = field(default_factory=lambda: np.zeros(6))


def _cmd(t, **cols):
    u = np.tile(NEUTRAL, (np.size(t), 1))
    for k, v in cols.items():
        u[:, SAM_INPUTS.index(k)] = v
    return u


def tight_loop_commands(t, period=1.0, rpm=RPM_MAX, tv=TV_MAX):
    s = _square(t, period)
    return _cmd(t, rpm_1=rpm * s, rpm_2=rpm * s, tv_pitch=tv * s)


def turbo_turn_commands(t, period=1.0, rpm=1000.0, tv=np.radians(5.0)):
    s = _square(t, period)
    return _cmd(t, rpm_1=rpm * s, rpm_2=rpm * s, tv_yaw=tv * s)


def helix_commands(t, period=1.0, rpm=RPM_MAX, tv=TV_MAX, tv_yaw=TV_MAX):
    s = _square(t, period)
    return _cmd(t, rpm_1=rpm * s, rpm_2=rpm * s, tv_pitch=tv * s, tv_yaw=np.full(np.size(t), tv_yaw))


def lcg_sweep_commands(t, t_forward=5.0, t_back=45.0):
    t = np.asarray(t)
    lcg = np.where(t < t_forward, 50.0, np.where(t < t_back, 100.0, 0.0))
    return _cmd(t, lcg=lcg)


def accelerating_turn_commands(t, ramp=30.0, rpm=RPM_MAX, tv=TV_MAX):
    r = rpm * np.clip(np.asarray(t) / ramp, 0.0, 1.0)
    return _cmd(t, rpm_1=r, rpm_2=r, tv_yaw=np.full(np.size(t), tv))


MANEUVERS: dict[str, Maneuver] = {
    "tight_loop": Maneuver("tight_loop", "vertical turbo-turn (+-1525 rpm, +-7 deg pitch vector, 1 s cycle)",
                           30.0, 0.02, tight_loop_commands),
    "turbo_turn": Maneuver("turbo_turn", "horizontal turbo-turn (+-1000 rpm, +-5 deg yaw vector, 1 s cycle)",
                           40.0, 0.02, turbo_turn_commands),
    "helix": Maneuver("helix", "loop cycle with a constant +7 deg yaw vector", 40.0, 0.02, helix_commands),
    "lcg_sweep": Maneuver("lcg_sweep", "propellers off; LCG forward at 5 s, back at 45 s", 85.0, 0.02,
                          lcg_sweep_commands),
    "accelerating_turn": Maneuver("accelerating_turn", "rpm ramp 0 -> 1525 in 30 s, yaw vector 7 deg",
                                  30.0, 0.02, accelerating_turn_commands),
}


@dataclass
class ManeuverResult:
    """Result of :func:`run_maneuver`: ``frame`` (pandas DataFrame, see module docstring),
    the :class:`uvsim.SimulationResult` ``sim``, ``metrics`` (dict) and ``wall_time`` (s)."""

    name: str
    dataset: str
    frame: object
    sim: object
    metrics: dict
    wall_time: float


def to_frame(sim):
    """LOG_FORMAT DataFrame of a SAM simulation: states, Euler angles, commands as
    ``thrust_1..7``, actuator states ``*_act``."""
    return sim.to_pandas()


def run_maneuver(name: str, dataset: str = "multifidelity", dt: float | None = None,
                 duration: float | None = None, vehicle=None) -> ManeuverResult:
    """Simulate maneuver ``name`` (see :data:`MANEUVERS`) with the hull data set ``dataset``."""
    from uvsim.sam.model import make_model
    from uvsim.simulate import simulate

    if name not in MANEUVERS:
        raise SimulationError(f"unknown maneuver {name!r}; known: {', '.join(MANEUVERS)}")
    m = MANEUVERS[name]
    dt = m.dt if dt is None else float(dt)
    duration = m.duration if duration is None else float(duration)
    if not (np.isfinite(dt) and np.isfinite(duration) and dt > 0 and duration > dt):
        raise SimulationError(f"maneuver {name}: need 0 < dt < duration, got dt={dt}, duration={duration}")
    n = int(duration / dt) + 1
    if n > MAX_SAMPLES:
        raise SimulationError(f"maneuver {name}: duration {duration:g} s at dt {dt:g} s is {n:.3g} samples "
                              f"(~{n * BYTES_PER_SAMPLE / 1e9:.3g} GB); at most {MAX_SAMPLES:.0e}: shorten --duration "
                              "or lengthen --dt")
    veh = load_sam(dataset) if vehicle is None else vehicle
    taus = servo_time_constants(veh)
    if taus and dt > min(taus.values()):
        fastest = min(taus, key=taus.get)
        raise SimulationError(f"maneuver {name}: dt {dt:g} s is longer than the fastest actuator time constant "
                              f"({fastest}, {taus[fastest]:g} s); RK4 then misses (or blows up on) that lag: "
                              f"use dt <= {taus[fastest]:g} s (default {m.dt:g} s)")
    t = np.arange(0.0, duration + 0.5 * dt, dt)
    u = m.commands(t)
    model = make_model(veh)
    t0 = time.perf_counter()
    sim = simulate(veh, t, u, input_kind="thrust", nu0=m.nu0, model=model)
    wall = time.perf_counter() - t0
    frame = to_frame(sim)
    return ManeuverResult(name, dataset, frame, sim, maneuver_metrics(name, frame), wall)


# ----------------------------------------------------------------------------- measurements
def dominant_frequency(t, x, t_start: float = 0.0) -> float:
    """Frequency (Hz) of the largest FFT peak of ``x`` (mean removed) after ``t_start``."""
    t = np.asarray(t)
    t_start = min(t_start, 0.5 * (t[0] + t[-1]))  # short runs: use the second half
    sel = t >= t_start
    x = np.asarray(x)[sel] - np.mean(np.asarray(x)[sel])
    dt = float(np.median(np.diff(t[sel])))
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))
    f = np.fft.rfftfreq(x.size, dt)
    spec[0] = 0.0
    return float(f[int(np.argmax(spec))])


def cycle_amplitude(t, x, period: float, t_start: float = 5.0) -> float:
    """Mean half peak-to-peak of ``x`` over the whole cycles of length ``period`` (s)
    after ``t_start`` (the oscillation amplitude of a signal forced at that period)."""
    t, x = np.asarray(t), np.asarray(x)
    starts = np.arange(t_start, t[-1] - period + 1e-9, period)
    amps = [0.5 * np.ptp(x[(t >= a) & (t < a + period)]) for a in starts]
    return float(np.mean(amps)) if amps else float("nan")


def circle_radius(x, y) -> float:
    """Radius (m) of the least-squares circle through the points ``(x, y)`` (algebraic
    fit: ``x^2 + y^2 = 2 a x + 2 b y + c``, ``R = sqrt(c + a^2 + b^2)``)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    A = np.stack([2.0 * x, 2.0 * y, np.ones_like(x)], axis=1)
    (a, b, c), *_ = np.linalg.lstsq(A, x * x + y * y, rcond=None)
    return float(np.sqrt(c + a * a + b * b))


def maneuver_metrics(name: str, df) -> dict:
    """The numbers seed 003 states qualitatively, measured on a maneuver's frame.

    Besides extents, speeds and angle ranges: ``mean_surge_m_s`` (mean ``u`` after 5 s);
    ``elevation_min_deg`` / ``elevation_max_deg`` for the motions in the vertical x-z plane
    (loop, LCG sweep: angle of the body x axis in that plane, unwrapped, so a pitch past the
    vertical shows as > 90 deg); for the loop,
    ``loop_period_s`` (360 deg over the mean rate of that angle after 5 s); for the
    turbo-turn, the yaw-rate ``yaw_rate_freq_hz`` and ``yaw_rate_amplitude_rad_s`` (mean
    half peak-to-peak per 1 s command cycle after 5 s) and ``mean_yaw_rate_rad_s``; for
    the accelerating turn, ``turn_radius_m`` (circle fitted to the horizontal path) and
    ``sideslip_deg`` (mean ``atan2(v, u)``) over the last 5 s; for the LCG sweep, the pitch
    settled at the end of each LCG phase (mean over 40-45 s and 80-85 s)."""
    t = df["t"].to_numpy()
    pos = df[["x", "y", "z"]].to_numpy()
    ext = pos.max(axis=0) - pos.min(axis=0)
    roll, pitch, yaw = (np.unwrap(df[k].to_numpy()) for k in ("roll", "pitch", "yaw"))
    speed = np.linalg.norm(df[["u", "v", "w"]].to_numpy(), axis=1)
    out = {
        "extent_x_m": float(ext[0]), "extent_y_m": float(ext[1]), "extent_z_m": float(ext[2]),
        "max_speed_m_s": float(speed.max()),
        "roll_range_deg": float(np.degrees(roll.max() - roll.min())),
        "pitch_range_deg": float(np.degrees(pitch.max() - pitch.min())),
        "yaw_range_deg": float(np.degrees(yaw.max() - yaw.min())),
        "max_abs_pitch_deg": float(np.degrees(np.abs(df["pitch"].to_numpy()).max())),
    }
    # total rotation of the body x axis in the vertical plane (pitch through 180 deg and beyond):
    # angle of the x axis in the NED x-z plane, unwrapped, from the quaternion
    q = df[["qw", "qx", "qy", "qz"]].to_numpy()
    from uvsim.kinematics import quat_to_rotation

    R = quat_to_rotation(q)
    ex = R[:, :, 0]  # body x axis in NED
    elev = np.unwrap(np.arctan2(-ex[:, 2], np.hypot(ex[:, 0], ex[:, 1]) * np.sign(ex[:, 0] + 1e-300)))
    out["flight_path_rotation_deg"] = float(np.degrees(elev.max() - elev.min()))
    if name in ("tight_loop", "lcg_sweep"):  # motions in the NED x-z plane, where elev is the pitch
        out["elevation_min_deg"] = float(np.degrees(elev.min()))
        out["elevation_max_deg"] = float(np.degrees(elev.max()))
    heading = np.unwrap(np.arctan2(ex[:, 1], ex[:, 0]))
    out["heading_rotation_deg"] = float(np.degrees(heading.max() - heading.min()))
    late = t >= min(5.0, 0.5 * (t[0] + t[-1]))
    out["mean_surge_m_s"] = float(df["u"].to_numpy()[late].mean())
    if name == "tight_loop":
        out["box_xz_m"] = float(max(ext[0], ext[2]))
        rate = abs(elev[late][-1] - elev[late][0]) / (t[late][-1] - t[late][0])
        out["loop_period_s"] = float(2 * np.pi / rate) if rate > 0 else float("inf")
    if name in ("turbo_turn", "helix", "tight_loop"):
        out["yaw_rate_freq_hz"] = dominant_frequency(t, df["r"].to_numpy(), 5.0)
        out["pitch_rate_freq_hz"] = dominant_frequency(t, df["q"].to_numpy(), 5.0)
    if name == "turbo_turn":
        r = df["r"].to_numpy()
        out["box_xy_m"] = float(max(ext[0], ext[1]))
        out["yaw_rate_amplitude_rad_s"] = cycle_amplitude(t, r, 1.0, 5.0)
        out["mean_yaw_rate_rad_s"] = float(r[late].mean())
        out["depth_change_m"] = float(pos[-1, 2] - pos[0, 2])
    if name in ("accelerating_turn", "turbo_turn"):
        # seed 003 monitors the accelerating turn "up to 90 deg yaw angle"; the field turbo-turn
        # (sec. V-D) was "a turbo-turn over 90 deg yaw angle"
        k = int(np.argmax(np.abs(heading - heading[0]) >= np.pi / 2))
        out["time_to_90deg_heading_s"] = float(t[k]) if k > 0 else float("nan")
        out["speed_at_90deg_heading_m_s"] = float(speed[k]) if k > 0 else float("nan")
    if name == "accelerating_turn":
        end = t >= t[-1] - 5.0
        out["final_speed_m_s"] = float(speed[-1])
        out["turn_radius_m"] = circle_radius(pos[end, 0], pos[end, 1])
        out["sideslip_deg"] = float(np.degrees(np.arctan2(df["v"].to_numpy()[end], df["u"].to_numpy()[end]).mean()))
        out["max_abs_roll_deg"] = float(np.degrees(np.abs(df["roll"].to_numpy()).max()))
    if name == "lcg_sweep":
        p = np.degrees(df["pitch"].to_numpy())
        out["min_pitch_deg"] = float(p.min())
        out["max_pitch_deg"] = float(p.max())
        for a, b in ((40.0, 45.0), (80.0, 85.0)):
            sel = (t >= a) & (t < b)
            if sel.any():
                out[f"pitch_{a:g}_{b:g}s_deg"] = float(np.degrees(elev[sel].mean()))
    return out
