"""Signature evidence: which shape does the generalized-force residual have?

Each test regresses the pooled inverse-dynamics residual (all runs, samples
where it is observable; :func:`uvsim.diagnosis.residuals.force_residual`) on
the regressors that one kind of missing effect would produce, and reports the
fraction of the residual's sum of squares that they explain (``strength``, an
R^2 between 0 and 1, about 0 when the residual is noise) plus the fitted
numbers that seed a candidate's parameters.

=========================  ==============================================  ===================
signature                  regressors                                      points to
=========================  ==============================================  ===================
constant in NED            a constant per NED force component              current (horizontal),
                           (compared with a constant in the body frame)    ballast (vertical)
growing with distance      displacement from the run's start, beyond a     tether
                           constant (NED force; partial R^2)
lagging the input          ``lowpass(tau_c, T0) - tau_c`` (the force a     thruster_lag
                           first-order lag of ``T0 = 0.2 s`` removes)
sign-dependent on input    ``B min(f_c, 0)`` beyond the symmetric ``B f_c``  thrust_asymmetry
coupling                   DOF j's ``nu_j`` and ``|nu_j| nu_j`` for the     coupled_damping
                           force of DOF i != j (measured velocities only)
=========================  ==============================================  ===================

Apart (:func:`base_coefficient_evidence`): DOF i's own ``nu_i``, ``|nu_i| nu_i``
and acceleration, which wrong base coefficients would explain; it explains a
``none`` answer.

The evidence ranks and seeds the candidates; the decision is made by fitting
each candidate through the simulator (:mod:`uvsim.diagnosis.core`).
"""
from __future__ import annotations

import numpy as np

from uvsim.diagnosis.residuals import commanded_thrusts

DOF_NAMES = ("X", "Y", "Z", "K", "M", "N")
NU_NAMES = ("u", "v", "w", "p", "q", "r")
LAG_T0 = 0.2  # s, nominal time constant of the lag regressor
#: R^2 above which a signature is reported as present (about twice the largest value noise alone
#: gave on clean synthetic tank data, 0.07)
PRESENT = 0.15


def _lowpass(t: np.ndarray, x: np.ndarray, T: float) -> np.ndarray:
    """First-order lag ``T y' = x - y`` (exact for a zero-order-held ``x``), y(0) = x(0)."""
    y = np.empty_like(x)
    y[0] = x[0]
    for i in range(1, len(t)):
        a = np.exp(-(t[i] - t[i - 1]) / T)
        y[i] = a * y[i - 1] + (1 - a) * x[i - 1]
    return y


def _r2(y: np.ndarray, X: np.ndarray) -> tuple[float, np.ndarray]:
    """Explained fraction of ``sum y^2`` by least squares on ``X`` (no intercept) and the coefficients."""
    ok = np.isfinite(y) & np.isfinite(X).all(axis=1)
    y, X = y[ok], X[ok]
    tot = float(y @ y)
    if tot <= 0 or y.size < X.shape[1] + 2:
        return 0.0, np.zeros(X.shape[1])
    beta, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ beta
    return max(0.0, 1.0 - float(r @ r) / tot), beta


def _stack(parts):
    return np.concatenate(parts, axis=0) if parts else np.zeros((0, 6))


def collect(vehicle, runs, force_res) -> dict:
    """Pooled arrays (samples of all runs) used by the signature tests."""
    body, ned, nu, disp, lag, asym, sym, pos, nud = [], [], [], [], [], [], [], [], []
    for run, fr in zip(runs, force_res):
        tau_c, f_c = commanded_thrusts(vehicle, run)
        body.append(fr["body"])
        ned.append(fr["ned"])
        nu.append(fr["nu_measured"])
        nud.append(fr["nu_dot"])
        pos.append(fr["pos"])
        disp.append(fr["pos"] - fr["pos"][0])
        lag.append(_lowpass(run.t, tau_c, LAG_T0) - tau_c)
        if f_c is None:
            asym.append(np.minimum(tau_c, 0.0))
        else:
            asym.append(np.minimum(f_c, 0.0) @ vehicle.actuators.matrix.T)
        sym.append(tau_c)
    return {k: _stack(v) for k, v in dict(body=body, ned=ned, nu=nu, disp=disp, lag=lag, asym=asym, sym=sym,
                                          pos=pos, nud=nud).items()}


def evidence(vehicle, runs, force_res) -> list[dict]:
    """The signature tests (module docstring) on the runs' force residuals.

    Returns a list of dicts ``{signature, strength, present, points_to, detail}``,
    strongest first."""
    d = collect(vehicle, runs, force_res)
    out = []
    body, ned = d["body"], d["ned"]
    forces_ok = np.isfinite(ned[:, :3]).all(axis=1)

    # --- constant in NED (vs body) -------------------------------------------
    if forces_ok.sum() > 10:
        F = ned[forces_ok, :3]
        Fb = body[forces_ok, :3]
        mean_ned = F.mean(axis=0)
        tot = float(np.sum(F * F))
        r2_ned = float(F.shape[0] * mean_ned @ mean_ned / tot) if tot > 0 else 0.0
        mean_b = Fb.mean(axis=0)
        totb = float(np.sum(Fb * Fb))
        r2_body = float(Fb.shape[0] * mean_b @ mean_b / totb) if totb > 0 else 0.0
        horiz = float(np.hypot(mean_ned[0], mean_ned[1]))
        pts = []
        if horiz > 0.5 * abs(mean_ned[2]):
            pts.append("current")
        if abs(mean_ned[2]) > 0.5 * horiz:
            pts.append("ballast")
        out.append({"signature": "constant in NED", "strength": r2_ned,
                    "present": bool(r2_ned > PRESENT and r2_ned >= r2_body),
                    "points_to": pts,
                    "detail": {"mean_force_ned_N": mean_ned.tolist(), "r2_body_constant": r2_body}})

        # --- growing with distance from the start --------------------------------
        X = np.column_stack([np.ones(forces_ok.sum()), d["disp"][forces_ok]])
        G = np.zeros((3, 3))
        a = np.zeros(3)
        rss_c = rss_d = 0.0
        for i in range(3):
            y = F[:, i]
            beta, *_ = np.linalg.lstsq(X, y, rcond=None)
            a[i], G[i] = beta[0], beta[1:]
            rss_d += float(np.sum((y - X @ beta) ** 2))
            rss_c += float(np.sum((y - y.mean()) ** 2))
        # partial R^2: the share of what the constant leaves that the displacement explains
        r2_dist = max(0.0, (rss_c - rss_d) / rss_c) if rss_c > 0 else 0.0
        k_est = float(-np.trace(G) / 3.0)
        out.append({"signature": "growing with distance from the start", "strength": r2_dist,
                    "present": bool(r2_dist > PRESENT and k_est > 0), "points_to": ["tether"],
                    "detail": {"gradient_N_per_m": G.tolist(), "offset_N": a.tolist(), "stiffness_N_per_m": k_est,
                               "mean_start_position_m": d["pos"][forces_ok][0].tolist() if forces_ok.any() else None}})

    ok = np.isfinite(body).any(axis=1)  # rows with forces and/or moments (NaN entries are skipped by _r2)
    if ok.sum() > 10:
        # scale each DOF so forces and moments weigh alike
        B = body[ok]
        fin = np.isfinite(B)
        cnt = fin.sum(axis=0)
        ss = np.where(fin, B * B, 0.0).sum(axis=0)
        s = np.sqrt(np.divide(ss, cnt, out=np.zeros(6), where=cnt > 0))
        s = np.where(s > 0, s, 1.0)
        y = (B / s).ravel()
        # --- lagging the input ----------------------------------------------------
        r2_lag, beta = _r2(y, (d["lag"][ok] / s).ravel()[:, None])
        out.append({"signature": "lagging the input", "strength": r2_lag,
                    "present": bool(r2_lag > PRESENT and beta[0] > 0), "points_to": ["thruster_lag"],
                    "detail": {"coefficient": float(beta[0]),
                               "time_constant_s_estimate": float(LAG_T0 * beta[0]) if beta[0] > 0 else None}})
        # --- sign-dependent on the input -------------------------------------------
        Xs = np.column_stack([(d["sym"][ok] / s).ravel(), (d["asym"][ok] / s).ravel()])
        r2_both, beta2 = _r2(y, Xs)
        r2_sym, _ = _r2(y, Xs[:, :1])
        gain = r2_both - r2_sym
        out.append({"signature": "sign-dependent on the input", "strength": float(max(gain, 0.0)),
                    "present": bool(gain > PRESENT), "points_to": ["thrust_asymmetry"],
                    "detail": {"reverse_ratio_estimate": float(1.0 + beta2[1] / max(1e-9, 1.0 + beta2[0])),
                               "symmetric_gain_error": float(beta2[0]), "r2_symmetric_only": r2_sym}})
    # --- coupling one DOF's velocity to another DOF's force --------------------
    pairs = coupling_pairs(d)
    if pairs:
        best = pairs[0]
        out.append({"signature": "coupling one DOF's velocity to another DOF's force", "strength": best["r2"],
                    "present": bool(best["r2"] > PRESENT), "points_to": ["coupled_damping"],
                    "detail": {"pairs": pairs[:4]}})
    out.sort(key=lambda e: -e["strength"])
    return out


def base_coefficient_evidence(vehicle, runs, force_res) -> dict | None:
    """The residual's regression on each DOF's own velocity and acceleration
    (:func:`own_dof`): what wrong base coefficients (diagonal damping, added mass,
    inertia) leave.  Kept apart from :func:`evidence` because most missing effects
    also correlate with the DOF's own motion (a thruster lag looks like extra
    inertia); it is used to explain a ``none`` answer."""
    own = own_dof(collect(vehicle, runs, force_res))
    if not own:
        return None
    best = max(own, key=lambda o: o["r2"])
    return {"signature": "own-DOF velocity and acceleration (base coefficients)", "strength": best["r2"],
            "present": bool(best["r2"] > PRESENT), "points_to": ["calibration (re-tune the base coefficients)"],
            "detail": {"per_dof": own}}


def own_dof(d: dict) -> list[dict]:
    """Per DOF i, the R^2 of ``tau_res,i`` on its own ``nu_i``, ``|nu_i| nu_i`` and
    ``nu_dot_i``: what wrong diagonal damping or added mass (the base coefficients,
    not an extra effect) leaves.  Only measured velocities are used."""
    body, nu, nud = d["body"], d["nu"], d["nud"]
    out = []
    for i in range(6):
        ok = np.isfinite(body[:, i]) & np.isfinite(nu[:, i]) & np.isfinite(nud[:, i])
        if ok.sum() < 10:
            continue
        x = nu[ok, i]
        r2, beta = _r2(body[ok, i], np.column_stack([x, np.abs(x) * x, nud[ok, i]]))
        out.append({"dof": DOF_NAMES[i], "r2": float(r2), "d_linear": float(beta[0]), "d_quadratic": float(beta[1]),
                    "d_inertia": float(beta[2])})
    return out


def coupling_pairs(d: dict) -> list[dict]:
    """For each force DOF i and velocity DOF j != i, the fraction of ``tau_res,i``'s
    sum of squares that ``nu_j`` (linear) or ``|nu_j| nu_j`` (quadratic), whichever
    explains more, adds to a constant and DOF i's own regressors (``nu_i``,
    ``|nu_i| nu_i``, ``nu_dot_i`` where measured: a constant force or a wrong
    diagonal coefficient is not a coupling),
    with its coefficient (a first estimate of the derivative); sorted by that R^2.
    Only measured velocities are used."""
    body, nu, nud = d["body"], d["nu"], d["nud"]
    out = []
    for i in range(6):
        for j in range(6):
            if j == i:
                continue
            ok = np.isfinite(body[:, i]) & np.isfinite(nu[:, j])  # measured velocities only
            if ok.sum() < 10:
                continue
            y = body[ok, i]
            x = nu[ok, j]
            if np.sqrt(np.mean(x * x)) < 1e-6:
                continue
            own_ok = np.isfinite(nu[ok, i]) & np.isfinite(nud[ok, i])
            one = np.ones((ok.sum(), 1))  # a constant (ballast, current) is not a coupling either
            if own_ok.all():
                xi = nu[ok, i]
                own = np.column_stack([one, xi, np.abs(xi) * xi, nud[ok, i]])
            else:
                own = one
            r2_own = _r2(y, own)[0]
            best = None
            for quad in (False, True):
                reg = (np.abs(x) * x if quad else x)[:, None]
                r2, beta = _r2(y, np.column_stack([reg, own]))
                if best is None or r2 > best[0]:
                    best = (r2, beta[0], quad)
            r2, beta, quad = best
            name = f"{DOF_NAMES[i]}_{NU_NAMES[j]}{NU_NAMES[j] if quad else ''}"
            out.append({"name": name, "force": i, "velocity": j, "quadratic": quad,
                        "r2": float(max(r2 - r2_own, 0.0)), "coefficient": float(beta)})
    out.sort(key=lambda p: -p["r2"])
    return out
