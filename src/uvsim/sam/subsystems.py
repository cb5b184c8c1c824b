"""SAM actuator subsystems as force terms with internal states, limits and rates
(seed 003 sec. V-A-1, Fig. 8; smarc-project/smarc_modelling SAM.py).

The run's input vector is a vector of actuator *commands* (not forces); the vehicle
file's ``thrusters`` section is a :class:`CommandInputs` term that declares the command
columns and produces no force itself.  Each subsystem reads its column(s) (``input``
index), keeps the actual actuator position as an internal state and moves it toward the
saturated command with a first-order lag, rate-limited::

    x_dot = clip((clip(cmd, lo, hi) - x) / tau, -rate, rate)

Saturation at ``lo``/``hi`` is part of the actuator model (a servo cannot go past its
end stop); it is documented here and in docs/sam.md rather than silent.

* :class:`Propulsion` (``sam_propulsion``): two counter-rotating propellers on a
  thrust-vectoring gimbal.  States: ``rpm_1, rpm_2`` (rev/min), ``tv_pitch, tv_yaw`` (rad).
  Thrust and torque per propeller (Fossen 2021 sec. 9.4 / smarc_modelling SAM.py)::

      n > 0:  T = rho D^4 (K_T0 n|n| + (K_Tmax - K_T0)/J_max (V_a/D) |n|)
              Q = rho D^5 (K_Q0 n|n| + (K_Qmax - K_Q0)/J_max (V_a/D) |n|)
      n < 0:  T = r_rev rho D^4 K_T0 n|n|,  Q = r_rev rho D^5 K_Q0 n|n|

  with ``n`` in rev/s, ``V_a = w_a u_r`` and ``r_rev`` the reverse/forward thrust ratio
  at equal |rpm| (``reverse_thrust_ratio``).  The force on the hull is the thrust times
  ``1 - t`` (thrust deduction ``t``, Fossen's remus100.py ``(1 - t_prop) X_prop``; the
  torque is not reduced).  The thrust acts along the nozzle direction
  ``d = [cos dp cos dy, -sin dy, sin dp cos dy]`` at the propeller position (positive
  ``tv_pitch`` gives a nose-up moment, positive ``tv_yaw`` a positive yaw moment for
  forward thrust); propeller ``i`` spins with sense ``s_i`` (+1, -1) and its reaction
  torque on the hull is ``-s_i Q_i d``, so equal rpm cancel in roll.
* :class:`VariableBuoyancy` (``sam_vbs``): a piston cylinder taking in sea water; state
  ``vbs`` (% of stroke).  Mass change ``dm = rho_w pi r^2 L (vbs - vbs_ref) / 100`` at the
  cylinder position; the displaced volume (buoyancy) is unchanged.
* :class:`MovingMass` (``sam_lcg``): the battery pack moving along x; state ``lcg`` (% of
  stroke), position ``r_ref + (lcg - lcg_ref)/100 * stroke * e_x``.
* :class:`RevolvingMasses` (``sam_tcg``): two masses revolving about the x axis at radius
  ``radius``; state ``tcg`` (rad from straight down, positive towards starboard),
  position ``[x, radius sin phi, radius cos phi]``.

Mass-changing terms return the change of mass, first moment and inertia tensor (about
the body origin) relative to the vehicle file's rigid body, which describes the vehicle
with every subsystem at its reference (``*_ref``) position.  The core model then rebuilds
``M_RB`` and ``C_RB`` and the restoring term uses the new weight and centre of gravity.
"""
from __future__ import annotations

import math

import numpy as np

from uvsim.errors import SimulationError, VehicleError
from uvsim.forces import register
from uvsim.forces.actuators import Actuators
from uvsim.forces.base import ForceTerm
from uvsim.schema import check_keys


def _num(spec: dict, key: str, where: str, default=None, positive=False):
    val = spec.get(key, default)
    try:
        v = float(val)
    except (TypeError, ValueError):
        raise VehicleError(f"{where}.{key}: expected a number, got {val!r}") from None
    if not np.isfinite(v) or (positive and v <= 0):
        raise VehicleError(f"{where}.{key}: expected a {'positive' if positive else 'finite'} number, got {val!r}")
    return v


def _index(val, where, key="input"):
    if isinstance(val, bool) or not isinstance(val, int) or val < 0:
        raise VehicleError(f"{where}.{key}: expected a column index >= 0, got {val!r}")
    return val


def _point_inertia(m, r):
    """Inertia tensor of point masses ``m`` (n,) at ``r`` (n, 3) about the origin, (n, 3, 3)."""
    rr = np.einsum("ni,nj->nij", r, r)
    return m[:, None, None] * (np.einsum("ni,ni->n", r, r)[:, None, None] * np.eye(3) - rr)


class _Servo:
    """Limits and dynamics of one actuator channel."""

    def __init__(self, spec: dict, where: str, lo, hi, tau, rate, ref=None):
        keys = ("min", "max", "time_constant", "rate") + (() if ref is None else ("reference",))
        check_keys(spec, keys, where, error=VehicleError)
        self.lo = _num(spec, "min", where, lo)
        self.hi = _num(spec, "max", where, hi)
        if self.hi <= self.lo:
            raise VehicleError(f"{where}: max ({self.hi}) must exceed min ({self.lo})")
        self.tau = _num(spec, "time_constant", where, tau, positive=True)
        self.rate = _num(spec, "rate", where, rate, positive=True)
        self.ref = None if ref is None else _num(spec, "reference", where, ref)
        if self.ref is not None and not self.lo <= self.ref <= self.hi:
            raise VehicleError(f"{where}.reference: {self.ref} outside [{self.lo}, {self.hi}]")

    def to_dict(self):
        d = {"min": self.lo, "max": self.hi, "time_constant": self.tau, "rate": self.rate}
        if self.ref is not None:
            d["reference"] = self.ref
        return d

    def derivative(self, cmd, x):
        """``clip((clip(cmd) - x) / tau, -rate, rate)``, zero within a dead band of 1e-9 of
        the range (so a settled actuator is exactly constant; see :class:`uvsim.sam.model.SamModel`)."""
        c = np.minimum(np.maximum(cmd, self.lo), self.hi)
        e = c - x
        d = np.minimum(np.maximum(e / self.tau, -self.rate), self.rate)
        return np.where(np.abs(e) > 1e-9 * (self.hi - self.lo), d, 0.0)

    def derivative1(self, cmd: float, x: float) -> float:
        """Scalar version of :meth:`derivative`."""
        c = min(max(cmd, self.lo), self.hi)
        e = c - x
        if abs(e) <= 1e-9 * (self.hi - self.lo):
            return 0.0
        return min(max(e / self.tau, -self.rate), self.rate)

    def initial(self, cmd):
        return np.minimum(np.maximum(cmd, self.lo), self.hi)


# ----------------------------------------------------------------------------- inputs
@register("command_inputs")
class CommandInputs(Actuators):
    """Declares the command columns of a vehicle whose actuators are subsystem terms.

    Inputs are given with ``input_kind="thrust"`` (per-actuator commands; uvsim's input
    kinds are force / thrust / pwm) and must have ``len(names)`` columns.  Produces no
    force: the subsystem terms (``effects``) read their columns.
    """

    def __init__(self, names, units=None, description=""):
        if not isinstance(names, list) or not names or not all(isinstance(x, str) for x in names):
            raise VehicleError("thrusters (command_inputs).names: expected a non-empty list of column names")
        super().__init__(matrix=None, curves=None, names=list(names), specs=None)
        self.units = list(units) if units is not None else None
        self.description = str(description)

    @property
    def n_thrusters(self) -> int:
        return len(self.names)

    def forces(self, ctx, prep):
        if ctx.input_kind != "thrust":
            raise SimulationError(f"vehicle takes actuator commands ({', '.join(self.names)}) with input_kind='thrust', "
                                  f"got {ctx.input_kind!r}")
        return np.zeros((ctx.u.shape[0], 6))

    def check_inputs(self, kind: str, k: int, where: str = "inputs") -> None:
        if kind != "thrust":
            raise SimulationError(f"{where}: this vehicle takes actuator commands ({', '.join(self.names)}) "
                                  f"with input_kind='thrust', got {kind!r}")
        if k != len(self.names):
            raise SimulationError(f"{where}: {k} command columns, expected {len(self.names)} ({', '.join(self.names)})")

    def to_dict(self):
        d = {"type": self.kind, "names": list(self.names)}
        if self.units is not None:
            d["units"] = list(self.units)
        if self.description:
            d["description"] = self.description
        return d


# ----------------------------------------------------------------------------- propulsion
@register("sam_propulsion")
class Propulsion(ForceTerm):
    """Counter-rotating propellers with thrust vectoring (see module docstring).

    Parameters (vehicle file, SI units except rpm)
    ----------
    inputs : [i_rpm1, i_rpm2, i_tv_pitch, i_tv_yaw] command columns.
    position : (3,) propeller thrust point in the body frame, m.
    diameter : propeller diameter D, m.
    K_T0, K_Tmax, K_Q0, K_Qmax, J_max : open-water coefficients (-).
    wake_fraction_factor : ``w_a`` in ``V_a = w_a u_r`` (-).
    reverse_thrust_ratio : thrust (and torque) of reversed rotation relative to forward
        rotation at the same |rpm| and zero advance, in (0, 1.5] (-).
    thrust_deduction : thrust deduction number ``t`` in [0, 0.5): the hull feels ``(1 - t) T`` (-).
    rho : water density, kg/m^3.
    spin : [s_1, s_2] rotation senses (+1 / -1).
    rpm : servo spec {min, max, time_constant, rate} (rev/min, s, rev/min/s).
    tv : servo spec of both gimbal axes {min, max, time_constant, rate} (rad, s, rad/s).
    """

    n_states = 4

    def __init__(self, inputs=(0, 1, 2, 3), position=(-0.72, 0.0, 0.0), diameter=0.14, K_T0=0.4566,
                 K_Tmax=0.1798, K_Q0=0.0700, K_Qmax=0.0312, J_max=0.6632, wake_fraction_factor=0.944,
                 reverse_thrust_ratio=1.0, thrust_deduction=0.0, rho=1025.0, spin=(1, -1), rpm=None, tv=None,
                 reverse_factor=None):
        w = "effects (sam_propulsion)"
        if reverse_factor is not None:
            raise VehicleError(f"{w}.reverse_factor: replaced by reverse_thrust_ratio (reverse/forward thrust at "
                               f"equal |rpm|, = 1 / reverse_factor) with its source; got reverse_factor = "
                               f"{reverse_factor!r}")
        inputs = list(inputs)
        if len(inputs) != 4:
            raise VehicleError(f"{w}.inputs: expected 4 column indices (rpm_1, rpm_2, tv_pitch, tv_yaw)")
        self.inputs = [_index(i, w, "inputs") for i in inputs]
        self.position = np.asarray(position, float)
        if self.position.shape != (3,) or not np.all(np.isfinite(self.position)):
            raise VehicleError(f"{w}.position: expected 3 finite numbers")
        self.coef = {k: _num({k: v}, k, w, positive=True) for k, v in
                     dict(diameter=diameter, K_T0=K_T0, K_Tmax=K_Tmax, K_Q0=K_Q0, K_Qmax=K_Qmax, J_max=J_max,
                          wake_fraction_factor=wake_fraction_factor, reverse_thrust_ratio=reverse_thrust_ratio,
                          rho=rho).items()}
        if self.coef["reverse_thrust_ratio"] > 1.5:
            raise VehicleError(f"{w}.reverse_thrust_ratio: expected a ratio in (0, 1.5] (reverse/forward thrust at "
                               f"equal |rpm|), got {reverse_thrust_ratio!r}")
        self.coef["thrust_deduction"] = t = _num({"thrust_deduction": thrust_deduction}, "thrust_deduction", w)
        if not 0.0 <= t < 0.5:
            raise VehicleError(f"{w}.thrust_deduction: expected a number t in [0, 0.5) (the hull feels (1 - t) T), "
                               f"got {thrust_deduction!r}")
        self.spin = [float(s) for s in spin]
        if len(self.spin) != 2 or any(abs(abs(s) - 1) > 1e-12 for s in self.spin):
            raise VehicleError(f"{w}.spin: expected two senses +1/-1")
        self.rpm = _Servo(dict(rpm or {}), f"{w}.rpm", -1525.0, 1525.0, 0.1, 1.0e5)
        self.tv = _Servo(dict(tv or {}), f"{w}.tv", -math.radians(7), math.radians(7), 0.05, math.radians(40))

    def state_names(self):
        return ["rpm_1_act", "rpm_2_act", "tv_pitch_act", "tv_yaw_act"]

    def to_dict(self):
        d = {"type": self.kind, "inputs": list(self.inputs), "position": self.position.tolist(), "spin": self.spin,
             "rpm": self.rpm.to_dict(), "tv": self.tv.to_dict()}
        d.update(self.coef)
        return d

    def prepare(self, params, n):
        c = self.coef
        D = c["diameter"]
        return {
            "kt": (c["rho"] * D ** 4, c["K_T0"], (c["K_Tmax"] - c["K_T0"]) / c["J_max"] / D),
            "kq": (c["rho"] * D ** 5, c["K_Q0"], (c["K_Qmax"] - c["K_Q0"]) / c["J_max"] / D),
        }

    def initial_state(self, prep, n, u0, input_kind):
        x = np.zeros((n, 4))
        if u0.shape[-1] > max(self.inputs):
            x[:, :2] = self.rpm.initial(u0[:, self.inputs[:2]])
            x[:, 2:] = self.tv.initial(u0[:, self.inputs[2:]])
        return x

    def state_derivative(self, ctx, prep, x):
        u = ctx.u
        if x.shape[0] == 1:
            i = self.inputs
            u0, x0 = u[0].tolist(), x[0].tolist()
            r, t = self.rpm.derivative1, self.tv.derivative1
            return np.array([[r(u0[i[0]], x0[0]), r(u0[i[1]], x0[1]), t(u0[i[2]], x0[2]), t(u0[i[3]], x0[3])]])
        d = np.empty_like(x)
        d[:, :2] = self.rpm.derivative(u[:, self.inputs[:2]], x[:, :2])
        d[:, 2:] = self.tv.derivative(u[:, self.inputs[2:]], x[:, 2:])
        return d

    def thrust_torque(self, rpm, u_r, prep):
        """Thrust (N) and torque (N m) of propellers at ``rpm`` (n, 2) for surge speed ``u_r`` (n,)."""
        c = self.coef
        n_rps = rpm / 60.0
        a = np.abs(n_rps)
        va = (c["wake_fraction_factor"] * u_r)[:, None]
        r4, k0, k1 = prep["kt"]
        r5, q0, q1 = prep["kq"]
        fwd = n_rps > 0
        rr = c["reverse_thrust_ratio"]
        T = np.where(fwd, r4 * (k0 * a * n_rps + k1 * va * a), rr * r4 * k0 * a * n_rps)
        Q = np.where(fwd, r5 * (q0 * a * n_rps + q1 * va * a), rr * r5 * q0 * a * n_rps)
        return T, Q

    def _forces1(self, x, u_r, prep):
        """Scalar path of :meth:`forces` for one trajectory (same equations)."""
        c = self.coef
        r4, k0, k1 = prep["kt"]
        r5, q0, q1 = prep["kq"]
        va = c["wake_fraction_factor"] * u_r
        T = []
        Q = []
        for rpm in x[:2]:
            n = rpm / 60.0
            a = abs(n)
            if n > 0:
                T.append(r4 * (k0 * a * n + k1 * va * a))
                Q.append(r5 * (q0 * a * n + q1 * va * a))
            else:
                T.append(c["reverse_thrust_ratio"] * r4 * k0 * a * n)
                Q.append(c["reverse_thrust_ratio"] * r5 * q0 * a * n)
        dp, dy = x[2], x[3]
        cy = math.cos(dy)
        dx, dyy, dz = math.cos(dp) * cy, -math.sin(dy), math.sin(dp) * cy
        Tt = (1.0 - c["thrust_deduction"]) * (T[0] + T[1])
        Fx, Fy, Fz = Tt * dx, Tt * dyy, Tt * dz
        px, py, pz = self.position.tolist()
        Mr = -(self.spin[0] * Q[0] + self.spin[1] * Q[1])
        return [Fx, Fy, Fz, py * Fz - pz * Fy + Mr * dx, pz * Fx - px * Fz + Mr * dyy, px * Fy - py * Fx + Mr * dz]

    def forces(self, ctx, prep):
        x = ctx.states[self._index(ctx)]
        if x.shape[0] == 1:
            return np.array([self._forces1(x[0].tolist(), float(ctx.nu_r[0, 0]), prep)])
        T, Q = self.thrust_torque(x[:, :2], ctx.nu_r[:, 0], prep)
        dp, dy = x[:, 2], x[:, 3]
        cy = np.cos(dy)
        d = np.stack([np.cos(dp) * cy, -np.sin(dy), np.sin(dp) * cy], -1)  # (n, 3)
        Ttot = (1.0 - self.coef["thrust_deduction"]) * (T[:, 0] + T[:, 1])
        F = Ttot[:, None] * d
        Mroll = -(self.spin[0] * Q[:, 0] + self.spin[1] * Q[:, 1])
        M = np.cross(self.position, F) + Mroll[:, None] * d
        return np.concatenate([F, M], axis=1)

    _state_key = None

    def bind(self, vehicle, index):
        """Copy that knows its index in the model's term list (the key of its states in
        ``ctx.states``); called by :class:`uvsim.model.Model`."""
        import copy

        new = copy.copy(self)
        new._state_key = index
        return new

    def _index(self, ctx):
        idx = self._state_key
        if idx is None or idx not in ctx.states:
            raise SimulationError("effects (sam_propulsion): not bound to a model; use it inside a uvsim Model")
        return idx


class _MassTerm(ForceTerm):
    """A one-state subsystem that only moves / changes mass (no direct force)."""

    n_states = 1
    changes_mass = True
    state_label = "x"

    def state_names(self):
        return [f"{self.state_label}_act"]

    def initial_state(self, prep, n, u0, input_kind):
        if u0.shape[-1] > self.input:
            return self.servo.initial(u0[:, [self.input]])
        return np.full((n, 1), self.servo.ref)

    def prepare(self, params, n):
        return {"key": None, "val": None}

    def state_derivative(self, ctx, prep, x):
        if x.shape[0] == 1:
            return np.array([[self.servo.derivative1(float(ctx.u[0, self.input]), float(x[0, 0]))]])
        return self.servo.derivative(ctx.u[:, [self.input]], x)

    def forces(self, ctx, prep):
        return np.zeros((ctx.nu.shape[0], 6))

    def mass_properties(self, ctx, prep, x):
        """``(dm (n,), d_first_moment (n, 3), dI (n, 3, 3))`` relative to the reference
        position; cached on the state value (unchanged while the actuator is settled)."""
        key = x[:, 0].tobytes()
        if prep is not None and prep["key"] == key:
            return prep["val"]
        n = x.shape[0]
        dm, r1, m1, r0, m0 = self._masses(x[:, 0], n)
        dfirst = m1[:, None] * r1 - m0[:, None] * r0
        dI = _point_inertia(m1, r1) - _point_inertia(m0, r0)
        val = (dm, dfirst, dI)
        if prep is not None:
            prep["key"], prep["val"] = key, val
        return val


@register("sam_vbs")
class VariableBuoyancy(_MassTerm):
    """Variable buoyancy system: a piston cylinder of sea water (see module docstring).

    Parameters: ``input`` column, ``position`` (3,) m, ``radius`` m, ``stroke`` m,
    ``rho`` kg/m^3, ``servo`` {min, max (%), reference (%), time_constant (s), rate (%/s)}.
    """

    state_label = "vbs"

    def __init__(self, input=4, position=(0.0, 0.0, 0.0), radius=0.0425, stroke=0.045, rho=1025.0, servo=None):
        w = "effects (sam_vbs)"
        self.input = _index(input, w)
        self.position = np.asarray(position, float)
        if self.position.shape != (3,):
            raise VehicleError(f"{w}.position: expected 3 numbers")
        self.radius = _num({"radius": radius}, "radius", w, positive=True)
        self.stroke = _num({"stroke": stroke}, "stroke", w, positive=True)
        self.rho = _num({"rho": rho}, "rho", w, positive=True)
        self.servo = _Servo(dict(servo or {}), f"{w}.servo", 0.0, 100.0, 0.5, 7.0, ref=50.0)

    @property
    def full_mass(self) -> float:
        """Water mass of a full cylinder, kg."""
        return self.rho * math.pi * self.radius ** 2 * self.stroke

    def _masses(self, s, n):
        m1 = self.full_mass * s / 100.0
        m0 = np.full(n, self.full_mass * self.servo.ref / 100.0)
        r = np.broadcast_to(self.position, (n, 3))
        return m1 - m0, r, m1, r, m0

    def to_dict(self):
        return {"type": self.kind, "input": self.input, "position": self.position.tolist(), "radius": self.radius,
                "stroke": self.stroke, "rho": self.rho, "servo": self.servo.to_dict()}


@register("sam_lcg")
class MovingMass(_MassTerm):
    """Longitudinal CG trim: a mass moving along the body x axis (see module docstring).

    Parameters: ``input`` column, ``mass`` kg, ``position`` (3,) m at the reference
    command, ``stroke`` m (0..100 %), ``servo`` {min, max, reference (%), time_constant, rate (%/s)}.
    """

    state_label = "lcg"

    def __init__(self, input=5, mass=2.6, position=(0.0, 0.0, 0.0), stroke=0.223, servo=None):
        w = "effects (sam_lcg)"
        self.input = _index(input, w)
        self.mass = _num({"mass": mass}, "mass", w, positive=True)
        self.position = np.asarray(position, float)
        if self.position.shape != (3,):
            raise VehicleError(f"{w}.position: expected 3 numbers")
        self.stroke = _num({"stroke": stroke}, "stroke", w, positive=True)
        self.servo = _Servo(dict(servo or {}), f"{w}.servo", 0.0, 100.0, 0.5, 15.0, ref=50.0)

    def _masses(self, s, n):
        m = np.full(n, self.mass)
        r0 = np.broadcast_to(self.position, (n, 3))
        r1 = r0.copy()
        r1[:, 0] += (s - self.servo.ref) / 100.0 * self.stroke
        return np.zeros(n), r1, m, r0, m

    def to_dict(self):
        return {"type": self.kind, "input": self.input, "mass": self.mass, "position": self.position.tolist(),
                "stroke": self.stroke, "servo": self.servo.to_dict()}


@register("sam_tcg")
class RevolvingMasses(_MassTerm):
    """Transversal CG trim: masses revolving about the x axis (see module docstring).

    Parameters: ``input`` column, ``mass`` kg (both masses together), ``x`` m, ``radius``
    m, ``servo`` {min, max, reference (rad), time_constant (s), rate (rad/s)}.
    """

    state_label = "tcg"

    def __init__(self, input=6, mass=0.5, x=0.0, radius=0.04, servo=None):
        w = "effects (sam_tcg)"
        self.input = _index(input, w)
        self.mass = _num({"mass": mass}, "mass", w, positive=True)
        self.x = _num({"x": x}, "x", w)
        self.radius = _num({"radius": radius}, "radius", w, positive=True)
        self.servo = _Servo(dict(servo or {}), f"{w}.servo", -math.pi / 2, math.pi / 2, 0.2, math.radians(60), ref=0.0)

    def _pos(self, phi):
        return np.stack([np.full_like(phi, self.x), self.radius * np.sin(phi), self.radius * np.cos(phi)], -1)

    def _masses(self, s, n):
        m = np.full(n, self.mass)
        return np.zeros(n), self._pos(s), m, self._pos(np.full(n, self.servo.ref)), m

    def to_dict(self):
        return {"type": self.kind, "input": self.input, "mass": self.mass, "x": self.x, "radius": self.radius,
                "servo": self.servo.to_dict()}


def servo_time_constants(vehicle) -> dict[str, float]:
    """{"<effect>.<servo>": time constant, s} of every actuator servo among ``vehicle``'s
    effects (the first-order lags above): the fastest sets the longest integration step."""
    out = {}
    for term in getattr(vehicle, "effects", ()):
        for name, obj in vars(term).items():
            if isinstance(obj, _Servo):
                out[f"{type(term).__name__}.{name}"] = float(obj.tau)
    return out
