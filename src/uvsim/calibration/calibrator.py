"""``Calibrator``: seed 000's GA per DOF, then one joint fit of every training run.

>>> from uvsim.calibration import Calibrator
>>> cal = Calibrator(population=60, generations=30, seed=1, free="z_b").fit(
...     "path/to/dataset")                                          # doctest: +SKIP
>>> cal.params_["X_udot"], cal.uncertainty_["X_udot"]            # doctest: +SKIP
>>> cal.report_["validation_rmse"]                                 # doctest: +SKIP

Fit (docs/calibration.md):

1. **GA** (global stage, seed 000 sec. 4.4, Tables 3-4): for every DOF with training runs
   marked with it (``dof: surge`` ... in the manifest), its Table 3 parameters on its
   own runs (:func:`uvsim.calibration.stages.ga_stage`, :func:`uvsim.calibration.ga.run_ga`,
   fitness :mod:`uvsim.calibration.fitness`).  Skipped when no run is marked (``dof: mixed``).
2. **Joint stage**: one windowed prediction-error fit (:func:`uvsim.fitting.fit`) of
   every training run (marked and mixed), from the GA's values (or the vehicle's),
   freeing the Table 3 parameters (rigid-body inertias fixed unless freed) of the GA's
   DOFs and, for mixed runs, every DOF's that the data excite
   (:mod:`uvsim.calibration.selection`), plus ``free`` minus ``fix``
   (:func:`uvsim.calibration.stages.joint_stage`, :mod:`uvsim.calibration.joint`).
3. **Report**: open-loop metrics of every run for the initial and the fitted vehicle
   (:mod:`uvsim.calibration.report`), uncertainties, identifiability.
"""
from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import Mapping

import numpy as np

from uvsim.calibration.evaluation import DEFAULT_BATCH_ROWS, DaskMap, ProcessMap, SerialMap
from uvsim.calibration.ga import GASettings
from uvsim.calibration.inputs import as_dataset, latency_setting, resolve_vehicle
from uvsim.calibration.joint import joint_checkpoint_path
from uvsim.calibration.latency_estimate import refit_with_latency
from uvsim.calibration.params import DOF_PARAMETERS, parse_dofs
from uvsim.calibration.report import build_report, evaluate_runs, identifiability_report
from uvsim.calibration.selection import check_bounds, effective_inertia_start, expand_names
from uvsim.calibration.stages import ga_stage, joint_stage
from uvsim.calibration import supply_voltage as supply
from uvsim.calibration import trade_off as trade
from uvsim.errors import CalibrationError
from uvsim.estimation.lag import attitude_lag_setting
from uvsim.fitting.evaluate import check_judge_horizon
from uvsim.fitting.objective import check_loss, continuity_factors
from uvsim.fitting.parameters import cb_not_below_cg, default_bounds, physical_bounds
from uvsim.latency import runs_for
from uvsim.measurements import measurements_for
from uvsim.plausibility import check_runs, parse_allow
from uvsim.progress import Progress, as_progress
from uvsim.fit_settings import DEFAULT_CONTINUITY, DEFAULT_HORIZONS, DEFAULT_SAMPLE_WEIGHTING  # noqa: F401
from uvsim.schema import check_workers, real_number, whole_number
from uvsim.signals import check_sample_weighting, check_signal_settings

log = logging.getLogger("uvsim")

class Calibrator:
    """Calibrate a vehicle to logged runs (module docstring).

    Parameters
    ----------
    dofs : "surge,yaw" or a list: the DOFs to fit (GA of the runs marked with them;
        the joint stage uses those runs, the unmarked / mixed ones, and the Table 3
        parameters of these DOFs only).  Default: every DOF.
    population, generations, tournament, crossover, mutation : seed 000 Table 4
        (60, 30, 5, 0.5, 0.25).
    mutation_indpb, mutation_sigma, seeded_fraction, seeded_sigma : GA details the
        paper does not give (see :class:`uvsim.calibration.ga.GASettings`).
    seed : random seed; the same seed gives the identical result (also with workers).
    margin : default relative search range of inertias, added masses and damping in the GA
        stage, and in the joint stage without priors (0.5 = +-50 %); other families:
        :func:`uvsim.fitting.parameters.default_bounds`. With priors (the default) the joint
        stage's bounds are physical limits only: :func:`uvsim.fitting.parameters.physical_bounds`.
    bounds : {name: (low, high)} explicit bounds (every stage).
    free : names or families (``"z_b,thruster_gain_*"``) freed in the joint stage in
        addition to the default set; fix : names or families never fitted.
    signal_weights : weights by group (position, depth, attitude, velocity, rates,
        acceleration) or channel; 0 leaves a signal out of every stage.  They multiply
        the GA's per-DOF channel selection (``ga_channels``).
    noise : 1-sigma noise levels by group or channel (default: estimated per run).
    ga_channels : "own" (each DOF's GA looks at its own channels,
        :data:`uvsim.calibration.params.DOF_CHANNELS`; seed 000) or "all".
    sample_weighting : "per_second" (default, :data:`DEFAULT_SAMPLE_WEIGHTING`): a channel
        logged at a lower rate than the run's fastest is weighted up by the ratio of the
        rates (a 10 Hz depth beside a 100 Hz IMU by 10), so every channel counts per second
        of log (:func:`uvsim.signals.per_second_factors`); "per_sample": every sample
        alike. Joint stage only (the GA's fitness already averages each channel over its own
        samples); channels logged at one rate (motion capture) are unaffected.
    low_speed_exponent : GA run weight = manifest weight x (amplitude / median
        amplitude) ** -low_speed_exponent; 0 (default): the manifest weights.
    refine : run the joint stage (default True).
    horizons : window lengths of the joint stage's continuation, s (None: whole runs); default
        :data:`DEFAULT_HORIZONS`, 2 s windows.  A whole-run stage scales each channel by its own RMS
        error of the free simulation (the verdict's measure).
    continuity : factors of the joint stage's continuity-defect sd at its last horizon, one
        stage each (:func:`uvsim.fitting.fit`); default :data:`DEFAULT_CONTINUITY`.  1 is
        diagnosis' softer setting, under which windows restart more freely.
    max_iter : Levenberg-Marquardt iterations per continuation stage (80). A last stage that
        stops there is not converged: the report's ``status.caveats`` says it is unfinished,
        beside the verdict on the model it reached.
    attitude_bias : fit a constant roll and pitch offset per run whose roll and pitch come
        from an attitude filter beside a gyro (joint stage; prior sd
        :data:`uvsim.fitting.objective.ATTITUDE_BIAS_SIGMA`, 0.01 rad; a fitted offset beyond
        3 prior sds is flagged).
    gyro_bias : fit a constant gyro bias per run (joint stage; the GA removes each run's
        median rate residual).
    acc_bias : fit a constant accelerometer offset (body axes) per run that logs an
        accelerometer (joint stage; prior sd the vehicle's ``sensors.imu.acc_bias_sd``, else
        :data:`uvsim.fitting.objective.ACC_BIAS_SIGMA`, 0.1 m/s^2; beyond 3 prior sds flagged).
    screen : free mixed runs' candidates only if the data excite them.
    attitude_lag : time constant (s) of the attitude filter that logged the Euler angles
        (a first-order lag in their measurement model, :mod:`uvsim.estimation.lag`), or
        "auto" (default): estimated from the training runs' gyro and angles, used when
        longer than 1.5 sample intervals; 0: none.
    latency : how late the logged sensors read relative to the logged inputs, s
        (:mod:`uvsim.latency`): None (default) the vehicle file's ``sensors.latency`` (0 when
        it states none); a number: that latency, for the start model too; "auto": the file's
        latency for the start, then estimated after the joint fit with the fitted model
        (:mod:`uvsim.calibration.latency_estimate`) and, when it lowers the windowed cost by
        at least 2 %, the joint fit is run again from its result with it.  The fitted vehicle
        file states the latency it was fitted with.
    supply_voltage : None (default) or "auto": after the joint fit (and the latency's), fit again
        with the start vehicle's thrusters on the T200 voltage family (``supply_voltage`` freed
        beside the first fit's parameters) and keep that fit when its open-loop Fit % on the
        *training* runs is higher in every channel (:mod:`uvsim.calibration.supply_voltage`);
        needs the vehicle's thrusters on the shipped ``t200_16v`` curve.
    trade_off : None (default) or "explore": when the verdict is a trade-off, fit again with the
        structure the worse channels point to freed (thruster positions, centre of buoyancy) and
        keep a refit whose verdict is *better* (:mod:`uvsim.calibration.trade_off`; the report's
        ``trade_off`` lists what was tried).
    initial_velocity : "zero" | "differentiate" for the GA's and the open-loop
        evaluation's unknown initial velocities (the joint stage estimates them).
    judge_horizon : what the verdict, the report's RMSEs and Fit % and the plots compare
        (:func:`uvsim.fitting.evaluate.judged_prediction`, as ``uvsim diagnose`` does): "auto"
        (default) free simulations of whole runs, or predictions over windows from the logged
        states on closed-loop logs: :data:`uvsim.fitting.evaluate.DECLARED_CLOSED_LOOP_HORIZON_S`
        when the manifest says a run was flown under an autopilot,
        :data:`uvsim.fitting.evaluate.CLOSED_LOOP_HORIZON_S` when the starting model's free
        simulation leaves the validation data; "whole"; or a window length in seconds.
    prior : the joint stage fits maximum a posteriori with the starting vehicle as the prior
        (default True): each free parameter's prior mean is the vehicle file's value, its
        width the file's ``uncertainty:`` entry or :func:`uvsim.fitting.priors.default_prior_sd`
        (50 %), and the data count with their effective information
        (:mod:`uvsim.fitting.priors`); False: least squares within the bounds only.
    loss : "linear" (default) or "huber": the joint stage's measurement residuals beyond
        3 noise sigmas cost linearly (spikes, dropouts, bursts of model error;
        :func:`uvsim.fitting.objective.robust_residuals`).
    workers : local processes (GA evaluations and joint stage; results do not depend on it).
    dask : dask.distributed scheduler address or "local" for the GA evaluations.
    batch_rows : largest number of trajectories per batched GA simulation.
    checkpoint : file written after every GA generation (the joint stage writes
        ``<checkpoint>.joint``); resume : checkpoint to continue from.
    progress : True: tqdm bars (GA generations, joint iterations); a :class:`uvsim.progress.Progress`:
        its bars or one line per stage (GA, joint fits, latency scan, free simulations).
    effects : extra force terms added to the vehicle (dicts or ForceTerm objects).
    allow : names of plausibility checks (:mod:`uvsim.plausibility`) that may fail; every
        other check of the runs against the vehicle raises before the fit.

    Attributes (after :meth:`fit`)
    ------------------------------
    params_ : {name: fitted value} (GA and joint stage).
    uncertainty_ : {name: 1-sigma (joint stage) or None}.
    ga_params_ : GA best values.
    fit_ : the joint stage's :class:`uvsim.fitting.FitResult` (None without it).
    vehicle_, initial_vehicle_ : fitted and starting :class:`uvsim.vehicle.Vehicle`.
    logbook_ : {dof: deap.tools.Logbook}.
    identifiability_ : the joint stage's identifiability analysis.
    report_ : the JSON-ready report (docs/calibration.md).
    evaluations_, wall_seconds_ : GA fitness evaluations and total fit time.
    """

    def __init__(self, *, dofs=None, population: int = 60, generations: int = 30, seed: int = 0,
                 tournament: int = 5, crossover: float = 0.5, mutation: float = 0.25, mutation_indpb: float = 0.5,
                 mutation_sigma: float = 0.1, seeded_fraction: float = 0.1, seeded_sigma: float = 0.02,
                 margin: float = 0.5, bounds: Mapping | None = None, free=None, fix=None,
                 signal_weights: Mapping | None = None, noise: Mapping | None = None, ga_channels: str = "own",
                 sample_weighting: str = DEFAULT_SAMPLE_WEIGHTING, low_speed_exponent: float = 0.0, refine: bool = True, horizons=DEFAULT_HORIZONS,
                 continuity=DEFAULT_CONTINUITY,
                 max_iter: int = 80, gyro_bias: bool = True, attitude_bias: bool = True, acc_bias: bool = True,
                 screen: bool = True,
                 attitude_lag="auto", latency=None, supply_voltage=None, trade_off=None,
                 initial_velocity: str = "zero", judge_horizon="auto", prior: bool = True, loss: str = "linear",
                 workers: int = 1, dask: str | None = None, batch_rows: int = DEFAULT_BATCH_ROWS, checkpoint=None,
                 resume=None, progress=False, effects=None, allow=()):
        self.dofs = dofs
        self.population, self.generations, self.seed = population, generations, seed
        self.tournament, self.crossover, self.mutation = tournament, crossover, mutation
        self.mutation_indpb, self.mutation_sigma = mutation_indpb, mutation_sigma
        self.seeded_fraction, self.seeded_sigma = seeded_fraction, seeded_sigma
        self.margin, self.bounds, self.free, self.fix = margin, bounds, free, fix
        self.signal_weights, self.noise, self.ga_channels = signal_weights, noise, ga_channels
        self.sample_weighting = sample_weighting
        self.low_speed_exponent, self.refine = low_speed_exponent, refine
        self.horizons, self.max_iter, self.gyro_bias, self.screen = horizons, max_iter, gyro_bias, screen
        self.continuity = continuity
        self.attitude_lag = attitude_lag
        self.latency = latency
        self.supply_voltage = supply_voltage
        self.trade_off = trade_off
        self.attitude_bias = attitude_bias
        self.acc_bias = acc_bias
        self.initial_velocity = initial_velocity
        self.judge_horizon = judge_horizon
        self.prior = prior
        self.loss = loss
        self.workers, self.dask, self.batch_rows = workers, dask, batch_rows
        self.checkpoint, self.resume, self.progress = checkpoint, resume, progress
        self.effects = effects
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

    def _workers(self) -> int:
        return 1 if self.workers is None else check_workers(self.workers, "workers", error=CalibrationError)

    def _hook(self, evaluator):
        if self.dask:
            return DaskMap(evaluator, self.dask, workers=self.workers if self.workers > 1 else None)
        return SerialMap() if self._workers() == 1 else ProcessMap(evaluator, self._workers())

    def _horizons(self) -> list:
        hs = [self.horizons] if isinstance(self.horizons, (int, float)) or self.horizons is None else self.horizons
        out = []
        for h in hs:
            if h is not None and not (isinstance(h, (int, float)) and np.isfinite(h) and h > 0):
                raise CalibrationError(f"horizons: expected positive window lengths in s (or None for whole runs), "
                                       f"got {h!r}")
            out.append(None if h is None else float(h))
        if not out:
            raise CalibrationError("horizons: give at least one window length")
        return out

    def _continuity(self) -> list:
        return continuity_factors(self.continuity)

    def _lag(self, runs) -> dict:
        """The attitude lag to use (``attitude_lag``) and how it was obtained."""
        return attitude_lag_setting(runs, self.attitude_lag)

    def _meas(self, runs, weights=None, **kw) -> list:
        kw.setdefault("sample_weighting", self.sample_weighting)
        return [measurements_for(r, self.initial_vehicle_, noise=self.noise, weights=weights,
                                 attitude_lag=self.lag_["tau"], **kw) for r in runs]

    def _check_settings(self) -> None:
        """The numeric and on/off settings, before any work: whole numbers are not truncated, strings
        not parsed, ranges not clipped (each a CalibrationError naming the setting)."""
        err = CalibrationError
        if not 0 < real_number(self.margin, "margin", error=err) < 1:
            raise err(f"margin {self.margin!r}: expected a fraction between 0 and 1 (0.5 = +-50 %)")
        if self.ga_channels not in ("own", "all"):
            raise err(f"ga_channels {self.ga_channels!r}: expected 'own' or 'all'")
        whole_number(self.population, "population", minimum=2, error=err)
        whole_number(self.generations, "generations", minimum=0, error=err)
        whole_number(self.tournament, "tournament", minimum=1, error=err)
        # random.seed(-1) is random.seed(1) (Python seeds with |n|) and numpy refuses negative seeds
        whole_number(self.seed, "seed", minimum=0, error=err, hint="; the same seed gives the same result")
        whole_number(self.max_iter, "max_iter", minimum=1, error=err)
        whole_number(self.batch_rows, "batch_rows", minimum=1, error=err)
        check_workers(self.workers, "workers", error=err, none_ok=True)
        check_judge_horizon(self.judge_horizon)
        for name in ("crossover", "mutation", "mutation_indpb", "mutation_sigma", "seeded_fraction", "seeded_sigma",
                     "low_speed_exponent"):
            real_number(getattr(self, name), name, error=err)  # not NaN, inf or text (GASettings checks ranges)
        for name in ("refine", "gyro_bias", "attitude_bias", "acc_bias", "screen", "prior", "progress"):
            if name == "progress" and isinstance(self.progress, Progress):
                continue
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise err(f"{name} {getattr(self, name)!r}: expected True or False (a string such as 'no' is true "
                          "in Python)")

    # ------------------------------------------------------------------ fit
    def fit(self, dataset, vehicle=None) -> "Calibrator":
        """Fit to ``dataset`` (a :class:`uvsim.logs.Dataset`, a dataset directory or a
        list of Runs) starting from ``vehicle`` (name, file or Vehicle; default the
        manifest's vehicle, also a file beside the manifest).  Returns self."""
        t0 = time.perf_counter()
        self._check_settings()  # before reading the runs, not after the GA
        self._progress = as_progress(bool(self.progress) if isinstance(self.progress, np.bool_) else self.progress)
        ds = as_dataset(dataset)
        veh = resolve_vehicle(vehicle, ds)
        check_runs(ds.runs, veh, parse_allow(self.allow, "allow"))  # units, sampling, PWM range
        if self.effects:
            veh = veh.with_effects(list(self.effects))
        if self.latency is not None and self.latency != "auto":
            veh = veh.with_latency(latency_setting(self.latency))
        self.initial_vehicle_ = veh
        check_loss(self.loss)
        check_sample_weighting(self.sample_weighting)
        check_signal_settings(self.noise, self.signal_weights)  # before the GA, not after it
        horizons = self._horizons()
        self._continuity()  # a bad value is an error before the GA, not after it
        base = veh.parameters()
        # the training runs as the vehicle predicts them (sensors.latency; uvsim.latency)
        train = runs_for(veh, [r for r in ds.runs if r.split == "train"])
        present = [d for d in DOF_PARAMETERS if any(r.dof == d for r in train)]
        if self.dofs is None:
            dofs, ga_dofs = list(DOF_PARAMETERS), present
        else:
            dofs = parse_dofs(self.dofs)
            missing = [d for d in dofs if d not in present]
            if missing and not any(r.dof in (None, "mixed") for r in train):
                raise CalibrationError(f"{ds.path}: no training runs for dof(s) {missing} "
                                       f"(training runs exist for: {present or 'none'})")
            ga_dofs = [d for d in dofs if d in present]
        runs = [r for r in train if r.dof in dofs or r.dof in (None, "mixed")]
        if not runs:
            raise CalibrationError(f"{ds.path}: no training runs (split: train) to calibrate with")
        if self.resume is not None and not Path(self.resume).is_file() \
                and not joint_checkpoint_path(self.resume).is_file():
            raise CalibrationError(f"checkpoint {self.resume} does not exist")
        self.lag_ = self._lag(runs)
        if self.latency == "auto" and not self.refine:
            raise CalibrationError("latency='auto' (--latency auto) is estimated after the joint fit; "
                                   "it needs refine=True (no --no-refine)")
        self.latency_ = self._latency_record(veh, None)
        if supply.check_setting(self.supply_voltage) == "auto":
            if not self.refine:
                raise CalibrationError("supply_voltage='auto' (--supply-voltage auto) refits after the joint fit; "
                                       "it needs refine=True (no --no-refine)")
            why = supply.not_applicable(veh)
            if why:
                raise CalibrationError(why)
        self.supply_voltage_ = None
        if trade.check_setting(self.trade_off) == "explore" and not self.refine:
            raise CalibrationError("trade_off='explore' (--trade-off explore) refits after the joint fit; it needs "
                                   "refine=True (no --no-refine)")
        bounds = check_bounds(self.bounds, base)
        fixed = expand_names(self.fix, list(base), "fix")
        extra = expand_names(self.free, list(base), "free")
        both = sorted(set(fixed) & set(extra))
        if both:
            raise CalibrationError(f"parameter(s) {both} are both freed and fixed")

        fitted = {k for d in dofs for k in DOF_PARAMETERS[d]} | set(extra)
        idle = sorted(k for k in bounds if k not in fitted or k in fixed)
        if idle:
            raise CalibrationError(f"bounds given for {idle}, which no stage fits; free them (free=..., --free) "
                                   "or drop their bounds")
        for k, b in bounds.items():  # before any work: the user's bounds keep the CB above the CG
            cb_not_below_cg(k, b, base, fitted, explicit=True)

        def bounds_of(k):  # explicit, else the default family bounds around the vehicle's value
            if k in bounds:
                return cb_not_below_cg(k, bounds[k], base, fitted, explicit=True)
            return cb_not_below_cg(k, default_bounds(k, float(base[k]), float(self.margin)), base, fitted)

        def joint_bounds_of(k):  # with priors: physical limits only (the prior keeps values near the file's)
            if k in bounds or not self.prior:
                return bounds_of(k)
            return cb_not_below_cg(k, physical_bounds(k, float(base[k]), float(self.margin)), base, fitted)

        # ---------------------------------------------------------------- GA stage
        ga_dofs = [d for d in ga_dofs if any(k not in fixed for k in DOF_PARAMETERS[d])]
        ga = {"best": {}, "logbooks": {}, "evaluations": 0, "generations_run": 0, "wall_s": 0.0}
        ga_values, problems = {}, {}
        self._ga_run_weights = {}
        if not self.refine and not ga_dofs:
            raise CalibrationError(f"{ds.path}: nothing to calibrate: no training run is marked with a DOF "
                                   f"({', '.join(DOF_PARAMETERS)}) for the GA, and refine=False (--no-refine) skips "
                                   "the joint fit that calibrates mixed runs")
        if ga_dofs:
            ga, ga_values, problems = ga_stage(self, veh, train, ga_dofs, fixed, bounds_of, base)
        t_ga = time.perf_counter()
        # ---------------------------------------------------------------- joint stage
        fit_res, screen = None, {"relative_sigma": {}, "not_excited": [], "threshold": None}
        params = dict(ga_values)
        meas = self._meas(runs, self.signal_weights)
        if self.refine:
            start, joint_bounds = effective_inertia_start(params, base, extra, fixed, joint_bounds_of, bounds)
            params.update(start)
            start_veh = veh.with_parameters(params) if params else veh
            def joint(start_vehicle, bounds, names=None, tag="", prior_mean=None):  # this fit's joint stage
                return joint_stage(self, ds, start_vehicle, runs, meas, dofs, ga_dofs, fixed, extra, bounds, horizons,
                                       tag=tag, names=names, prior_mean=prior_mean)

            fit_res, screen = joint(start_veh, joint_bounds)
            if self.latency == "auto" and fit_res is not None:
                first = fit_res
                fit_res, start_veh, scan = refit_with_latency(
                    lambda v, names, tag: joint(v, joint_bounds, names, tag)[0], start_veh, fit_res, runs, meas,
                    attitude_bias=bool(self.attitude_bias), progress=self._progress)
                self.latency_ = self._latency_record(start_veh, scan)
                if scan["use"]:
                    self.latency_["first_fit"] = {"cost": float(first.cost), "stages": first.stages,
                                                  "free_parameters": list(first.names)}
            if self.supply_voltage == "auto" and fit_res is not None:
                self.supply_voltage_, kept = supply.refit(
                    lambda v, bounds, names, mean: joint(v, bounds, names, ".supply",
                                                         mean if self.prior else None)[0],
                    veh, dict(params), start_veh, fit_res, runs, meas, joint_bounds, margin=float(self.margin),
                    prior_mean=self.initial_vehicle_.parameters(), initial_velocity=self.initial_velocity,
                    judge_horizon=self.judge_horizon)
                if kept is not None:
                    log.info("supply voltage %.2f V: better on the training runs, in every channel; keeping that fit",
                             self.supply_voltage_["value"])
                    fit_res, start_veh, veh, joint_bounds = kept
        t_ref = time.perf_counter()
        report_bounds = joint_bounds if self.refine else bounds_of

        def finish(res, label="fitted and starting"):  # params_, vehicle_, report_ ... of one joint result
            values, unc = dict(params), {k: None for k in params}
            if res is not None:
                values.update(res.values)
                unc.update({k: res.std.get(k) for k in res.values})
            self.ga_params_, self.params_, self.uncertainty_, self.fit_ = ga_values, values, unc, res
            self.screen_ = screen
            self.logbook_ = ga["logbooks"]
            self.evaluations_ = ga["evaluations"]
            self.vehicle_ = veh.with_parameters(values, name=f"{veh.name}_calibrated").with_latency(
                self.latency_["value"])
            self.dofs_ = ga_dofs
            self._train_runs = runs
            with self._progress.stage(f"free simulations of the {len(ds.runs)} runs with the {label} model "
                                      "(report, verdict)"):
                self.identifiability_ = identifiability_report(self)
                self.report_ = build_report(self, ds, runs, problems, ga, report_bounds, t0, t_ga, t_ref)
            return self.report_.get("verdict")

        verdict = finish(fit_res)
        self.trade_off_ = None
        if self.trade_off == "explore" and fit_res is not None and (verdict or {}).get("status") == "trade-off":
            first = fit_res
            warm = start_veh.with_parameters(first.values)

            mean = self.initial_vehicle_.parameters()
            if (self.supply_voltage_ or {}).get("used"):  # the kept voltage refit's prior (supply.refit)
                mean = {**mean, "supply_voltage": self.supply_voltage_["nominal_voltage"]}

            def refit(h, names):
                return joint(warm, joint_bounds, names, h.tag, mean if self.prior else None)[0]

            self.trade_off_, adopted = trade.explore(
                refit, lambda res: finish(res, "refitted"), verdict, first.values, list(first.names), fixed,
                list(start_veh.parameters()), self.initial_vehicle_.parameters())
            finish(adopted if adopted is not None else first)
            if adopted is not None:
                log.info("after a trade-off: keeping the fit with the %s freed", self.trade_off_["adopted"])
        self.report_["trade_off"] = self.trade_off_  # None: not asked, or the verdict was no trade-off
        if self.trade_off_ is not None and self.report_.get("verdict"):
            self.report_["verdict"]["message"] += f" ({trade.message(self.trade_off_)})"
        self.wall_seconds_ = self.report_["wall_seconds"]
        return self

    def _latency_record(self, veh, scan) -> dict:
        how = "auto" if self.latency == "auto" else ("file" if self.latency is None else "given")
        return {"value": float(veh.sensor_latency), "how": how, "scan": scan}

    # ------------------------------------------------------------------ results
    def predict(self, runs) -> dict:
        """Evaluation of ``runs`` with the fitted vehicle as the verdict judged them (the report's
        ``judged``: free simulations of whole runs, or windows on closed-loop logs;
        :func:`uvsim.calibration.report.evaluate_runs`; gyro biases of training runs from the
        joint stage)."""
        self._check_fitted()
        runs = list(runs)
        meas = self._meas(runs)
        gb = self.fit_.gyro_bias if self.fit_ is not None else None
        return evaluate_runs(self.vehicle_, runs, meas, gb, initial_velocity=self.initial_velocity,
                             judged_as=self.report_.get("judged"))

    def _check_fitted(self):
        if not hasattr(self, "vehicle_"):
            raise CalibrationError("this Calibrator is not fitted yet; call fit(dataset, vehicle) first")
