"""One diagnosis's runs and its fits through the simulator.

:class:`SimulatorFits` holds the training and validation runs, their measurement models, what
the training runs allow the equation error (their motions, used by the screening of its subclass
:class:`uvsim.diagnosis.selector.Selector`), the re-tuned base coefficients and the fits made so
far.  It fits a model on the training runs through the simulator (windowed prediction error,
:func:`uvsim.fitting.fit`), gives a model's validation costs and the validation runs' predictions
the verdict compares, and fits one candidate together with the current model's free parameters
with the evidence that judges it (:meth:`SimulatorFits.fit_candidate`,
:func:`uvsim.diagnosis.decision.compare`).  Every fit is stored under a fingerprint of what it
fitted, so a diagnosis interrupted and resumed from its checkpoint repeats no finished fit.
"""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from uvsim.checkpoint import fingerprint
from uvsim.diagnosis.candidates import Candidate, mirror_start
from uvsim.diagnosis.decision import compare
from uvsim.diagnosis.starts import candidate_starts
from uvsim.errors import CalibrationError, UvsimError, VehicleError
from uvsim.fitting import fit
from uvsim.fitting.equation_error import motion_or_why
from uvsim.fitting.dead_reckoning import dead_reckoned_xy
from uvsim.fitting.evaluate import open_loop, windowed
from uvsim.fitting.parameters import FreeParameter, ParameterSpace, default_bounds
from uvsim.fitting.verdict import score
from uvsim.forces import make_term
from uvsim.measurements import measurements_for
from uvsim.progress import as_progress

#: Decrease the Gauss-Newton model predicts for its own minimizer, relative to the cost, at
#: which a diagnosis fit stops (uvsim.fitting.solver): the decisions compare costs that differ
#: by percents (MIN_RELATIVE = 5 %), so 1e-4 is ample (1e-5 cost two more linearizations per fit for changes in the fifth digit;
#: docs/performance.md).
FTOL = 1e-4


def free_space(vehicle, free: Sequence[str], bounds: Mapping, start: Mapping, fixed: Mapping) -> ParameterSpace:
    """The parameter space of ``vehicle`` with ``free`` within ``bounds``, started at ``start``
    (clipped into the bounds; the vehicle's value where missing) and ``fixed`` values for the rest."""
    base = vehicle.parameters()
    fp = []
    for n in free:
        lo, hi = bounds[n]
        s0 = float(np.clip(start.get(n, base[n]), lo, hi))  # seeds may come from a screening at a bound
        fp.append(FreeParameter(n, s0, lo, hi))
    return ParameterSpace(fp, base, {k: v for k, v in fixed.items() if k not in free})


class SimulatorFits:
    """The runs and fits of one diagnosis (module docstring).

    ``store`` is a dict of finished fits by fingerprint (restored from a checkpoint), and
    ``on_fit(store)`` is called after every new fit (to save the checkpoint); ``say``: the
    progress (:func:`uvsim.progress.as_progress`: a callable(message) or a Progress), the fits
    and screenings are its stages."""

    def __init__(self, vehicle, train, val, *, retune, noise, weights, horizon, max_iter, workers, say,
                 store=None, on_fit=None, attitude_lag: float = 0.0):
        self.base_vehicle = vehicle
        #: What the verdict compares (:meth:`predictions`): None, free simulations of whole runs;
        #: a number, predictions over windows of that many seconds (closed-loop logs)
        self.judge_horizon: float | None = None
        self.train, self.val = train, val
        self.noise, self.weights = noise, weights
        self.horizon, self.max_iter, self.workers = horizon, max_iter, workers
        self.progress = as_progress(say)
        self.say = self.progress.say
        # the calibration's measurement model: logged Euler angles trail by the attitude filter's lag
        self.meas_tr = [measurements_for(r, vehicle, noise=noise, weights=weights, run_weight=1.0,
                                         attitude_lag=attitude_lag) for r in train]
        self.meas_va = [measurements_for(r, vehicle, noise=noise, weights=weights, run_weight=1.0,
                                         attitude_lag=attitude_lag) for r in val]
        # the equation error of every training run it can use; the others are named, with why
        motions = [motion_or_why(r) for r in train]
        self.motions = [m for m, _ in motions]
        #: every training run without x/y has a horizontal track from its attitude and DVL
        self.has_track = bool(train) and all(dead_reckoned_xy(r) is not None for r in train)
        self.motion_why = {r.name: why for r, (m, why) in zip(train, motions) if m is None}
        self._say_unscreened()
        self.retune = list(retune or [])
        p = vehicle.parameters()
        unknown = [n for n in self.retune if n not in p]
        if unknown:
            raise CalibrationError(f"retune: unknown base parameter(s) {unknown} of vehicle {vehicle.name}")
        self.retune_bounds = {n: default_bounds(n, p[n], 0.5) for n in self.retune}
        self.fits = 0
        self.not_observable: list = []
        self.store = {} if store is None else store
        self.on_fit = on_fit

    def _say_unscreened(self) -> None:
        """Say which training runs the equation-error screening cannot use, and why (it is in
        every step's report too, ``screening.not_used``)."""
        if not self.motion_why:
            return
        used = len(self.train) - len(self.motion_why)
        self.say(f"equation-error screening on {used} of {len(self.train)} training run(s); not used: "
                 + "; ".join(self.motion_why.values())
                 + ("" if used else "; the screening is off: each effect's simplest variant is fitted through "
                                    "the simulator"))

    # ---------------------------------------------------------------- models
    def vehicle_for(self, accepted: Sequence[Candidate], extra: Candidate | None = None):
        specs = [c.spec for c in accepted if c.spec is not None]
        if extra is not None and extra.spec is not None:
            specs.append(extra.spec)
        return self.base_vehicle.with_effects(specs) if specs else self.base_vehicle

    def space(self, vehicle, free: Sequence[str], bounds: Mapping, start: Mapping, fixed: Mapping) -> ParameterSpace:
        return free_space(vehicle, free, bounds, start, fixed)

    def _fit(self, kind: str, vehicle, space: ParameterSpace, runs, meas, max_iter: int, label: str):
        """``fit`` with the store: a fit already made (same model, free parameters, start and
        fixed values, runs) is taken from it."""
        key = fingerprint({"kind": kind, "effects": [e.to_dict() for e in vehicle.effects],
                           "free": [(p.name, p.start, p.lower, p.upper) for p in space.free],
                           "fixed": space.fixed, "runs": [r.name for r in runs], "max_iter": max_iter})
        if key in self.store:
            self.say(f"{label}: taken from the checkpoint")
            return self.store[key]
        res = fit(vehicle, runs, space, meas=meas, horizons=(self.horizon,), max_iter=max_iter,
                  workers=self.workers, ftol=FTOL)
        self.store[key] = res
        if self.on_fit is not None:
            self.on_fit(self.store)
        return res

    def fit_train(self, vehicle, space, label: str, max_iter: int | None = None):
        self.fits += 1
        with self.progress.stage(f"fit {self.fits}: {label} ({space.p} parameter(s)) on {len(self.train)} "
                                 "training run(s)"):
            return self._fit("train", vehicle, space, self.train, self.meas_tr,
                             self.max_iter if max_iter is None else max_iter, label)

    def val_cost(self, vehicle, values: Mapping) -> dict:
        """Per-window validation costs of a model with fixed parameters (nodes re-estimated)."""
        sp = ParameterSpace([], vehicle.parameters(), dict(values))
        res = self._fit("validation", vehicle, sp, self.val, self.meas_va, self.max_iter, "validation cost")
        w = np.concatenate(res.window_costs)
        return {"windows": w, "cost": float(w.sum()), "n": int(res.n_residuals),
                "per_entry": float(w.sum() / max(res.n_residuals, 1))}

    def validation(self, vehicle, values: Mapping) -> dict:
        """A model's validation costs (:meth:`val_cost`) with its open-loop blocks
        (:meth:`open_loop_blocks`) under ``open_loop``: what :func:`compare` reads."""
        vc = self.val_cost(vehicle, values)
        vc["open_loop"] = self.open_loop_blocks(vehicle, values)
        return vc

    def predictions(self, vehicle, values: Mapping | None = None) -> list[dict]:
        """The validation runs as the verdict compares them (the report's before/after RMSE and
        plots): free simulations of whole runs (:func:`uvsim.fitting.evaluate.open_loop`), or with
        :attr:`judge_horizon` set, predictions over windows of that many seconds from the logged
        states (:func:`uvsim.fitting.evaluate.windowed`, closed-loop logs)."""
        known = vehicle.parameters()
        over = {k: v for k, v in (values or {}).items() if k in known}
        if self.judge_horizon is None:
            return open_loop(vehicle, self.val, overrides=over, meas=self.meas_va)
        return windowed(vehicle, self.val, self.judge_horizon, overrides=over, meas=self.meas_va)

    def open_loop_blocks(self, vehicle, values: Mapping) -> dict:
        """The validation runs' predictions (:meth:`predictions`: free simulations from their
        logged starts, or windows of :attr:`judge_horizon` on closed-loop logs): ``meas``,
        ``preds`` (what :func:`uvsim.fitting.verdict.compare` compares), ``score`` (the pooled
        score, :func:`uvsim.fitting.verdict.score`; inf when a simulation diverges) and
        ``horizon_s`` (the windows' length, None for whole runs)."""
        preds = [o["pred"] for o in self.predictions(vehicle, values)]
        return {"meas": self.meas_va, "preds": preds, "score": score(self.meas_va, preds),
                "horizon_s": self.judge_horizon}

    def open_loop_cost(self, vehicle, values: Mapping) -> float:
        """The pooled score of the free simulations of the validation runs (:meth:`open_loop_blocks`);
        lower is better, inf when a simulation diverges."""
        return self.open_loop_blocks(vehicle, values)["score"]

    # ---------------------------------------------------------------- one candidate
    def current(self, accepted, values) -> dict:
        """The current model: vehicle, values, free parameters (re-tuned + accepted effects) and their bounds."""
        free = list(self.retune) + [n for a in accepted for n in a.free]
        bounds = {**self.retune_bounds, **{n: a.bounds[n] for a in accepted for n in a.free}}
        return {"vehicle": self.vehicle_for(accepted), "values": dict(values), "free": free, "bounds": bounds}

    def fit_candidate(self, c: Candidate, s, cur, val_cur) -> dict:
        """Output-error fit of ``c`` together with the current model's free parameters,
        and its validation cost."""
        clash = sorted(set(c.free) & set(cur["free"]))
        if clash:  # e.g. a fouled unit's reverse ratio beside an accepted per-thruster asymmetry
            return {"effect": c.effect, "variant": c.variant, "candidate": c, "free": c.free, "accepted": False,
                    "why": f"not fitted: {', '.join(clash)} already free in the current model"}
        vehicle_cur, values_cur = cur["vehicle"], cur["values"]
        veh = vehicle_cur.with_effects([c.spec]) if c.spec is not None else vehicle_cur
        # start from the screening estimate (the best of its multi-start); without one, from
        # the catalogue's starts
        catalogue = [{**values_cur, **st} for st in candidate_starts(c)]
        if s and s.get("values"):
            starts = [{**values_cur, **c.start, **s["values"]}]
            if s.get("multistart") and len(catalogue) > 1:
                starts += catalogue  # a tether: anchors in four directions beside the screening start
            if s.get("mirror"):
                starts.append({**starts[0], **mirror_start(c, starts[0])})
        else:
            starts = catalogue
        free = list(cur["free"]) + c.free
        bounds = {**cur["bounds"], **c.bounds}
        label = c.label + (f" + {len(cur['free'])} current" if cur["free"] else "")
        best = None
        for st in starts:
            sp = self.space(veh, free, bounds, st, values_cur)
            try:
                res = self.fit_train(veh, sp, label)
            except (UvsimError, np.linalg.LinAlgError):
                continue
            if best is None or res.cost < best.cost:
                best = res
        row = {"effect": c.effect, "variant": c.variant, "candidate": c, "free": c.free}
        if best is None:
            row.update(accepted=False, why="every fit failed")
            return row
        vals = {**values_cur, **best.values}
        problem = None
        if c.spec is not None:
            try:
                make_term(c.spec).with_parameters({k: v for k, v in best.values.items() if k in c.free})
            except VehicleError as exc:
                problem = f"fitted values are not physical: {exc}"
        vc = self.validation(veh, vals)
        cmp = compare(val_cur, vc, best, c)
        row.update(result=best, values={k: best.values[k] for k in c.free}, std={k: best.std.get(k) for k in c.free},
                   train_cost=best.cost, val=vc, compare=cmp, problem=problem,
                   open_loop_cost=vc["open_loop"]["score"],
                   at_bounds=[n for n in best.at_bounds if n in c.free], vehicle=veh, all_values=vals)
        return row
