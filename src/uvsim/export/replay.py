"""Replay check: the exported model integrated under the target's own equations, against uvsim.

:func:`replay_check` reads the exported file back (:func:`uvsim.export.gz_sim.parse_gz_sdf`
or :func:`uvsim.export.uuv_simulator.parse_uuv_xacro`, so the numbers are the file's, in
its FLU link frame and ENU world), and steps it the way Gazebo does:

* a rigid body about the link origin: ``M v_dot + C(v) v = f`` with ``M`` from the
  file's ``<inertial>`` (mass, centre of mass, inertia about it; Fossen 2021 eq. 3.44) and
  ``C(v) v`` its parameterization-independent Coriolis term (eq. 3.46).  With
  ``<fluid_added_mass>`` the engine's ``M`` includes ``M_A`` and its Coriolis term
  ``C_A(v) v`` (gz-math ``Inertial::SpatialMatrix``; the plugin's comment,
  :mod:`uvsim.export.plugins`);
* semi-implicit Euler at the physics step ``h`` (velocities first, then the pose with
  the new velocities), as DART, ODE and Bullet step rigid bodies;
* the plugin's wrench (:class:`uvsim.export.plugins.GzHydrodynamics` or
  :class:`~uvsim.export.plugins.UuvFossen`) from the velocity at the start of the
  step, including its finite-difference (gz-sim) or filtered (UUV Simulator)
  acceleration;
* gravity at the centre of mass and buoyancy ``rho g V`` at the buoyancy volume's
  centre (gz-sim Buoyancy system, uniform density; UUV Simulator ``BuoyantObject``);
* thrust along each thruster joint's axis at the joint: commands in newtons from uvsim's
  curve at the logged PWM (gz-sim Thruster system in force mode, clamped to
  ``min/max_thrust_cmd``) or the xacro's ``LinearInterp`` PWM -> thrust table (UUV
  Simulator), generalized forces applied as a body wrench.

The result is compared with uvsim's own simulation of the same inputs from the same
initial state: the largest position (m) and attitude (rad) deviation over the run.
:func:`stable_step` gives the largest physics step for which the added-mass term of a
mode is stable (gz-sim#1923).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uvsim.errors import VehicleError
from uvsim.export.frames import S3, S6, frd_to_flu_matrix
from uvsim.export.plugins import GzHydrodynamics, UuvFossen
from uvsim.kinematics import quat_to_rotation
from uvsim.rigid_body import skew

#: NED -> ENU on world vectors (its own inverse).
T_NED_ENU = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: Default physics step, s (gz-sim's and Gazebo classic's default max_step_size).
DEFAULT_STEP = 0.001


@dataclass
class ReplayResult:
    """Deviation of the target's replay from uvsim's simulation of one run.

    ``position_m``, ``attitude_rad``: largest deviation over the run; ``t`` (n,) times,
    ``position_error`` (n,) m, ``attitude_error`` (n,) rad; ``diverged``: the replay left
    any finite range; ``target``, ``mode``, ``physics_step``."""

    target: str
    mode: str
    physics_step: float
    t: np.ndarray
    position_error: np.ndarray
    attitude_error: np.ndarray
    diverged: bool

    @property
    def position_m(self) -> float:
        return float(np.nanmax(self.position_error)) if not self.diverged else float("inf")

    @property
    def attitude_rad(self) -> float:
        return float(np.nanmax(self.attitude_error)) if not self.diverged else float("inf")

    def summary(self) -> str:
        if self.diverged:
            return (f"{self.target} ({self.mode}), physics step {self.physics_step * 1e3:g} ms: the replay DIVERGED "
                    f"(t = {self.t[np.argmax(~np.isfinite(self.position_error))]:.3g} s)")
        return (f"{self.target} ({self.mode}), physics step {self.physics_step * 1e3:g} ms: largest deviation from "
                f"uvsim over {self.t[-1] - self.t[0]:.1f} s: {1e3 * self.position_m:.3g} mm, "
                f"{1e3 * self.attitude_rad:.3g} mrad")

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame({"t": self.t, "position_error_m": self.position_error,
                             "attitude_error_rad": self.attitude_error})


def _rigid_mass(parsed: dict) -> np.ndarray:
    """6x6 rigid-body mass matrix about the link origin from the file's inertial block (FLU)."""
    m, c, J = parsed["mass"], np.asarray(parsed["cg"], float), np.asarray(parsed["inertia_cg"], float)
    M = np.zeros((6, 6))
    M[:3, :3] = m * np.eye(3)
    M[:3, 3:] = -m * skew(c)
    M[3:, :3] = m * skew(c)
    M[3:, 3:] = J + m * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
    return M


def _rot(q):
    """Rotation matrix of a unit quaternion ``[w, x, y, z]`` (body -> world)."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _quat_mul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def _exp_quat(w, h):
    a = np.linalg.norm(w) * h
    if a < 1e-15:
        return np.array([1.0, 0.0, 0.0, 0.0])
    axis = w / np.linalg.norm(w)
    return np.concatenate([[np.cos(a / 2)], np.sin(a / 2) * axis])


def _frd_ned_to_flu_enu(q_frd_ned: np.ndarray) -> np.ndarray:
    """Rotation FLU -> ENU of a body whose FRD -> NED attitude is ``q``: ``T R S``."""
    R = T_NED_ENU @ quat_to_rotation(np.asarray(q_frd_ned, float)[None])[0] @ S3
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(R).as_quat()
    return np.array([w, x, y, z])


class _Target:
    """The exported model inside its simulator (module docstring)."""

    def __init__(self, target: str, parsed: dict, vehicle, mode: str, g: float):
        self.target, self.mode, self.g = target, mode, g
        self.parsed = parsed
        self.M = _rigid_mass(parsed)
        self.rho = parsed.get("water_density", vehicle.rho)
        self.V = parsed["buoyancy_volume"] if target == "gz-sim" else parsed["volume"]
        self.cb = np.asarray(parsed["cb"], float)
        self.cg = np.asarray(parsed["cg"], float)
        if target == "gz-sim":
            self.plugin = GzHydrodynamics.from_sdf(parsed)
            if parsed["fluid_added_mass"]:
                self.M = self.M + parsed["added_mass"]  # the engine carries M_A (SpatialMatrix)
        else:
            self.plugin = UuvFossen(parsed["added_mass"], parsed["linear"], np.diag(parsed["quadratic"]))
        self.Minv = np.linalg.inv(self.M)
        self.thr = parsed.get("thrusters", [])
        self.current_enu = np.zeros(3)

    def thrust_wrench(self, u: np.ndarray, kind: str, curves) -> np.ndarray:
        if kind == "force":
            return S6 @ np.asarray(u, float)  # FRD generalized force -> FLU
        f = np.zeros(6)
        for i, th in enumerate(self.thr):
            if kind == "thrust":
                T = float(u[i])
            elif self.target == "gz-sim":  # a bridge sends uvsim's curve's thrust; the plugin clamps it
                T = float(curves[i].thrust(np.array([u[i]]))[0])
            else:                          # UUV Simulator: the xacro's LinearInterp table
                T = float(np.interp(u[i], th["pwm"], th["thrust"]))
            a = np.asarray(th["axis"], float)
            F = T * a / np.linalg.norm(a)
            f[:3] += F
            f[3:] += np.cross(th["position"], F)
        return f

    def step(self, p, q, v, f_thr, h):
        R = _rot(q)                                      # FLU -> ENU
        vc_b = R.T @ self.current_enu
        s = v.copy()
        s[:3] -= vc_b
        if self.target == "gz-sim":
            w_h = self.plugin.wrench(s, h, abs_state=v)["total"]
        else:  # UUV Simulator works in FRD: flip, apply, flip back (HydrodynamicModel.cc:128-140)
            w_h = S6 @ self.plugin.wrench(S6 @ s, h)["total"]
        fg = R.T @ np.array([0.0, 0.0, -self.parsed["mass"] * self.g])
        fb = R.T @ np.array([0.0, 0.0, self.rho * self.g * self.V])
        restoring = np.concatenate([fg + fb, np.cross(self.cg, fg) + np.cross(self.cb, fb)])
        ab = self.M @ v  # C(v) v = [w x a; v x a + w x b] (Fossen 2021 eq. 3.46)
        cor = np.concatenate([np.cross(v[3:], ab[:3]), np.cross(v[:3], ab[:3]) + np.cross(v[3:], ab[3:])])
        tau = w_h + restoring + f_thr - cor
        v_new = v + h * (self.Minv @ tau)
        p_new = p + h * (R @ v_new[:3])
        q_new = _quat_mul(q, _exp_quat(v_new[3:], h))
        return p_new, q_new / np.linalg.norm(q_new), v_new


def replay_check(vehicle, t, inputs, *, input_kind: str = "force", target: str = "gz-sim",
                 added_mass: str = "fluid", physics_step: float = DEFAULT_STEP, pos0=None, q0=None,
                 text: str | None = None) -> ReplayResult:
    """Replay ``inputs`` (n, k) at times ``t`` (n,) through the exported model inside
    ``target`` ("gz-sim" or "uuv-simulator") and compare with uvsim (module docstring).

    The physics step is ``physics_step`` rounded so that it divides each sample interval.
    ``added_mass``: the gz-sim mode ("fluid" or "plugin"); ``text``: an exported file to
    check instead of exporting ``vehicle`` again; ``pos0`` (3,) NED, ``q0`` (4,) FRD->NED
    quaternion of the start (default origin, level); the vehicle starts at rest."""
    from uvsim.simulate import simulate
    from uvsim.vehicle import load_vehicle

    veh = load_vehicle(vehicle)
    t = np.asarray(t, float)
    U = np.asarray(inputs, float).reshape(t.size, -1)
    if not (np.isfinite(physics_step) and 0 < physics_step <= 0.1):
        raise VehicleError(f"physics_step {physics_step!r}: expected seconds in (0, 0.1]")
    if veh.effects:
        raise VehicleError(f"{veh.source}: effects {[e.kind for e in veh.effects]} have no counterpart in {target}; "
                           "the replay would compare two different models")
    if text is None and target == "gz-sim":
        from uvsim.export.gz_sim import gz_sdf

        text = gz_sdf(veh, added_mass=added_mass)[0]
    elif text is None and target == "uuv-simulator":
        from uvsim.export.uuv_simulator import uuv_xacro

        text = uuv_xacro(veh)[0]
    if target == "gz-sim":
        from uvsim.export.gz_sim import parse_gz_sdf

        parsed = parse_gz_sdf(text)
        mode = "fluid added mass" if parsed["fluid_added_mass"] else "plugin added mass"
    elif target == "uuv-simulator":
        from uvsim.export.uuv_simulator import parse_uuv_xacro

        parsed, mode = parse_uuv_xacro(text), "HMFossen"
    else:
        raise VehicleError(f"target {target!r}: the replay check knows gz-sim and uuv-simulator")
    pos0 = np.zeros(3) if pos0 is None else np.asarray(pos0, float)
    q0 = np.array([1.0, 0.0, 0.0, 0.0]) if q0 is None else np.asarray(q0, float)
    ref = simulate(veh, t, U, input_kind=input_kind, pos0=pos0, q0=q0, nu0=np.zeros(6))
    Yr = ref.y
    tg = _Target(target, parsed, veh, mode, veh.g)
    tg.current_enu = T_NED_ENU @ np.asarray(veh.current_ned, float)
    curves = veh.actuators.curves
    p, q, v = T_NED_ENU @ pos0, _frd_ned_to_flu_enu(q0), np.zeros(6)
    n = t.size
    pos_err, att_err = np.full(n, np.nan), np.full(n, np.nan)
    diverged = False
    for i in range(n):
        if i:
            f_thr = tg.thrust_wrench(U[i - 1], input_kind, curves)  # held over the sample interval
            # a fixed step that divides the sample interval (no sliver steps: the plugins divide by it)
            n_sub = max(1, int(round((t[i] - t[i - 1]) / physics_step)))
            h = (t[i] - t[i - 1]) / n_sub
            for _ in range(n_sub):
                p, q, v = tg.step(p, q, v, f_thr, h)
            if not (np.all(np.isfinite(v)) and np.linalg.norm(v) < 1e3):
                diverged = True
                break
        R_flu_enu = quat_to_rotation(q[None])[0]
        R_frd_ned = T_NED_ENU @ R_flu_enu @ S3
        R_ref = quat_to_rotation(Yr[i, 3:7][None])[0]
        pos_err[i] = np.linalg.norm(T_NED_ENU @ p - Yr[i, :3])
        cosang = np.clip((np.trace(R_ref.T @ R_frd_ned) - 1.0) / 2.0, -1.0, 1.0)
        att_err[i] = np.arccos(cosang)
    return ReplayResult(target, mode, physics_step, t, pos_err, att_err, diverged)


def standard_maneuver(duration: float = 60.0, rate: float = 50.0) -> tuple[np.ndarray, np.ndarray]:
    """The replay check's maneuver: generalized forces (FRD: X, Y, Z N; K, M, N N m), 10 s each
    of surge 10 N; surge and a 1 N m turn; sway 8 N; heave -5 N (up); -8 N with a -1 N m turn;
    10 N, 5 N and 0.5 N m (the BlueROV2 Heavy reaches 0.53 m/s and 1.4 rad/s).  Returns
    ``(t, inputs)``."""
    t = np.arange(0.0, duration + 1e-9, 1.0 / rate)
    phases = np.array([[10, 0, 0, 0, 0, 0], [10, 0, 0, 0, 0, 1.0], [0, 8, 0, 0, 0, 0], [0, 0, -5, 0, 0, 0],
                       [-8, 0, 0, 0, 0, -1.0], [10, 5, 0, 0, 0, 0.5]], float)
    return t, phases[np.minimum((t // 10).astype(int), 5)]


def stable_step(vehicle, *, added_mass: str = "fluid", speed: float = 1.0, target: str = "gz-sim") -> dict:
    """Largest physics step (s) at which each DOF's added-mass and damping terms are stable
    under the target's stepping, from the per-DOF linearization at ``speed`` (m/s or rad/s)
    of the recurrences of :func:`replay_check`:

    * engine-carried added mass (gz-sim ``fluid``): ``(m + a) v' = (m + a + h d) v``,
      stable for ``h < 2 (m + a) / |d|``;
    * plugin added mass from the previous step's finite difference (gz-sim ``plugin``):
      ``m v_{k+1} = (m - a + h d) v_k + a v_{k-1}``, whose roots leave the unit circle for
      ``a >= m`` at any step (gz-sim#1923) and otherwise for h above a bound found by
      bisection;
    * UUV Simulator's filtered acceleration: the same with the filter's state (bisection).

    ``d = L + 2 Q |speed|`` the damping slope.  Returns per DOF ``{"h_max", "ratio" a/m}``
    (``h_max`` 0.0 when unstable at every step, inf when stable at every step) and
    ``overall`` (the smallest)."""
    from uvsim.export.frames import damping_matrices
    from uvsim.vehicle import load_vehicle

    veh = load_vehicle(vehicle)
    DL, DQ = damping_matrices(veh)
    m = np.diag(veh.M_RB)
    a = np.diag(veh.added_mass_matrix)
    d = np.diag(DL) + 2.0 * np.diag(DQ) * abs(speed)
    names = ("surge", "sway", "heave", "roll", "pitch", "yaw")
    out = {}
    for i in range(6):
        out[names[i]] = {"h_max": _h_max(m[i], a[i], d[i], target, added_mass), "ratio": float(a[i] / m[i])}
    out["overall"] = min(x["h_max"] for x in out.values())
    return out


def _spectral_radius(m, a, d, h, target, mode) -> float:
    if target == "gz-sim" and mode == "fluid":
        return abs(1.0 + h * d / (m + a))
    if target == "gz-sim":   # state (v_k, v_{k-1})
        A = np.array([[(m - a + h * d) / m, a / m], [1.0, 0.0]])
    else:                    # state (v_k, v_{k-1}, af_{k-1}); af_k = 0.7 af_{k-1} + 0.3 (v_k - v_{k-1}) / h
        al = 0.3
        # m v_{k+1} = m v_k + h (d v_k - a af_k)
        A = np.array([[1.0 + h * d / m - h * a / m * al / h, h * a / m * al / h, -h * a / m * (1 - al)],
                      [1.0, 0.0, 0.0],
                      [al / h, -al / h, 1 - al]])
    return float(max(abs(np.linalg.eigvals(A))))


def _h_max(m, a, d, target, mode) -> float:
    if target == "gz-sim" and mode == "fluid":
        return float("inf") if d >= 0 else float(2.0 * (m + a) / abs(d))
    tiny = 1e-6
    if _spectral_radius(m, a, d, tiny, target, mode) >= 1.0:
        return 0.0
    lo, hi = tiny, 10.0
    if _spectral_radius(m, a, d, hi, target, mode) < 1.0:
        return float("inf")
    for _ in range(60):
        mid = np.sqrt(lo * hi)
        if _spectral_radius(m, a, d, mid, target, mode) < 1.0:
            lo = mid
        else:
            hi = mid
    return float(lo)
