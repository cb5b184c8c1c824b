"""Measurement models: what each sensor logs, given the true motion of one run.

Written independently of ``uvsim.synthetic``/``uvsim.metrics``; attitude conversions use
:class:`scipy.spatial.transform.Rotation`.  The sensor settings of a dataset are a dict
(``ScenarioSpec.sensors``) with any of these sections:

``mocap``  ``sigma_position`` (m), ``sigma_attitude`` (rad): position of the body origin
           plus white noise; quaternion ``q (x) exp(delta)``, ``delta ~ N(0, sigma^2 I)``
           (a body-frame rotation error).
``imu``    ``position`` (m, body), ``gyro_sigma`` (rad/s), ``acc_sigma`` (m/s^2), per run
           ``gyro_bias``/``acc_bias`` (3,): gyro ``omega + b + n``; accelerometer the specific
           force at the IMU, ``f = v_dot + omega x v + omega_dot x r + omega x (omega x r) - g k``
           (``k = R^T e_3``; a level vehicle at rest reads ``(0, 0, -g)``) ``+ b + n``.
``euler``  ``time_constant`` (s), ``sigma`` (rad), ``yaw`` (bool): an attitude filter's
           roll, pitch (and yaw) as a first-order lag of the true ZYX angles
           (``y_k = a y_(k-1) + (1 - a) x_k``, ``a = exp(-dt / T)``, started at ``x_0``) plus noise.
``depth``  ``position`` (m, body), ``rate_hz`` (10), ``mode`` (``native``: NaN between the
           sensor's samples; ``held``: repeated; ``interpolated``: linear, NaN after the last),
           ``sigma`` (m): NED z of the sensor point ``z + (R r_p)_z``.
``dvl``    ``position`` (m, body), ``sigma`` (m/s): ``v + omega x r_dvl`` (bottom lock).
``clock``  ``jitter`` (s): the logger's time stamps; row ``k`` (true sample time ``t_k``) is
           stamped ``t_k + e_k``, ``e_k ~ N(0, jitter^2)``, pushed later where needed so that
           each stamp follows the one before by at least :data:`MIN_STAMP_GAP` of a sample
           interval (:func:`stamps`).  Only the ``t`` column changes: every row still holds the
           inputs commanded at ``t_k`` and the readings taken at ``t_k``.

Any section may also have ``latency`` (s, default 0): the reading logged at ``t_k`` is the
sensor's model applied to the truth at ``t_k - latency`` (the truth's ``delayed`` arrays,
made by :func:`uvsim.scenarios.generate.simulate_spec`; before the run starts, ``t_k <
latency``, the vehicle is held at its initial state with no acceleration).  The attitude
filter's lag acts on the delayed angles; the depth sensor still delivers at the log samples
of its own rate.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from uvsim.scenarios.effects import ScenarioError

#: Noise-group name -> (columns, sigma key in its section).
GROUPS = {
    "position": ("mocap", ("x", "y", "z"), "sigma_position"),
    "attitude": ("mocap", ("qw", "qx", "qy", "qz"), "sigma_attitude"),
    "rates": ("imu", ("p", "q", "r"), "gyro_sigma"),
    "acceleration": ("imu", ("acc_x", "acc_y", "acc_z"), "acc_sigma"),
    "euler": ("euler", ("roll", "pitch", "yaw"), "sigma"),
    "depth": ("depth", ("depth",), "sigma"),
    "velocity": ("dvl", ("u", "v", "w"), "sigma"),
}
DEPTH_MODES = ("native", "held", "interpolated")
#: Sections that produce log columns (``clock`` only stamps the rows).
GROUP_SECTIONS = frozenset(sec for sec, _, _ in GROUPS.values())
#: Smallest step between two time stamps, as a fraction of the sample interval: a stamp that
#: would not follow its predecessor by this much is moved later (a logger stamps the rows in
#: the order it reads them, so its time never runs backwards).
MIN_STAMP_GAP = 0.05
#: Largest sensor latency the settings accept, s (ArduSub telemetry and sensor pipelines delay
#: by tens of ms; a second would be a broken link, not a latency).
MAX_LATENCY = 1.0


#: Required settings of each sensor section (numbers unless noted).
SECTION_KEYS = {"mocap": ("sigma_position", "sigma_attitude"), "imu": ("position", "gyro_sigma", "acc_sigma"),
                "euler": ("time_constant", "sigma"), "depth": ("position", "sigma"), "dvl": ("position", "sigma"),
                "clock": ("jitter",)}


def validate_sensors(sensors) -> None:
    """Raise :class:`ScenarioError` naming the section and key of a malformed sensor setting."""
    if not isinstance(sensors, dict) or not sensors:
        raise ScenarioError(f"scenario spec: sensors: expected a mapping with some of {sorted(SECTION_KEYS)}")
    for name, sec in sensors.items():
        if name not in SECTION_KEYS:
            raise ScenarioError(f"scenario spec: sensors.{name}: unknown sensor; "
                                f"expected one of {sorted(SECTION_KEYS)}")
        for key in SECTION_KEYS[name]:
            val = np.asarray(sec.get(key) if isinstance(sec, dict) else None, dtype=object)
            shape = (3,) if key == "position" else ()
            try:
                ok = val.shape == shape and np.all(np.isfinite(val.astype(float)))
            except (TypeError, ValueError):
                ok = False
            if not ok or (key != "position" and float(val) <= 0):
                want = "[x, y, z] in m (body)" if key == "position" else "a positive number"
                got = sec.get(key) if isinstance(sec, dict) else None
                raise ScenarioError(f"scenario spec: sensors.{name}.{key} = {got!r}; expected {want}")
        lat = sec.get("latency", 0.0) if isinstance(sec, dict) else 0.0
        if isinstance(lat, bool) or not isinstance(lat, (int, float)) or not 0.0 <= lat <= MAX_LATENCY:
            raise ScenarioError(f"scenario spec: sensors.{name}.latency = {lat!r}; expected seconds in "
                                f"[0, {MAX_LATENCY:g}]")
    if not any(name in GROUP_SECTIONS for name in sensors):
        raise ScenarioError(f"scenario spec: sensors: no measuring sensor; expected some of {sorted(GROUP_SECTIONS)}")
    if "depth" in sensors and sensors["depth"].get("mode", "native") not in DEPTH_MODES:
        raise ScenarioError(f"scenario spec: sensors.depth.mode {sensors['depth'].get('mode')!r}; "
                            f"expected one of {list(DEPTH_MODES)}")


def rotations(q: np.ndarray) -> Rotation:
    """scipy rotations of scalar-first quaternions (n, 4)."""
    return Rotation.from_quat(np.asarray(q)[:, [1, 2, 3, 0]])


def scalar_first(rot: Rotation) -> np.ndarray:
    return rot.as_quat()[:, [3, 0, 1, 2]]


def depth_sample_index(n_t: int, rate_hz: float, sensor_hz: float) -> np.ndarray:
    """Indices of the log samples at which a slower sensor delivers a reading."""
    step = rate_hz / sensor_hz
    if abs(step - round(step)) > 1e-9 or step < 1:
        raise ScenarioError(f"depth sensor at {sensor_hz:g} Hz needs a log rate that is a multiple of it; "
                            f"got {rate_hz:g} Hz")
    return np.arange(0, n_t, int(round(step)))


def _lag(x: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """``y_k = a y_(k-1) + (1 - a) x_k``, ``a = exp(-dt / tau)``, ``y_0 = x_0``, along axis 0."""
    a = np.exp(-dt / tau)
    from scipy.signal import lfilter  # here, not at import (0.6 s of every command's start)

    return lfilter([1.0 - a], [1.0, -a], x, axis=0, zi=a * x[:1])[0]


def measure(truth: dict, sensors: dict, run_params: dict, rng: np.random.Generator | None) -> dict:
    """Sensor readings of one run.

    Parameters
    ----------
    truth : ``t`` (n_t,), ``pos`` (n_t, 3), ``quat`` (n_t, 4) scalar first, ``nu`` (n_t, 6),
        ``nu_dot`` (n_t, 6), ``g`` (m/s^2), ``rate_hz``; with sensor latencies ``delayed``:
        latency (s) -> the same ``pos``, ``quat``, ``nu``, ``nu_dot`` at ``t - latency``.
    sensors : the dataset's sensor settings (module docstring).
    run_params : per-run ``gyro_bias``, ``acc_bias`` (3,).
    rng : noise generator, or None for noise- and bias-free readings.

    Returns
    -------
    dict group -> array (n_t, c): ``position``, ``attitude`` (quaternion), ``rates``,
    ``acceleration``, ``euler`` (n_t, 2 or 3), ``depth`` (n_t, 1), ``velocity``.
    """
    n_t = truth["t"].size
    noisy = rng is not None

    def noise(sigma, shape):
        return rng.normal(0.0, sigma, size=shape) if noisy else np.zeros(shape)

    views = {}

    def at(section):
        """The truth a section sees: (pos, quat, nu, nu_dot, rotations), delayed by its latency."""
        lat = float(sensors[section].get("latency", 0.0))
        if lat not in views:
            src = truth
            if lat > 0:
                src = truth.get("delayed", {}).get(lat)
                if src is None:
                    raise ScenarioError(f"sensors.{section}.latency = {lat:g} s: the truth has no samples delayed "
                                        "by it (simulate_spec makes them)")
            views[lat] = (src["pos"], src["quat"], src["nu"], src["nu_dot"], rotations(src["quat"]))
        return views[lat]

    out = {}
    if "mocap" in sensors:
        s = sensors["mocap"]
        pos, quat, _, _, rot = at("mocap")
        out["position"] = pos + noise(s["sigma_position"], (n_t, 3))
        qm = scalar_first(rot * Rotation.from_rotvec(noise(s["sigma_attitude"], (n_t, 3))))
        qm *= np.where((qm * quat).sum(axis=1) < 0, -1.0, 1.0)[:, None]   # same hemisphere as the truth
        out["attitude"] = qm
    if "imu" in sensors:
        s = sensors["imu"]
        _, _, nu, nu_dot, rot = at("imu")
        v, w = nu[:, :3], nu[:, 3:]
        bias = np.asarray(run_params.get("gyro_bias", 0.0)) if noisy else 0.0
        out["rates"] = w + bias + noise(s["gyro_sigma"], (n_t, 3))
        r = np.asarray(s["position"], dtype=float)
        k = rot.inv().apply([0.0, 0.0, 1.0])
        f = (nu_dot[:, :3] + np.cross(w, v) + np.cross(nu_dot[:, 3:], r) + np.cross(w, np.cross(w, r))
             - truth["g"] * k)
        out["acceleration"] = (f + (np.asarray(run_params.get("acc_bias", 0.0)) if noisy else 0.0)
                               + noise(s["acc_sigma"], (n_t, 3)))
    if "euler" in sensors:
        s = sensors["euler"]
        rot = at("euler")[4]
        ypr = np.unwrap(rot.as_euler("ZYX"), axis=0)
        rpy = ypr[:, ::-1]
        k = 3 if s.get("yaw", False) else 2
        e = _lag(rpy[:, :k], 1.0 / truth["rate_hz"], s["time_constant"]) + noise(s["sigma"], (n_t, k))
        if k == 3:
            e[:, 2] = np.angle(np.exp(1j * e[:, 2]))
        out["euler"] = e
    if "depth" in sensors:
        s = sensors["depth"]
        pos, _, _, _, rot = at("depth")
        z = pos[:, 2] + rot.apply(np.asarray(s["position"], dtype=float))[:, 2]
        idx = depth_sample_index(n_t, truth["rate_hz"], s.get("rate_hz", 10.0))
        native = z[idx] + noise(s["sigma"], idx.size)
        d = np.full(n_t, np.nan)
        mode = s.get("mode", "native") if noisy else "native"
        if mode == "native":
            d[idx] = native
        elif mode == "held":
            d = native[np.searchsorted(idx, np.arange(n_t), side="right") - 1]
        elif mode == "interpolated":
            last = idx[-1]
            d[: last + 1] = np.interp(np.arange(last + 1), idx, native)
        else:
            raise ScenarioError(f"sensors.depth.mode {mode!r}: expected one of {list(DEPTH_MODES)}")
        out["depth"] = d[:, None]
    if "dvl" in sensors:
        s = sensors["dvl"]
        nu = at("dvl")[2]
        v, w = nu[:, :3], nu[:, 3:]
        out["velocity"] = v + np.cross(w, np.asarray(s["position"], dtype=float)) + noise(s["sigma"], (n_t, 3))
    return out


def stamps(t: np.ndarray, jitter: float, rate_hz: float, rng: np.random.Generator) -> np.ndarray:
    """Logged time stamps of the rows taken at the true times ``t`` (``clock`` in the module
    docstring): ``t + N(0, jitter^2)``, each at least ``MIN_STAMP_GAP / rate_hz`` after the one
    before (a stamp that would not be is moved later, ``s_k = max(s_k, s_(k-1) + gap)``)."""
    gap = MIN_STAMP_GAP / float(rate_hz)
    k = np.arange(t.size)
    s = np.asarray(t, dtype=float) + rng.normal(0.0, jitter, size=t.size)
    return np.maximum.accumulate(s - gap * k) + gap * k


def columns(readings: dict, sensors: dict) -> dict:
    """Log columns (name -> (n_t,) array) of :func:`measure` output."""
    cols = {}
    for group, arr in readings.items():
        names = GROUPS[group][1]
        for i in range(arr.shape[1]):
            cols[names[i]] = arr[:, i]
    return cols


def deviation_snr(a: dict, b: dict, sensors: dict) -> tuple[float, float, dict]:
    """How far apart two noise-free readings are, in noise sigmas.

    Every channel's difference is divided by its noise level (attitude: the rotation
    vector between the two quaternions, per axis, over ``sigma_attitude``).

    Returns
    -------
    sum of squares, number of terms, and per group ``(sum of squares, number of terms)``.
    """
    ss, n, per = 0.0, 0, {}
    for group, xa in a.items():
        section, _, key = GROUPS[group]
        sigma = float(sensors[section][key])
        if group == "attitude":
            d = (rotations(xa).inv() * rotations(b[group])).as_rotvec()
        else:
            d = xa - b[group]
        d = d[np.isfinite(d)] / sigma
        ss += float((d * d).sum())
        n += d.size
        per[group] = (float((d * d).sum()), int(d.size))
    return ss, n, per
