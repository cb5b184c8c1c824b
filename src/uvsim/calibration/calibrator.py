"""``Calibrator``: seed 000's GA calibration plus refinement, as one estimator.

>>> from uvsim.calibration import Calibrator
>>> cal = Calibrator(dofs="surge,yaw", population=60, generations=30, seed=1).fit(
...     "path/to/dataset", "bluerov2_heavy_initial")               # doctest: +SKIP
>>> cal.params_["X_udot"], cal.uncertainty_["X_udot"]            # doctest: +SKIP
>>> cal.report_["validation_rmse"]                                 # doctest: +SKIP

Fit = for every DOF: build the :class:`DofProblem` (Table 3 parameters, bounds
around the initial values, signal scales from the DOF's training runs), run the
GA (:func:`uvsim.calibration.ga.run_ga`) for all DOFs in lock step, refine each
DOF's best individual by least squares (:func:`uvsim.calibration.refine.refine_dof`),
assemble the fitted vehicle and evaluate it on the training and validation runs.
"""
from __future__ import annotations

import time
from pathlib import Path
from typing import Mapping

import numpy as np

from uvsim.calibration.batching import prepare_runs, simulate_dataset
from uvsim.calibration.evaluation import DEFAULT_BATCH_ROWS, BatchEvaluator, DaskMap, DofProblem, ProcessMap, SerialMap
from uvsim.calibration.ga import GASettings, fingerprint, run_ga
from uvsim.calibration.params import (
    DOF_PARAMETERS,
    EFFECTIVE_INERTIA,
    LINEAR_DAMPING,
    QUADRATIC_DAMPING,
    parameter_bounds,
    default_channel_weights,
    parse_dofs,
)
from uvsim.calibration.refine import identifiability, joint_residuals, refine_dof, refine_joint
from uvsim.errors import CalibrationError
from uvsim.logs import Dataset, read_dataset
from uvsim.metrics import channel_mask, check_weights, component_weights, pooled_rmse, run_metrics, signal_scales
from uvsim.plausibility import check_runs, parse_allow
from uvsim.vehicle import load_vehicle


#: The joint refinement's Jacobian copies are evaluated in this many chunks (spread
#: over the workers); a constant, so that serial and parallel runs compute the same
#: batches and give identical results.
JOINT_CHUNKS = 2
#: 1-sigma above this fraction of the value: reported as "weakly_determined".
WEAK_RELATIVE_SIGMA = 0.25


def _as_dataset(data) -> Dataset:
    if isinstance(data, Dataset):
        return data
    if isinstance(data, (str, Path)):
        return read_dataset(data)
    runs = list(data)
    if not runs:
        raise CalibrationError("no runs given")
    return Dataset(path=Path("."), vehicle=None, description="runs given in memory", runs=runs)


def _resolve_vehicle(vehicle, ds: Dataset):
    if vehicle is None:
        if ds.vehicle is None:
            raise CalibrationError(f"{ds.path}: no vehicle given and the manifest names none")
        vehicle = ds.vehicle_file or ds.vehicle
    return load_vehicle(vehicle)


def _group_amplitude(measured, scales) -> float:
    """RMS over logged groups of (the run's spread / group scale): how much the run moves."""
    sc = signal_scales([measured])
    vals = [sc[g] / scales[g] for g in sc if g in scales]
    return float(np.sqrt(np.mean(np.square(vals)))) if vals else 1.0


class Calibrator:
    """Calibrate a vehicle's inertia, added mass and damping to logged runs.

    Parameters
    ----------
    dofs : "surge,yaw" or a list; default: every DOF with training runs.
    population, generations, tournament, crossover, mutation : seed 000 Table 4
        (60, 30, 5, 0.5, 0.25).
    mutation_indpb, mutation_sigma, seeded_fraction, seeded_sigma : GA details the
        paper does not give (see :class:`uvsim.calibration.ga.GASettings`).
    seed : random seed; the same seed gives the identical result (also with workers).
    margin : default relative search range around each initial value (0.5 = +-50 %).
    bounds : {name: (low, high)} explicit bounds.
    signal_weights : weights by signal group ("position", "attitude", "velocity",
        "rates") and/or channel ("x", ..., "yaw", "u", ..., "r"), used for every DOF.
        Default: each DOF uses only its own channels (:data:`DOF_CHANNELS`, e.g.
        x and u for surge, roll and p for roll).
    noise : {group: 1-sigma noise} used as normalization scale instead of the
        measured spread.
    low_speed_exponent : run weight = manifest weight x (amplitude / median
        amplitude) ** -low_speed_exponent; 0 (default) uses the manifest weights
        only (seed 000: "weights ... to improve the low-speed movements").
    refine : run the least-squares refinement after the GA (default True).
    merge_inertia : "auto" | "always" | "never" (see :mod:`uvsim.calibration.refine`).
    estimate_initial_velocity : fit each run's unknown initial velocity (DOF axis) in
        the refinement.
    initial_velocity : "zero" | "differentiate" for unknown initial velocities.
    workers : local processes for the GA evaluations (1 = serial).
    dask : dask.distributed scheduler address or "local".
    batch_rows : largest number of trajectories per batched simulation.
    checkpoint : file written after every generation; resume : checkpoint to continue.
    progress : tqdm bar per generation.
    effects : extra force terms added to the vehicle (dicts or ForceTerm objects).
    max_nfev : least-squares function-evaluation limit per DOF and sweep.
    refine_sweeps : Jacobi sweeps of the per-DOF refinement (the DOFs of a sweep run
        in parallel on the workers): each DOF is refined with the other DOFs' values
        from the previous sweep, because the "decoupled" runs
        are not fully decoupled (e.g. a positively buoyant vehicle rises during a
        surge run, so the surge trajectory depends on the heave parameters through
        the Coriolis / Munk terms).  The GA itself is per DOF, as in seed 000.
    joint : after the sweeps, refine all DOFs' parameters together on every logged
        channel of all training runs (:func:`uvsim.calibration.refine.refine_joint`).
    joint_weights : signal weights of the joint fit (default: all channels 1).
    allow : names of plausibility checks (:mod:`uvsim.plausibility`) that may fail; every
        other check of the runs against the vehicle raises before the fit.

    Attributes (after :meth:`fit`)
    ------------------------------
    params_ : {name: fitted value} of every fitted parameter.
    uncertainty_ : {name: 1-sigma or None (not separately identifiable)}.
    ga_params_ : GA best values before refinement.
    vehicle_ : the fitted :class:`uvsim.vehicle.Vehicle`.
    initial_vehicle_ : the starting vehicle.
    logbook_ : {dof: deap.tools.Logbook}.
    identifiability_ : {dof: identifiability analysis}.
    report_ : the JSON-ready report (keys of issue 5).
    evaluations_, wall_seconds_ : GA fitness evaluations and total fit time.
    """

    def __init__(self, *, dofs=None, population: int = 60, generations: int = 30, seed: int = 0,
                 tournament: int = 5, crossover: float = 0.5, mutation: float = 0.25, mutation_indpb: float = 0.5,
                 mutation_sigma: float = 0.1, seeded_fraction: float = 0.1, seeded_sigma: float = 0.02,
                 margin: float = 0.5, bounds: Mapping | None = None, signal_weights: Mapping | None = None,
                 noise: Mapping | None = None, low_speed_exponent: float = 0.0, refine: bool = True,
                 merge_inertia: str = "auto", estimate_initial_velocity: bool = False,
                 initial_velocity: str = "zero", workers: int = 1, dask: str | None = None,
                 batch_rows: int = DEFAULT_BATCH_ROWS, checkpoint=None, resume=None, progress: bool = False,
                 effects=None, max_nfev: int = 20, refine_sweeps: int = 1, joint: bool = True,
                 joint_weights: Mapping | None = None, allow=()):
        self.dofs = dofs
        self.population, self.generations, self.seed = population, generations, seed
        self.tournament, self.crossover, self.mutation = tournament, crossover, mutation
        self.mutation_indpb, self.mutation_sigma = mutation_indpb, mutation_sigma
        self.seeded_fraction, self.seeded_sigma = seeded_fraction, seeded_sigma
        self.margin, self.bounds = margin, bounds
        self.signal_weights, self.noise, self.low_speed_exponent = signal_weights, noise, low_speed_exponent
        self.refine, self.merge_inertia = refine, merge_inertia
        self.estimate_initial_velocity, self.initial_velocity = estimate_initial_velocity, initial_velocity
        self.workers, self.dask, self.batch_rows = workers, dask, batch_rows
        self.checkpoint, self.resume, self.progress = checkpoint, resume, progress
        self.effects, self.max_nfev, self.refine_sweeps = effects, max_nfev, refine_sweeps
        self.joint, self.joint_weights = joint, joint_weights
        self.allow = allow

    # ------------------------------------------------------------------ helpers
    def get_params(self, deep: bool = True) -> dict:
        """Constructor arguments (scikit-learn convention)."""
        import inspect

        return {k: getattr(self, k) for k in inspect.signature(type(self).__init__).parameters if k != "self"}

    def _settings(self) -> GASettings:
        return GASettings(population=int(self.population), generations=int(self.generations),
                          tournament=int(self.tournament), crossover=float(self.crossover),
                          mutation=float(self.mutation), mutation_indpb=float(self.mutation_indpb),
                          mutation_sigma=float(self.mutation_sigma), seeded_fraction=float(self.seeded_fraction),
                          seeded_sigma=float(self.seeded_sigma), seed=int(self.seed))

    def _hook(self, evaluator):
        if self.dask:
            return DaskMap(evaluator, self.dask, workers=self.workers if self.workers > 1 else None)
        if self.workers is None or int(self.workers) <= 1:
            if self.workers is not None and int(self.workers) < 1:
                raise CalibrationError(f"workers must be >= 1, got {self.workers}")
            return SerialMap()
        return ProcessMap(evaluator, int(self.workers))

    # ------------------------------------------------------------------ fit
    def fit(self, dataset, vehicle=None) -> "Calibrator":
        """Fit to ``dataset`` (a :class:`uvsim.logs.Dataset`, a dataset directory or a
        list of Runs) starting from ``vehicle`` (name, file or Vehicle; default the
        manifest's vehicle).  Returns self."""
        t0 = time.perf_counter()
        ds = _as_dataset(dataset)
        veh = _resolve_vehicle(vehicle, ds)
        check_runs(ds.runs, veh, parse_allow(self.allow, "allow"))  # units, sampling, PWM range
        if self.effects:
            veh = veh.with_effects(list(self.effects))
        self.initial_vehicle_ = veh
        train = [r for r in ds.runs if r.split == "train"]
        present = [d for d in DOF_PARAMETERS if any(r.dof == d for r in train)]
        if self.dofs is None:
            dofs = present
            if not dofs:
                raise CalibrationError(f"{ds.path}: no training run is marked with a dof "
                                       f"({', '.join(DOF_PARAMETERS)}); nothing to calibrate")
        else:
            dofs = parse_dofs(self.dofs)
            missing = [d for d in dofs if d not in present]
            if missing:
                raise CalibrationError(f"{ds.path}: no training runs for dof(s) {missing} "
                                       f"(training runs exist for: {present or 'none'})")
        user_weights = check_weights(self.signal_weights) if self.signal_weights is not None else None
        runs = [r for d in dofs for r in train if r.dof == d]
        batch = prepare_runs(runs, initial_velocity=self.initial_velocity)
        base = veh.parameters()
        problems = {}
        for d in dofs:
            idx = np.array([i for i, r in enumerate(runs) if r.dof == d])
            measured = [batch.measured[i] for i in idx]
            scales = signal_scales(measured, self.noise)
            w = np.array([runs[i].weight for i in idx], float)
            if self.low_speed_exponent:
                amp = np.array([_group_amplitude(m, scales) for m in measured])
                w = w * (amp / np.median(amp)) ** (-float(self.low_speed_exponent))
            names = DOF_PARAMETERS[d]
            b = parameter_bounds(names, base, margin=self.margin, bounds=self.bounds)
            sw = user_weights if user_weights is not None else default_channel_weights(d)
            used = [g for g in scales if np.any(component_weights(g, sw) > 0)
                    and any(np.any(channel_mask(m).get(g, np.zeros(3, bool)) & (component_weights(g, sw) > 0))
                            for m in measured)]
            if not used:
                raise CalibrationError(
                    f"dof {d}: its training runs log none of the signals the fitness uses "
                    f"({[k for k, v in sw.items() if v > 0]}); logged: "
                    f"{sorted({g for m in measured for g in channel_mask(m)})}; set signal_weights")
            problems[d] = DofProblem(d, names, b[:, 0], b[:, 1], np.array([base[k] for k in names]), idx, w,
                                     scales, sw)
        evaluator = BatchEvaluator(veh, batch, problems, self.batch_rows)
        settings = self._settings()
        problem_key = fingerprint({
            "vehicle": veh.to_dict(), "runs": [(r.name, r.dof, r.weight, float(np.nansum(r.data.to_numpy())))
                                               for r in runs],
            "scales": {d: p.scales for d, p in problems.items()}, "bounds": {d: p.lower.tolist() + p.upper.tolist()
                                                                             for d, p in problems.items()},
            "weights": {d: p.run_weights.tolist() for d, p in problems.items()},
            "signal_weights": self.signal_weights, "initial_velocity": self.initial_velocity})
        hook = self._hook(evaluator)
        try:
            ga = run_ga(problems, evaluator, hook, settings, checkpoint=self.checkpoint, resume=self.resume,
                        progress=self.progress, problem_key=problem_key)
            t_ga = time.perf_counter()
            ga_values = {}
            for d in dofs:
                ga_values.update(dict(zip(problems[d].names, map(float, problems[d].decode(ga["best"][d])))))
            params, unc, ident, refine_info, eff_sigma = self._refine(hook, evaluator, dofs, ga_values)
        finally:
            hook.close()
        t_ref = time.perf_counter()
        self.ga_params_ = ga_values
        self.params_ = params
        self.uncertainty_ = unc
        self.identifiability_ = ident
        self.logbook_ = ga["logbooks"]
        self.evaluations_ = ga["evaluations"]
        self.vehicle_ = veh.with_parameters(params, name=f"{veh.name}_calibrated")
        self.dofs_ = dofs
        self._train_runs = runs
        self.report_ = self._report(ds, dofs, problems, ga, ga_values, refine_info, eff_sigma, t0, t_ga, t_ref)
        self.wall_seconds_ = self.report_["wall_seconds"]
        return self

    def _refine(self, hook, evaluator, dofs, ga_values):
        """Jacobi sweeps of per-DOF refinements (in the workers when there are any):
        in each sweep every DOF is refined with the other DOFs' values of the previous sweep."""
        params = dict(ga_values)
        unc: dict = {k: None for k in params}
        ident, refine_info, eff_sigma = {}, {}, {}
        merge = {d: self.merge_inertia for d in dofs}
        for sweep in range(int(self.refine_sweeps) if self.refine else 0):
            args = [(d, dict(params), merge[d], self.estimate_initial_velocity, self.max_nfev) for d in dofs]
            results = hook.run_tasks(evaluator, _refine_task, args)
            for d, ref in zip(dofs, results):
                merge[d] = "always" if ref["merged"] else "never"
                params.update(ref["values"])
                unc.update(ref["uncertainty"])
                eff_sigma[d] = ref["effective_inertia_sigma"]
                refine_info[d] = {k: ref[k] for k in ("merged", "initial_velocity", "cost", "nfev", "message",
                                                     "residual_rms")}
                refine_info[d]["sweeps"] = sweep + 1
        if self.refine and self.joint and len(dofs) > 1:
            all_measured = [evaluator.batch.measured[i] for p in evaluator.problems.values() for i in p.run_index]
            jw = check_weights(self.joint_weights, "joint_weights") if self.joint_weights is not None else None
            merged = {d: (refine_info[d]["merged"] if d in refine_info else None) for d in dofs}
            jscales = signal_scales(all_measured, self.noise)
            n_chunks = JOINT_CHUNKS

            def evaluate(cols, base, X):
                chunks = [c for c in np.array_split(X, min(n_chunks, len(X))) if len(c)]
                out = hook.run_tasks(evaluator, _joint_task, [(cols, base, jscales, jw, c) for c in chunks])
                return np.vstack(out)

            ref = refine_joint(evaluator.vehicle, evaluator.batch, evaluator.problems, params, merged, jscales,
                               weights=jw, max_nfev=self.max_nfev, evaluate=evaluate)
            params.update(ref["values"])
            unc.update(ref["uncertainty"])
            eff_sigma.update(ref["effective_inertia_sigma"])
            refine_info["joint"] = {k: ref[k] for k in ("cost", "nfev", "message", "residual_rms",
                                                        "residual_autocorrelation", "variance_inflation")}
        results = hook.run_tasks(evaluator, _ident_task, [(d, dict(params)) for d in dofs])
        ident = dict(zip(dofs, results))
        for d in dofs:  # what the data determine only loosely, and fits stopped by a bound
            prob = evaluator.problems[d]
            weak, at_bound = [], []
            for k, lo, hi in zip(prob.names, prob.lower, prob.upper):
                sg = unc.get(k)
                if sg is not None and sg > WEAK_RELATIVE_SIGMA * abs(params[k]):
                    weak.append(k)
                if min(abs(params[k] - lo), abs(params[k] - hi)) <= 1e-6 * (hi - lo):
                    at_bound.append(k)
            ident[d]["weakly_determined"] = weak
            ident[d]["at_bound"] = at_bound
        return params, unc, ident, refine_info, eff_sigma

    # ------------------------------------------------------------------ evaluation
    def predict(self, runs) -> list[dict]:
        """Simulated signals of ``runs`` with the fitted vehicle (:func:`simulate_dataset`)."""
        self._check_fitted()
        return simulate_dataset(self.vehicle_, runs, initial_velocity=self.initial_velocity)

    def _check_fitted(self):
        if not hasattr(self, "vehicle_"):
            raise CalibrationError("this Calibrator is not fitted yet; call fit(dataset, vehicle) first")

    def _evaluate(self, vehicle, runs) -> dict:
        """{run name: run_metrics} for runs (grouped by input kind for batching)."""
        out = {}
        groups: dict = {}
        for r in runs:
            groups.setdefault((r.input_kind, r.inputs.shape[1]), []).append(r)
        for grp in groups.values():
            batch = prepare_runs(grp, initial_velocity=self.initial_velocity)
            pred = simulate_dataset(vehicle, batch)
            for r, m, p in zip(grp, batch.measured, pred):
                out[r.name] = (m, p)
        return out

    def _report(self, ds, dofs, problems, ga, ga_values, refine_info, eff_sigma, t0, t_ga, t_ref) -> dict:
        fitted = self._evaluate(self.vehicle_, ds.runs)
        initial = self._evaluate(self.initial_vehicle_, ds.runs)

        def pooled(pairs, split):
            sel = [pairs[r.name] for r in ds.runs if r.split == split]
            return pooled_rmse(sel) if sel else {}

        per_run = {}
        for r in ds.runs:
            m = run_metrics(*fitted[r.name])
            m0 = run_metrics(*initial[r.name])
            per_run[r.name] = {
                "dof": r.dof, "split": r.split, "weight": r.weight,
                "rmse": {k: v for k, v in m.items() if k not in ("channels", "groups")},
                "nrmse": {c: v["nrmse"] for c, v in m["channels"].items()},
                "fit_percent": {**{c: v["fit_percent"] for c, v in m["channels"].items()},
                                **{g: v["fit_percent"] for g, v in m["groups"].items()}},
                "initial_rmse": {k: v for k, v in m0.items() if k not in ("channels", "groups")},
                "channels": m["channels"],
            }
        p = self.vehicle_.parameters()
        eff = {d: p[a] + p[b] for d, (a, b) in EFFECTIVE_INERTIA.items()}
        settings = self._settings()
        return {
            "vehicle": self.initial_vehicle_.name,
            "dataset": str(ds.path),
            "dofs": dofs,
            "parameters": dict(self.params_),
            "uncertainty": dict(self.uncertainty_),
            "initial_parameters": {k: float(self.initial_vehicle_.parameters()[k]) for k in self.params_},
            "ga_parameters": dict(ga_values),
            "bounds": {k: [float(lo), float(hi)] for d in dofs
                       for k, lo, hi in zip(problems[d].names, problems[d].lower, problems[d].upper)},
            "effective_inertia": eff,
            "effective_inertia_uncertainty": {d: eff_sigma.get(d) for d in dofs},
            "linear_damping": {d: p[k] for d, k in LINEAR_DAMPING.items()},
            "quadratic_damping": {d: p[k] for d, k in QUADRATIC_DAMPING.items()},
            "validation_rmse": pooled(fitted, "validation"),
            "training_rmse": pooled(fitted, "train"),
            "initial_validation_rmse": pooled(initial, "validation"),
            "initial_training_rmse": pooled(initial, "train"),
            "per_run": per_run,
            "identifiability": self.identifiability_,
            "refinement": refine_info,
            "signal_scales": {d: problems[d].scales for d in dofs},
            "run_weights": {self._train_runs[int(i)].name: float(w) for d in dofs
                            for i, w in zip(problems[d].run_index, problems[d].run_weights)},
            "evaluations": int(ga["evaluations"]),
            "generations_run": int(ga["generations_run"]),
            "ga_seconds": float(ga["wall_s"]),
            "refine_seconds": float(t_ref - t_ga),
            "wall_seconds": float(time.perf_counter() - t0),
            "settings": {**settings.__dict__, "margin": self.margin, "workers": self.workers, "dask": self.dask,
                         "batch_rows": self.batch_rows, "low_speed_exponent": self.low_speed_exponent,
                         "signal_weights": {d: problems[d].signal_weights for d in dofs},
                         "noise": dict(self.noise or {}),
                         "refine": self.refine, "merge_inertia": self.merge_inertia,
                         "refine_sweeps": self.refine_sweeps, "max_nfev": self.max_nfev, "joint": self.joint,
                         "initial_velocity": self.initial_velocity,
                         "estimate_initial_velocity": self.estimate_initial_velocity},
            "logbook": {d: [dict(rec) for rec in lb] for d, lb in ga["logbooks"].items()},
        }


def _vehicle_for(evaluator, dof, params):
    names = evaluator.problems[dof].names
    return evaluator.vehicle.with_parameters({k: v for k, v in params.items() if k not in names})


def _refine_task(evaluator, dof, params, merge, estimate_iv, max_nfev):
    """One DOF's refinement (runs in a worker): the other DOFs at ``params``."""
    prob = evaluator.problems[dof]
    veh_d = _vehicle_for(evaluator, dof, params)
    start = {k: params[k] for k in prob.names}
    a = identifiability(veh_d, evaluator.batch, prob, start) if merge == "auto" else None
    return refine_dof(veh_d, evaluator.batch, prob, start, merge_inertia=merge,
                      estimate_initial_velocity=estimate_iv, max_nfev=max_nfev, ident=a)


def _ident_task(evaluator, dof, params):
    prob = evaluator.problems[dof]
    return identifiability(_vehicle_for(evaluator, dof, params), evaluator.batch, prob,
                           {k: params[k] for k in prob.names})


def _joint_task(evaluator, cols, base, scales, weights, X):
    return joint_residuals(evaluator.vehicle, evaluator.batch, evaluator.problems, cols, base, scales, weights, X)
