"""One call that fits free model parameters to logged runs: ``fit(vehicle, runs, space)``.

The fit minimizes the windowed prediction error of :mod:`uvsim.fitting.objective`
with the nuisance-eliminating Levenberg-Marquardt of :mod:`uvsim.fitting.solver`,
over a *continuation* in the window length (``horizons``, e.g. ``(2.0, 6.0)`` s: the
result of each stage starts the next; short windows keep the cost close to quadratic,
longer ones add the long-horizon information) and then in the continuity of the windows
(``continuity``, factors of the continuity defects' standard deviation at the last
horizon, e.g. ``(1.0, 0.05)``: a smaller factor lets the windows restart less, so the cost
comes closer to the free simulation's, :mod:`uvsim.fitting.objective`), for runs of any input kinds (one
windowed problem per input kind, one shared parameter vector).  It is the refinement
of :class:`uvsim.calibration.Calibrator` and the candidate fit of
:func:`uvsim.diagnosis.diagnose`.

Results: fitted values, cluster-robust 1-sigma uncertainties
(:func:`uvsim.fitting.solver.covariance`), the identifiability of the free parameters
(:func:`identifiability`), parameters at a bound or at the physical limit, per-run
nuisance estimates (gyro biases) and per-window costs (for model comparison,
:mod:`uvsim.fitting.compare`).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from uvsim.errors import CalibrationError
from uvsim.fitting.objective import WindowedProblem, continuity_factors
from uvsim.fitting.parameters import ParameterSpace
from uvsim.fitting.priors import make_prior
from uvsim.fitting.solver import covariance, solve
from uvsim.fitting.windows import whole_runs
from uvsim.fitting.worker_pool import with_worker_pool
from uvsim.measurements import measurements_for

#: Relative singular value below which a direction of the free parameters counts as
#: not identifiable by the data.
NULL_TOL = 1e-3
#: |correlation| above which two parameters are reported as strongly correlated.
CORR_REPORT = 0.9
DEFAULT_HORIZONS = (2.0,)
#: Continuity factors of the stages at the last horizon (1: the defects' sd is
#: :data:`uvsim.fitting.objective.DEFECT_SIGMA`); diagnosis uses this default.
DEFAULT_CONTINUITY = (1.0,)


@dataclass
class FitResult:
    """Outcome of :func:`fit` (attributes are JSON-friendly apart from ``problems``)."""

    names: list
    values: dict
    std: dict
    covariance: np.ndarray
    cost: float
    n_residuals: int
    stages: list
    gyro_bias: dict
    at_bounds: list
    physical_limit: list
    identifiability: dict
    z: np.ndarray = field(repr=False, default=None)
    nus: list = field(repr=False, default_factory=list)
    problems: list = field(repr=False, default_factory=list)
    window_costs: list = field(repr=False, default_factory=list)
    #: index into the fitted runs of each entry of ``nus`` / ``window_costs``
    order: list = field(repr=False, default_factory=list)
    #: the prior (maximum a posteriori fit, :mod:`uvsim.fitting.priors`): {name: mean},
    #: {name: standard deviation}, and the data weight at the solution; empty / None without
    prior_mean: dict = field(default_factory=dict)
    prior_sd: dict = field(default_factory=dict)
    data_weight: float | None = None
    #: run name -> fitted [roll, pitch] offset (rad) of its attitude filter (runs that have one)
    attitude_bias: dict = field(default_factory=dict)
    #: run name -> fitted accelerometer offset [x, y, z] (m/s^2, body axes) (runs that log one)
    acc_bias: dict = field(default_factory=dict)

    def summary(self) -> dict:
        return {"values": self.values, "std": self.std, "cost": self.cost, "n_residuals": self.n_residuals,
                "stages": self.stages, "gyro_bias": self.gyro_bias, "attitude_bias": self.attitude_bias,
                "acc_bias": self.acc_bias, "at_bounds": self.at_bounds,
                "physical_limit": self.physical_limit, "identifiability": self.identifiability}


def group_by_input(runs: Sequence) -> list[list[int]]:
    """Indices of runs grouped by (input kind, input count), in first-seen order."""
    groups: dict = {}
    for i, r in enumerate(runs):
        groups.setdefault((r.input_kind, len(r.input_columns)), []).append(i)
    return list(groups.values())


#: Runs per windowed problem, and samples: a problem takes runs until it would exceed either.
#: The problems are the units of work of the solver's workers; a size fixed by the data (not
#: by the number of workers) keeps results independent of it.  The sample cap lets two long
#: runs (2 x 35 s at 100 Hz) go to two workers.
RUNS_PER_PROBLEM = 8
SAMPLES_PER_PROBLEM = 3000


def _chunks(idx: list, sizes: list) -> list[list]:
    """``idx`` cut, in order, into chunks of at most RUNS_PER_PROBLEM runs and (unless a run
    alone is longer) SAMPLES_PER_PROBLEM samples."""
    out, cur, n = [], [], 0
    for i, m in zip(idx, sizes):
        if cur and (len(cur) == RUNS_PER_PROBLEM or n + m > SAMPLES_PER_PROBLEM):
            out.append(cur)
            cur, n = [], 0
        cur.append(i)
        n += m
    if cur:
        out.append(cur)
    return out


def build_problems(vehicle, runs, meas, space: ParameterSpace, horizon, z_ref, *, gyro_bias=True,
                   attitude_bias: bool = False, acc_bias: bool = False, initial_velocity="zero", loss: str = "linear",
                   continuity: float = 1.0) -> tuple[list, list]:
    """:class:`WindowedProblem` s of at most :data:`RUNS_PER_PROBLEM` runs and
    :data:`SAMPLES_PER_PROBLEM` samples of one input kind each; returns (problems, run order)."""
    probs, order = [], []
    for idx in group_by_input(runs):
        # the reference trajectories of the whole group in one batch (few large numpy calls
        # rather than many small ones), then cut into the problems
        z = space.z0 if z_ref is None else np.asarray(z_ref, float)
        yref, _, _ = whole_runs(vehicle, [runs[i] for i in idx], [meas[i].sensors for i in idx], space, z,
                                initial_velocity=initial_velocity)
        a = 0
        for sub in _chunks(idx, [runs[i].t.size for i in idx]):
            probs.append(WindowedProblem(vehicle, [runs[i] for i in sub], [meas[i] for i in sub], space, horizon,
                                         z_ref=z_ref, gyro_bias=gyro_bias, attitude_bias=attitude_bias,
                                         acc_bias=acc_bias, initial_velocity=initial_velocity,
                                         yref=yref[a:a + len(sub)], loss=loss,
                                         continuity=continuity))
            order += sub
            a += len(sub)
    return probs, order


@with_worker_pool
def fit(vehicle, runs, space: ParameterSpace, *, meas=None, horizons: Sequence = DEFAULT_HORIZONS,
        max_iter: int = 20, gyro_bias: bool = True, attitude_bias: bool = False, acc_bias: bool = False,
        noise=None, weights=None,
        initial_velocity: str = "zero",
        z0=None, progress=None, workers: int = 1, ftol: float = 1e-6, checkpoint=None,
        on_iteration=None, prior_mean=None, prior_sd=None, loss: str = "linear",
        continuity: Sequence = DEFAULT_CONTINUITY, stage_meas=None) -> FitResult:
    """Fit ``space``'s free parameters of ``vehicle`` to ``runs`` (module docstring).

    Parameters
    ----------
    vehicle : Vehicle (effects already added).
    runs : :class:`uvsim.logs.Run` list (training runs).
    space : the free parameters.
    meas : their measurement models (built from ``noise``/``weights`` when omitted).
    horizons : window lengths, s, of the continuation stages (None = whole runs).
    continuity : factors of the continuity defects' standard deviation: the stages before the
        last horizon use the first, the last horizon one stage per factor in turn (so the
        defaults, ``(1.0,)``, give one stage per horizon).
    max_iter : Levenberg-Marquardt iterations per stage.
    gyro_bias : fit a constant gyro bias per run that logs rates.
    attitude_bias : fit a constant roll and pitch offset per run whose attitude comes from a
        filter beside a gyro (:data:`uvsim.fitting.objective.ATTITUDE_BIAS_SIGMA` prior).
    acc_bias : fit a constant accelerometer offset per run that logs one
        (:func:`uvsim.fitting.objective.acc_bias_sd` prior).
    z0 : start (scaled) instead of the space's start values.
    progress : callable(message) for stage / iteration reports.
    workers : processes for the simulations (results do not depend on it), kept for all the
        stages (:class:`uvsim.fitting.worker_pool.WorkerPool`; a pool given is used as it is).
    ftol : a stage stops when an iteration lowers the cost by less than this fraction.
    checkpoint : optional store of the fit's progress, any object with ``load()``
        (the saved state or None) and ``save(state, progress="...")``: saved after every
        accepted Levenberg-Marquardt step and every finished stage; a fit given a
        checkpoint with a saved state continues from it (finished stages are not
        redone) and gives the result of an uninterrupted fit.  The caller makes sure
        the state belongs to the same problem (e.g. by a fingerprint).
    on_iteration : callable(stage index, iteration, cost) after every accepted step
        (e.g. a progress bar).
    prior_mean : {name: value} of every free parameter: fit maximum a posteriori with a
        Gaussian prior there (:mod:`uvsim.fitting.priors`; the data weighted by their
        effective information); ``prior_sd`` {name: standard deviation} overrides
        :func:`uvsim.fitting.priors.default_prior_sd`. The reported ``std`` is then the
        posterior's.
    loss : "linear" (least squares) or "huber": the measurement residuals beyond
        :data:`uvsim.fitting.objective.HUBER_SCALE` noise sigmas cost linearly (outliers,
        dropouts, bursts of model error; :func:`uvsim.fitting.objective.robust_residuals`).
    stage_meas : optional ``stage_meas(horizon, values) -> meas or None``, called at the start of
        every stage with its horizon and start values ({name: value} of the free parameters): the
        measurement models that stage uses (None: ``meas``).  The calibration's whole-run stage
        scales each channel by its own RMS error there (:func:`uvsim.fitting.evaluate.judged_scales`).
        It must depend on the values only, so that a resumed fit rebuilds the same stage.
    """
    runs = list(runs)
    if not runs:
        raise CalibrationError("no runs to fit")
    if meas is None:
        meas = [measurements_for(r, vehicle, noise=noise, weights=weights) for r in runs]
    say = progress or (lambda msg: None)
    z = space.z0 if z0 is None else np.asarray(z0, float)
    horizons = list(horizons)
    continuity = continuity_factors(continuity)
    if not horizons:
        raise CalibrationError("fit: give at least one horizon")
    # the stages: (window length, continuity factor)
    plan = [(H, continuity[0]) for H in horizons[:-1]] + [(horizons[-1], c) for c in continuity]
    prior = None if prior_mean is None else make_prior(space, prior_mean, prior_sd)
    saved = checkpoint.load() if checkpoint is not None else None
    stages = [] if saved is None else list(saved["stages"])
    first = 0 if saved is None else int(saved["stage"])
    if saved is not None:
        z = np.array(saved["z"], float)
    res = None
    problems = []

    def meas_of(H, z_start):
        got = None if stage_meas is None else stage_meas(H, space.as_dict(z_start))
        return meas if got is None else got

    if saved is not None and first == len(plan):  # every stage finished: the final linearization only
        z_start = np.array(saved["z_start"])
        problems, order = build_problems(vehicle, runs, meas_of(plan[-1][0], z_start), space, plan[-1][0], z_start,
                                         gyro_bias=gyro_bias, attitude_bias=attitude_bias, acc_bias=acc_bias,
                                         initial_velocity=initial_velocity, loss=loss, continuity=plan[-1][1])
        res = solve(problems, z, saved["nus"], max_iter=0, workers=workers, prior=prior)
        # the finished fit's own cost (re-evaluated here in a batch of another size, the sum may
        # differ in its last bit with the BLAS kernels of some machines)
        res["cost"] = stages[-1]["cost"]
    for si, (H, cont) in enumerate(plan):
        if si < first:
            continue
        t0 = time.perf_counter()
        z_start = z
        problems, order = build_problems(vehicle, runs, meas_of(H, z), space, H, z, gyro_bias=gyro_bias,
                                         attitude_bias=attitude_bias, acc_bias=acc_bias,
                                         initial_velocity=initial_velocity, loss=loss, continuity=cont)
        label = ("whole runs" if H is None else f"{H:g} s windows") + ("" if cont == 1 else f", continuity {cont:g}")
        say(f"fitting {space.p} parameter(s) on {len(runs)} run(s), {label}")

        def on_step(st, si=si, z_start=z_start, label=label):
            if checkpoint is not None:
                checkpoint.save({"stage": si, "z": z_start, "stages": stages, "solver": st},
                                progress=f"stage {si + 1} of {len(plan)} ({label}), iteration {st['iteration']}")

        def on_it(it, c, si=si, label=label):
            say(f"  {label}: iteration {it}, cost {c:.6g}")
            if on_iteration is not None:
                on_iteration(si, it, c)

        st0 = saved["solver"] if saved is not None and si == first else None
        res = solve(problems, z, max_iter=max_iter, workers=workers, ftol=ftol, progress=on_it, state=st0,
                    on_step=on_step, prior=prior)
        z = res["z"]
        stages.append({"horizon_s": H, "continuity": cont, "iterations": res["iterations"], "cost": float(res["cost"]),
                       "message": res["message"], "windows": int(sum(p.lay.W for p in problems)),
                       "simulated_parameter_sets": int(res["evaluations"]),
                       "seconds": float(time.perf_counter() - t0),
                       **({"data_weight": float(res["data_weight"])} if prior is not None else {})})
        if checkpoint is not None:
            checkpoint.save({"stage": si + 1, "z": z, "z_start": z_start, "nus": res["nus"], "stages": stages,
                             "solver": None},
                            progress=f"stage {si + 1} of {len(plan)} ({label}) finished")
    blocks = res["blocks"]
    cov = covariance(res.get("posterior_blocks", blocks)) if space.p else None
    sc = space.scale
    values = space.as_dict(z)
    if cov is not None:
        # without a prior the cluster-robust sandwich; with one the posterior (w S + P)^-1, which is
        # the prior's covariance along what the data do not see (the sandwich would be 0 there)
        C = (cov["robust"] if prior is None else np.linalg.pinv(cov["information"])) * np.outer(sc, sc)
        std = {k: float(np.sqrt(max(C[i, i], 0.0))) for i, k in enumerate(space.names)}
        info = cov["information"] if prior is None else covariance(blocks)["information"]  # the data's own
        ident = identifiability(info / np.outer(sc, sc), space.names, C)
    else:
        C, std, ident = np.zeros((0, 0)), {}, {}
    # per-run nuisance: sensor biases (in the problems' run order)
    gb, ab, cb = {}, {}, {}
    k = 0
    for prob in problems:
        for r, run in enumerate(prob.runs):
            g, a, c = prob.split_bias(r, prob.split_nuisance(r, res["nus"][k])[1])
            for got, into in ((g, gb), (a, ab), (c, cb)):
                if got is not None:
                    into[run.name] = [float(x) for x in got]
            k += 1
    n_res = int(sum(b.n for b in blocks))
    out = FitResult(space.names, values, std, C, float(res["cost"]), n_res, stages, gb, space.at_bounds(z),
                    space.physical_limit(z), ident, z, res["nus"], problems, [b.window_sse for b in blocks],
                    order, attitude_bias=ab, acc_bias=cb)
    if prior is not None:
        sc = space.scale
        out.prior_mean = {k: float(prior.mean_z[i] * sc[i]) for i, k in enumerate(space.names)}
        out.prior_sd = {k: float(prior.sd_z[i] * sc[i]) for i, k in enumerate(space.names)}
        out.data_weight = float(res["data_weight"])
    return out


def identifiability(info: np.ndarray, names: Sequence[str], cov: np.ndarray | None = None) -> dict:
    """Identifiability of the free parameters from the information matrix ``info``
    (p, p) in physical units (``J^T J`` with the nuisance profiled out).

    The columns are normalized (``D^-1/2 info D^-1/2``, ``D = diag(info)``); its
    eigenvalues are the squared singular values of the column-normalized Jacobian.
    A direction with relative singular value below :data:`NULL_TOL` changes no residual:
    the data cannot separate the parameters along it (e.g. ``I_xx`` and ``K_pdot`` in
    decoupled roll runs, which enter only as their sum).

    Returns dict with ``parameters``, ``relative_singular_values``, ``condition_number``,
    ``not_identifiable`` (directions: {name: coefficient}), ``identifiable_combinations``
    (readable, e.g. ``"I_xx + K_pdot"``) and ``correlations`` (pairs with |r| >
    :data:`CORR_REPORT`, from ``cov``)."""
    names = list(names)
    p = len(names)
    d = np.sqrt(np.maximum(np.diag(info), 1e-300))
    N = info / np.outer(d, d)
    ev, V = np.linalg.eigh(0.5 * (N + N.T))
    ev = np.maximum(ev[::-1], 0.0)
    V = V[:, ::-1]
    s = np.sqrt(ev)
    srel = s / s[0] if p and s[0] > 0 else s
    null, comb, involved = [], [], set()
    for kk in np.flatnonzero(srel < NULL_TOL):
        v = V[:, kk] / d  # back to physical units
        v = v / np.max(np.abs(v))
        if v[np.argmax(np.abs(v))] < 0:
            v = -v
        direction = {names[i]: float(round(v[i], 4)) for i in range(p) if abs(v[i]) > 0.05}
        null.append({"direction": direction, "relative_singular_value": float(srel[kk])})
        inv = [i for i in range(p) if abs(v[i]) > 0.05]
        involved.update(inv)
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
    comb += [names[i] for i in range(p) if i not in involved]
    corr_pairs = {}
    if cov is not None and p:
        sd = np.sqrt(np.maximum(np.diag(cov), 1e-300))
        corr = cov / np.outer(sd, sd)
        for i in range(p):
            for j in range(i + 1, p):
                if abs(corr[i, j]) > CORR_REPORT:
                    corr_pairs[f"{names[i]}~{names[j]}"] = float(corr[i, j])
    return {"parameters": names, "relative_singular_values": [float(x) for x in srel],
            "condition_number": float(srel[0] / srel[-1]) if p and srel[-1] > 0 else float("inf"),
            "correlations": corr_pairs, "not_identifiable": null, "identifiable_combinations": comb}
