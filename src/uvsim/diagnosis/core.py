"""``diagnose``: residual -> candidate effects -> refit -> before/after, by forward selection.

Procedure (issue 10; docs/diagnose.md):

1. **Baseline.**  The given model, with the base coefficients named in ``retune``
   re-fitted, on the training runs by the windowed prediction error of
   :mod:`uvsim.fitting` (multiple shooting, node states and gyro biases as nuisance).
2. **Screen** (:mod:`uvsim.fitting.equation_error`): every candidate variant
   (:mod:`uvsim.diagnosis.candidates`) is fitted to the inverse-dynamics residual of the
   current model, which takes a fraction of a second and needs no simulation; its
   share of the residual it removes ranks the effects, picks each effect's variant
   (the simplest whose reduction is within :data:`VARIANT_SHARE` of the best variant's)
   and seeds the parameters.
3. **Fit** the ``top`` effects through the simulator (windowed output error, started
   from the screening estimate and from the catalogue's default start: a small
   multi-start), with the current model's parameters fixed.
4. **Judge** (:func:`_judge`): in the training fit, a Wald test of "the effect is off"
   with the cluster-robust covariance (windows as clusters, so autocorrelated residuals
   do not make it optimistic) must reject at :data:`WALD_P`; on the validation runs
   (node states re-estimated with the parameters fixed) the cost must drop by at least
   :data:`MIN_RELATIVE`, confirmed by a block bootstrap over windows
   (:mod:`uvsim.fitting.compare`) in :data:`VAL_LEVEL` of the resamples; and the fitted
   values must be physical (the effect's field ranges).  Among variants of one effect,
   the simplest that is not significantly worse than the best (bootstrap at
   :data:`LEVEL`) wins; among effects, the largest improvement.
5. **Forward selection.**  The accepted effect joins the model, everything chosen so far
   (plus ``retune``) is re-fitted together, and steps 2-4 repeat with the remaining
   effects until nothing significant is left or ``max_effects`` are in.
6. **Report** every step (before/after costs, each candidate's numbers and why it was
   or was not accepted), the open-loop validation RMSE of the given and the corrected
   model, and the corrected vehicle.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from uvsim.diagnosis.candidates import EFFECTS, Candidate, catalogue, coupled_candidate, coupling_terms
from uvsim.errors import CalibrationError, UvsimError, VehicleError
from uvsim.fitting import fit
from uvsim.fitting.compare import bootstrap_improvement
from uvsim.fitting.equation_error import EquationError, measured_motion
from uvsim.fitting.evaluate import open_loop, pooled
from uvsim.fitting.parameters import FreeParameter, ParameterSpace, default_bounds
from uvsim.forces import make_term
from uvsim.logs import Dataset, read_dataset
from uvsim.measurements import measurements_for
from uvsim.plausibility import check_runs, parse_allow
from uvsim.vehicle import load_vehicle

#: One-sided confidence level of "significantly better" (block bootstrap), used to compare
#: variants; the acceptance of an effect uses VAL_LEVEL together with the Wald test.
LEVEL = 0.99
#: Acceptance: the robust Wald test of "the effect is off" on the training fit must give a
#: p-value below WALD_P, and the validation cost must drop by MIN_RELATIVE with the drop
#: confirmed in VAL_LEVEL of the block-bootstrap resamples of the validation windows.  The
#: two pieces of evidence are complementary: on clean scenarios the Wald test alone accepted
#: spurious thruster lags (p ~ 1e-6) that made the validation runs worse, and a handful of
#: validation windows alone (two runs) cannot reach 99 % for a real but moderate effect.
WALD_P = 1e-4
VAL_LEVEL = 0.9
#: Smallest share of the validation cost an accepted effect must remove (practical
#: significance: with thousands of samples a 1 % improvement can be "significant").
MIN_RELATIVE = 0.05
#: A variant is as good as the best of its effect when it removes this share of what the
#: best removes in the screening.
VARIANT_SHARE = 0.9
#: Validation cost per residual entry (in squared noise sigmas) below which the model
#: is "at the noise level" (confidence "high").
AT_NOISE = 1.5
#: Candidates fitted through the simulator: at most ``top`` effects whose screening
#: reduction is at least this share of the best one's (and above SCREEN_FLOOR).
SCREEN_SHARE = 0.25
SCREEN_FLOOR = 0.01
#: Simpler variants of a winning effect are fitted and compared on validation only when
#: their screening reduction is at least this share of the winner's.
SIMPLER_SHARE = 0.5
#: At most this many simpler variants are fitted to challenge a winner (cost control).
MAX_SIMPLER = 1
#: After an accepted candidate, the next one is fitted too only if its screening reduction
#: is at least this share of the accepted one's (a close call the validation decides).
CLOSE_SHARE = 0.8
DEFAULT_HORIZON = 3.0
#: Relative cost decrease at which a diagnosis fit stops: the decisions compare costs
#: that differ by percents, so 1e-5 is ample.
FTOL = 1e-5


@dataclass
class Diagnosis:
    """Result of :func:`diagnose`.

    Attributes
    ----------
    report : JSON-serializable dict (keys in docs/diagnose.md).
    vehicle_before, vehicle_after : the given and the corrected vehicle.
    effects : accepted (Candidate, fitted values) in the order they were chosen.
    train, validation : the runs.
    open_loop_before, open_loop_after : per validation run, free-simulation results
        (:func:`uvsim.fitting.evaluate.open_loop`) of the given and corrected model.
    """

    report: dict
    vehicle_before: object
    vehicle_after: object
    effects: list
    train: list
    validation: list
    open_loop_before: list = field(repr=False, default_factory=list)
    open_loop_after: list = field(repr=False, default_factory=list)
    measurements_validation: list = field(repr=False, default_factory=list)


def _split(dataset: Dataset) -> tuple[list, list, str]:
    train, val = dataset.train, dataset.validation
    if val and train:
        return train, val, "from the manifest"
    runs = dataset.runs
    if len(runs) < 3:
        raise CalibrationError(f"{dataset.path}: need at least 3 runs to diagnose (training and validation), "
                               f"got {len(runs)}")
    val = runs[2::3]
    train = [r for r in runs if r not in val]
    return train, val, ("the manifest has no training/validation split: every third run is used for validation "
                        f"({', '.join(r.name for r in val)})")


class _Selector:
    """State and steps of one diagnosis (module docstring)."""

    def __init__(self, vehicle, train, val, *, retune, noise, weights, horizon, max_iter, workers, say):
        self.base_vehicle = vehicle
        self.train, self.val = train, val
        self.noise, self.weights = noise, weights
        self.horizon, self.max_iter, self.workers, self.say = horizon, max_iter, workers, say
        self.meas_tr = [measurements_for(r, vehicle, noise=noise, weights=weights, run_weight=1.0) for r in train]
        self.meas_va = [measurements_for(r, vehicle, noise=noise, weights=weights, run_weight=1.0) for r in val]
        self.motions = [measured_motion(r) for r in train]
        self.retune = list(retune or [])
        p = vehicle.parameters()
        unknown = [n for n in self.retune if n not in p]
        if unknown:
            raise CalibrationError(f"retune: unknown base parameter(s) {unknown} of vehicle {vehicle.name}")
        self.retune_bounds = {n: default_bounds(n, p[n], 0.5) for n in self.retune}
        self.fits = 0

    # ---------------------------------------------------------------- models
    def vehicle_for(self, accepted: Sequence[Candidate], extra: Candidate | None = None):
        specs = [c.spec for c in accepted if c.spec is not None]
        if extra is not None and extra.spec is not None:
            specs.append(extra.spec)
        return self.base_vehicle.with_effects(specs) if specs else self.base_vehicle

    def space(self, vehicle, free: Sequence[str], bounds: Mapping, start: Mapping, fixed: Mapping) -> ParameterSpace:
        base = vehicle.parameters()
        fp = []
        for n in free:
            lo, hi = bounds[n]
            s0 = float(np.clip(start.get(n, base[n]), lo, hi))  # seeds may come from a screening at a bound
            fp.append(FreeParameter(n, s0, lo, hi))
        return ParameterSpace(fp, base, {k: v for k, v in fixed.items() if k not in free})

    def fit_train(self, vehicle, space, label: str, max_iter: int | None = None):
        self.fits += 1
        self.say(f"fitting {label} ({space.p} parameter(s)) on {len(self.train)} training run(s)")
        return fit(vehicle, self.train, space, meas=self.meas_tr, horizons=(self.horizon,),
                   max_iter=self.max_iter if max_iter is None else max_iter, workers=self.workers, ftol=FTOL)

    def val_cost(self, vehicle, values: Mapping) -> dict:
        """Per-window validation costs of a model with fixed parameters (nodes re-estimated)."""
        sp = ParameterSpace([], vehicle.parameters(), dict(values))
        res = fit(vehicle, self.val, sp, meas=self.meas_va, horizons=(self.horizon,), max_iter=self.max_iter,
                  workers=self.workers, ftol=FTOL)
        w = np.concatenate(res.window_costs)
        return {"windows": w, "cost": float(w.sum()), "n": int(res.n_residuals),
                "per_entry": float(w.sum() / max(res.n_residuals, 1))}

    def seed_retune(self, vehicle) -> dict:
        """Equation-error estimate of the re-tuned base coefficients (the start of the
        baseline fit; damping and added mass enter the inverse dynamics linearly)."""
        motions = [m for m in self.motions if m is not None]
        if not motions or not self.retune:
            return {}
        self.say(f"equation-error start for the {len(self.retune)} re-tuned coefficient(s)")
        sp = self.space(vehicle, self.retune, self.retune_bounds, {}, {})
        try:
            return EquationError(vehicle, motions, sp).gauss_newton(iterations=3)["values"]
        except (UvsimError, np.linalg.LinAlgError, ValueError):
            return {}

    # ---------------------------------------------------------------- screening
    def screen(self, cur, cands: list, coupled: bool = True) -> tuple[list, dict]:
        """Equation-error reduction and seed of every candidate, each fitted together with
        the current model's free parameters (``cur``: vehicle, values, free, bounds), and the
        coupled-damping pick; returns (candidates with their screening numbers, info)."""
        motions = [m for m in self.motions if m is not None]
        info = {"available": bool(motions)}
        if not motions:
            return [(c, None) for c in cands], info
        veh0, vals0 = cur["vehicle"], dict(cur["values"])
        ee0 = EquationError(veh0, motions, ParameterSpace([], veh0.parameters(), vals0))
        if cur["free"]:  # the current model at its own equation-error optimum
            sp0 = self.space(veh0, cur["free"], cur["bounds"], vals0, vals0)
            vals0.update(EquationError(veh0, motions, sp0, scale=ee0.scale).gauss_newton(iterations=2)["values"])
        r0 = EquationError(veh0, motions, ParameterSpace([], veh0.parameters(), vals0), scale=ee0.scale).residuals(
            np.zeros((1, 0)))[0]
        rss0 = float(r0 @ r0)
        info.update(rss=rss0, n=int(r0.size), scale=ee0.scale.tolist())
        out = []
        # one Jacobian for the families that are linear in their parameters and picked by
        # regression: the off-diagonal damping derivatives (forward stepwise, two of them)
        # and each thruster's gain (one variant per thruster)
        terms = [t for t in coupling_terms() if t not in cur["free"]] if coupled else []
        veh_c = veh0.with_effects([{"type": "coupled_damping", **{t: 0.0 for t in terms}}]) if terms else veh0
        gains = [f"thruster_gain_{i + 1}" for i in range(veh0.n_thrusters)]
        lin = list(cur["free"]) + terms + (gains if any(c.effect == "thruster_gain" for c in cands) else [])
        bnd = {**cur["bounds"], **{t: (-1e4, 1e4) for t in terms}, **{g: (0.05, 1.5) for g in gains}}
        sp_l = self.space(veh_c, lin, bnd, vals0, vals0)
        J, rl = EquationError(veh_c, motions, sp_l, scale=ee0.scale).jacobian()
        J = J / sp_l.scale[:, None]  # per unit of each parameter
        nb = len(cur["free"])
        base_cols = list(range(nb))
        if coupled:
            cands = cands + [coupled_candidate(_stepwise(J[nb:nb + len(terms)], rl, terms, k=2, base=J[:nb]))]
        single = {}
        for i, g in enumerate(gains):
            col = nb + len(terms) + i
            if col < J.shape[0]:
                single[g] = _ls_step(J[base_cols + [col]], rl, [*cur["free"], g], {**vals0})
        tether_best = (np.inf, {})  # the best tether so far seeds the next (more general) variant
        order = sorted(cands, key=lambda c: (c.effect != "tether", c.complexity if c.effect == "tether" else 0,
                                             c.variant != "3d"))
        for c in order:
            if c.effect == "thruster_gain" and len(c.free) == 1 and c.free[0] in single:
                vals, rss = single[c.free[0]]
                out.append((c, {"reduction": max(0.0, 1.0 - rss / rss0), "values": vals}))
                continue
            veh = veh0.with_effects([c.spec]) if c.spec is not None else veh0
            best = None
            # a small multi-start on the cheap equation error (the global stage) for the first
            # tether; the more general ones start from the best simpler tether
            if c.effect == "tether" and tether_best[1]:
                starts = [{**c.start, **{k: v for k, v in tether_best[1].items() if k in c.free}}]
            else:
                starts = _starts(c)
            for st in starts:
                try:
                    r = self._joint_gn(veh, motions, c, cur, vals0, st, J[:nb], ee0.scale)
                except (UvsimError, np.linalg.LinAlgError, ValueError) as exc:
                    r = {"rss": np.inf, "values": {}, "error": str(exc)}
                if best is None or r["rss"] < best["rss"]:
                    best = r
            red = max(0.0, 1.0 - best["rss"] / rss0) if np.isfinite(best["rss"]) else 0.0
            if c.effect == "tether" and best.get("values") and best["rss"] < tether_best[0]:
                tether_best = (best["rss"], {k: v for k, v in best["values"].items() if k.startswith("tether_")})
            out.append((c, {"reduction": red, "values": best["values"], **({"error": best["error"]}
                                                                            if "error" in best else {})}))
        return out, info

    def _joint_gn(self, veh, motions, c: Candidate, cur, vals0: Mapping, start: Mapping, J_base: np.ndarray,
                  scale: np.ndarray, iterations: int = 2) -> dict:
        """Gauss-Newton on the equation error of candidate ``c`` together with the current
        free parameters: the candidate's columns are re-differentiated at every step, the
        current parameters' columns ``J_base`` (per unit, at ``vals0``) are reused (they move
        little), so a step costs ``1 + len(c.free)`` evaluations."""
        base = dict(vals0)
        names_b = list(cur["free"])
        lo_b = np.array([cur["bounds"][n][0] for n in names_b])
        hi_b = np.array([cur["bounds"][n][1] for n in names_b])
        xc = {n: float(start.get(n, c.start[n])) for n in c.free}
        best = None
        for it in range(iterations + 1):
            sp = self.space(veh, c.free, c.bounds, xc, base)
            ee = EquationError(veh, motions, sp, scale=scale)
            Jc, r = ee.jacobian()
            rss = float(r @ r)
            if best is None or rss < best["rss"]:
                best = {"rss": rss, "values": {**{n: base[n] for n in names_b}, **xc}}
            if it == iterations:
                break
            Jc = Jc / sp.scale[:, None]
            A = np.vstack([J_base, Jc]).T
            d, *_ = np.linalg.lstsq(A, -r, rcond=None)
            nb = len(names_b)
            if nb:
                b = np.clip(np.array([base[n] for n in names_b]) + d[:nb], lo_b, hi_b)
                base.update(zip(names_b, map(float, b)))
            xc = {n: float(np.clip(xc[n] + dd, *c.bounds[n])) for n, dd in zip(c.free, d[nb:])}
        return best

    # ---------------------------------------------------------------- one step
    def current(self, accepted, values) -> dict:
        """The current model: vehicle, values, free parameters (re-tuned + accepted effects) and their bounds."""
        free = list(self.retune) + [n for a in accepted for n in a.free]
        bounds = {**self.retune_bounds, **{n: a.bounds[n] for a in accepted for n in a.free}}
        return {"vehicle": self.vehicle_for(accepted), "values": dict(values), "free": free, "bounds": bounds}

    def step(self, accepted, values_cur, val_cur, *, exclude, only, top, k_step) -> dict:
        cur = self.current(accepted, values_cur)
        vehicle_cur = cur["vehicle"]
        run0 = self.train[0]
        dt = float(np.median(np.concatenate([np.diff(r.t) for r in self.train])))
        has_pos = any(r.has_position for r in self.train)
        p_ref = np.nanmean(np.array([np.where(np.isfinite(r.position[0]), r.position[0], 0.0) for r in self.train]),
                           axis=0)
        depths = [r.position[:, 2] for r in self.train if r.has_position and np.isfinite(r.position[:, 2]).any()]
        depths += [r.depth for r in self.train if r.has_depth]
        z_max = float(max(np.nanmax(z) for z in depths)) if depths else None
        cands = catalogue(input_kind=run0.input_kind, n_thrusters=vehicle_cur.n_thrusters, dt=dt, p_ref=p_ref, has_position=has_pos, z_max=z_max, only=only,
                          exclude=exclude)
        self.say(f"step {k_step}: screening {len(cands) + 1} candidate variant(s) by equation error")
        want_coupled = "coupled_damping" not in exclude and (only is None or "coupled_damping" in only)
        screened, ee_info = (self.screen(cur, cands, coupled=want_coupled) if cands
                             else ([], {"available": False}))
        # per effect: the simplest variant within VARIANT_SHARE of the best variant's reduction
        by_effect: dict = {}
        for c, s in screened:
            by_effect.setdefault(c.effect, []).append((c, s))
        choice = []
        for eff, lst in by_effect.items():
            if ee_info.get("available"):
                bestred = max(s["reduction"] for _, s in lst)
                ok = [(c, s) for c, s in lst if s["reduction"] >= VARIANT_SHARE * bestred]
                c, s = min(ok, key=lambda cs: (cs[0].complexity, -cs[1]["reduction"]))
                choice.append((c, s, bestred))
            else:
                c, s = min(lst, key=lambda cs: cs[0].complexity)
                choice.append((c, s, 0.0))
        choice.sort(key=lambda x: -x[2])
        rows = []
        for c, s, red in choice:
            rows.append({"effect": c.effect, "variant": c.variant, "screening_reduction": s["reduction"] if s else None,
                         "fitted": False})
        fitted = []
        if ee_info.get("available"):
            lead = choice[0][2] if choice else 0.0
            picked = [x for x in choice if x[2] >= max(SCREEN_SHARE * lead, SCREEN_FLOOR)][: max(top, 1)]
        else:
            picked = choice
        # through the simulator in screening order; stop at the first accepted candidate unless
        # the next one screened nearly as well (then the validation decides between them)
        lead_ok = None
        for c, s, red in picked:
            if lead_ok is not None and red < CLOSE_SHARE * lead_ok:
                break
            row = self.fit_candidate(c, s, cur, val_cur)
            row["accepted"], row["why"] = _judge(row, val_cur)
            fitted.append(row)
            if row["accepted"] and lead_ok is None:
                lead_ok = red
        if lead_ok is None and ee_info.get("available"):
            # nothing accepted: the equation error is blunt for small effects in slow logs (10 Hz), so
            # the next effects by screening rank get an output-error fit too, up to `top` fits in all
            done = {id(r["candidate"]) for r in fitted}
            for c, s, red in choice:
                if len(fitted) >= max(top, 1):
                    break
                if id(c) in done:
                    continue
                row = self.fit_candidate(c, s, cur, val_cur)
                row["accepted"], row["why"] = _judge(row, val_cur)
                fitted.append(row)
                if row["accepted"]:
                    break
        return {"screening": ee_info, "screened": rows, "fitted": fitted, "all_screened": screened, "cur": cur}

    def fit_candidate(self, c: Candidate, s, cur, val_cur) -> dict:
        """Output-error fit of ``c`` together with the current model's free parameters,
        and its validation cost."""
        vehicle_cur, values_cur = cur["vehicle"], cur["values"]
        veh = vehicle_cur.with_effects([c.spec]) if c.spec is not None else vehicle_cur
        # start from the screening estimate (the best of its multi-start); without one, from
        # the catalogue's starts
        starts = [{**values_cur, **c.start, **s["values"]}] if s and s.get("values") else \
            [{**values_cur, **st} for st in _starts(c)]
        free = list(cur["free"]) + c.free
        bounds = {**cur["bounds"], **c.bounds}
        best = None
        for st in starts:
            sp = self.space(veh, free, bounds, st, values_cur)
            try:
                res = self.fit_train(veh, sp, c.label + (f" + {len(cur['free'])} current" if cur["free"] else ""))
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
        vc = self.val_cost(veh, vals)
        cmp = bootstrap_improvement(val_cur["windows"], vc["windows"], level=LEVEL)
        cmp["wald"] = _wald(best, c)
        row.update(result=best, values={k: best.values[k] for k in c.free}, std={k: best.std.get(k) for k in c.free},
                   train_cost=best.cost, val=vc, compare=cmp, problem=problem,
                   at_bounds=[n for n in best.at_bounds if n in c.free], vehicle=veh, all_values=vals)
        return row


def _ls_step(J: np.ndarray, r: np.ndarray, names: Sequence[str], start: Mapping) -> tuple[dict, float]:
    """One Gauss-Newton step on the columns ``J`` (k, m) (per unit of each named parameter)
    from ``start``: (values, residual sum of squares of the linearization)."""
    coef, *_ = np.linalg.lstsq(J.T, -r, rcond=None)
    res = r + J.T @ coef
    vals = {n: float(start.get(n, 0.0 if not n.startswith("thruster_gain") else 1.0)) + float(c)
            for n, c in zip(names, coef)}
    return vals, float(res @ res)


def _stepwise(J: np.ndarray, r: np.ndarray, names: Sequence[str], k: int = 2, base: np.ndarray | None = None
              ) -> list[str]:
    """Forward stepwise selection of ``k`` regressors (rows of ``J``, (n_terms, m)) that,
    together with the ``base`` regressors (always in), best explain ``-r`` (least squares);
    at most one per force row (the first letter)."""
    chosen: list[int] = []
    B = np.zeros((0, J.shape[1])) if base is None else base
    for _ in range(k):
        best, best_rss = None, np.inf
        for j in range(J.shape[0]):
            if j in chosen or names[j][0] in {names[c][0] for c in chosen}:
                continue
            A = np.vstack([B, J[chosen + [j]]]).T
            coef, *_ = np.linalg.lstsq(A, -r, rcond=None)
            res = r + A @ coef
            rss = float(res @ res)
            if rss < best_rss:
                best, best_rss = j, rss
        if best is None:
            break
        chosen.append(best)
    return [names[j] for j in chosen]


def _starts(c: Candidate) -> list[dict]:
    """Start values of a candidate's multi-start: the catalogue start, plus for a tether
    anchors in four directions (the pull direction is what the data decide)."""
    if c.effect != "tether":
        return [dict(c.start)]
    out = []
    n0, e0 = c.start["tether_anchor_n"] + 5.0, c.start["tether_anchor_e"]  # the reference position
    for dn, de in ((-5.0, 0.0), (5.0, 0.0), (0.0, -5.0), (0.0, 5.0)):
        out.append({**c.start, "tether_anchor_n": n0 + dn, "tether_anchor_e": e0 + de})
    return out


def _wald(res, c: Candidate) -> dict:
    """In-sample Wald test of the effect being off (``c.null``) with the fit's cluster-robust
    covariance (windows as clusters, so correlated residuals within a window do not make it
    optimistic): ``W = (theta - theta_0)^T C^-1 (theta - theta_0)`` ~ chi^2_k under the null."""
    from scipy.stats import chi2

    null = c.null
    idx = [res.names.index(n) for n in null if n in res.names]
    if not idx:
        return {"W": None, "k": 0, "p": None}
    d = np.array([res.values[res.names[i]] - null[res.names[i]] for i in idx])
    C = res.covariance[np.ix_(idx, idx)]
    W = float(d @ np.linalg.pinv(C) @ d)
    return {"W": W, "k": len(idx), "p": float(chi2.sf(W, len(idx)))}


def _judge(row, val_cur) -> tuple[bool, str]:
    """The acceptance rule (module docstring): physical values, an in-sample robust Wald
    test of the effect being off at :data:`WALD_P`, and on the validation runs a
    reduction of the cost by at least :data:`MIN_RELATIVE` that the block bootstrap over
    windows confirms at :data:`VAL_LEVEL` (one-sided)."""
    if "compare" not in row:
        return False, row.get("why", "not fitted")
    cmp = row["compare"]
    if row["problem"]:
        return False, row["problem"]
    w = cmp.get("wald") or {}
    if w.get("p") is not None and not w["p"] < WALD_P:
        return False, (f"not significant in the training runs: robust Wald test p = {w['p']:.2g} "
                       f"(needs < {WALD_P:g}; the fitted effect is indistinguishable from none)")
    if cmp["relative"] < MIN_RELATIVE:
        return False, (f"does not help the validation runs: validation cost {-100 * cmp['relative']:+.1f} % "
                       f"(needs a reduction of >= {100 * MIN_RELATIVE:.0f} %)")
    if cmp["p_better"] < VAL_LEVEL:
        return False, (f"not confirmed on the validation runs: the cost drops {100 * cmp['relative']:.1f} % but "
                       f"the bootstrap over windows finds it better in only {100 * cmp['p_better']:.0f} % of "
                       f"resamples (needs {100 * VAL_LEVEL:.0f} %)")
    return True, (f"significant: Wald p = {w.get('p', float('nan')):.1g} in training, validation cost "
                  f"-{100 * cmp['relative']:.1f} % (better in {100 * cmp['p_better']:.1f} % of resamples)")


def diagnose(data, vehicle=None, *, retune: Sequence[str] | None = None, only: Sequence[str] | None = None,
             noise: Mapping[str, float] | None = None, weights: Mapping[str, float] | None = None,
             horizon: float = DEFAULT_HORIZON, max_effects: int = 2, top: int = 3, max_iter: int = 12,
             workers: int = 1, progress=None, allow=()) -> Diagnosis:
    """Diagnose which catalogue effects the model lacks (module docstring).

    Parameters
    ----------
    data : dataset directory (LOG_FORMAT) or a :class:`uvsim.logs.Dataset`.
    vehicle : the model (name, file or Vehicle); default the manifest's vehicle.
    retune : base coefficients re-fitted with every model (e.g. ``["X_uu", "N_rr"]``),
        within +-50 % (``uvsim.fitting.parameters.default_bounds``).
    only : restrict the candidate effects to these catalogue names.
    noise : 1-sigma noise by signal group or channel; estimated where not given.
    weights : weights by signal group or channel (0 leaves a channel out).
    horizon : window length of the fits, s.
    max_effects : largest number of effects added (forward selection steps).
    top : candidates fitted through the simulator per step (by screening rank).
    max_iter : Levenberg-Marquardt iterations per fit.
    workers : processes for the simulations.
    progress : callable(message).
    allow : names of plausibility checks (:mod:`uvsim.plausibility`) that may fail; every
        other finding is an error naming the file, column and row.
    """
    t_start = time.perf_counter()
    say = progress or (lambda msg: None)
    dataset = data if isinstance(data, Dataset) else read_dataset(data)
    if vehicle is None:
        vehicle = dataset.vehicle_file or dataset.vehicle
        if vehicle is None:
            raise CalibrationError(f"{dataset.path}: no vehicle given and the manifest names none")
    veh = load_vehicle(vehicle)
    check_runs(dataset.runs, veh, parse_allow(allow, "allow"))  # units, sampling, PWM range
    if only is not None:
        unknown = sorted(set(only) - set(EFFECTS))
        if unknown:
            raise CalibrationError(f"unknown candidate effect(s) {unknown}; known: {', '.join(EFFECTS)}")
    if not (isinstance(max_effects, int) and max_effects >= 1):
        raise CalibrationError(f"max_effects must be a positive integer, got {max_effects!r}")
    if not (horizon is None or (np.isfinite(horizon) and horizon > 0)):
        raise CalibrationError(f"horizon must be a positive number of seconds, got {horizon!r}")
    train, val, split_note = _split(dataset)
    kinds = {(r.input_kind, r.inputs.shape[1]) for r in train + val}
    if len(kinds) > 1:
        raise CalibrationError(f"{dataset.path}: runs mix input kinds {sorted(kinds)}; diagnose one kind at a time")
    sel = _Selector(veh, train, val, retune=retune, noise=noise, weights=weights, horizon=horizon,
                    max_iter=max_iter, workers=workers, say=say)

    # 1. baseline ----------------------------------------------------------------------
    values: dict = {}
    if sel.retune:
        start = sel.seed_retune(veh)
        sp = sel.space(veh, sel.retune, sel.retune_bounds, start, {})
        base_fit = sel.fit_train(veh, sp, "the baseline (re-tuned base coefficients)")
        values = dict(base_fit.values)
    say("validation cost of the baseline")
    val_given = sel.val_cost(veh, {})
    val_cur = sel.val_cost(veh, values) if values else val_given
    accepted: list = []
    accepted_values: list = []
    steps = []
    exclude: set = set()
    for k in range(1, max_effects + 1):
        st = sel.step(accepted, values, val_cur, exclude=exclude, only=only, top=top, k_step=k)
        table = []
        winners = [row for row in st["fitted"] if row.get("accepted")]
        best = _parsimonious(winners)
        if best is not None:
            best = _richer_challenger(sel, best, st, val_cur) or best
            best = _simplest_sufficient(sel, best, st, accepted, values, val_cur) or best
        for row in st["fitted"]:
            table.append(_row_report(row, best))
        step_rep = {"step": k, "before_cost_per_entry": val_cur["per_entry"], "screening": st["screening"],
                    "screened": st["screened"], "candidates": table, "chosen": None}
        if best is None:
            steps.append(step_rep)
            break
        c = best["candidate"]
        accepted.append(c)
        exclude.add(c.effect)
        # the candidate was fitted together with everything chosen before and the re-tuned
        # coefficients: its fit is the new model
        joint = best["result"]
        values = dict(best["all_values"])
        val_new = best["val"]
        step_rep.update(chosen=c.label, after_cost_per_entry=val_new["per_entry"],
                        joint_fit={"values": joint.values, "std": joint.std, "cost": joint.cost,
                                   "at_bounds": joint.at_bounds})
        steps.append(step_rep)
        accepted_values.append(joint)
        val_cur = val_new

    # result ------------------------------------------------------------------------------
    veh_after = sel.vehicle_for(accepted)
    if values:
        veh_after = veh_after.with_parameters(values)
    say("open-loop validation before / after")
    ol_before = open_loop(veh, val, meas=sel.meas_va)
    ol_after = open_loop(veh_after, val, meas=sel.meas_va)
    final = accepted_values[-1] if accepted_values else None
    effects_rep = []
    for c in accepted:
        effects_rep.append({"effect": c.effect, "variant": c.variant, "notes": c.notes,
                            "parameters": {n: {"value": values[n], "std": (final.std.get(n) if final else None),
                                               "unit": _unit(c, n)} for n in c.free}})
    at_noise = val_cur["per_entry"] <= AT_NOISE
    names = [c.effect for c in accepted]
    if accepted:
        confidence = "high" if at_noise else "partial"
        msg = (f"{' + '.join(c.label for c in accepted)}: validation cost {val_given['per_entry']:.2f} -> "
               f"{val_cur['per_entry']:.2f} squared noise sigmas per residual. "
               + ("The residual is now at the noise level." if at_noise else
                  "Something the catalogue does not explain remains (the cost is above the noise level)."))
    else:
        confidence = "none"
        msg = ("none: no catalogue effect removes a significant part of the validation cost "
               f"({val_cur['per_entry']:.2f} squared noise sigmas per residual). "
               + ("The model is at the noise level." if at_noise else
                  "The cost is above the noise level: an effect outside the catalogue, or base coefficients to "
                  "calibrate (uvsim calibrate, or --retune)."))
    report = {
        "effects": effects_rep,
        "effect": names[0] if len(names) == 1 else ("none" if not names else "+".join(names)),
        "confidence": confidence,
        "message": msg,
        "retuned": {n: {"value": values.get(n), "before": veh.parameters()[n]} for n in sel.retune},
        "steps": steps,
        "rmse_before": pooled(ol_before),
        "rmse_after": pooled(ol_after),
        "validation_cost_per_entry": {"given": val_given["per_entry"], "baseline": steps[0]["before_cost_per_entry"]
                                      if steps else val_given["per_entry"], "final": val_cur["per_entry"]},
        "criterion": {"method": "block bootstrap over validation windows (uvsim.fitting.compare)",
                      "level": LEVEL, "min_relative": MIN_RELATIVE, "horizon_s": horizon,
                      "variant_share": VARIANT_SHARE, "at_noise": AT_NOISE},
        "noise": {r.name: m.describe() for r, m in zip(train + val, sel.meas_tr + sel.meas_va)},
        "sampling_notes": [n for m in sel.meas_tr + sel.meas_va for n in m.notes],
        "vehicle": veh.name,
        "data": str(dataset.path),
        "runs": {"train": [r.name for r in train], "validation": [r.name for r in val], "split": split_note},
        "fits": sel.fits,
        "seconds": time.perf_counter() - t_start,
    }
    return Diagnosis(report, veh, veh_after, list(zip(accepted, [dict(values) for _ in accepted])), train, val,
                     ol_before, ol_after, sel.meas_va)


def _parsimonious(winners: list):
    """Among the accepted candidates of a step, the one with the fewest parameters whose
    validation cost is not significantly worse (bootstrap at :data:`LEVEL`) than the best's
    (two effects can describe the same force: a constant-tension tether pulling straight
    down is a ballast); ties by the lower validation cost.  None without a winner."""
    if not winners:
        return None
    top = min(winners, key=lambda r: r["val"]["cost"])
    ok = [r for r in winners
          if r is top or not bootstrap_improvement(r["val"]["windows"], top["val"]["windows"], level=LEVEL)["significant"]]
    return min(ok, key=lambda r: (r["candidate"].complexity, r["val"]["cost"]))


def _richer_challenger(sel, best, st, val_cur):
    """The winning effect's variant that removed most of the equation error, when that is
    not the winner (the screening prefers the simplest of near-equals, but it is blunt to
    details such as a tether's pull law): fitted, and it replaces the winner when it is
    significantly better on validation (bootstrap at :data:`LEVEL`, by at least
    :data:`MIN_RELATIVE`).  Returns the new winner or None."""
    c = best["candidate"]
    same = [(cc, s) for cc, s in st["all_screened"] if cc.effect == c.effect and s]
    if not same:
        return None
    top_c, top_s = max(same, key=lambda cs: cs[1].get("reduction", 0.0))
    if top_c is c or top_c.complexity <= c.complexity:
        return None
    row = sel.fit_candidate(top_c, top_s, st["cur"], val_cur)
    if "compare" not in row:
        return None
    ok, why = _judge(row, val_cur)
    row["accepted"], row["why"] = ok, why
    st["fitted"].append(row)
    if not ok:
        return None
    better = bootstrap_improvement(best["val"]["windows"], row["val"]["windows"], level=LEVEL)
    if better["p_better"] >= VAL_LEVEL and better["relative"] >= MIN_RELATIVE:
        row["why"] = why + f"; significantly better than {c.variant} on validation"
        return row
    return None


def _simplest_sufficient(sel, best, st, accepted, values, val_cur):
    """Among the winning effect's variants simpler than the winner, the simplest that is
    not significantly worse than it on validation (fitted here); None to keep the winner."""
    c = best["candidate"]
    red = {id(cc): (s or {}).get("reduction", 0.0) for cc, s in st["all_screened"]}
    # simpler variants that the screening does not already rule out (at least half the winner's reduction)
    simpler = [cc for cc, _ in st["all_screened"] if cc.effect == c.effect and cc.complexity < c.complexity
               and red[id(cc)] >= SIMPLER_SHARE * red.get(id(c), 0.0)]
    simpler.sort(key=lambda cc: cc.complexity)
    simpler = simpler[:MAX_SIMPLER]
    for cc in simpler:
        s = next((s for x, s in st["all_screened"] if x is cc), None)
        row = sel.fit_candidate(cc, s, st["cur"], val_cur)
        if "compare" not in row:
            continue
        ok, why = _judge(row, val_cur)
        if not ok:
            continue
        worse = bootstrap_improvement(row["val"]["windows"], best["val"]["windows"], level=LEVEL)
        if not worse["significant"]:
            row["accepted"], row["why"] = True, why + f"; simplest variant as good as {c.variant}"
            st["fitted"].append(row)
            return row
    return None


def _unit(c: Candidate, name: str) -> str:
    if c.spec is None:
        return "m" if name.startswith("thruster_") and name.split("_")[1] in "xyz" else "-"
    try:
        term = make_term(dict(c.spec))
        return term.units().get(name, "") if hasattr(term, "units") else ""
    except UvsimError:
        return ""


def _row_report(row, best) -> dict:
    out = {"effect": row["effect"], "variant": row["variant"], "free": list(row["free"]),
           "accepted": bool(row.get("accepted")), "chosen": row is best, "why": row.get("why", "")}
    if "compare" in row:
        out.update(values=row["values"], std=row["std"], train_cost=row["train_cost"],
                   validation_cost_per_entry=row["val"]["per_entry"], compare=row["compare"],
                   at_bounds=row["at_bounds"])
    return out


def save_fixed_vehicle(diag: Diagnosis, path):
    """Write the corrected vehicle with provenance comments."""
    from uvsim.vehicle import save_vehicle

    rep = diag.report
    ann = {}
    for e in rep["effects"]:
        for k, d in e["parameters"].items():
            std = d.get("std")
            key = k.split("_", 1)[1] if k.startswith(e["effect"] + "_") else k
            ann[key] = f"diagnosed: {d['value']:.6g}" + (f" +- {std:.2g}" if std is not None else "") + f" {d['unit']}"
    header = (f"{diag.vehicle_after.name}: corrected by `uvsim diagnose` on {rep['data']}\n"
              f"effects: {rep['effect']} ({rep['confidence']}); {rep['message']}\n"
              f"validation RMSE before {rep['rmse_before']} after {rep['rmse_after']}")
    return save_vehicle(diag.vehicle_after, path, header=header, annotations=ann)
