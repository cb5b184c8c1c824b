"""Integrators: fixed-step RK4 (single or batched) and adaptive ``solve_ivp``.

Inputs are sampled signals held constant between samples (zero-order hold), as a
logged run provides them: the input of row ``i`` acts on ``[t_i, t_{i+1})``.  RK4
takes one step (or ``substeps`` steps) per sample interval and returns the state at
every sample time.  After each step the quaternion is renormalized.

The batched integrator advances ``n`` trajectories at once with numpy (one parameter
set and one input sequence per row).  Trajectories of different lengths share one
call: shorter time grids are padded by repeating their last time, which makes the
extra steps zero-length (``dt = 0``) so their states stay put.

:func:`simulate_run` simulates a logged run from the initial state
:mod:`uvsim.initial_state` estimates from its measurements.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

from uvsim.errors import SimulationError
from uvsim.schema import did_you_mean, whole_number
from uvsim.kernels import compiled_advance
from uvsim.kernels.plan import compiled_plan
from uvsim.kernels.run import blowup_message, rk4_compiled
from uvsim.initial_state import (  # noqa: F401 (INITIAL_WINDOW_S, check_initial_window re-exported)
    INITIAL_WINDOW_S, check_initial_window, initial_state_from_run)
from uvsim.kinematics import quat_to_euler
from uvsim.model import NU, POS, QUAT, Model
from uvsim.vehicle_schema import check_current_speed

#: Speeds beyond which a trajectory is declared blown up (m/s or rad/s): far above
#: anything an underwater vehicle does (hydrobatic AUVs reach ~5 m/s, seed 003 V-C).
BLOWUP_SPEED = 1.0e3


@dataclass
class SimulationResult:
    """Output of :func:`simulate` (python-control style result object).

    Attributes
    ----------
    t : (n_t,) sample times, s.
    y : (n_t, n_y) or (n_batch, n_t, n_y) states.
    state_names : names of the columns of ``y``.
    inputs : the inputs used, (n_t, k) or (n_batch, n_t, k).
    input_kind : "force" | "thrust" | "pwm".
    """

    t: np.ndarray
    y: np.ndarray
    state_names: list
    inputs: np.ndarray | None = None
    input_kind: str = "force"
    input_names: list | None = None
    vehicle: str = ""
    meta: dict = field(default_factory=dict)
    #: (n_t, 6) or (n_batch, n_t, 6) accelerations at the samples, when requested
    nu_dot: np.ndarray | None = None

    @property
    def position(self) -> np.ndarray:
        return self.y[..., POS]

    @property
    def quaternion(self) -> np.ndarray:
        return self.y[..., QUAT]

    @property
    def euler(self) -> np.ndarray:
        """ZYX Euler angles [roll, pitch, yaw] (rad), shape (..., n_t, 3)."""
        return quat_to_euler(self.y[..., QUAT])

    @property
    def nu(self) -> np.ndarray:
        return self.y[..., NU]

    def to_pandas(self, index: int | None = None):
        """A DataFrame with the LOG_FORMAT columns (t, x, y, z, qw..qz, roll, pitch,
        yaw, u..r), term states and inputs.  For a batched result give ``index``."""
        import pandas as pd

        y = self.y if self.y.ndim == 2 else self.y[0 if index is None else index]
        u = None
        if self.inputs is not None:
            u = self.inputs if self.inputs.ndim == 2 else self.inputs[0 if index is None else index]
        cols = {"t": self.t if self.t.ndim == 1 else self.t[0 if index is None else index]}
        names = self.state_names
        for j, nm in enumerate(names[:7]):
            cols[nm] = y[:, j]
        e = quat_to_euler(y[:, QUAT])
        cols["roll"], cols["pitch"], cols["yaw"] = e[:, 0], e[:, 1], e[:, 2]
        for j, nm in enumerate(names[7:], start=7):
            cols[nm] = y[:, j]
        if u is not None and self.input_names:
            for j, nm in enumerate(self.input_names):
                cols[nm] = u[:, j]
        return pd.DataFrame(cols)


def input_names(kind: str, k: int) -> list[str]:
    if kind == "force":
        return ["X", "Y", "Z", "K", "M", "N"]
    return [f"{kind}_{i + 1}" for i in range(k)]


def _check_time(t: np.ndarray, where: str) -> None:
    if t.ndim != 1 or t.size < 2:
        raise SimulationError(f"{where}: need at least two sample times")
    if not np.all(np.isfinite(t)):
        raise SimulationError(f"{where}: non-finite sample time")
    d = np.diff(t)
    if np.any(d <= 0):
        i = int(np.argmax(d <= 0)) + 1
        raise SimulationError(f"{where}: time must be strictly increasing (row {i}: t = {t[i]} after {t[i - 1]})")


#: Most RK4 steps per sample interval (``substeps``).  RK4's error per unit time falls as h^4, so at
#: 100 substeps of a 50 Hz log (a 0.2 ms step, 2000 times shorter than the BlueROV2's fastest time
#: constant, 0.4 s) it is 1e-13 of the one-step error, at float64 rounding; more only costs time
#: (1000 substeps of a 4 s run took 16 s; ``--substeps 100000000`` would have integrated for days).
MAX_SUBSTEPS = 100


def check_substeps(substeps) -> int:
    """``substeps`` checked: a whole number 1..MAX_SUBSTEPS (not truncated, not clipped)."""
    return whole_number(substeps, "substeps", minimum=1, maximum=MAX_SUBSTEPS, error=SimulationError,
                        hint=f" (RK4 steps per sample interval; beyond {MAX_SUBSTEPS} the step's error is below rounding)")


def _check_time_values(t, where: str) -> np.ndarray:
    """``t`` as a float array; text or other non-numbers are a SimulationError naming ``where``."""
    try:
        return np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise SimulationError(f"{where}: expected sample times in s (numbers), got {str(t)[:80]}") from None


def _rk4_loop(model: Model, T: np.ndarray, U: np.ndarray, y0: np.ndarray, substeps: int, on_blowup: str,
              progress=None, accel: np.ndarray | None = None, V: np.ndarray | None = None) -> np.ndarray:
    """Core RK4 loop.  ``T`` (n, n_t) times, ``U`` (n, n_t, k) inputs, ``y0`` (n, n_y),
    ``V`` (n, n_t) battery voltages or None (held over each interval like ``U``).
    ``accel`` (n, n_t, 6), if given, receives ``nu_dot`` at every sample: the model's
    acceleration at the sample's state with that sample's (held) input, i.e. the first
    RK4 stage of the step that starts there (what an accelerometer at that time sees)."""
    substeps = check_substeps(substeps)
    with np.errstate(all="ignore"):  # blow-ups are detected below and reported, not warned about
        return _rk4_steps(model, T, U, y0, substeps, on_blowup, progress, V, accel)


def _check_voltage(voltage, shape: tuple, where: str = "voltage") -> np.ndarray | None:
    """Validated battery voltages (V) broadcast to ``shape``, or None.  NaN entries mean
    "not logged" (voltage-dependent curves use their nominal voltage there)."""
    if voltage is None:
        return None
    V = np.asarray(voltage, dtype=float)
    try:
        V = np.broadcast_to(V, shape)
    except ValueError:
        raise SimulationError(f"{where}: expected shape {shape} (one voltage per sample), got {V.shape}") from None
    bad = np.isinf(V) | (V <= 0)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        raise SimulationError(f"{where}: battery voltage {V[idx]!r} V at index {idx} is not a positive finite number")
    return V


def _rk4_steps(model, T, U, y0, substeps, on_blowup, progress, V=None, accel=None):
    advance = compiled_advance()
    plan = None if advance is None else compiled_plan(model)
    if plan is not None:  # the compiled kernel (uvsim.kernels), where installed and the model allows
        return rk4_compiled(advance, plan, model, T, U, y0, substeps, on_blowup, progress, V, accel, BLOWUP_SPEED)
    n, n_t = T.shape
    Y = np.empty((n, n_t, model.n_y))
    y = y0.copy()
    Y[:, 0] = y
    alive = np.ones(n, bool)
    rhs = model.rhs
    shared_t = bool(np.all(T == T[:1]))
    for i in range(n_t - 1):
        u = U[:, i]
        v = None if V is None else V[:, i]
        # shared grid: scalar t and h; per-row grids: t (n,) and h (n,) per row, so every
        # row's stages are evaluated at its own times (time-varying currents, schedules)
        if shared_t:
            t = T[0, i]
            h = (T[0, i + 1] - t) / substeps
            hc = h
        else:
            t = T[:, i].copy()
            h = (T[:, i + 1] - t) / substeps
            hc = h[:, None]
        for sub in range(substeps):
            k1 = rhs(t, y, u, v)
            if accel is not None and sub == 0:
                accel[:, i] = k1[:, 7:13]
            k2 = rhs(t + 0.5 * h, y + (0.5 * hc) * k1, u, v)
            k3 = rhs(t + 0.5 * h, y + (0.5 * hc) * k2, u, v)
            k4 = rhs(t + h, y + hc * k3, u, v)
            y = y + (hc / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
            q = y[:, 3:7]
            q /= np.sqrt((q * q).sum(axis=1))[:, None]
            t = t + h
        Y[:, i + 1] = y
        if (i & 15) == 15 or i == n_t - 2:
            fin = np.isfinite(y).all(axis=1) & (np.abs(y[:, 7:13]).max(axis=1) < BLOWUP_SPEED)
            bad = alive & ~fin
            if bad.any():
                j = int(np.argmax(bad))
                if on_blowup == "raise":
                    raise SimulationError(blowup_message(j, T[j, i + 1], BLOWUP_SPEED))
                alive &= fin
                y[bad] = np.nan
                Y[bad, : i + 2] = np.where(np.isfinite(Y[bad, : i + 2]), Y[bad, : i + 2], np.nan)
        if progress is not None:
            progress.update(1)
    if accel is not None:
        t_end = T[0, -1] if shared_t else T[:, -1]
        accel[:, -1] = rhs(t_end, y, U[:, -1], None if V is None else V[:, -1])[:, 7:13]
    return Y


def simulate(vehicle, t, inputs, *, input_kind: str = "force", pos0=None, q0=None, nu0=None,
             overrides: Mapping[str, Any] | None = None, current=None, method: str = "rk4",
             substeps: int = 1, rtol: float = 1e-8, atol: float = 1e-10, on_blowup: str = "raise",
             model: Model | None = None, voltage=None, counter=None) -> SimulationResult:
    """Simulate one trajectory.

    Parameters
    ----------
    vehicle : Vehicle or str
        Vehicle object, built-in name or file.
    t : array_like, shape (n_t,)
        Sample times, s, strictly increasing.
    inputs : array_like, shape (n_t, k)
        Inputs at the sample times, held until the next sample: generalized forces
        (k = 6: X, Y, Z [N], K, M, N [N m]), per-thruster thrust [N] or PWM [us].
    input_kind : {"force", "thrust", "pwm"}
    pos0, q0, nu0 : initial NED position (3,), quaternion (4,), body velocity (6,).
    overrides : named parameters replacing the vehicle's.
    current : None, a constant NED current (3,) m/s, or ``f(t) -> (v_c, v_c_dot)``.
    method : "rk4" (fixed step, one step per sample interval times ``substeps``) or
        any :func:`scipy.integrate.solve_ivp` method name ("RK45", "DOP853", "LSODA", ...).
    on_blowup : "raise" (default) or "nan" (mark the trajectory NaN and continue).
    voltage : array_like, shape (n_t,), optional
        Battery voltage (V) at the sample times, held until the next sample like the
        inputs; feeds voltage-dependent thrust curves (NaN: the curve's nominal
        voltage).  None (default): every curve at its nominal voltage.
    counter : an object with ``update(n)`` told of every ``n`` sample intervals done by "rk4"
        (a :class:`uvsim.progress.Stage`, a tqdm bar), or None.

    Returns
    -------
    SimulationResult
    """
    t = _check_time_values(t, "t")
    _check_time(t, "t")
    U = np.asarray(inputs, dtype=float)
    if U.ndim == 1:
        U = U[:, None]
    if U.shape[0] != t.size:
        raise SimulationError(f"inputs: {U.shape[0]} rows for {t.size} sample times")
    if not np.all(np.isfinite(U)):
        i = int(np.argmax(~np.isfinite(U).all(axis=1)))
        raise SimulationError(f"inputs: non-finite value at row {i}")
    if model is None:
        model = _make_model(vehicle, overrides, input_kind, current, n=1)
    model.check_inputs(U.shape[1])
    V = _check_voltage(voltage, t.shape)
    y0 = model.initial_state(pos0, q0, nu0, U[0][None, :])
    check_method(method)
    for name, tol in (("rtol", rtol), ("atol", atol)):
        if not (isinstance(tol, (int, float, np.floating)) and np.isfinite(tol) and tol > 0):
            raise SimulationError(f"{name} {tol!r}: expected a positive tolerance (solve_ivp would change it in silence)")
    if method.lower() == "rk4":
        check_substeps(substeps)
        Y = _rk4_loop(model, t[None, :], U[None], y0, substeps, on_blowup, counter,
                      V=None if V is None else V[None])[0]
    else:
        Y = _solve_ivp(model, t, U, y0[0], method, rtol, atol, on_blowup, V)
    return SimulationResult(t, Y, model.state_names, U, model.input_kind, input_names(model.input_kind, U.shape[1]),
                            model.vehicle.name, {"method": method})


#: The integration methods by name: our fixed-step "rk4" and scipy.integrate.solve_ivp's
#: (scipy docs, solve_ivp ``method``: RK45, RK23, DOP853, Radau, BDF, LSODA).
IVP_METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")


def check_method(method) -> None:
    """Refuse an unknown integration method by name (with the nearest one), before any work."""
    if not isinstance(method, str):
        raise SimulationError(f"method: expected a name (rk4 or one of {', '.join(IVP_METHODS)}), got {method!r}")
    if method.lower() == "rk4" or method in IVP_METHODS:
        return
    raise SimulationError(f"method {method!r}: unknown{did_you_mean(method, ['rk4', *IVP_METHODS])}; expected "
                          f"rk4 (fixed step) or a scipy solve_ivp method: {', '.join(IVP_METHODS)}")


def _make_model(vehicle, overrides, input_kind, current, n=None) -> Model:
    cur_fn = None
    ov = dict(overrides or {})
    if current is not None:
        if callable(current):
            cur_fn = current
        else:
            c = np.asarray(current, dtype=float)
            if c.shape != (3,) or not np.all(np.isfinite(c)):
                raise SimulationError(f"current: expected 3 finite numbers (N, E, D m/s), got {current!r}")
            check_current_speed(c, f"current {c.tolist()}", SimulationError)  # as --current and current_ned
            ov.update(current_n=c[0], current_e=c[1], current_d=c[2])
    return Model(vehicle, ov, n=n, input_kind=input_kind, current=cur_fn)


def _solve_ivp(model: Model, t, U, y0, method, rtol, atol, on_blowup, V=None):
    from scipy.integrate import solve_ivp

    def fun(tt, yy):
        i = min(max(int(np.searchsorted(t, tt, side="right")) - 1, 0), len(t) - 1)
        return model.rhs(tt, yy[None, :], U[i][None, :], None if V is None else V[i:i + 1])[0]

    try:
        sol = solve_ivp(fun, (t[0], t[-1]), y0, method=method, t_eval=t, rtol=rtol, atol=atol)
    except ValueError as exc:
        raise SimulationError(f"solve_ivp ({method}): {exc}") from None
    if not sol.success or sol.y.shape[1] != t.size:
        if on_blowup == "raise":
            raise SimulationError(f"solve_ivp ({method}) failed: {sol.message}")
        Y = np.full((t.size, y0.size), np.nan)
        Y[: sol.y.shape[1]] = sol.y.T
        return Y
    Y = sol.y.T.copy()
    Y[:, QUAT] /= np.linalg.norm(Y[:, QUAT], axis=1, keepdims=True)
    return Y


def simulate_batch(vehicle, t, inputs, *, input_kind: str = "force", y0=None, pos0=None, q0=None, nu0=None,
                   overrides: Mapping[str, Any] | None = None, current=None, substeps: int = 1,
                   on_blowup: str = "nan", model: Model | None = None, progress=False,
                   return_acceleration: bool = False, voltage=None) -> SimulationResult:
    """Simulate ``n`` trajectories at once with RK4 (numpy-vectorized).

    Parameters
    ----------
    t : (n_t,) shared sample times or (n, n_t) per-trajectory times (pad shorter runs
        by repeating their last time; the padded steps have zero length).
    inputs : (n, n_t, k) inputs per trajectory (or (n_t, k), shared).
    overrides : named parameters, each a float or an array of shape (n,): one
        parameter set per trajectory.
    y0 : (n, n_y) full initial states, or give ``pos0`` (n, 3), ``q0`` (n, 4), ``nu0`` (n, 6).
    on_blowup : "nan" (default; a diverging trajectory becomes NaN from then on and
        the others continue) or "raise".
    return_acceleration : also return ``nu_dot`` (n, n_t, 6) at every sample in
        ``result.nu_dot`` (the model's acceleration with that sample's input; used by
        accelerometer measurement models).
    voltage : (n, n_t) or (n_t,) battery voltages (V), held like the inputs, or None
        (see :func:`simulate`).
    progress : the steps as a stage (:func:`uvsim.progress.as_progress`: True a tqdm bar).

    Returns
    -------
    SimulationResult with ``y`` of shape (n, n_t, n_y).
    """
    T = _check_time_values(t, "t")
    U = np.asarray(inputs, dtype=float)
    if U.ndim == 2:
        U = U[None]
    sizes = [U.shape[0]] + [np.size(v) for v in (overrides or {}).values() if np.ndim(v) > 0]
    if T.ndim == 2:
        sizes.append(T.shape[0])
    if y0 is not None:
        sizes.append(np.shape(y0)[0])
    n = max(sizes)
    if model is None:
        model = _make_model(vehicle, overrides, input_kind, current, n=n)
    n = model.n
    T = np.broadcast_to(T, (n, T.shape[-1])) if T.ndim == 1 else T
    if T.shape[0] != n:
        raise SimulationError(f"t: {T.shape[0]} time grids for a batch of {n}")
    d = np.diff(T, axis=1)
    if np.any(d < 0) or not np.all(np.isfinite(T)):
        raise SimulationError("t: times must be finite and non-decreasing along each trajectory")
    U = np.broadcast_to(U, (n,) + U.shape[1:])
    if U.shape[1] != T.shape[1]:
        raise SimulationError(f"inputs: {U.shape[1]} samples for {T.shape[1]} sample times")
    if not np.all(np.isfinite(U)):
        raise SimulationError("inputs: non-finite values")
    model.check_inputs(U.shape[2])
    if y0 is None:
        y0 = model.initial_state(pos0, q0, nu0, U[:, 0])
    y0 = np.asarray(y0, dtype=float)
    if y0.shape != (n, model.n_y):
        raise SimulationError(f"y0: expected shape {(n, model.n_y)}, got {y0.shape}")
    from uvsim.progress import as_progress

    acc = np.empty((n, T.shape[1], 6)) if return_acceleration else None
    V = _check_voltage(voltage, T.shape)
    with as_progress(progress).stage(f"simulation of {n} trajectories x {T.shape[1]} samples", total=T.shape[1] - 1,
                                     unit="step", short="simulate", leave=False) as stage:
        Y = _rk4_loop(model, T, U, y0, substeps, on_blowup, stage, acc, V)
    res = SimulationResult(T[0] if np.all(T == T[:1]) else T, Y, model.state_names, U, model.input_kind,
                           input_names(model.input_kind, U.shape[2]), model.vehicle.name)
    res.nu_dot = acc
    return res


def simulate_run(vehicle, run, *, current=None, overrides=None, method: str = "rk4", substeps: int = 1,
                 on_blowup: str = "raise", initial_window_s: float = 0.0, progress=None) -> SimulationResult:
    """Simulate a logged :class:`uvsim.logs.Run`: start from its first measured state
    (velocities zero where not logged) and apply its inputs (and its battery voltage,
    :attr:`uvsim.logs.Run.voltage`, when it logged one), as late as the vehicle's sensors
    read (``sensors.latency``, :mod:`uvsim.latency`).  Input columns that do not
    fit the vehicle, and PWM outside its thrust curves, raise
    :class:`uvsim.errors.PlausibilityError` naming the run's file, column and row.  ``progress``:
    the simulation as a stage (:func:`uvsim.progress.as_progress`)."""
    from uvsim.latency import delay_inputs
    from uvsim.plausibility import require_inputs_match
    from uvsim.vehicle import load_vehicle

    vehicle = load_vehicle(vehicle)
    require_inputs_match(run, vehicle)
    run = delay_inputs(run, vehicle.sensor_latency)  # the vehicle's sensors.latency (uvsim.latency)
    pos0, q0, nu0, _ = initial_state_from_run(run, window_s=initial_window_s)
    from uvsim.progress import as_progress

    rk4 = isinstance(method, str) and method.lower() == "rk4"
    with as_progress(progress).stage(f"simulation of {run.name}: {len(run.t)} samples, {run.t[-1] - run.t[0]:.1f} s "
                                     f"({method})", total=len(run.t) - 1 if rk4 else None, unit="step",
                                     short=f"simulate {run.name}") as stage:
        return simulate(vehicle, run.t, run.inputs, input_kind=run.input_kind, pos0=pos0, q0=q0, nu0=nu0,
                        overrides=overrides, current=current, method=method, substeps=substeps, on_blowup=on_blowup,
                        voltage=run.voltage, counter=stage)
