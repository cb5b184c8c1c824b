"""Residuals of a model against logged runs.

Two kinds, both per run and over time:

* **output residuals** (:func:`output_residuals`): measured minus simulated
  signals (position error in m, attitude-error rotation vector in rad, velocity
  and rate errors), for whichever signals the run logged
  (:func:`uvsim.metrics.residual_components`; missing samples stay NaN);
* **generalized-force residual** (:func:`force_residual`) through the inverse
  dynamics: with ``nu`` and ``nu_dot`` estimated from the smoothed measured
  motion, ``tau_res = M (nu_dot_meas - f(eta, nu, u))`` where ``f`` is the model's
  acceleration (:meth:`uvsim.model.Model.rhs`).  Since the model's acceleration
  is ``M^-1 (sum of terms - C(nu) nu)``, this is exactly the force (body frame,
  N and N m) the model would need in addition to reproduce the measured motion:
  the force of the missing effect plus noise.  It is also rotated into NED
  (forces and moments), where a constant-in-NED effect (current, ballast) looks
  constant.

Smoothing and differentiation (:mod:`uvsim.estimation.derivatives`): a
Savitzky-Golay filter (cubic, 1 s window, ``FORCE_WINDOW_S``) differentiates the logged position
(rotated into the body frame with the logged attitude) and the unwrapped ZYX
Euler angles (converted to body rates, Fossen 2021 eq. 2.28); logged velocities
and rates are used as they are; ``nu_dot`` is the Savitzky-Golay derivative of
``nu``; the model's acceleration ``f(eta, nu, u)`` is passed through the same
(zero-phase) filter twice (the measured ``nu_dot`` went through two: position to
``nu`` to ``nu_dot``), so that both sides of the difference are equally smoothed
and input steps leave no filter artefact.  Components of ``nu`` that cannot be formed from the log (e.g. ``u, v`` of
a depth-only run) are taken from the simulation and the residual components
that depend on them are masked (NaN): forces need all of ``u, v, w``, moments all
of ``p, q, r``.  The first and last half window are masked too (there the filter
extrapolates).

Measurement noise (:func:`noise_levels`): per signal group, from second
differences of the raw signal, ``sigma = 1.4826 MAD(d2) / sqrt(6)`` (for white
noise ``var(x[i+1] - 2 x[i] + x[i-1]) = 6 sigma^2``; the motion's own curvature,
``a dt^2``, is far below mm-level noise at tank accelerations).  It sets the
scale that makes metres, radians and rad/s summable and tells when a residual
is "at the noise level".
"""
from __future__ import annotations

import numpy as np

from uvsim.calibration.batching import simulate_dataset
from uvsim.estimation.derivatives import body_acceleration, body_velocity, smooth_derivative
from uvsim.errors import CalibrationError
from uvsim.kinematics import quat_to_rotation
from uvsim.metrics import present_groups, residual_components, signals_from_run
from uvsim.model import Model
from uvsim.simulate import initial_state_from_run

#: Floor of an estimated noise level (m, rad, m/s, rad/s): below the 1e-6 rounding
#: of the logs written by uvsim, so it only matters for noise-free data.
NOISE_FLOOR = 1e-6
_GROUP_SIGNAL = {"position": "position", "attitude": "quaternion", "velocity": "velocity", "rates": "rates"}


def _mad_sigma(d2: np.ndarray) -> float:
    d2 = d2[np.isfinite(d2)]
    if d2.size < 5:
        return float("nan")
    return float(1.4826 * np.median(np.abs(d2 - np.median(d2))) / np.sqrt(6.0))


def noise_levels(runs) -> dict[str, float]:
    """Estimated 1-sigma measurement noise per signal group over ``runs``
    (pooled median of the per-channel estimates; see module docstring)."""
    est: dict[str, list] = {}
    for run in runs:
        m = signals_from_run(run)
        for g in present_groups(m):
            if g == "attitude":
                e = run.euler
                ok = np.isfinite(e).all(axis=1)
                x = np.unwrap(e[ok], axis=0) if ok.any() else e[:0]
            else:
                x = m[_GROUP_SIGNAL[g]]
            for j in range(x.shape[1]):
                col = x[:, j]
                if np.isfinite(col).sum() >= 5:
                    d2 = col[2:] - 2 * col[1:-1] + col[:-2]
                    s = _mad_sigma(d2)
                    if np.isfinite(s):
                        est.setdefault(g, []).append(s)
    return {g: max(float(np.median(v)), NOISE_FLOOR) for g, v in est.items()}


def output_residuals(runs, predicted) -> list[dict[str, np.ndarray]]:
    """Per run, measured minus predicted per signal group (n, 3) plus the
    attitude error angle (n,) under ``"attitude_angle"``; NaN where not measured."""
    out = []
    for run, pred in zip(runs, predicted):
        m = signals_from_run(run)
        comps = residual_components(m, pred)
        if "attitude" in comps:
            comps["attitude_angle"] = np.linalg.norm(comps["attitude"], axis=1)
        comps["t"] = run.t
        out.append(comps)
    return out


#: Savitzky-Golay window (s) for the inverse dynamics: longer than the 0.5 s used to
#: estimate initial velocities because the second derivative amplifies noise
#: (2 mm position noise at 20 Hz); still short against the 1-3 s time constants of
#: the tank runs.
FORCE_WINDOW_S = 1.0


def measured_motion(run, window_s: float = FORCE_WINDOW_S) -> tuple[np.ndarray, np.ndarray, str | None]:
    """``(nu, nu_dot, problem)``: body velocities (n, 6) and accelerations (n, 6)
    from the smoothed log (NaN where not available); ``problem`` says why none
    could be formed (non-uniform time, gaps), else None."""
    n = len(run.t)
    try:
        nu = body_velocity(run, window_s=window_s)
        nu_dot = body_acceleration(run, nu, window_s=window_s)
    except CalibrationError as exc:
        return np.full((n, 6), np.nan), np.full((n, 6), np.nan), str(exc)
    return nu, nu_dot, None


def commanded_thrusts(vehicle, run) -> tuple[np.ndarray, np.ndarray | None]:
    """``(tau_c (n, 6), f_c (n, k) or None)``: the commanded generalized force and,
    for per-thruster inputs, the commanded thrusts (thrust curves applied to PWM)."""
    act = vehicle.actuators
    u = run.inputs
    if run.input_kind == "force":
        return u.copy(), None
    groups = act.prepare({}, 1)["groups"]
    f = act.thrusts(u, run.input_kind, groups)
    return f @ act.matrix.T, f


def force_residual(vehicle, run, states: np.ndarray) -> dict:
    """Inverse-dynamics generalized-force residual of one run.

    Parameters
    ----------
    vehicle : the model (Vehicle).
    run : a :class:`uvsim.logs.Run`.
    states : (n, n_y) the model's simulated states of this run (fill-in for what
        the log cannot give, and the states of terms with internal states).

    Returns
    -------
    dict with ``t`` (n,), ``body`` (n, 6) residual [X, Y, Z, K, M, N] in the body
    frame (N, N m), ``ned`` (n, 6) forces and moments rotated into NED, ``nu`` (n, 6)
    velocities used (measured where possible), ``measured`` (6,) bool which of
    ``nu`` came from the log, ``pos`` (n, 3) NED position used, ``problem`` (str or None).
    """
    n = len(run.t)
    nu_m, nud_m, problem = measured_motion(run)
    y = np.array(states[:n], float, copy=True)
    have = np.isfinite(nu_m).all(axis=0) & np.isfinite(nud_m).all(axis=0)
    if run.has_attitude:
        q = run.quaternion
        okq = np.isfinite(q).all(axis=1)
        y[okq, 3:7] = q[okq]
    if run.has_position:
        p = run.position
        for j in range(3):
            ok = np.isfinite(p[:, j])
            y[ok, j] = p[ok, j]
    y[:, 7:13] = np.where(have[None, :], nu_m, y[:, 7:13])
    body = np.full((n, 6), np.nan)
    ned = np.full((n, 6), np.nan)
    if have.any():
        model = Model(vehicle, n=n, input_kind=run.input_kind)
        acc = model.rhs(float(run.t[0]), y, run.inputs)[:, 7:13]
        # the measured acceleration is a Savitzky-Golay (low-pass) estimate; filter the model's
        # acceleration the same way so that input steps do not leave a smoothing artefact
        # (twice: the measured nu_dot went through two filters, position -> nu -> nu_dot)
        for _ in range(2):
            acc = smooth_derivative(run.t, acc, deriv=0, window_s=FORCE_WINDOW_S,
                                    what=f"{run.name}: model acceleration")
        M = model.M if model.M.ndim == 2 else model.M[0]
        res = (np.where(have[None, :], nud_m, acc) - acc) @ M.T
        mask = np.array([have[:3].all()] * 3 + [have[3:].all()] * 3)
        body = np.where(mask[None, :], res, np.nan)
        # the filter's end segments (half a window) extrapolate a polynomial: not used
        half = int(round(0.5 * FORCE_WINDOW_S / float(np.median(np.diff(run.t)))))
        if 0 < half < n // 4:
            body[:half] = np.nan
            body[-half:] = np.nan
        R = quat_to_rotation(y[:, 3:7])
        ned[:, :3] = np.einsum("nij,nj->ni", R, body[:, :3])
        ned[:, 3:] = np.einsum("nij,nj->ni", R, body[:, 3:])
    elif problem is None:
        problem = "the log gives neither full body velocities nor full rates"
    nu_meas = np.where(have[None, :], nu_m, np.nan)
    # the model's (smoothed) acceleration along the measured motion: a noise-free stand-in for
    # nu_dot when regressing the residual on it (the measured nu_dot carries the residual's own noise)
    nud_meas = np.where(have[None, :], acc, np.nan) if have.any() else np.full((n, 6), np.nan)
    return {"t": run.t, "body": body, "ned": ned, "nu": y[:, 7:13], "nu_measured": nu_meas, "nu_dot": nud_meas,
            "measured": have, "pos": y[:, 0:3], "problem": problem}


def simulate(vehicle, runs, effects=None, overrides=None) -> list[dict]:
    """Simulated signals of ``runs`` (see :func:`uvsim.calibration.batching.simulate_dataset`)."""
    return simulate_dataset(vehicle, runs, overrides, effects)


#: Window (s) of the fit that estimates a run's initial position and attitude.
INITIAL_WINDOW_S = 1.0


def refine_initial_states(batch, window_s: float = INITIAL_WINDOW_S):
    """Re-estimate a :class:`uvsim.calibration.batching.RunBatch`'s initial positions and
    attitudes over the first ``window_s`` seconds (:func:`uvsim.simulate.initial_state_from_run`;
    an open-loop simulation inherits the error of its initial state, and a heading error grows
    into a position error along the path: 0.005 rad over 6 m is 30 mm, 15 times a 2 mm
    motion-capture noise).  In place; returns the batch."""
    for i, run in enumerate(batch.runs):
        pos, q0, _, _ = initial_state_from_run(run, window_s=window_s)
        if run.has_position:
            batch.pos0[i] = pos
        if run.has_attitude:
            batch.q0[i] = q0
    return batch
