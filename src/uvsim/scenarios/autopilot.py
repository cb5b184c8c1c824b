"""An ArduSub-like autopilot for the field-log generator (:mod:`uvsim.scenarios.field`, issue 48).

Written for the truth model of this package, apart from the fitting code.  Every array holds
``n`` vehicles flown at once (one per run of a dataset), trajectory last where it is a vector.

What ArduSub does that a log shows, and what is taken from it here:

* **Mixer** (ArduPilot ``libraries/AP_Motors/AP_Motors6DOF.cpp``, ``setup_motors``, frame
  ``SUB_FRAME_VECTORED_6DOF``, the BlueROV2 Heavy): each motor's output is
  ``o_i = roll r_i + pitch p_i + yaw y_i + throttle t_i + forward f_i + lateral l_i`` with the
  factors of :data:`MOTOR_FACTORS`; the roll/pitch/yaw part is scaled down when some motor would
  need more than 1 (``output_armed_stabilizing``: ``rpy_ratio``), the sum clipped to [-1, 1], and
  ``PWM = 1500 + 400 o`` (``calc_thrust_to_pwm``: ``MOT_SPIN_NEUTRAL`` 1500 us, outputs
  1100-1900 us).  ``MOT_n_DIRECTION`` (a parameter the vehicle's setup sets) reverses a motor whose
  positive output pushes against the direction the vehicle file calls positive:
  :func:`motor_directions`.
* **Pilot gain** (ArduSub ``joystick.cpp``: ``JS_GAIN_DEFAULT`` 0.5): the forward and lateral
  sticks reach the mixer times 0.5.
* **Modes** (ardusub.com, "Flight Modes"): STABILIZE holds roll and pitch level and the heading
  when the yaw stick is centred, the throttle stick goes to the vertical motors; DEPTH HOLD
  (``ALT_HOLD``) does the same and holds the depth when the throttle stick is centred, its
  deflection commanding a climb rate (``PILOT_SPEED_UP/DN``, 50 cm/s by default).
* **Controllers** (structure of ArduPilot's ``AC_AttitudeControl``: angle error -> rate target
  by a P gain -> rate PID -> motor output; ``AC_PosControl`` z: depth error -> climb-rate target
  -> PI -> throttle).  The gains (:data:`GAINS`) are ours, tuned for this vehicle's inertia and
  thrust (seed 000 Table 5, the T200 at 16 V): the structure is ArduSub's, not its numbers.
* **Attitude filter**: ArduSub fuses gyro, accelerometer and compass in an EKF; a vehicle whose
  compass is off (steel frames, motors: the common case in a harbour) has an unobservable yaw.
  Here a complementary filter: roll and pitch integrate the gyro and are pulled towards the
  accelerometer's tilt with a time constant (:data:`FILTER_TIME_CONSTANT`); yaw only integrates
  the gyro, so it drifts with the gyro's bias (Mahony et al. 2008, IEEE TAC 53(5), the
  explicit complementary filter without magnetometer).
"""
from __future__ import annotations

import numpy as np

#: ArduSub ``SUB_FRAME_VECTORED_6DOF`` motor factors (AP_Motors6DOF.cpp, ``setup_motors``):
#: rows motors 1..8, columns (roll, pitch, yaw, throttle, forward, lateral).  Motors 1-4 are the
#: horizontal vectored ones (front right, front left, rear right, rear left), 5-8 the vertical
#: ones (front right, front left, rear right, rear left), as in ArduSub's BlueROV2 Heavy frame
#: diagram (ardusub.com, "Frame types").
MOTOR_FACTORS = np.array([
    [0.0, 0.0, 1.0, 0.0, -1.0, 1.0],
    [0.0, 0.0, -1.0, 0.0, -1.0, -1.0],
    [0.0, 0.0, -1.0, 0.0, 1.0, 1.0],
    [0.0, 0.0, 1.0, 0.0, 1.0, -1.0],
    [1.0, -1.0, 0.0, -1.0, 0.0, 0.0],
    [-1.0, -1.0, 0.0, -1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0, -1.0, 0.0, 0.0],
    [-1.0, 1.0, 0.0, -1.0, 0.0, 0.0],
])
#: PWM of a motor output (AP_Motors6DOF.cpp ``calc_thrust_to_pwm``): neutral and range, us.
PWM_NEUTRAL, PWM_RANGE = 1500.0, 400.0
#: ArduSub ``joystick.cpp`` JS_GAIN_DEFAULT: the pilot's sticks reach the mixer times this.
PILOT_GAIN = 0.5
#: ArduSub ``PILOT_SPEED_UP`` / ``PILOT_SPEED_DN`` default, m/s (50 cm/s).
PILOT_CLIMB_RATE = 0.5
#: Depth (m) above which the pilot stops climbing, and the STABILIZE pilot's depth correction
#: (stick per m of depth error; ours: a thumb that notices a metre, not a centimetre).
SURFACE_MARGIN, PILOT_DEPTH_P = 0.8, 0.5
#: Largest yaw rate a full yaw stick asks for, rad/s (ours: ~30 deg/s, a calm pilot's turn).
PILOT_YAW_RATE = 0.5
#: Control loop, Hz (ArduSub's main loop runs the attitude and depth controllers at 400 Hz on a
#: Pixhawk; 50 Hz here keeps the truth's integration affordable and is still 5-10x the log).
CONTROL_HZ = 50.0
#: Complementary filter: time constant (s) pulling roll and pitch to the accelerometer's tilt
#: (Mahony et al. 2008: k_P ~ 1/tau of 0.5-5 s for a MEMS IMU; 2 s here).
FILTER_TIME_CONSTANT = 2.0
#: Controller gains (ours, module docstring).  Attitude: angle P (1/s); rate P, I, D per axis in
#: motor output per rad/s (roll, pitch, yaw).  Depth: P (1/s) to a climb rate, climb-rate P and I
#: to throttle (per m/s and per m).  Outputs are limited to [-1, 1] by the mixer.
GAINS = {
    "angle_p": np.array([4.0, 4.0, 3.0]),
    "rate_p": np.array([0.35, 0.35, 0.6]),
    "rate_i": np.array([0.15, 0.15, 0.2]),
    "rate_d": np.array([0.005, 0.005, 0.0]),
    "depth_p": 1.0,
    "climb_p": 1.5,
    "climb_i": 0.5,
}
#: Integrator limits (motor output units), as ArduPilot's ``IMAX``.
RATE_IMAX, CLIMB_IMAX = 0.3, 0.6


def motor_directions(thruster_directions: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """``MOT_n_DIRECTION`` (+1 / -1) of each motor: +1 when a positive output of ArduSub's mixer
    pushes along the vehicle file's direction of positive thrust, -1 when against it.  ArduSub's
    direction of motor ``i`` is the one its forward/lateral/throttle factors ask for (vertical
    motors: throttle -1 means a positive output pushes down, +z)."""
    f = MOTOR_FACTORS
    want = np.stack([f[:, 4], f[:, 5], -f[:, 3]], axis=1)
    s = np.sign((want * np.asarray(thruster_directions)).sum(axis=1))
    return np.where(s == 0, 1.0, s)


def wrap(a):
    """Angle(s) into (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(a), 2 * np.pi)


class Filter:
    """Complementary attitude filter without a compass (module docstring), ``n`` vehicles."""

    def __init__(self, rpy0: np.ndarray, dt: float, tau: float = FILTER_TIME_CONSTANT):
        self.rpy = np.array(rpy0, dtype=float)      # (3, n)
        self.dt, self.alpha = dt, dt / tau

    def update(self, gyro: np.ndarray, acc: np.ndarray) -> np.ndarray:
        """One step with gyro (3, n) rad/s and specific force (3, n) m/s^2; returns (3, n)."""
        phi, th, psi = self.rpy
        p, q, r = gyro
        t = np.tan(th)
        # Euler-angle kinematics (Fossen 2021 eq. 2.41)
        phi = phi + self.dt * (p + (q * np.sin(phi) + r * np.cos(phi)) * t)
        th = th + self.dt * (q * np.cos(phi) - r * np.sin(phi))
        psi = psi + self.dt * (q * np.sin(phi) + r * np.cos(phi)) / np.cos(th)
        # the accelerometer's tilt: f = (g sin th, -g sin phi cos th, -g cos phi cos th) at rest
        ax, ay, az = acc
        phi_a = np.arctan2(-ay, -az)
        th_a = np.arctan2(ax, np.sqrt(ay * ay + az * az))
        phi = phi + self.alpha * wrap(phi_a - phi)
        th = th + self.alpha * (th_a - th)
        self.rpy = np.array([wrap(phi), th, wrap(psi)])
        return self.rpy


class Autopilot:
    """STABILIZE / DEPTH HOLD with heading hold for ``n`` vehicles (module docstring).

    ``depth_hold`` (n,) bool: which vehicles fly in DEPTH HOLD (the others in STABILIZE)."""

    def __init__(self, n: int, dt: float, depth_hold: np.ndarray, depth0: np.ndarray, yaw0: np.ndarray,
                 gains: dict | None = None):
        self.g = {**GAINS, **(gains or {})}
        self.dt = dt
        self.depth_hold = np.asarray(depth_hold, dtype=bool)
        self.depth_target = np.array(depth0, dtype=float)
        self.yaw_target = np.array(yaw0, dtype=float)
        self.rate_int = np.zeros((3, n))
        self.prev_rate_err = np.zeros((3, n))
        self.climb_int = np.zeros(n)

    def step(self, sticks: np.ndarray, rpy: np.ndarray, gyro: np.ndarray, depth: np.ndarray,
             climb: np.ndarray) -> np.ndarray:
        """Motor outputs (8, n) in [-1, 1] for pilot ``sticks`` (4, n: forward, lateral, throttle,
        yaw, each in [-1, 1]), the filter's ``rpy`` (3, n), the gyro (3, n), the pressure sensor's
        depth (n,) and its rate of change (n,, m/s, + down)."""
        g, dt = self.g, self.dt
        fwd, lat, thr, yaw_stick = sticks
        # near the surface a pilot stops climbing (ArduSub's SURFACE_DEPTH, -10 cm by default, stops
        # a climb in DEPTH HOLD at the surface; here the pilot keeps SURFACE_MARGIN of water above)
        thr = np.where((depth < SURFACE_MARGIN) & (thr > 0), 0.0, thr)
        # heading hold: a centred yaw stick holds the heading it was released at
        yaw_free = np.abs(yaw_stick) > 0.05
        self.yaw_target = np.where(yaw_free, rpy[2], self.yaw_target)
        ang_err = np.array([-rpy[0], -rpy[1], wrap(self.yaw_target - rpy[2])])
        rate_t = g["angle_p"][:, None] * ang_err
        rate_t[2] = np.where(yaw_free, PILOT_YAW_RATE * yaw_stick, rate_t[2])
        err = rate_t - gyro
        self.rate_int = np.clip(self.rate_int + g["rate_i"][:, None] * err * dt, -RATE_IMAX, RATE_IMAX)
        d = (err - self.prev_rate_err) / dt
        self.prev_rate_err = err
        rpy_out = g["rate_p"][:, None] * err + self.rate_int + g["rate_d"][:, None] * d
        # depth: DEPTH HOLD holds the depth at a centred stick, else a climb rate (+ up);
        # STABILIZE passes the stick to the vertical motors
        thr_free = np.abs(thr) > 0.05
        self.depth_target = np.maximum(np.where(thr_free, depth, self.depth_target), SURFACE_MARGIN)
        climb_t = np.where(thr_free, PILOT_CLIMB_RATE * thr, g["depth_p"] * (depth - self.depth_target))
        c_err = climb_t - (-climb)
        self.climb_int = np.where(self.depth_hold, np.clip(self.climb_int + g["climb_i"] * c_err * dt,
                                                           -CLIMB_IMAX, CLIMB_IMAX), 0.0)
        # STABILIZE: the stick goes to the vertical motors, and the pilot's thumb holds the depth
        # loosely by eye (a P correction of PILOT_DEPTH_P per m, at most half a stick)
        by_hand = PILOT_GAIN * (thr + np.where(thr_free, 0.0, np.clip(PILOT_DEPTH_P * (depth - self.depth_target),
                                                                        -0.5, 0.5)))
        throttle = np.where(self.depth_hold, g["climb_p"] * c_err + self.climb_int, by_hand)
        return mix(rpy_out, np.array([throttle, PILOT_GAIN * fwd, PILOT_GAIN * lat]))


def mix(rpy: np.ndarray, linear: np.ndarray) -> np.ndarray:
    """ArduSub's mix (module docstring): ``rpy`` (3, n) roll, pitch, yaw and ``linear`` (3, n)
    throttle (+ up), forward, lateral, each in motor-output units; returns (8, n) in [-1, 1]."""
    F = MOTOR_FACTORS
    rpy_out = F[:, :3] @ rpy
    high = np.max(np.abs(rpy_out), axis=0)
    ratio = np.where(high > 1.0, 1.0 / np.maximum(high, 1e-12), 1.0)
    lin = F[:, 3:] @ np.clip(linear, -1.0, 1.0)
    return np.clip(ratio * rpy_out + lin, -1.0, 1.0)


def pwm(outputs: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """PWM (us, whole microseconds as the autopilot writes them) of motor outputs (8, n) with the
    motors' ``MOT_n_DIRECTION`` (8,)."""
    return np.rint(PWM_NEUTRAL + PWM_RANGE * directions[:, None] * outputs)


# pilot sticks ---------------------------------------------------------------------------------
#: What a pilot on a survey does with each stick: (probability a hold moves it, deflection
#: range).  Forward is the main stick, yaw and throttle next, lateral less (ours, after the
#: pilot runs of :mod:`uvsim.scenarios.inputs`).
STICK_USE = {"forward": (0.6, (0.3, 0.8)), "lateral": (0.3, (0.3, 0.7)), "throttle": (0.35, (0.3, 0.8)),
             "yaw": (0.45, (0.3, 0.9))}
#: Seconds of one manoeuvre (ramp, hold) and of the rest between (ours).
STICK_RAMP, STICK_HOLD, STICK_REST = (0.3, 1.0), (2.0, 8.0), (1.0, 5.0)


def sample_sticks(rng: np.random.Generator, duration: float) -> dict:
    """Stick knots ``{name: [[t, s], ...]}`` of one run (linear between knots, s in [-1, 1]):
    manoeuvres one after another, each moving some sticks, then releasing them."""
    knots = {k: [[0.0, 0.0]] for k in STICK_USE}
    t = float(rng.uniform(*STICK_REST))
    while t < duration:
        ramp, hold = float(rng.uniform(*STICK_RAMP)), float(rng.uniform(*STICK_HOLD))
        moved = [k for k, (p, _) in STICK_USE.items() if rng.random() < p] or ["forward"]
        for k in STICK_USE:
            level = 0.0
            if k in moved:
                lo, hi = STICK_USE[k][1]
                level = float(rng.uniform(lo, hi) * rng.choice([-1.0, 1.0]))
            knots[k] += [[round(t, 3), knots[k][-1][1]], [round(t + ramp, 3), level],
                         [round(t + ramp + hold, 3), level], [round(t + 2 * ramp + hold, 3), 0.0]]
        t += 2 * ramp + hold + float(rng.uniform(*STICK_REST))
    return knots


def sticks_at(knots: dict, t: np.ndarray) -> np.ndarray:
    """(4, n_t) stick deflections (forward, lateral, throttle, yaw) at times ``t``."""
    out = []
    for k in STICK_USE:
        a = np.asarray(knots[k], dtype=float)
        keep = np.r_[True, np.diff(a[:, 0]) > 0]
        out.append(np.interp(t, a[keep, 0], a[keep, 1]))
    return np.array(out)
