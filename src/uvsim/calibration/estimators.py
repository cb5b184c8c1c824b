"""Seed 002's identification methods (Chin, Lin & Lin 2018, sec. 5).

Heave (sec. 5.1, eq. 20-27)
    ``(m + Z_wdot) w_dot = Z + Z_w w [+ Z_ww |w| w] [+ Z_0]`` (our paper sign:
    ``Z_w``, ``Z_ww`` negative; ``Z_0`` is an optional constant net weight minus
    buoyancy).  Rearranged as the linear regression ``w_dot = H theta`` with
    ``H = [Z, -w, (-|w| w), (1)]`` and ``theta = [alpha, beta, (gamma), (delta)]``,
    ``alpha = 1 / (m + Z_wdot)``, ``beta = -Z_w alpha`` (eq. 21-22 as printed,
    with Z_w in the paper sign).  Solved by batch least squares (eq. 23,
    Moore-Penrose, with ``cov = sigma^2 (H^T H)^-1``) or by recursive least
    squares with forgetting factor ``lambda`` (eq. 24-27).

Yaw (sec. 5.2, eq. 28-33)
    ``(I_zz + N_rdot) r_dot = N + N_r r + N_rr |r| r`` (paper sign, negative).
    Steady-state runs (``r_dot = 0``) give ``N = -N_r r - N_rr |r| r``, a
    least-squares fit of the steady moment against the steady rate (eq. 30,
    Fig. 20).  The total yaw inertia then follows from a sinusoidal test
    (eq. 31-32): seed 002 divides the extra moment at peak acceleration by the
    peak acceleration (``peak`` estimate); :func:`yaw_inertia_sinusoid` also gives
    the least-squares estimate over the whole record.  Note: seed 002 calls this
    total ``N_rdot`` ("the added inertia = I_r + N_rdot"); we report both the
    total and ``N_rdot = total - I_zz``.

Where ``w``/``r`` or their derivatives are not logged they come from
:mod:`uvsim.estimation.derivatives` (Savitzky-Golay differentiation).
"""
from __future__ import annotations

import functools

import numpy as np

from uvsim.estimation.derivatives import body_acceleration, body_velocity, smooth_derivative
from uvsim.errors import CalibrationError
from uvsim.vehicle import load_vehicle


def generalized_forces(vehicle, run) -> np.ndarray:
    """Generalized force (n, 6) from a run's inputs: the X..N columns, or the
    vehicle's allocation matrix times per-thruster thrust (PWM mapped by the curves)."""
    veh = load_vehicle(vehicle)
    if run.input_kind == "force":
        return run.inputs
    act = veh.actuators
    act.check_inputs(run.input_kind, run.inputs.shape[1], f"{run.name}: inputs")
    f = act.thrusts(run.inputs, run.input_kind, act.prepare({}, 1)["groups"])
    return f @ act.matrix.T


def least_squares_fit(H: np.ndarray, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Batch least squares (seed 002 eq. 23): ``theta = (H^T H)^-1 H^T phi``.

    Returns (theta (p,), cov (p, p) = sigma^2 (H^T H)^-1, sigma^2).  Rows with NaN
    are skipped; raises :class:`CalibrationError` if H is rank deficient."""
    H = np.asarray(H, float)
    phi = np.asarray(phi, float)
    ok = np.isfinite(H).all(axis=1) & np.isfinite(phi)
    H, phi = H[ok], phi[ok]
    if H.shape[0] <= H.shape[1] or np.linalg.matrix_rank(H) < H.shape[1]:
        raise CalibrationError(f"least squares: regressor matrix ({H.shape[0]} x {H.shape[1]}) is not full rank; "
                               "the runs do not excite every term (seed 002 eq. 23 needs full-rank H)")
    theta, *_ = np.linalg.lstsq(H, phi, rcond=None)
    r = phi - H @ theta
    s2 = float(r @ r) / (H.shape[0] - H.shape[1])
    cov = s2 * np.linalg.inv(H.T @ H)
    return theta, cov, s2


def recursive_least_squares(H: np.ndarray, phi: np.ndarray, *, forgetting: float = 0.995,
                            theta0=None, P0: float = 100.0) -> np.ndarray:
    """Recursive least squares with forgetting factor (seed 002 eq. 24-27).

    ``theta(t) = theta(t-1) + K(t) eps(t)``, ``eps = phi(t) - theta(t-1)^T H(t)``,
    ``K = P H / (lambda + H^T P H)``, ``P = (P - K H^T P) / lambda``.  Seed 002
    starts from ``theta = 0``, ``P = 100 I`` (the defaults here).  ``forgetting``
    is lambda in (0, 1]; 1 is infinite memory.  (Seed 002 quotes 0.001, which in
    this form forgets everything at each step; 0.98-1 is the usual range.)
    Rows with NaN are skipped (the estimate is carried over).

    Returns
    -------
    (n, p) parameter history.
    """
    H = np.asarray(H, float)
    phi = np.asarray(phi, float)
    lam = float(forgetting)
    if not 0 < lam <= 1:
        raise CalibrationError(f"forgetting factor must be in (0, 1], got {forgetting}")
    n, p = H.shape
    theta = np.zeros(p) if theta0 is None else np.asarray(theta0, float).copy()
    P = P0 * np.eye(p)
    out = np.empty((n, p))
    for i in range(n):
        h = H[i]
        if np.isfinite(h).all() and np.isfinite(phi[i]):
            Ph = P @ h
            K = Ph / (lam + h @ Ph)
            eps = phi[i] - theta @ h
            theta = theta + K * eps
            P = (P - np.outer(K, Ph)) / lam
        out[i] = theta
    return out


def heave_regression(vehicle, runs, *, quadratic: bool = True, bias: bool = True, window_s: float = 0.5):
    """Regressors (H, phi) of the heave model over ``runs`` (module doc).

    ``w`` from the logged DVL velocity or else from the differentiated depth;
    ``w_dot`` from differentiating ``w`` (Savitzky-Golay, ``window_s``)."""
    Hs, phis = [], []
    for run in runs:
        nu = body_velocity(run, window_s=window_s)
        if not np.isfinite(nu[:, 2]).any():
            raise CalibrationError(f"{run.name}: no heave velocity w logged and no depth z to differentiate")
        acc = body_acceleration(run, nu, window_s=window_s)
        w, wd = nu[:, 2], acc[:, 2]
        Z = generalized_forces(vehicle, run)[:, 2]
        # w_dot is a Savitzky-Golay derivative, i.e. a smoothed quantity: smooth the
        # regressors with the same filter so both sides of eq. 20 see the same smoothing
        # (otherwise the force steps, sharp in Z but blurred in w_dot, bias alpha)
        sm = functools.partial(smooth_derivative, run.t, deriv=0, window_s=window_s, what=f"{run.name}: regressor")
        cols = [sm(Z), -sm(w)]
        if quadratic:
            cols.append(-sm(np.abs(w) * w))
        if bias:
            cols.append(np.ones_like(w))
        Hs.append(np.stack(cols, -1))
        phis.append(wd)
    return np.vstack(Hs), np.concatenate(phis)


def _heave_params(theta, cov, m, quadratic, bias):
    alpha, beta = theta[0], theta[1]
    J = [[-1 / alpha ** 2] + [0.0] * (len(theta) - 1)]  # d(Z_wdot)/d theta
    vals = {"Z_wdot": 1 / alpha - m, "Z_w": -beta / alpha}
    J.append([beta / alpha ** 2, -1 / alpha] + [0.0] * (len(theta) - 2))
    k = 2
    if quadratic:
        g = theta[k]
        vals["Z_ww"] = -g / alpha
        row = [0.0] * len(theta)
        row[0], row[k] = g / alpha ** 2, -1 / alpha
        J.append(row)
        k += 1
    if bias:
        d = theta[k]
        vals["Z_0"] = d / alpha
        row = [0.0] * len(theta)
        row[0], row[k] = -d / alpha ** 2, 1 / alpha
        J.append(row)
    J = np.array(J)
    C = J @ cov @ J.T
    sig = dict(zip(vals, np.sqrt(np.maximum(np.diag(C), 0.0)).tolist()))
    return {k: float(v) for k, v in vals.items()}, sig


def heave_least_squares(vehicle, runs, *, quadratic: bool = True, bias: bool = True, window_s: float = 0.5) -> dict:
    """Batch least-squares heave identification (seed 002 eq. 20-23).

    Returns {"parameters": {Z_wdot, Z_w, [Z_ww], [Z_0]}, "uncertainty": {...},
    "theta": [...], "sigma2": float}; values in our convention (added mass
    positive, damping paper sign)."""
    veh = load_vehicle(vehicle)
    H, phi = heave_regression(veh, runs, quadratic=quadratic, bias=bias, window_s=window_s)
    theta, cov, s2 = least_squares_fit(H, phi)
    vals, sig = _heave_params(theta, cov, veh.mass, quadratic, bias)
    return {"parameters": vals, "uncertainty": sig, "theta": theta.tolist(), "sigma2": s2}


def heave_recursive(vehicle, runs, *, forgetting: float = 0.995, quadratic: bool = True, bias: bool = True,
                    window_s: float = 0.5) -> dict:
    """RLS heave identification (seed 002 eq. 24-27): the parameter history and
    the final estimate (in our convention)."""
    veh = load_vehicle(vehicle)
    H, phi = heave_regression(veh, runs, quadratic=quadratic, bias=bias, window_s=window_s)
    hist = recursive_least_squares(H, phi, forgetting=forgetting)
    theta = hist[-1]
    vals, _ = _heave_params(theta, np.zeros((len(theta), len(theta))), veh.mass, quadratic, bias)
    return {"parameters": vals, "theta_history": hist, "theta": theta.tolist()}


def steady_state_points(vehicle, runs, *, dof_index: int = 5, window_s: float = 1.5, window_smooth: float = 0.5):
    """(rate, moment) at steady state, one point per run.

    The plateau is the longest stretch where the generalized force of
    ``dof_index`` is constant and non-zero; the steady state is the mean over its
    last ``window_s`` seconds.  The rate is the logged body rate (or the
    differentiated attitude)."""
    veh = load_vehicle(vehicle)
    pts = []
    for run in runs:
        tau = generalized_forces(veh, run)[:, dof_index]
        nu = body_velocity(run, window_s=window_smooth)[:, dof_index]
        const = np.r_[False, np.isclose(np.diff(tau), 0.0, atol=1e-9 * (1 + np.abs(tau).max()))] & (np.abs(tau) > 0)
        best, start = (0, 0), None
        for i, c in enumerate(np.r_[const, False]):
            if c and start is None:
                start = i - 1
            elif not c and start is not None:
                if i - start > best[1] - best[0]:
                    best = (start, i)
                start = None
        a, b = best
        if b - a < 3:
            raise CalibrationError(f"{run.name}: no constant non-zero input plateau for a steady-state point")
        t = run.t
        sel = np.arange(a, b)
        sel = sel[t[sel] >= t[b - 1] - window_s]
        pts.append((float(np.nanmean(nu[sel])), float(np.mean(tau[sel]))))
    return np.array(pts)


def yaw_steady_state_fit(rates: np.ndarray, moments: np.ndarray) -> dict:
    """Fit ``N = -N_r r - N_rr |r| r`` (seed 002 eq. 30, Fig. 20) to steady points.

    Returns {"parameters": {"N_r", "N_rr"} (paper sign, negative),
    "uncertainty": {...}, "seed002_form": {"N_r", "N_|r|r"} (seed 002's positive
    resistance coefficients)}."""
    r = np.asarray(rates, float)
    N = np.asarray(moments, float)
    theta, cov, _ = least_squares_fit(np.stack([-r, -np.abs(r) * r], -1), N)
    sig = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return {"parameters": {"N_r": float(theta[0]), "N_rr": float(theta[1])},
            "uncertainty": {"N_r": float(sig[0]), "N_rr": float(sig[1])},
            "seed002_form": {"N_r": float(-theta[0]), "N_|r|r": float(-theta[1])}}


def yaw_inertia_sinusoid(vehicle, run, N_r: float, N_rr: float, *, window_s: float = 0.5, I_zz: float | None = None,
                         peak_fraction: float = 0.95) -> dict:
    """Total yaw inertia ``J = I_zz + N_rdot`` from a sinusoidal-input run (seed 002 eq. 31-32).

    ``delta N = N - (-N_r r - N_rr |r| r)`` is the moment that accelerates the
    vehicle; ``J`` is its least-squares ratio to ``r_dot`` over the record
    (``"least_squares"``) and, as in seed 002, the ratio at the samples of peak
    acceleration (``"peak"``: mean over samples with ``|r_dot|`` above
    ``peak_fraction`` of its maximum).  ``r_dot`` is Savitzky-Golay
    differentiated.  ``N_rdot = J - I_zz`` (vehicle's I_zz unless given)."""
    veh = load_vehicle(vehicle)
    nu = body_velocity(run, window_s=window_s)
    r = nu[:, 5]
    rd = smooth_derivative(run.t, r, window_s=window_s, what=f"{run.name}: r")
    N = generalized_forces(veh, run)[:, 5]
    dN = N + N_r * r + N_rr * np.abs(r) * r
    dN = smooth_derivative(run.t, dN, deriv=0, window_s=window_s, what=f"{run.name}: moment")  # same filter as r_dot
    ok = np.isfinite(rd) & np.isfinite(dN)
    J_ls = float(np.sum(rd[ok] * dN[ok]) / np.sum(rd[ok] ** 2))
    pk = ok & (np.abs(rd) >= peak_fraction * np.nanmax(np.abs(rd)))
    J_pk = float(np.mean(dN[pk] / rd[pk]))
    Izz = veh.inertia["I_zz"] if I_zz is None else float(I_zz)
    return {"total_inertia": {"least_squares": J_ls, "peak": J_pk},
            "N_rdot": {"least_squares": J_ls - Izz, "peak": J_pk - Izz}, "I_zz": Izz}
