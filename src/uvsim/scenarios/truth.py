"""Assemble and run the truth model for a set of trajectories.

:func:`simulate_truth` is the entry point: a vehicle (:class:`VehicleData`), the logged
inputs of one or more runs, the effects, and per-trajectory masks saying which effect
is on in which trajectory.  The actuator chain is

    input -> commanded output (force, thrust, or the thrust table at the PWM)
          -> thrust_asymmetry -> weak_thruster (static, per sample)
          -> first-order lag (thruster_lag, inside the ODE) -> allocation -> tau
"""
from __future__ import annotations

import numpy as np

from uvsim.scenarios.dynamics import N_BASE, Plant, integrate
from uvsim.scenarios.effects import COMMAND_ORDER, Effect, ScenarioError
from uvsim.scenarios.vehicle_data import VehicleData

#: Default RK4 step bound, s (several sub-steps per log sample; see docs/scenarios.md for
#: the step-halving check of the integration error).
MAX_STEP = 0.002


def base_parts(veh: VehicleData, n: int, n_act: int) -> dict:
    """Per-trajectory arrays of the vehicle without effects (component first)."""
    W, B = veh.weight, veh.buoyancy
    return {
        "mass": np.full(n, veh.mass),
        "r_g": np.repeat(veh.r_g[:, None], n, axis=1),
        "inertia": np.repeat(veh.inertia_tensor()[:, :, None], n, axis=2),
        "added_mass": np.repeat(veh.added_mass_matrix()[:, :, None], n, axis=2),
        "linear": np.repeat(veh.linear_damping()[:, None], n, axis=1),
        "quadratic": np.repeat(veh.quadratic_damping()[:, None], n, axis=1),
        "load": np.full(n, W - B),
        "load_moment": np.repeat((W * veh.r_g - B * veh.r_b)[:, None], n, axis=1),
        "current": np.zeros((3, n)),
        "lag_time": np.zeros((n_act, n)),
    }


def commanded_outputs(veh: VehicleData, inputs: np.ndarray, kind: str) -> np.ndarray:
    """What the actuators are told to deliver: forces / thrusts as logged, or the thrust
    table at each PWM command.  ``inputs`` (..., k)."""
    if kind in ("force", "thrust"):
        return np.asarray(inputs, dtype=float)
    if kind == "pwm":
        lo, hi = veh.curve.pwm_range
        if np.any(inputs < lo) or np.any(inputs > hi):
            raise ScenarioError(f"PWM commands outside the thrust table's range [{lo:g}, {hi:g}] us")
        return veh.curve.thrust(inputs)
    raise ScenarioError(f"input kind {kind!r}: expected force, thrust or pwm")


def equilibrium_attitude(load_moment: np.ndarray) -> tuple[float, float]:
    """Roll and pitch (rad) at which the restoring moment ``m1 x k`` vanishes stably
    (``k = R^T e_3`` parallel to ``m1 = sum F_i r_i``; level when ``m1 = 0``)."""
    k = np.asarray(load_moment, dtype=float)
    if np.linalg.norm(k) < 1e-12:                     # CG on the CB: neutral in any attitude, start level
        return 0.0, 0.0
    k = k / np.linalg.norm(k)
    return float(np.arctan2(k[1], k[2])), float(-np.arcsin(np.clip(k[0], -1, 1)))


def simulate_truth(veh: VehicleData, t, inputs, kind: str, *, effects: list[Effect] = (), active=None,
                   pos0=None, quat0=None, nu0=None, max_step: float = MAX_STEP, renormalize: bool = True,
                   wrenches=()) -> dict:
    """Simulate ``n`` trajectories of the truth model on the shared sample grid ``t``.

    Parameters
    ----------
    veh : the (possibly perturbed) vehicle.
    t : (n_t,) s, sample times (uniform or not).
    inputs : (n_t, k) or (n, n_t, k) logged inputs (N / N m, N or us), held between samples.
    kind : "force", "thrust" or "pwm".
    effects : effects of the scenario.
    active : (len(effects), n) bool, which effect acts in which trajectory (default all).
    pos0 : (n, 3) m NED; quat0 : (n, 4) scalar first; nu0 : (n, 6).  Default origin, level, rest.
    max_step : s, RK4 step bound.
    wrenches : extra callables ``f(ctx) -> (6, n)`` (tests).

    Returns
    -------
    dict with ``t`` (n_t,), ``pos`` (n, n_t, 3), ``quat`` (n, n_t, 4), ``nu``, ``nu_dot``
    (n, n_t, 6), ``thrust`` (n, n_t, a) the delivered actuator outputs (N or N/N m).
    """
    t = np.asarray(t, dtype=float)
    U = np.asarray(inputs, dtype=float)
    if U.ndim == 2:
        U = U[None]
    n, n_t, k = U.shape
    if n_t != t.size:
        raise ScenarioError(f"inputs: {n_t} samples for {t.size} times")
    A = veh.allocation()
    if kind == "force":
        if k != 6:
            raise ScenarioError(f"force inputs need 6 columns (X..N), got {k}")
        alloc = np.eye(6)
    else:
        if k != A.shape[1]:
            raise ScenarioError(f"{kind} inputs: {k} columns for {A.shape[1]} thrusters")
        alloc = A
    active = np.ones((len(effects), n), dtype=bool) if active is None else np.asarray(active, dtype=bool)
    f = commanded_outputs(veh, U, kind).transpose(1, 2, 0)          # (n_t, a, n)
    parts = base_parts(veh, n, alloc.shape[1])
    for eff, rows in zip(effects, active):
        eff.modify(parts, rows)
    by_type = {e.type: (e, rows) for e, rows in zip(effects, active)}
    for name in COMMAND_ORDER:
        if name in by_type:
            f = by_type[name][0].map_commands(f, kind, A, by_type[name][1])
    plant = Plant(allocation=np.repeat(alloc[:, :, None], n, axis=2), **parts)
    plant.wrenches = [w for e, rows in zip(effects, active) if (w := e.wrench(parts, rows)) is not None]
    plant.wrenches += list(wrenches)
    y0 = np.zeros((N_BASE + alloc.shape[1], n))
    y0[0:3] = 0.0 if pos0 is None else np.asarray(pos0, dtype=float).T
    y0[3:7] = np.array([[1.0], [0.0], [0.0], [0.0]]) if quat0 is None else np.asarray(quat0, dtype=float).T
    y0[7:13] = 0.0 if nu0 is None else np.asarray(nu0, dtype=float).T
    y0[N_BASE:] = f[0]
    lag = by_type.get("thruster_lag")
    if lag is not None and lag[0].variant == "rest":
        y0[N_BASE:, lag[1]] = 0.0
    Y, nu_dot = integrate(plant, t, f, y0, max_step, renormalize=renormalize)
    delivered = np.where(plant.lagged[None], Y[:, N_BASE:], f)
    return {"t": t, "pos": Y[:, 0:3].transpose(2, 0, 1), "quat": Y[:, 3:7].transpose(2, 0, 1),
            "nu": Y[:, 7:13].transpose(2, 0, 1), "nu_dot": nu_dot.transpose(2, 0, 1),
            "thrust": delivered.transpose(2, 0, 1)}
