"""Fitting one candidate through the simulator, and scoring it.

Fit: :func:`scipy.optimize.least_squares` (trust-region reflective, within the
candidate's bounds) on the training runs' normalized output residuals
(:func:`uvsim.metrics.normalized_residuals`: every logged signal group divided by
its estimated noise level, so the residual is about N(0, 1) when the model is
right).  Fit variables are divided by their scale.  The Jacobian is a forward
difference computed in one batched simulation (one copy of every run per
perturbed variable, :func:`uvsim.calibration.batching.simulate_rows`).

Uncertainty: ``cov = s^2 (J^T J)^+ (1 + rho) / (1 - rho)``, the Gauss-Newton
covariance inflated for the lag-1 autocorrelation ``rho`` of the residuals
(simulation errors are correlated in time, so the independent-sample formula
would be far too optimistic), mapped to the effect's parameters with a
finite-difference Jacobian of the reparameterization (delta method).

Score (:func:`bic`): Bayesian information criterion on the *validation* runs,
``BIC = n_eff ln(RSS / n) + p ln(n_eff)`` with ``n`` residuals, ``p`` fitted
parameters and the effective sample size ``n_eff = n (1 - rho) / (1 + rho)`` of an
AR(1) residual (``rho`` of the baseline model's validation residual).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from uvsim.calibration.batching import RunBatch, simulate_rows
from uvsim.diagnosis.candidates import Candidate
from uvsim.metrics import normalized_residuals, pooled_rmse, residual_components, run_metrics, signals_from_states

FD_STEP = 1e-3   # forward-difference step in scaled fit variables (simulations are deterministic and smooth)
FILL = 30.0      # residual given to a diverged simulation (30 noise sigmas)


def lag1_autocorrelation(batch: RunBatch, predicted: list, scales: list) -> float:
    """Pooled lag-1 autocorrelation of the normalized output residual (per run and channel);
    ``scales`` holds one dict of noise levels per run."""
    num = den = 0.0
    for m, p, sc in zip(batch.measured, predicted, scales):
        for g, e in residual_components(m, p).items():
            e = e / sc[g]
            for j in range(e.shape[-1]):
                x = e[:, j]
                x = x[np.isfinite(x)]
                if x.size > 2:
                    x = x - x.mean()
                    num += float(x[1:] @ x[:-1])
                    den += float(x @ x)
    return float(np.clip(num / den, 0.0, 0.999)) if den > 0 else 0.0


def effective_n(n: int, rho: float) -> float:
    return max(1.0, n * (1.0 - rho) / (1.0 + rho))


def bic(rss: float, n: int, p: int, n_eff: float) -> float:
    """``n_eff ln(RSS / n) + p ln(n_eff)`` (module docstring)."""
    return float(n_eff * np.log(max(rss, 1e-300) / n) + p * np.log(n_eff))


class Objective:
    """Normalized residual vectors of a batch of runs for parameter sets ``X`` (P, p);
    ``scales`` is a list with one dict of noise levels per run."""

    def __init__(self, vehicle, batch: RunBatch, cand: Candidate, scales, weights=None):
        self.vehicle = vehicle.with_effects([cand.effect]) if cand.effect else vehicle
        self.batch, self.cand, self.scales, self.weights = batch, cand, scales, weights
        self.n_sims = 0

    def predict(self, X: np.ndarray) -> np.ndarray:
        """States (P * R, L, n_y); row ``i * R + r`` is parameter set i, run r."""
        X = np.atleast_2d(X)
        P, R = X.shape[0], self.batch.n_runs
        params = self.cand.to_params(X) if self.cand.n_params else {}
        overrides = {k: np.repeat(np.asarray(v, float), R) for k, v in params.items()}
        self.n_sims += P * R
        with np.errstate(all="ignore"):
            return simulate_rows(self.vehicle, self.batch, np.tile(np.arange(R), P), overrides or None)

    def signals(self, y_row: np.ndarray, r: int) -> dict:
        return signals_from_states(y_row[: self.batch.lengths[r]])

    def vectors(self, X: np.ndarray) -> np.ndarray:
        X = np.atleast_2d(X)
        Y = self.predict(X)
        R = self.batch.n_runs
        out = []
        for i in range(X.shape[0]):
            parts = [normalized_residuals(self.batch.measured[r], self.signals(Y[i * R + r], r), self.scales[r],
                                          self.weights, fill=FILL) for r in range(R)]
            v = np.concatenate(parts)
            out.append(np.where(np.isfinite(v), v, FILL))
        return np.array(out)

    def predicted(self, x: np.ndarray) -> list:
        Y = self.predict(np.atleast_2d(x))
        return [self.signals(Y[r], r) | {"states": Y[r, : self.batch.lengths[r]]} for r in range(self.batch.n_runs)]


@dataclass
class FitResult:
    x: np.ndarray                 # fit variables (physical units)
    params: dict                  # effect parameter name -> value
    std: dict                     # effect parameter name -> 1-sigma
    rss: float
    n: int
    nfev: int
    rho: float
    success: bool
    message: str


def fit(vehicle, batch: RunBatch, cand: Candidate, scales, *, max_nfev: int = 30, weights=None) -> FitResult:
    """Least-squares fit of ``cand`` on ``batch`` (module docstring); ``weights`` per signal group."""
    obj = Objective(vehicle, batch, cand, scales, weights)
    if cand.n_params == 0:
        r = obj.vectors(np.zeros((1, 0)))[0]
        return FitResult(np.zeros(0), {}, {}, float(r @ r), r.size, 1, 0.0, True, "nothing to fit")
    s = cand.scale
    cache = {}

    def fun(z):
        key = z.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = obj.vectors((z * s)[None])[0]
        return cache[key]

    def jac(z):
        f0 = fun(z)
        p = z.size
        Z = np.repeat(z[None], p, axis=0)
        h = np.full(p, FD_STEP)
        hi = cand.upper / s
        flip = Z[np.arange(p), np.arange(p)] + h > hi
        h[flip] = -h[flip]
        Z[np.arange(p), np.arange(p)] += h
        F = obj.vectors(Z * s)
        return ((F - f0[None]) / h[:, None]).T

    lo, hi = cand.lower / s, cand.upper / s
    z0 = np.clip(cand.x0 / s, lo + 1e-6 * (hi - lo), hi - 1e-6 * (hi - lo))
    res = least_squares(fun, z0, jac=jac, bounds=(lo, hi), method="trf", max_nfev=max_nfev,
                        ftol=1e-8, xtol=1e-8, gtol=1e-8)
    x = res.x * s
    r = fun(res.x)
    n, p = r.size, x.size
    # autocorrelation of the final residual, per run and group, via the predicted signals
    rho = lag1_autocorrelation(batch, obj.predicted(x), scales)
    J = jac(res.x)
    s2 = float(r @ r) / max(n - p, 1)
    cov_z = s2 * np.linalg.pinv(J.T @ J) * (1 + rho) / (1 - rho)
    cov_x = cov_z * np.outer(s, s)
    params, std = _map_with_uncertainty(cand, x, cov_x)
    return FitResult(x, params, std, float(r @ r), n, int(res.nfev), rho, bool(res.success), str(res.message))


def _map_with_uncertainty(cand: Candidate, x: np.ndarray, cov_x: np.ndarray):
    base = {k: float(v[0]) for k, v in cand.to_params(x[None]).items()}
    names = list(base)
    G = np.zeros((len(names), x.size))
    for j in range(x.size):
        h = 1e-6 * max(abs(x[j]), cand.scale[j])
        xp = x.copy()
        xp[j] += h
        vp = cand.to_params(xp[None])
        G[:, j] = [(float(vp[k][0]) - base[k]) / h for k in names]
    cov = G @ cov_x @ G.T
    std = {k: float(np.sqrt(max(cov[i, i], 0.0))) for i, k in enumerate(names)}
    return base, std


def evaluate(vehicle, batch: RunBatch, cand: Candidate, x: np.ndarray, scales, weights=None) -> dict:
    """Residual vector, pooled RMSE and per-run metrics of ``cand`` at ``x`` on ``batch``."""
    obj = Objective(vehicle, batch, cand, scales, weights)
    X = np.atleast_2d(x) if cand.n_params else np.zeros((1, 0))
    pred = obj.predicted(X[0])
    parts = [normalized_residuals(m, p, sc, weights, fill=FILL) for m, p, sc in zip(batch.measured, pred, scales)]
    v = np.concatenate(parts)
    v = np.where(np.isfinite(v), v, FILL)
    return {
        "vector": v,
        "rss": float(v @ v),
        "n": int(v.size),
        "rmse": pooled_rmse(zip(batch.measured, pred)),
        "per_run": {r.name: run_metrics(m, p) for r, m, p in zip(batch.runs, batch.measured, pred)},
        "predicted": pred,
    }
