"""Replay check: the exported model integrated under the target's own equations, against uvsim.

:func:`replay_check` reads the exported file back (:func:`uvsim.export.gz_sim.parse_gz_sdf`
or :func:`uvsim.export.uuv_simulator.parse_uuv_xacro`, so the numbers are the file's, in
its FLU link frame and ENU world), and steps it the way Gazebo does:

* one rigid body about the base link's origin: ``M v_dot + C(v) v = f`` with ``M`` the
  spatial inertia of the file's links (base link and thruster links: mass, centre of mass,
  inertia about it; Fossen 2021 eq. 3.44; the propellers' spin is not modelled) and
  ``C(v) v`` its parameterization-independent Coriolis term (eq. 3.46).  With
  ``<fluid_added_mass>`` the engine's ``M`` includes ``M_A`` and so its Coriolis term
  ``C_A(v) v`` (gz-physics ``dartsim/src/AddedMassFeatures.cc:45-71``: DART's spatial
  inertia plus the added mass; :mod:`uvsim.export.gz_sim`);
* semi-implicit Euler at the physics step ``h`` (velocities first, then the pose with
  the new velocities: ``p += h R v``, ``R <- R exp(h w)``), as DART and ODE step a free
  body (their exact position updates were not re-read here and may differ at O(h^2));
* the plugin's wrench (:class:`uvsim.export.plugins.GzHydrodynamics` or
  :class:`~uvsim.export.plugins.UuvFossen`) from the velocity at the start of the step
  (gz-sim: ``PreUpdate`` before the physics ``Update``; UUV Simulator: ``WorldUpdateBegin``),
  including its finite-difference (gz-sim) or filtered (UUV Simulator) acceleration;
  gz-sim applies it at the link origin (``Link::AddWorldWrench``), UUV Simulator at the
  base link's centre of mass (Gazebo classic ``ODELink::AddRelativeForce``);
* gravity ``m g`` at each link's centre of mass and buoyancy ``rho g V`` at the centre of
  buoyancy: gz-sim's Buoyancy system with a uniform density (everywhere, no surface:
  ``Buoyancy.cc:587-613``); UUV Simulator's ``BuoyantObject`` (``BuoyantObject.cc:82-119``:
  the whole volume below the surface z = 0, none above it for the bounding-box height 0 of a
  link without collisions; the position read from the centre of mass, ``uuv_simulator``
  module docstring);
* thrust along each thruster joint's axis at its link: commands in newtons (gz-sim Thruster
  system, clamped to ``min/max_thrust_cmd``: ``Thruster.cc:517-526``) from the PWM table the
  SDF carries for its bridge (at the run's battery voltage when the table has voltage
  sheets), or UUV Simulator's ``LinearInterp`` PWM -> thrust table with its clamps
  (``ThrusterPlugin.cc:203-241``); generalized-force inputs are applied as a body wrench.

The result is compared with uvsim's own simulation of the same inputs from the same
initial state (at rest): the largest position (m) and attitude (rad) deviation over the run.
:func:`stable_step` gives the largest physics step for which the added-mass term of a
mode is stable (gz-sim#1923).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from uvsim.errors import VehicleError
from uvsim.export.frames import S3, S6
from uvsim.export.plugins import GzHydrodynamics, UuvFossen
from uvsim.kinematics import quat_to_rotation
from uvsim.rigid_body import coriolis_from_momentum, cross, skew

#: NED -> ENU on world vectors (its own inverse).
T_NED_ENU = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: Default physics step, s (gz-sim's and Gazebo classic's default max_step_size).
DEFAULT_STEP = 0.001
#: Start depth (m, NED) of a replay without a logged position: deep enough that the standard
#: maneuver's 13.6 m rise of the positively buoyant BlueROV2 Heavy stays below UUV
#: Simulator's surface at z = 0 (uvsim's model has no surface; gz-sim's uniform Buoyancy neither).
DEFAULT_START_DEPTH = 20.0


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


def _spatial_inertia(m: float, c, J) -> np.ndarray:
    """6x6 rigid-body mass matrix about a link origin of mass ``m`` with centre of mass ``c``
    (3,) and inertia ``J`` (3x3) about it (Fossen 2021 eq. 3.44)."""
    c = np.asarray(c, float)
    M = np.zeros((6, 6))
    M[:3, :3] = m * np.eye(3)
    M[:3, 3:] = -m * skew(c)
    M[3:, :3] = m * skew(c)
    M[3:, 3:] = np.asarray(J, float) + m * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
    return M


def _rot(q):
    """Rotation matrix of a unit quaternion ``[w, x, y, z]`` (body -> world), unbatched
    (the replay's inner loop; :func:`uvsim.kinematics.quat_to_rotation` for arrays)."""
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
    from scipy.spatial.transform import Rotation

    R = T_NED_ENU @ quat_to_rotation(np.asarray(q_frd_ned, float)[None])[0] @ S3
    x, y, z, w = Rotation.from_matrix(R).as_quat()
    return np.array([w, x, y, z])


class _Target:
    """The exported model inside its simulator (module docstring)."""

    def __init__(self, target: str, parsed: dict, g: float, current_enu, patch_coriolis: bool = False):
        self.target, self.g, self.parsed = target, g, parsed
        self.thr = parsed.get("thrusters", [])
        self.cg = np.asarray(parsed["cg"], float)
        M = _spatial_inertia(parsed["mass"], self.cg, parsed["inertia_cg"])
        mc = parsed["mass"] * self.cg
        for th in self.thr:  # the thruster links, rigidly attached (their spin is not modelled)
            M = M + _spatial_inertia(th.get("mass", 0.0), th["position"], th.get("inertia", np.zeros((3, 3))))
            mc = mc + th.get("mass", 0.0) * np.asarray(th["position"], float)
        self.mass = float(M[0, 0])
        self.mass_moment = mc  # sum of m_i c_i: gravity acts at mc / mass
        if target == "gz-sim":
            self.plugin = GzHydrodynamics.from_sdf(parsed, coriolis_sign=-1.0 if patch_coriolis else 1.0)
            if parsed["fluid_added_mass"]:
                M = M + parsed["added_mass"]  # the engine carries M_A (AddedMassFeatures.cc:67-69)
            self.rho, self.V = parsed["water_density"], parsed["buoyancy_volume"]
            self.cb = np.asarray(parsed["cb"], float)
            self.hydro_at = np.zeros(3)      # Link::AddWorldWrench at the link origin
        else:
            self.plugin = UuvFossen(parsed["added_mass"], parsed["linear"], np.diag(parsed["quadratic"]))
            self.rho, self.V = parsed["fluid_density"], parsed["volume"]
            self.cb = self.cg + np.asarray(parsed["cb"], float)  # read from the centre of mass (ODE)
            self.hydro_at = self.cg          # AddRelativeForce: at the centre of mass (ODE)
        self.M = M
        self.Minv = np.linalg.inv(M)
        self.current_enu = np.asarray(current_enu, float)

    def thrust_wrench(self, u: np.ndarray, kind: str, voltage: float | None) -> np.ndarray:
        """Body wrench (FLU, about the link origin) of one input row."""
        if kind == "force":
            return S6 @ np.asarray(u, float)  # FRD generalized force -> FLU
        f = np.zeros(6)
        for i, th in enumerate(self.thr):
            T = float(u[i]) if kind == "thrust" else self._pwm_thrust(th, float(u[i]), voltage)
            if self.target == "gz-sim" and "max" in th:
                T = min(max(T, th["min"]), th["max"])              # Thruster.cc:520-521
            elif self.target != "gz-sim":
                T = min(max(T, th["limits"][0]), th["limits"][1])  # ThrusterPlugin.cc:235-236
            a = np.asarray(th["axis"], float)
            F = T * a / np.linalg.norm(a)
            f[:3] += F
            f[3:] += cross(th["position"], F)
        return f

    def _pwm_thrust(self, th: dict, pwm: float, voltage: float | None) -> float:
        if "pwm" not in th or "thrust" not in th:
            raise VehicleError(f"{self.target}: the exported file has no PWM -> thrust table for its thrusters")
        if self.target != "gz-sim":  # UUV Simulator: clamp the input, LinearInterp (ThrusterPlugin.cc:213-231)
            return float(np.interp(min(max(pwm, th["clamp"][0]), th["clamp"][1]), th["pwm"], th["thrust"]))
        sheets = th.get("sheets") or {}
        if voltage is None or not np.isfinite(voltage) or not sheets:
            return float(np.interp(pwm, th["pwm"], th["thrust"]))
        vs = np.array(sorted(sheets))  # the bridge applies the battery voltage, linearly between sheets
        if not vs[0] <= voltage <= vs[-1]:
            raise VehicleError(f"voltage {voltage:g} V outside the SDF table's {vs[0]:g}..{vs[-1]:g} V")
        j = int(np.clip(np.searchsorted(vs, voltage, side="right") - 1, 0, vs.size - 2))
        w = (voltage - vs[j]) / (vs[j + 1] - vs[j])
        T0, T1 = (float(np.interp(pwm, th["pwm"], sheets[v])) for v in vs[j:j + 2])
        return (1.0 - w) * T0 + w * T1

    def _volume(self, z: float) -> float:
        if self.target == "gz-sim":
            return self.V
        return self.V if z < 0.0 else 0.0   # BuoyantObject.cc:100-111 with bounding-box height 0

    def step(self, p, q, v, f_thr, h):
        R = _rot(q)                                      # FLU -> ENU
        s = v.copy()
        s[:3] -= R.T @ self.current_enu
        if self.target == "gz-sim":
            w_h = self.plugin.wrench(s, h, abs_state=v)["total"]
        else:  # UUV Simulator works in FRD: flip, apply, flip back (HydrodynamicModel.cc:128-140)
            w_h = S6 @ self.plugin.wrench(S6 @ s, h)["total"]
            w_h[3:] += cross(self.hydro_at, w_h[:3])
        e3 = R.T[:, 2]                                   # world up in the body frame
        fb = self.rho * self.g * self._volume(p[2]) * e3
        restoring = np.concatenate([-self.mass * self.g * e3 + fb,
                                    cross(self.mass_moment, -self.g * e3) + cross(self.cb, fb)])
        cor = coriolis_from_momentum(self.M @ v, v)   # C(v) v = [w x a; v x a + w x b] (Fossen 2021 eq. 3.46)
        tau = w_h + restoring + f_thr - cor
        v_new = v + h * (self.Minv @ tau)
        p_new = p + h * (R @ v_new[:3])
        q_new = _quat_mul(q, _exp_quat(v_new[3:], h))
        return p_new, q_new / np.linalg.norm(q_new), v_new


def _run_arrays(run, inputs, input_kind, pos0, voltage):
    """``(t, U, kind, pos0, voltage)`` from a :class:`uvsim.logs.Run`, a run CSV path, or
    times ``run`` (n,) with ``inputs`` (n, k)."""
    from uvsim.logs import read_run

    if isinstance(run, (str, Path)):
        run = read_run(run)
    if hasattr(run, "inputs") and hasattr(run, "input_kind"):
        if inputs is not None:
            raise VehicleError("replay_check: give a run, or times and inputs, not both")
        if pos0 is None and run.has_position and np.all(np.isfinite(run.position[0])):
            pos0 = run.position[0]
        if voltage is None and getattr(run, "has_voltage", False):
            voltage = run.voltage
        return np.asarray(run.t, float), np.asarray(run.inputs, float), run.input_kind, pos0, voltage
    if inputs is None:
        raise VehicleError("replay_check: inputs are needed with an array of times")
    t = np.asarray(run, float)
    return t, np.asarray(inputs, float).reshape(t.size, -1), input_kind or "force", pos0, voltage


#: Most physics steps of a replay, refused before any work: the replay steps in Python at about
#: 0.2 ms a step (the standard 60 s maneuver at Gazebo's 1 ms: 60 000 steps, 12 s), so 1e6 steps
#: are about 3 minutes; ``--physics-step 1e-9`` asked for 6e10 steps (four months).
MAX_REPLAY_STEPS = 1_000_000


def replay_check(vehicle, run, inputs=None, *, input_kind: str | None = None, target: str = "gz-sim",
                 added_mass: str = "fluid", physics_step: float = DEFAULT_STEP, pos0=None, q0=None, voltage=None,
                 text: str | None = None, patch_coriolis: bool = False) -> ReplayResult:
    """Replay a run's inputs through the exported model inside ``target`` ("gz-sim" or
    "uuv-simulator") and compare with uvsim's simulation of the same inputs (module docstring).

    Parameters
    ----------
    vehicle : Vehicle, built-in name or vehicle file
    run : uvsim.logs.Run, path of a run CSV, or array (n,)
        The run (its inputs, input kind, battery voltage and first logged position are used),
        or the sample times ``t`` (s) with ``inputs``.
    inputs : array (n, k), optional
        Inputs held over each sample interval (with times as ``run``): generalized forces
        FRD (k = 6), per-thruster thrust (N) or PWM (us), as ``input_kind`` says (default "force").
    target : {"gz-sim", "uuv-simulator"}
    added_mass : {"fluid", "plugin"}
        The gz-sim mode (:func:`uvsim.export.gz_sim.gz_sdf`).
    physics_step : float
        Physics step, s, rounded so that it divides each sample interval.
    pos0 : (3,) NED start, default the run's first logged position, else
        (0, 0, :data:`DEFAULT_START_DEPTH`) (below UUV Simulator's surface); ``q0`` (4,) FRD->NED
        quaternion, default level.  The vehicle starts at rest.
    voltage : array (n,), optional
        Battery voltage per sample (a run's own by default): uvsim's curves and the gz-sim
        bridge use it, UUV Simulator's table cannot.
    text : str, optional
        An exported file to check instead of exporting ``vehicle`` again.
    patch_coriolis : bool
        gz-sim only: flip the sign of the plugin's Coriolis term (``Hydrodynamics.cc:578``), what
        an upstream fix would give.

    Returns
    -------
    ReplayResult
    """
    from uvsim.simulate import simulate
    from uvsim.vehicle import load_vehicle

    veh = load_vehicle(vehicle)
    t, U, kind, pos0, voltage = _run_arrays(run, inputs, input_kind, pos0, voltage)
    if not (np.isfinite(physics_step) and 0 < physics_step <= 0.1):
        raise VehicleError(f"physics_step {physics_step!r}: expected seconds in (0, 0.1]")
    steps = float(t[-1] - t[0]) / physics_step
    if steps > MAX_REPLAY_STEPS:
        raise VehicleError(f"physics_step {physics_step:g} s: {steps:.3g} steps over the {t[-1] - t[0]:g} s replayed "
                           f"(about {steps * 2e-4 / 3600:.2g} h); at most {MAX_REPLAY_STEPS:.0e}: use a step of at least "
                           f"{float(t[-1] - t[0]) / MAX_REPLAY_STEPS:.2g} s (Gazebo's default is {DEFAULT_STEP:g} s) or a "
                           "shorter run")
    if veh.effects:
        raise VehicleError(f"{veh.source}: effects {[e.kind for e in veh.effects]} have no counterpart in {target}; "
                           "the replay would compare two different models")
    if target not in ("gz-sim", "uuv-simulator"):
        raise VehicleError(f"target {target!r}: the replay check knows gz-sim and uuv-simulator")
    if text is None and target == "gz-sim":
        from uvsim.export.gz_sim import gz_sdf

        text = gz_sdf(veh, added_mass=added_mass)[0]
    elif text is None:
        from uvsim.export.uuv_simulator import uuv_xacro

        text = uuv_xacro(veh, force=True)[0]  # measure what the export refuses without --force
    if target == "gz-sim":
        from uvsim.export.gz_sim import parse_gz_sdf

        parsed = parse_gz_sdf(text)
        mode = ("fluid added mass" if parsed["fluid_added_mass"] else "plugin added mass"
                + (", Coriolis sign patched" if patch_coriolis else ""))
        current_enu = parsed["current_enu"]
    else:
        from uvsim.export.uuv_simulator import parse_uuv_xacro

        parsed, mode = parse_uuv_xacro(text), "HMFossen"
        current_enu = T_NED_ENU @ np.asarray(veh.current_ned, float)  # the world's, set as the export warns
    pos0 = np.array([0.0, 0.0, DEFAULT_START_DEPTH]) if pos0 is None else np.asarray(pos0, float)
    q0 = np.array([1.0, 0.0, 0.0, 0.0]) if q0 is None else np.asarray(q0, float)
    V = None if voltage is None else np.asarray(voltage, float).reshape(t.size)
    if V is not None and np.all(np.isnan(V)):  # NaN: the curves' nominal voltage (uvsim.simulate)
        V = None
    ref = simulate(veh, t, U, input_kind=kind, pos0=pos0, q0=q0, nu0=np.zeros(6), voltage=V)
    Yr = ref.y
    tg = _Target(target, parsed, veh.g, current_enu, patch_coriolis=patch_coriolis)
    p, q, v = T_NED_ENU @ pos0, _frd_ned_to_flu_enu(q0), np.zeros(6)
    n = t.size
    pos_err, att_err = np.full(n, np.nan), np.full(n, np.nan)
    diverged = False
    for i in range(n):
        if i:
            f_thr = tg.thrust_wrench(U[i - 1], kind, None if V is None else V[i - 1])  # held over the interval
            # a fixed step that divides the sample interval (no sliver steps: the plugins divide by it)
            n_sub = max(1, int(round((t[i] - t[i - 1]) / physics_step)))
            h = (t[i] - t[i - 1]) / n_sub
            for _ in range(n_sub):
                p, q, v = tg.step(p, q, v, f_thr, h)
            if not (np.all(np.isfinite(v)) and np.linalg.norm(v) < 1e3):
                diverged = True
                break
        R_frd_ned = T_NED_ENU @ _rot(q) @ S3
        R_ref = quat_to_rotation(Yr[i, 3:7][None])[0]
        pos_err[i] = np.linalg.norm(T_NED_ENU @ p - Yr[i, :3])
        att_err[i] = np.arccos(np.clip((np.trace(R_ref.T @ R_frd_ned) - 1.0) / 2.0, -1.0, 1.0))
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
    of the recurrences of :func:`replay_check` (rigid mass ``m``, added mass ``a``, damping
    slope ``d = L + 2 Q |speed|`` <= 0):

    * engine-carried added mass (gz-sim ``fluid``): ``(m + a) v' = (m + a + h d) v``,
      stable for ``h < 2 (m + a) / |d|``;
    * plugin added mass from the previous step's finite difference (gz-sim ``plugin``,
      ``Hydrodynamics.cc:552-566``): ``m v_{k+1} = (m - a + h d) v_k + a v_{k-1}``.  By the
      Jury test its roots stay inside the unit circle iff ``a < m`` and
      ``h < 2 (m - a) / |d|``: unstable at every step once ``a >= m`` (gz-sim#1923), and the
      bound shrinks with ``1 - a/m``;
    * UUV Simulator's filtered acceleration (``alpha = 0.3``): the same with the filter's
      state, bound found by bisection on the spectral radius.

    An undamped DOF (``d = 0``) keeps its physical root at 1 (constant velocity): counted as
    stable.  Returns per DOF ``{"h_max", "ratio" a/m}`` (``h_max`` 0.0 when unstable at every
    step, inf when stable at every step) and ``overall`` (the smallest).  Necessary, not
    sufficient: the coupling between DOFs is ignored (the replay is the check)."""
    from uvsim.export.frames import damping_matrices
    from uvsim.vehicle import load_vehicle

    if target not in ("gz-sim", "uuv-simulator") or added_mass not in ("fluid", "plugin"):
        raise VehicleError(f"stable_step: target {target!r}, added_mass {added_mass!r}: expected gz-sim or "
                           "uuv-simulator and fluid or plugin")
    veh = load_vehicle(vehicle)
    DL, DQ = damping_matrices(veh)
    m = np.diag(veh.M_RB)
    a = np.diag(veh.added_mass_matrix)
    d = np.minimum(np.diag(DL) + 2.0 * np.diag(DQ) * abs(speed), 0.0)
    names = ("surge", "sway", "heave", "roll", "pitch", "yaw")
    out = {}
    for i in range(6):
        out[names[i]] = {"h_max": _h_max(m[i], a[i], d[i], target, added_mass), "ratio": float(a[i] / m[i])}
    out["overall"] = min(x["h_max"] for x in out.values())
    return out


def _uuv_radius(m, a, d, h) -> float:
    """Largest root of UUV Simulator's recurrence other than an undamped DOF's root at 1; state
    ``(v_k, v_{k-1}, af_{k-1})``, ``af_k = 0.7 af_{k-1} + 0.3 (v_k - v_{k-1}) / h``,
    ``m v_{k+1} = m v_k + h (d v_k - a af_k)``."""
    al = 0.3
    A = np.array([[1.0 + h * d / m - a / m * al, a / m * al, -h * a / m * (1 - al)],
                  [1.0, 0.0, 0.0],
                  [al / h, -al / h, 1 - al]])
    z = np.linalg.eigvals(A)
    if d == 0.0:
        z = np.delete(z, np.argmin(np.abs(z - 1.0)))
    return float(max(abs(z)))


def _h_max(m, a, d, target, mode) -> float:
    if target == "gz-sim" and mode == "fluid":
        return float("inf") if d == 0 else float(2.0 * (m + a) / abs(d))
    if target == "gz-sim":  # Jury: p(z) = m z^2 - (m - a + h d) z - a
        if a >= m:
            return 0.0
        return float("inf") if d == 0 else float(2.0 * (m - a) / abs(d))
    tiny = 1e-6
    if _uuv_radius(m, a, d, tiny) >= 1.0:
        return 0.0
    lo, hi = tiny, 10.0
    if _uuv_radius(m, a, d, hi) < 1.0:
        return float("inf")
    for _ in range(60):
        mid = np.sqrt(lo * hi)
        if _uuv_radius(m, a, d, mid) < 1.0:
            lo = mid
        else:
            hi = mid
    return float(lo)
