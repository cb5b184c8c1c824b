"""One diagnosis's steps: screening by equation error, the order of the fits, their judgement.

:class:`Selector` is the :class:`~uvsim.diagnosis.simulator_fits.SimulatorFits` of a diagnosis
(its runs, measurement models and fits through the simulator) with the forward step:
:meth:`Selector.step` screens every candidate variant of :mod:`uvsim.diagnosis.candidates` on the
inverse-dynamics residual of the current model (:mod:`uvsim.fitting.equation_error`, no
simulation), picks each effect's variant and the effects to fit, fits them through the simulator
in screening order (:meth:`SimulatorFits.fit_candidate
<uvsim.diagnosis.simulator_fits.SimulatorFits.fit_candidate>`, together with the current model's
free parameters) and judges them (:mod:`uvsim.diagnosis.decision`).
"""
from __future__ import annotations

from contextlib import nullcontext

import numpy as np

from uvsim.diagnosis.candidates import (Candidate, catalogue, coupled_candidate, coupling_terms, mirror_start,
                                        observability)
from uvsim.diagnosis.decision import judge
from uvsim.diagnosis.regression import BaseBlock, ls_step, stepwise
from uvsim.diagnosis.screening import screen_candidates
from uvsim.diagnosis.simulator_fits import SimulatorFits
from uvsim.errors import UvsimError
from uvsim.fitting.equation_error import EquationError
from uvsim.fitting.parameters import GAIN_RANGE, ParameterSpace
from uvsim.fitting.worker_pool import WorkerPool

#: A variant is as good as the best of its effect when it removes this share of what the
#: best removes in the screening.
VARIANT_SHARE = 0.9
#: Candidates fitted through the simulator: at most ``top`` effects whose screening
#: reduction is at least this share of the best one's (and above SCREEN_FLOOR).
SCREEN_SHARE = 0.25
SCREEN_FLOOR = 0.01
#: After an accepted candidate, the next one is fitted too only if its screening reduction
#: is at least this share of the accepted one's (a close call the validation decides).
CLOSE_SHARE = 0.8
#: Effects that act mainly as forces (not moments): without linear velocities in the log
#: the equation error cannot rank them, so they are fitted through the simulator anyway.
FORCE_EFFECTS = ("tether", "ballast", "current")


def has_moment_arm(c: Candidate) -> bool:
    """Whether ``c`` frees where its force acts (an attachment or a position off the origin),
    so that it can exert a moment about the body origin."""
    return any(n.startswith(("tether_attach_", "ballast_x", "ballast_y", "ballast_z")) for n in c.free)


class Selector(SimulatorFits):
    """The screening and steps of one diagnosis (module docstring); its state, the runs and the
    fits through the simulator, and the arguments are :class:`SimulatorFits`'s."""

    # ---------------------------------------------------------------- the re-tune's start
    def seed_retune(self, vehicle) -> dict:
        """Equation-error estimate of the re-tuned base coefficients (the start of the
        baseline fit; damping and added mass enter the inverse dynamics linearly)."""
        motions = [m for m in self.motions if m is not None]
        if not motions or not self.retune:
            return {}
        with self.progress.stage(f"equation-error start for the {len(self.retune)} re-tuned coefficient(s)"):
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
        info = {"available": bool(motions), "runs": [m.name for m in motions], "not_used": dict(self.motion_why)}
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
        # one Jacobian for the families that are linear in their parameters and picked by
        # regression: the off-diagonal damping derivatives (forward stepwise, two of them)
        # and each thruster's gain (one variant per thruster)
        terms = [t for t in coupling_terms() if t not in cur["free"]] if coupled else []
        veh_c = veh0.with_effects([{"type": "coupled_damping", **{t: 0.0 for t in terms}}]) if terms else veh0
        gains = [f"thruster_gain_{i + 1}" for i in range(veh0.n_thrusters)]
        lin = list(cur["free"]) + terms + (gains if any(c.effect == "thruster_gain" for c in cands) else [])
        bnd = {**cur["bounds"], **{t: (-1e4, 1e4) for t in terms}, **{g: GAIN_RANGE for g in gains}}
        sp_l = self.space(veh_c, lin, bnd, vals0, vals0)
        J, rl = EquationError(veh_c, motions, sp_l, scale=ee0.scale).jacobian()
        J = J / sp_l.scale[:, None]  # per unit of each parameter
        nb = len(cur["free"])
        base = BaseBlock(J[:nb])  # the current parameters' columns, factored once for every candidate
        if coupled:
            cands = cands + [coupled_candidate(stepwise(J[nb:nb + len(terms)], rl, terms, k=2, base=base))]
        single = {}
        for i, g in enumerate(gains):
            col = nb + len(terms) + i
            if col < J.shape[0]:
                cp = base.project(J[col])  # the RSS grows by (g - g_hat)^2 |cp|^2 away from the optimum g_hat
                single[g] = (*ls_step(base, J[col], rl, [*cur["free"], g], {**vals0}), float(cp @ cp))
        order = sorted(cands, key=lambda c: (c.effect != "tether", c.complexity if c.effect == "tether" else 0,
                                             c.variant != "3d"))
        pool = self.workers if isinstance(self.workers, WorkerPool) else None
        res = screen_candidates(order, motions, cur, vals0, base, ee0.scale, single, rss0, pool=pool)
        return list(zip(order, res)), info

    # ---------------------------------------------------------------- one step
    def signals(self) -> tuple[bool, np.ndarray, float | None, bool]:
        """What the training runs log for the catalogue: (x/y, logged or dead-reckoned from the
        attitude and a DVL, :mod:`uvsim.fitting.dead_reckoning`; the reference position; the
        deepest z or depth, None without; depth or z)."""
        has_pos = any(r.has_position for r in self.train) or self.has_track
        p_ref = np.nanmean(np.array([np.where(np.isfinite(r.position[0]), r.position[0], 0.0) for r in self.train]),
                           axis=0)
        depths = [r.position[:, 2] for r in self.train if r.has_position and np.isfinite(r.position[:, 2]).any()]
        depths += [r.depth for r in self.train if r.has_depth]
        z_max = float(max(np.nanmax(z) for z in depths)) if depths else None
        has_depth = any(r.has_depth or (r.has_position and np.isfinite(r.position[:, 2]).any()) for r in self.train)
        return has_pos, p_ref, z_max, has_depth

    def step(self, accepted, values_cur, val_cur, *, exclude, only, top, k_step, variants=None,
             floor: float | None = None) -> dict:
        """One forward step on the model of ``accepted`` (module docstring).  ``floor``: only effects
        whose screening reduction reaches it are fitted (the challengers of the base model's thrust
        scale, :func:`uvsim.diagnosis.step_choice.base_effect_challenge`: an effect that removes less of
        the equation error than the scale is not fitted to compete with it); None: no floor."""
        cur = self.current(accepted, values_cur)
        vehicle_cur = cur["vehicle"]
        run0 = self.train[0]
        dt = float(np.median(np.concatenate([np.diff(r.t) for r in self.train])))
        has_pos, p_ref, z_max, has_depth = self.signals()
        cands = catalogue(input_kind=run0.input_kind, n_thrusters=vehicle_cur.n_thrusters, dt=dt, p_ref=p_ref,
                          has_position=has_pos, z_max=z_max, only=only, exclude=exclude, has_depth=has_depth,
                          base=vehicle_cur.parameters())
        # a base-model variant re-tunes nothing the model already frees (--retune, an accepted re-tune)
        cands = [c for c in cands if not set(c.free) & set(cur["free"])]
        if variants is not None:  # e.g. step 0: the thrust curve alone
            cands = [c for c in cands if c.variant in variants]
        self.not_observable = observability(
            has_position=has_pos, has_depth=has_depth, z_max=z_max, n_thrusters=vehicle_cur.n_thrusters,
            has_velocity=any(np.isfinite(r.velocity[:, :2]).any() for r in self.train))
        # variants whose extra parameters act through inertia are not screened: the equation
        # error cannot separate a piece's mass from the re-tuned added mass (step_choice.inertia_challenger)
        held = [c for c in cands if c.tags.get("open_loop")]
        cands = [c for c in cands if not c.tags.get("open_loop")]
        screening = None
        if any(m is not None for m in self.motions):
            screening = f"step {k_step}: screening {len(cands) + 1} candidate variant(s) by equation error"
        else:  # said at the start too (Selector._say_unscreened): the choice below is by simplicity alone
            self.say(f"step {k_step}: no equation-error screening (no training run allows it): the simplest variant "
                     "of each effect is fitted through the simulator")
        want_coupled = "coupled_damping" not in exclude and (only is None or "coupled_damping" in only)
        with self.progress.stage(screening) if screening else nullcontext():
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
        if floor is not None and ee_info.get("available"):
            choice = [x for x in choice if x[2] >= floor]
        fitted = []
        no_velocity = not any(m.have[:3].any() for m in self.motions if m is not None)
        if ee_info.get("available") and no_velocity:
            # the rotational equation error sees a ballast's moments w r only: its mirror (-w, -r)
            # has the same moments and the opposite vertical force, which only the simulator's
            # depth can tell apart (IMU + depth scenario 30007: a foam float fitted as a weight
            # at the mirrored point, open-loop depth 269 -> 479 mm); both starts are fitted
            choice = [(c, ({**s, "mirror": True} if s and mirror_start(c, s.get("values") or {}) else s), red)
                      for c, s, red in choice]
        if ee_info.get("available"):
            lead = choice[0][2] if choice else 0.0
            picked = [x for x in choice if x[2] >= max(SCREEN_SHARE * lead, SCREEN_FLOOR)][: max(top, 1)]
            if no_velocity and floor is None:
                # no linear velocities in the log (IMU + depth): the equation error has only the
                # rotational DOFs and cannot rank effects that act mainly as forces, so the
                # simplest variant of each of them that can exert a moment is fitted through the
                # simulator as well (without x/y and velocities, the gyro and the attitude, which
                # see the moment, carry most of what is logged: a pull at the body origin shows
                # only in depth and the accelerometer)
                have = {x[0].effect for x in picked}
                for eff in FORCE_EFFECTS:
                    lst = [(c, s) for c, s in by_effect.get(eff, []) if eff not in have]
                    lst = [cs for cs in lst if has_moment_arm(cs[0])] or lst
                    if lst:
                        c, s = min(lst, key=lambda cs: cs[0].complexity)
                        # its screening (rotational DOFs only) is no guide to where the force acts:
                        # the catalogue's multi-start as well
                        picked.append((c, {**(s or {}), "multistart": True}, 0.0))
        else:
            picked = choice
        # through the simulator in screening order; stop at the first accepted candidate unless
        # the next one screened nearly as well (then the validation decides between them)
        replaced: set = set()

        def fit_judged(c, s) -> bool:
            return self.fit_judged(c, s, cur, val_cur, fitted, screened, replaced)

        lead_ok = None
        for c, s, red in picked:
            if lead_ok is not None and red < CLOSE_SHARE * lead_ok:
                break
            if fit_judged(c, s) and lead_ok is None:
                lead_ok = red
        if lead_ok is None and ee_info.get("available"):
            # nothing accepted: the equation error is blunt for small effects in slow logs (10 Hz), so
            # the next effects by screening rank get an output-error fit too, up to `top` fits in all
            done = {id(r["candidate"]) for r in fitted}
            for c, s, red in choice:
                # a fit refused because a parameter ran to the edge of its range (the candidate absorbed
                # something it does not describe) does not use up the budget of `top` fits
                spent = sum(1 for r in fitted if not r.get("bound_rejected"))
                if spent >= max(top, 1) or len(fitted) >= 2 * max(top, 1):
                    break
                if id(c) in done:
                    continue
                if fit_judged(c, s):
                    break
        return {"screening": ee_info, "screened": rows, "fitted": fitted, "all_screened": screened, "cur": cur,
                "held": held}

    def fit_judged(self, c: Candidate, s, cur, val_cur, fitted: list, screened, replaced: set) -> bool:
        """Fit and judge ``c`` (its row appended to ``fitted``); a variant refused for a
        parameter on the edge of its search range is followed, once per effect (``replaced``),
        by the effect's best-screened variant in ``screened`` that does not have that parameter
        and was not fitted yet.  Why: a parameter the data drive to a search bound is one they
        do not pin, and the same effect without it may describe what was logged (pair 110: a
        cable with drag, taut beyond 2.7 m of slack, fitted as ``horizontal_full`` with the
        slack length on its 50 m bound, which switches the elastic pull off and leaves tension
        and drag).  True when a fit was accepted."""
        def one(cand, scr, **extra) -> dict:
            row = {**self.fit_candidate(cand, scr, cur, val_cur), **extra}
            row["accepted"], row["why"] = judge(row, val_cur)
            fitted.append(row)
            return row

        row = one(c, s)
        if row["accepted"] or not row.get("bound_rejected") or c.effect in replaced:
            return bool(row["accepted"])
        replaced.add(c.effect)
        hits = set(row["bound_hits"])
        done = {id(r["candidate"]) for r in fitted}
        alt = [(cc, ss) for cc, ss in screened if cc.effect == c.effect and id(cc) not in done
               and not hits & set(cc.free) and ss and ss.get("reduction", 0.0) > 0.0]
        if not alt:
            return False
        cc, ss = max(alt, key=lambda x: x[1]["reduction"])
        return bool(one(cc, ss, replaces=c.label)["accepted"])
