"""Levenberg-Marquardt on a windowed problem, with the per-run nuisance eliminated.

The unknowns are the global parameters ``z`` (p, scaled, bounded) and, per run, the
nuisance vector ``nu_r`` (free node components of its windows and its sensor biases:
gyro, attitude filter).
A run's residual depends on ``z`` and its own ``nu_r`` only, so the normal equations
have an arrow structure and the nuisance is eliminated run by run (Schur complement,
as in bundle adjustment: Triggs et al. 2000, "Bundle adjustment - a modern
synthesis", sec. 6.1)::

    S dz = -(g_z - sum_r B_r^T D_r^-1 g_r),   S = A - sum_r B_r^T D_r^-1 B_r
    dnu_r = -D_r^-1 (g_r + B_r dz)

with ``A = J_z^T J_z``, ``B_r = J_r^T J_z``, ``D_r = J_r^T J_r`` (+ Levenberg-Marquardt
damping ``lambda diag``), ``g = J^T r``.  Damping update after Madsen, Nielsen &
Tingleff (2004), "Methods for non-linear least squares problems", sec. 3.2 (Nielsen's
update).  Stopping: at every fresh linearization, when the decrease the Gauss-Newton model
predicts for its own minimizer (variables held at a bound excepted, the step not cut back
into the box) is below ``ftol`` times the cost (the Newton
decrement test, Boyd & Vandenberghe 2004, sec. 9.5.1; no trial simulation is then needed
and the linearization at hand is the final one), when an accepted step lowered the cost by
less than ``ftol`` times it while the linearization predicted that step well (ratio above
1/4: the ``ftol`` test of scipy.optimize.least_squares), when a step is below ``xtol``, or
after ``max_iter`` iterations.  The second test ends the slow tail of a fit that crawls
along a flat valley (a prior-held fit of a real-log-sized case took 43 iterations where the
cost stopped changing by 1e-6 after 27; its parameters moved by less than 0.001 posterior
sd in the last 16, docs/performance.md).  Bounds on ``z``: a step that would leave the box is cut
back into it, and a variable at a bound whose step points outward is held for that
step (a simple active set).

After an accepted step the next trial point is linearized at once (:data:`SPECULATE`): its
base row is the trial, and the linearization is the next iteration's when the step is
accepted, as most are; after a rejection the next trial is simulated alone.

The linearization of each problem (residuals, forward-difference Jacobians and the normal-
equation pieces of each run) is :mod:`uvsim.fitting.linearization`; the evaluators that run
it in this process or in a pool of processes are :mod:`uvsim.fitting.evaluators`.

Uncertainty: ``S`` at the solution is the information on ``z`` after the nuisance is
profiled out; the reported covariance is the cluster-robust sandwich
``S^-1 (sum_w s_w s_w^T) S^-1`` with ``s_w`` the projected score of window ``w``
(Liang & Zeger 1986): residuals of one window may be correlated in any way, windows
are treated as independent, so the uncertainty is not made optimistic by the strong
autocorrelation of trajectory residuals.
"""
from __future__ import annotations

import time

import numpy as np

from uvsim.blas import single_thread
from uvsim.fitting.evaluators import PoolEvaluator, PriorEvaluator, SerialEvaluator
from uvsim.fitting.worker_pool import PersistentEvaluator, WorkerPool
from uvsim.fitting.linearization import reduced_system

#: After an accepted step, the next trial point is linearized at once (Jacobian included)
#: instead of simulated alone and linearized when accepted: a trial simulates one parameter
#: set per window, and on tank-size problems (20 windows of 150 steps) its cost is the numpy
#: overhead of 600 model evaluations, 30-45 % of a whole linearization's; most trial steps
#: are accepted.  A rejected one wastes a linearization, so after a rejection the next trial
#: is simulated alone.  The trial's cost is then the base row of a batched simulation, equal
#: to the single simulation's to the last bit or two (docs/performance.md).
SPECULATE = True


def _cost(blocks) -> float:
    return 0.5 * float(sum(b.rss for b in blocks))


def _predicted_decrease(blocks, dz, dnus) -> float:
    """Decrease of 1/2 |r|^2 predicted by the linearization for the step (dz, dnus)."""
    pred = 0.0
    for b, dn in zip(blocks, dnus):
        g = float(b.gz @ dz) + (float(b.gn @ dn) if dn.size else 0.0)
        h = float(dz @ b.A @ dz) + (float(2 * dn @ b.B @ dz + dn @ b.D @ dn) if dn.size else 0.0)
        pred += -g - 0.5 * h
    return pred


def _newton_decrement(blocks, z, lo, hi) -> float:
    """Decrease of 1/2 |r|^2 that the Gauss-Newton model predicts for its own minimizer
    (the undamped step, not cut back into the box; variables held at a bound stay): the
    stopping test, as the Newton decrement is in
    Boyd & Vandenberghe (2004), *Convex Optimization*, sec. 9.5.1.  The damped step's
    prediction would not do: with a large damping it is small far from the optimum."""
    dz, dnus = _step(blocks, 0.0, z, lo, hi, clip=False)
    return _predicted_decrease(blocks, dz, dnus)


def _step(blocks, lam, z, lo, hi, clip: bool = True):
    """The damped step (dz, per-run dnu); variables at a bound whose step points outward are
    held.  ``clip``: cut the step back into the box (else the model's own minimizer over the
    variables not held, as the convergence test needs: a clipped step predicts little
    decrease even far from the optimum)."""
    S, rhs, per = reduced_system(blocks, lam)
    p = z.size
    held = np.zeros(p, bool)
    for _ in range(p + 1):
        Sh, rh = S.copy(), rhs.copy()
        Sh[held, :] = 0.0
        Sh[:, held] = 0.0
        Sh[held, held] = 1.0
        rh[held] = 0.0
        dz = np.linalg.lstsq(Sh, rh, rcond=None)[0] if p else np.zeros(0)
        out = ((z <= lo + 1e-12) & (dz < 0)) | ((z >= hi - 1e-12) & (dz > 0))
        if not (out & ~held).any():
            break
        held |= out
    if clip:
        dz = np.clip(z + dz, lo, hi) - z
    dnus = []
    for pr in per:
        if pr is None:
            dnus.append(np.zeros(0))
        else:
            Dinv_B, Dinv_g = pr
            dnus.append(-(Dinv_g + Dinv_B @ dz))
    return dz, dnus


def _problems(prob) -> list:
    return list(prob) if isinstance(prob, (list, tuple)) else [prob]


def solve(prob, z0: np.ndarray, nus0: list | None = None, *, max_iter: int = 20,
          ftol: float = 1e-6, xtol: float = 1e-7, progress=None, workers: int = 1, state: dict | None = None,
          on_step=None, prior=None) -> dict:
    """Levenberg-Marquardt from (z0, nus0) (module docstring).

    ``prob`` is a :class:`WindowedProblem` or a list of them sharing one parameter space
    (e.g. one per input kind and chunk of runs); ``nus0`` lists the runs' nuisance
    vectors in order.  ``workers`` > 1 linearizes the problems in that many processes
    (same result), a :class:`~uvsim.fitting.worker_pool.WorkerPool` in its processes.  Returns dict with ``z``, ``nus``, ``cost`` (1/2 sum r^2), ``blocks``
    (:class:`uvsim.fitting.linearization.RunNormal` per run at the solution, with window scores), ``iterations``,
    ``evaluations`` (parameter sets simulated per run chunk), ``message``, ``history``
    (cost per accepted step), ``seconds``.  Runs with one BLAS thread per process (small
    matrix products; see :mod:`uvsim.fitting.objective`).

    Resumable: ``on_step(state)`` is called after every accepted step that does not end
    the iterations, with a dict of everything the iteration depends on (``z``, ``nus``,
    the damping, counters); ``solve(..., state=that)`` continues from it and gives the
    result an uninterrupted call would have given (the linearization at a point is
    deterministic; rejected steps after the saved one are repeated identically).

    ``prior``: a :class:`uvsim.fitting.priors.Prior` on ``z`` (maximum a posteriori, the
    data weighted as that module says).  Then ``blocks`` are the data's own blocks at the
    solution, ``posterior_blocks`` the weighted data's and the prior's (for
    :func:`covariance`: the posterior), and ``data_weight`` the final weight."""
    probs = _problems(prob)
    if isinstance(workers, WorkerPool):  # processes kept across fits (a diagnosis)
        ev = PersistentEvaluator(probs, workers) if len(probs) > 1 else SerialEvaluator(probs)
    else:
        ev = PoolEvaluator(probs, int(workers)) if workers and int(workers) > 1 and len(probs) > 1 \
            else SerialEvaluator(probs)
    if prior is not None:
        ev = PriorEvaluator(ev, prior)
    try:
        with single_thread():
            res = _solve(probs, ev, z0, nus0, max_iter=max_iter, ftol=ftol, xtol=xtol, progress=progress,
                         state=state, on_step=on_step)
    finally:
        ev.close()
    if prior is not None:
        res["posterior_blocks"], res["blocks"] = res["blocks"], ev.raw
        res["data_weight"] = ev.w
    return res


def _solve(probs, ev, z0, nus0, *, max_iter, ftol, xtol, progress, state=None, on_step=None):
    t0 = time.perf_counter()
    space = probs[0].space
    lo, hi = space.z_lower, space.z_upper
    # simulated parameter sets per linearization (a node moved along a shift axis needs none)
    n_sets = 1 + space.p + max(sum(1 for c in np.flatnonzero(p.free.any(axis=0)) if c not in p.shift_axes)
                               for p in probs)
    if state is None:
        z = np.clip(np.asarray(z0, float), lo, hi)
        if nus0 is None:
            nus0 = [n for p in probs for n in p.zero_nuisance()]
        nus = [np.array(n, float) for n in nus0]
        blocks = ev.linearize(z, nus, scores=True)
        cost = _cost(blocks)
        history = [cost]
        lam, nu_f = 1e-3, 2.0
        evals = n_sets
        it0 = 0
    else:  # continue after the accepted step ``state`` describes (see solve)
        z, nus = np.array(state["z"], float), [np.array(n, float) for n in state["nus"]]
        cost, history, lam, nu_f = state["cost"], list(state["history"]), state["lam"], state["nu_f"]
        evals, it0 = state["evaluations"], state["iteration"]
        blocks = ev.linearize(z, nus, scores=True)
        if getattr(ev, "reweighs", False):
            cost = _cost(blocks)
    message = "maximum number of iterations reached"
    it = it0
    # speculative linearization at the trial point (SPECULATE): not where the evaluator
    # re-weighs or keeps the data's own blocks (PriorEvaluator), whose trial cost must use
    # the weight of the current point
    speculate = SPECULATE and not isinstance(ev, PriorEvaluator)
    at_z = True  # ``blocks`` is the linearization (with window scores) at ``z``
    for it in range(it0 + 1, max_iter + 1):
        if nu_f == 2.0 and _newton_decrement(blocks, z, lo, hi) <= ftol * cost:
            # at a fresh linearization, the decrease the Gauss-Newton model predicts for its own
            # minimizer is below ftol: converged here, no trial simulation, and these blocks are
            # the final ones
            message = "converged: predicted relative cost decrease below ftol"
            break
        dz, dnus = _step(blocks, lam, z, lo, hi)
        pred = _predicted_decrease(blocks, dz, dnus)
        z_new = z + dz
        nus_new = [a + b for a, b in zip(nus, dnus)]
        ahead = None
        if speculate and nu_f == 2.0:
            # the last step was accepted, so this one likely is too: linearize at the trial
            # point at once (its base row is the trial); a rejection wastes one linearization
            try:
                with np.errstate(all="ignore"):  # a trial that ran away is rejected, as below
                    ahead = ev.linearize(z_new, nus_new, scores=True)
            except np.linalg.LinAlgError:  # its Jacobian broke (a run-away trial): simulate it alone
                ahead = None
            evals += n_sets
        if ahead is not None:
            c_new = _cost(ahead)
        else:
            c_new = _cost(ev.linearize(z_new, nus_new, jacobian=False))
            evals += 1
        rho = (cost - c_new) / pred if pred > 0 else -1.0
        if np.isfinite(c_new) and rho > 0:
            # the step of the parameters; with none free (node states and biases alone, e.g. a
            # validation cost), of the nuisance: an empty dz would end every such fit after one step
            if z.size:
                step_small = np.linalg.norm(dz) <= xtol * (np.linalg.norm(z) + xtol)
            else:
                step_small = (np.sqrt(sum(float(d @ d) for d in dnus))
                              <= xtol * (np.sqrt(sum(float(n @ n) for n in nus)) + xtol))
            # scipy.optimize.least_squares' ftol test: the step lowered the cost by less than ftol of
            # it and the linearization predicted that well (rho > 1/4)
            stalled = cost - c_new < ftol * cost and rho > 0.25
            z, nus, cost = z_new, nus_new, c_new
            history.append(cost)
            lam *= max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
            nu_f = 2.0
            if progress is not None:
                progress(it, cost)
            if step_small or stalled:
                at_z = ahead is not None
                if at_z:
                    blocks = ahead
                message = "converged: step below xtol" if step_small else "converged: relative cost decrease below ftol"
                break
            if ahead is not None:
                blocks = ahead
            else:
                blocks = ev.linearize(z, nus, scores=True)
                evals += n_sets
            if getattr(ev, "reweighs", False):  # the data weight was re-estimated: the cost at it
                cost = _cost(blocks)
                history[-1] = cost
            if on_step is not None:
                st = {"z": z.copy(), "nus": [n.copy() for n in nus], "cost": cost, "history": list(history),
                      "lam": lam, "nu_f": nu_f, "evaluations": evals, "iteration": it}
                if isinstance(ev, PriorEvaluator):  # for the record: a resumed fit re-estimates it at z
                    st["data_weight"] = ev.w
                on_step(st)
        else:
            lam *= nu_f
            nu_f *= 2.0
            if lam > 1e12 or pred <= 0:
                message = ("converged: no further decrease predicted" if pred <= 0 else
                           "stopped: no decrease possible (damping limit)")
                break
    if not at_z:
        blocks = ev.linearize(z, nus, scores=True)  # at the solution, with the window scores
        evals += n_sets
    return {"z": z, "nus": nus, "cost": cost, "blocks": blocks, "iterations": it, "evaluations": evals,
            "message": message, "history": history, "seconds": time.perf_counter() - t0}


def covariance(blocks) -> dict:
    """Plain and cluster-robust covariances of z at a solution (module docstring);
    ``blocks`` from :func:`solve` (with window scores)."""
    S, _, per = reduced_system(blocks, 0.0)
    p = S.shape[0]
    Sinv = np.linalg.pinv(S)
    q = sum(b.D.shape[0] for b in blocks)
    clusters = sum(int(b.window_sse.size) for b in blocks)
    n = sum(b.n for b in blocks)
    rss = float(sum(b.rss for b in blocks))
    meat = np.zeros((p, p))
    for b in blocks:
        meat += b.scores.T @ b.scores
    s2 = rss / max(n - p - q, 1)
    return {"plain": s2 * Sinv, "robust": Sinv @ meat @ Sinv, "information": S, "s2": s2, "n": n, "q": q,
            "clusters": clusters}
