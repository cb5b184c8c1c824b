"""Local refinement after the GA, uncertainty and identifiability.

:func:`refine_dof` minimizes the sum of squared normalized residuals
(:func:`uvsim.metrics.normalized_residuals`, each run weighted by its fitness
weight) of one DOF's training runs with :func:`scipy.optimize.least_squares`
(trust-region reflective, within the GA bounds), starting from the GA's best
individual.  The Jacobian is a forward-difference Jacobian computed in one
batched simulation (base point + one perturbed copy per parameter, times every
run).

Uncertainty: the Gauss-Newton covariance ``cov = s^2 (J^T J)^+`` at the solution
with ``s^2 = sum r^2 / (m - p)`` (m residuals, p parameters), the usual
nonlinear-least-squares estimate, inflated by ``(1 + rho) / (1 - rho)`` where rho
is the lag-1 autocorrelation of the residuals (:func:`ar1_inflation`): the plain
formula assumes independent residuals, which trajectory residuals are not.

Identifiability: the singular values of the column-scaled Jacobian of *all* of
the DOF's parameters.  A direction whose relative singular value is below
``NULL_TOL`` changes no residual: the data cannot separate the parameters along
it.  In decoupled single-DOF runs the rigid-body inertia and the added inertia
(e.g. ``I_xx`` and ``K_pdot``) only enter as their sum, so only ``I_xx + K_pdot``
is identifiable.  When such a pair is found (``merge_inertia="auto"``) the
refinement fits the sum and keeps the GA's split between the two; their
individual uncertainties are then reported as ``None`` and the sum's as the
effective-inertia uncertainty.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np
from scipy.optimize import least_squares

from uvsim.calibration.batching import RunBatch, simulate_rows
from uvsim.calibration.params import EFFECTIVE_INERTIA
from uvsim.errors import CalibrationError
from uvsim.metrics import normalized_residuals, signals_from_states

#: Relative singular value below which a parameter direction counts as not identifiable.
NULL_TOL = 1e-3
#: |correlation| above which two parameters are reported as strongly correlated.
CORR_REPORT = 0.9
#: Initial-velocity axis of each DOF (index into nu).
DOF_AXIS = {"surge": 0, "sway": 1, "heave": 2, "roll": 3, "pitch": 4, "yaw": 5}
NU0_SCALE = 0.1  # m/s or rad/s, scale of the initial-velocity unknowns
FD_STEP = 1e-6   # forward-difference step in scaled parameters


class _Residuals:
    """Batched residual vectors of a set of runs for parameter vectors x (B, n_x).

    ``problem`` supplies run_index, run_weights, scales, signal_weights and dof
    (a :class:`DofProblem` or any object with those attributes)."""

    def __init__(self, vehicle, batch: RunBatch, problem, columns, base: Mapping[str, float]):
        self.vehicle, self.batch, self.problem = vehicle, batch, problem
        self.columns = columns  # list of (kind, payload, scale): kind "param" | "sum" | "nu0"
        self.base = dict(base)

    def values(self, x: np.ndarray) -> tuple[dict, dict]:
        """Physical parameter values and initial-velocity overrides for one x (n_x,)."""
        vals, nu0 = {}, {}
        for xi, (kind, payload, scale) in zip(x, self.columns):
            v = xi * scale
            if kind == "param":
                vals[payload] = v
            elif kind == "sum":
                (a, b), rho = payload
                vals[a], vals[b] = rho * v, (1 - rho) * v
            else:
                nu0[payload] = v
        return vals, nu0

    def __call__(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(X)
        prob, batch = self.problem, self.batch
        R = len(prob.run_index)
        rows = np.tile(prob.run_index, len(X))
        ov = {k: np.empty(len(rows)) for k in self.base}
        nu0 = batch.nu0[rows].copy()
        for b, x in enumerate(X):
            vals, nu = self.values(x)
            sl = slice(b * R, (b + 1) * R)
            for k in self.base:
                ov[k][sl] = vals.get(k, self.base[k])
            for r, v in nu.items():
                nu0[b * R + r, DOF_AXIS[prob.dof]] = v
        y = simulate_rows(self.vehicle, batch, rows, ov, nu0=nu0)
        out = []
        for b in range(len(X)):
            parts = []
            for j, r in enumerate(prob.run_index):
                n = batch.lengths[r]
                pred = signals_from_states(y[b * R + j, :n])
                parts.append(normalized_residuals(batch.measured[r], pred, prob.scales, prob.signal_weights,
                                                  run_weight=float(prob.run_weights[j]), fill=1e3))
            out.append(np.concatenate(parts))
        return np.array(out)


def ar1_inflation(r: np.ndarray) -> tuple[float, float]:
    """(lag-1 autocorrelation rho of the residual vector, variance inflation (1 + rho) / (1 - rho)).

    Gauss-Newton uncertainties assume independent residuals.  Tank-run residuals are
    strongly autocorrelated (an initial-state error or a slightly wrong parameter
    shifts a whole trajectory), which makes the plain formula optimistic by orders
    of magnitude; inflating the covariance by the AR(1) factor (effective sample
    size n (1 - rho) / (1 + rho)) is the usual first-order correction."""
    r = np.asarray(r, float)
    if r.size < 3 or not np.any(r):
        return 0.0, 1.0
    rho = float(np.dot(r[:-1], r[1:]) / np.dot(r, r))
    rho = min(max(rho, 0.0), 0.999)
    return rho, (1 + rho) / (1 - rho)


def _jacobian(F: _Residuals, x: np.ndarray, step: float = FD_STEP) -> tuple[np.ndarray, np.ndarray]:
    h = step * np.maximum(1.0, np.abs(x))
    X = np.vstack([x, x + np.diag(h)])
    Y = F(X)
    return Y[0], ((Y[1:] - Y[0]) / h[:, None]).T


def identifiability(vehicle, batch: RunBatch, problem, values: Mapping[str, float]) -> dict:
    """Identifiability of all of ``problem``'s parameters at ``values``.

    Returns
    -------
    dict with ``parameters``, ``relative_singular_values``, ``condition_number``,
    ``correlations`` (pairs with |r| > CORR_REPORT), ``not_identifiable`` (list of
    {"direction": {name: coefficient}, "relative_singular_value"}) and
    ``identifiable_combinations`` (human-readable list, e.g. ``"I_xx + K_pdot"``).
    """
    names = list(problem.names)
    scale = np.array([abs(values[k]) or 1.0 for k in names])
    cols = [("param", k, s) for k, s in zip(names, scale)]
    F = _Residuals(vehicle, batch, problem, cols, {k: values[k] for k in names})
    x = np.array([values[k] for k in names]) / scale
    _, J = _jacobian(F, x)
    Jn = J / np.maximum(np.linalg.norm(J, axis=0), 1e-300)
    _, s, Vt = np.linalg.svd(Jn, full_matrices=False)
    srel = s / s[0] if s[0] > 0 else s
    cov = np.linalg.pinv(J.T @ J)
    d = np.sqrt(np.maximum(np.diag(cov), 1e-300))
    corr = cov / np.outer(d, d)
    corr_pairs = {}
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            if abs(corr[i, j]) > CORR_REPORT:
                corr_pairs[f"{names[i]}~{names[j]}"] = float(corr[i, j])
    null, comb, involved_all = [], [], set()
    colnorm = np.linalg.norm(J, axis=0)
    for k in np.flatnonzero(srel < NULL_TOL):
        v = Vt[k] / np.maximum(colnorm, 1e-300)  # back to x (scaled) units
        v = v * scale  # physical units
        v = v / np.max(np.abs(v))
        if v[np.argmax(np.abs(v))] < 0:
            v = -v
        direction = {names[i]: float(round(v[i], 4)) for i in range(len(names)) if abs(v[i]) > 0.05}
        null.append({"direction": direction, "relative_singular_value": float(srel[k])})
        inv = [i for i in range(len(names)) if abs(v[i]) > 0.05]
        involved_all.update(inv)
        if len(inv) == 2:
            a, b = v[inv[1]], -v[inv[0]]
            m = max(abs(a), abs(b))
            a, b = a / m, b / m
            if a < 0:
                a, b = -a, -b
            ta = names[inv[0]] if abs(a - 1) < 1e-3 else f"{a:.3g}*{names[inv[0]]}"
            tb = names[inv[1]] if abs(abs(b) - 1) < 1e-3 else f"{abs(b):.3g}*{names[inv[1]]}"
            comb.append(f"{ta} {'+' if b >= 0 else '-'} {tb}")
        else:
            comb.append("combinations orthogonal to " + " ".join(f"{c:+.3g}*{n}" for n, c in direction.items()))
    comb += [names[i] for i in range(len(names)) if i not in involved_all]
    return {
        "parameters": names,
        "relative_singular_values": [float(v) for v in srel],
        "condition_number": float(srel[0] / srel[-1]) if srel[-1] > 0 else float("inf"),
        "correlations": corr_pairs,
        "not_identifiable": null,
        "identifiable_combinations": comb,
    }


def _add_columns(names, pair, init, start, lower, upper, cols, x0, lb, ub) -> None:
    """Append the scaled least-squares columns of parameters ``names`` (each scaled by
    its initial magnitude) to ``cols, x0, lb, ub``; the two parameters of ``pair`` (an
    unidentifiable inertia + added-inertia pair, or None) become one column for their
    sum, keeping their split ratio at the start value."""
    for k in names:
        if pair and k in pair:
            continue
        s = abs(init[k]) or 1.0
        cols.append(("param", k, s))
        x0.append(start[k] / s)
        lb.append(lower[k] / s)
        ub.append(upper[k] / s)
    if pair:
        a, b = pair
        S = start[a] + start[b]
        s = abs(init[a] + init[b])
        cols.append(("sum", ((a, b), start[a] / S), s))
        x0.append(S / s)
        lb.append((lower[a] + lower[b]) / s)
        ub.append((upper[a] + upper[b]) / s)


def refine_dof(vehicle, batch: RunBatch, problem, start: Mapping[str, float], *, merge_inertia: str = "auto",
               estimate_initial_velocity: bool = False, max_nfev: int = 40, ident: dict | None = None) -> dict:
    """Least-squares refinement of one DOF from ``start`` values (module doc).

    Parameters
    ----------
    merge_inertia : "auto" (fit the inertia + added-inertia sum when the data cannot
        separate them), "always" or "never".
    estimate_initial_velocity : also fit the unknown (not logged) initial velocity of
        the DOF's own axis in each run.
    ident : output of :func:`identifiability` at ``start`` (computed if None).

    Returns
    -------
    dict with ``values`` (name -> fitted value), ``uncertainty`` (name -> 1-sigma or
    None), ``merged`` (the summed pair or None), ``effective_inertia_sigma``,
    ``initial_velocity`` (run name -> fitted value), ``cost``, ``nfev``, ``message``.
    """
    if merge_inertia not in ("auto", "always", "never"):
        raise CalibrationError(f"merge_inertia {merge_inertia!r}: expected auto, always or never")
    names = list(problem.names)
    lower = dict(zip(names, problem.lower))
    upper = dict(zip(names, problem.upper))
    pair = EFFECTIVE_INERTIA.get(problem.dof)
    merged = None
    if pair and all(p in names for p in pair) and merge_inertia != "never":
        if merge_inertia == "always":
            merged = pair
        else:
            ident = ident if ident is not None else identifiability(vehicle, batch, problem, start)
            for nd in ident["not_identifiable"]:
                if set(nd["direction"]) == set(pair):
                    merged = pair
    init = dict(zip(names, problem.initial))
    cols, x0, lb, ub = [], [], [], []
    _add_columns(names, merged, init, start, lower, upper, cols, x0, lb, ub)
    nu_runs = []
    if estimate_initial_velocity:
        ax = DOF_AXIS[problem.dof]
        for j, r in enumerate(problem.run_index):
            if not batch.nu0_known[r, ax]:
                cols.append(("nu0", j, NU0_SCALE))
                x0.append(batch.nu0[r, ax] / NU0_SCALE)
                lb.append(-10.0)
                ub.append(10.0)
                nu_runs.append(j)
    x0 = np.clip(np.array(x0, float), lb, ub)
    F = _Residuals(vehicle, batch, problem, cols, {k: start[k] for k in names})

    def fun(x):
        return F(x[None])[0]

    def jac(x):
        return _jacobian(F, x)[1]

    res = least_squares(fun, x0, jac=jac, bounds=(np.array(lb), np.array(ub)), method="trf",
                        max_nfev=max_nfev, x_scale=1.0)
    vals, nu = F.values(res.x)
    values = {k: start[k] for k in names}
    values.update(vals)
    m, p = res.fun.size, res.x.size
    s2 = float(res.fun @ res.fun) / max(m - p, 1)
    J = _jacobian(F, res.x)[1]
    rho, infl = ar1_inflation(res.fun)
    cov = infl * s2 * np.linalg.pinv(J.T @ J)
    scales = np.array([c[2] for c in cols])
    sig = np.sqrt(np.maximum(np.diag(cov), 0.0)) * scales
    unc: dict = {}
    eff_sigma = None
    nu_fit = {}
    for (kind, payload, _), sg in zip(cols, sig):
        if kind == "param":
            unc[payload] = float(sg)
        elif kind == "sum":
            unc[payload[0][0]] = unc[payload[0][1]] = None
            eff_sigma = float(sg)
        else:
            nu_fit[batch.runs[problem.run_index[payload]].name] = float(nu[payload])
    if eff_sigma is None and pair and all(p in names for p in pair):
        ia, ib = [next(i for i, c in enumerate(cols) if c[1] == p) for p in pair]
        eff_sigma = float(np.sqrt(max(cov[ia, ia] * scales[ia] ** 2 + cov[ib, ib] * scales[ib] ** 2
                                      + 2 * cov[ia, ib] * scales[ia] * scales[ib], 0.0)))
    elif eff_sigma is None and pair and pair[1] in names:
        eff_sigma = unc.get(pair[1])  # m is fixed: sigma(m + X_udot) = sigma(X_udot)
    return {"values": {k: float(v) for k, v in values.items()}, "uncertainty": unc,
            "merged": list(merged) if merged else None, "effective_inertia_sigma": eff_sigma,
            "initial_velocity": nu_fit, "cost": float(res.cost), "nfev": int(res.nfev),
            "residual_autocorrelation": rho, "variance_inflation": infl,
            "message": str(res.message), "residual_rms": float(np.sqrt(np.mean(res.fun ** 2)))}


class _Joint:
    """Problem-like view of all training runs for the joint refinement."""

    def __init__(self, problems: dict, scales: dict, weights: dict | None):
        self.dof = None
        idx, w = [], []
        for p in problems.values():
            idx += list(p.run_index)
            w += list(p.run_weights)
        self.run_index = np.array(idx, int)
        self.run_weights = np.array(w, float)
        self.scales = scales
        self.signal_weights = weights


def joint_residuals(vehicle, batch, problems, columns, base, scales, weights, X) -> np.ndarray:
    """Residual vectors (B, m) of all training runs for scaled parameter vectors X (B, n_x)."""
    F = _Residuals(vehicle, batch, _Joint(problems, dict(scales), dict(weights or {})), columns, base)
    return F(X)


def refine_joint(vehicle, batch: RunBatch, problems: dict, start: Mapping[str, float], merged: Mapping,
                 scales: Mapping[str, float], *, weights: Mapping[str, float] | None = None,
                 max_nfev: int = 30, evaluate=None) -> dict:
    """Least squares over every DOF's parameters at once on all training runs.

    The tank runs are not fully decoupled (a positively buoyant vehicle rises
    during every run; sway runs excite yaw through the Munk moment), so a final
    joint fit on all logged channels (``weights``, default all 1; ``scales`` one
    per group over all runs) removes the bias the per-DOF fits leave.  Pairs in
    ``merged`` (dof -> (inertia, added inertia) or None) are fitted as sums.
    ``evaluate(columns, base, X) -> (B, m)`` may spread the batched residual
    evaluations (the Jacobian's perturbed copies) over worker processes; default:
    :func:`joint_residuals` in this process.  Returns the same keys as
    :func:`refine_dof` (per parameter)."""
    init = {}
    for p in problems.values():
        init.update(dict(zip(p.names, p.initial)))
    lower, upper = {}, {}
    for p in problems.values():
        lower.update(dict(zip(p.names, p.lower)))
        upper.update(dict(zip(p.names, p.upper)))
    cols, x0, lb, ub = [], [], [], []
    for d, p in problems.items():
        _add_columns(p.names, merged.get(d), init, start, lower, upper, cols, x0, lb, ub)
    x0 = np.clip(np.array(x0, float), lb, ub)
    base = {k: start[k] for k in init}
    F = _Residuals(vehicle, batch, _Joint(problems, dict(scales), dict(weights or {})), cols, base)
    if evaluate is not None:
        def Fx(X):
            return evaluate(cols, base, X)
    else:
        Fx = F
    res = least_squares(lambda x: F(x[None])[0], x0, jac=lambda x: _jacobian(Fx, x)[1],
                        bounds=(np.array(lb), np.array(ub)), method="trf", max_nfev=max_nfev)
    vals, _ = F.values(res.x)
    values = {k: float(start[k]) for k in init}
    values.update({k: float(v) for k, v in vals.items()})
    m, p_ = res.fun.size, res.x.size
    s2 = float(res.fun @ res.fun) / max(m - p_, 1)
    J = res.jac
    rho, infl = ar1_inflation(res.fun)
    cov = infl * s2 * np.linalg.pinv(J.T @ J)
    sc = np.array([c[2] for c in cols])
    sig = np.sqrt(np.maximum(np.diag(cov), 0.0)) * sc
    unc, eff = {}, {}
    for (kind, payload, _), sg in zip(cols, sig):
        if kind == "param":
            unc[payload] = float(sg)
        else:
            unc[payload[0][0]] = unc[payload[0][1]] = None
            dof = next(d for d, pr in merged.items() if pr and tuple(pr) == tuple(payload[0]))
            eff[dof] = float(sg)
    for d, p in problems.items():
        if d not in eff:
            pair = EFFECTIVE_INERTIA[d]
            eff[d] = unc.get(pair[1]) if pair[0] not in p.names else None
    return {"values": values, "uncertainty": unc, "effective_inertia_sigma": eff, "cost": float(res.cost),
            "nfev": int(res.nfev), "message": str(res.message), "residual_autocorrelation": rho,
            "variance_inflation": infl,
            "residual_rms": float(np.sqrt(np.mean(res.fun ** 2)))}
