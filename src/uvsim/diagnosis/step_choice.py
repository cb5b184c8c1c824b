"""Which candidate a step keeps, and whether the effects chosen before stay.

Every candidate fitted here is judged by :func:`uvsim.diagnosis.decision.judge`; what is decided
here is which of the judged ones the diagnosis names.

* :func:`parsimonious` -- among accepted candidates of one step, the simplest that is not
  clearly worse than the best (:func:`clearly_better`: two effects can describe one force).
* :func:`richer_challenger`, :func:`simplest_sufficient` -- among the variants of the
  winning effect, a richer one replaces the winner only when significantly better on
  validation, and a simpler one when its validation cost is within MIN_RELATIVE of the
  winner's.
* :func:`alternative_challenger` -- a variant that is an alternative to the winner with as
  many parameters (a thrust lag that starts at rest rather than at the command) is fitted
  too, and the lower open-loop validation cost wins (the runs' starts are what differ); also
  for a variant the open-loop verdict alone refused.
* :func:`inertia_challenger` -- the winner's richer variant whose extra parameters act through
  inertia (a ballast piece's own mass) wins on a lower open-loop validation cost.
* :func:`blocked_fallback` -- when no candidate of a step is accepted, the challengers of each one
  the open-loop verdict alone refused get their chance.
* :func:`unit_beside_base` -- when every unit's gain wins the challenge of the base model's
  thrust curve (:func:`base_effect_challenge`), the curve plus the one outlying unit
  (:func:`outlying_unit`), which the winner nests, replaces it when as good on validation.
* :func:`still_needed` -- backward elimination: with two effects in, the earlier one is
  judged again on top of a model without it, and dropped when no longer significant (the
  diagnosis then takes another forward step).

The thresholds shared with the acceptance (LEVEL, VAL_LEVEL, MIN_RELATIVE) are
:mod:`uvsim.diagnosis.decision`'s; docs/diagnose.md gives the method and its references.
"""
from __future__ import annotations

import numpy as np

from uvsim.diagnosis.candidates import BASE_MODEL, inertia_start
from uvsim.diagnosis.decision import LEVEL, MIN_RELATIVE, VAL_LEVEL, clearly_better, compare, judge
from uvsim.diagnosis.units import farthest_from_median
from uvsim.errors import UvsimError
from uvsim.fitting.compare import bootstrap_improvement

#: Simpler variants of a winning effect are fitted and compared on validation only when
#: their screening reduction is at least this share of the winner's.
SIMPLER_SHARE = 0.5
#: At most this many simpler variants are fitted to challenge a winner (cost control).
MAX_SIMPLER = 1


def still_needed(sel, accepted: list, values: dict, val_cur: dict, joint) -> tuple[list, dict, dict, object, list]:
    """Backward elimination (the second half of stepwise selection, Efroymson 1960): once
    later effects are in, each earlier effect must still earn its place.  For every accepted
    effect but the last (judged already against the others), the model without it is
    re-fitted (from the joint values) and the effect is judged (:func:`judge`, the same
    rule as when it entered) as a candidate on top of that model; an effect that is no
    longer significant there is dropped.  Why: forward selection takes the best single
    explanation first, and a flexible effect can stand in for the one still missing (IMU +
    depth scenario 30007: a tether from a 3-D attachment point took up a foam piece's
    buoyancy in step 1, the piece entered in step 2, and the tether stayed, Wald p = 0.11
    beside it).  The open-loop guard, which the effect passed when it entered, does not
    drop it here: the joint model passed the verdict against the model before the later
    effect, and a guard-only refusal removed a real thruster lag beside a weak thruster
    (benchmark seed 118, significant in training and on the windowed validation; the
    later effect's own re-fit without it simulated the position better).  The base-model
    step is not re-judged.

    ``accepted``: the chosen candidates in order; ``values``: the joint fit's values;
    ``val_cur``: its validation costs (with ``open_loop``); ``joint``: its fit result.
    Returns (accepted, values, val_cur, joint, report rows) after the drops."""
    rows = []
    for c in [a for a in accepted[:-1] if a.effect != BASE_MODEL]:
        if len([a for a in accepted if a.effect != BASE_MODEL]) < 2:
            break
        reduced = [a for a in accepted if a is not c]
        cur = sel.current(reduced, {k: v for k, v in values.items() if k not in c.free})
        veh = cur["vehicle"]
        sp = sel.space(veh, cur["free"], cur["bounds"], values, cur["values"])
        try:
            res = sel.fit_train(veh, sp, f"the model without {c.label} (is it still needed?)")
        except (UvsimError, np.linalg.LinAlgError) as exc:
            rows.append({"effect": c.effect, "variant": c.variant, "kept": True,
                         "why": f"the model without it could not be fitted ({exc}); kept"})
            continue
        vals = {**cur["values"], **res.values}
        vc = sel.validation(veh, vals)
        cmp = compare(vc, val_cur, joint, c)
        row = {"candidate": c, "problem": None, "compare": cmp, "values": {n: values[n] for n in c.free},
               "at_bounds": [n for n in joint.at_bounds if n in c.free]}
        ok, why = judge(row, vc)
        if not ok and row.get("guard_blocked"):
            ok, why = True, f"still significant beside the later effect; the open-loop verdict ({why}) is the entry rule"
        rows.append({"effect": c.effect, "variant": c.variant, "kept": bool(ok), "why": why, "compare": cmp,
                     "validation_cost_per_entry_without": vc["per_entry"]})
        if not ok:
            accepted, values, val_cur, joint = reduced, vals, vc, res
    return accepted, values, val_cur, joint, rows


def parsimonious(winners: list):
    """Among the accepted candidates of a step, the one with the fewest parameters whose
    validation cost is not clearly worse (:func:`clearly_better`) than the best's
    (two effects can describe the same force: a constant-tension tether pulling straight
    down is a ballast); ties by the lower validation cost.  None without a winner."""
    if not winners:
        return None
    top = min(winners, key=lambda r: r["val"]["cost"])
    ok = [r for r in winners if r is top or not clearly_better(r["val"]["windows"], top["val"]["windows"])]
    return min(ok, key=lambda r: (r["candidate"].complexity, r["val"]["cost"]))


def richer_challenger(sel, best, st, val_cur):
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
    ok, why = judge(row, val_cur)
    row["accepted"], row["why"] = ok, why
    st["fitted"].append(row)
    if not ok:
        return None
    better = bootstrap_improvement(best["val"]["windows"], row["val"]["windows"], level=LEVEL)
    if better["p_better"] >= VAL_LEVEL and better["relative"] >= MIN_RELATIVE:
        row["why"] = why + f"; significantly better than {c.variant} on validation"
        return row
    return None


def alternative_challenger(sel, best, st, val_cur, *, blocked: bool = False):
    """The winner's alternatives (variants of its effect tagged ``alternatives`` with the
    same tag value and as many parameters, e.g. the two starts of a thrust lag), fitted;
    among the accepted ones the lowest open-loop validation cost (free simulations of the
    validation runs from their logged starts, :meth:`Selector.open_loop_cost`) wins.
    ``blocked``: ``best`` was refused by the open-loop verdict alone (``guard_blocked``), so
    only an accepted alternative can win; what the guard refused may be the start of the
    runs, which is exactly where the alternatives differ (benchmark pair 118: a lag from
    rest beside a weak thruster, fitted as ``steady``, removes 93 % of the windowed
    validation cost and makes the open-loop attitude 93 % worse; ``from_rest`` is accepted,
    validation position RMSE 436 -> 3.2 mm).  Alternatives already fitted in this step are
    not fitted again; the accepted ones among them compete.

    Why open loop: the alternatives differ only in how a run starts, which neither the
    equation error (it sees the logged motion, not the thrust history) nor the windowed
    cost can tell apart (each window's initial velocities are estimated, so they absorb the
    drift a lag from rest leaves behind: benchmark seed 6, windowed costs within 0.02 %,
    open-loop position RMSE 53 mm steady against 8 mm from rest).  Returns the new winner
    or None."""
    c = best["candidate"]
    group = c.tags.get("alternatives")
    if group is None:
        return None
    alts = [(cc, s) for cc, s in st["all_screened"]
            if cc is not c and cc.effect == c.effect and cc.tags.get("alternatives") == group
            and cc.complexity == c.complexity]
    done = {id(r["candidate"]): r for r in st["fitted"] if r.get("candidate") is not None}
    rows = _fitted_with_open_loop(sel, None, st, val_cur, [(cc, s) for cc, s in alts if id(cc) not in done])
    rows += [done[id(cc)] for cc, _ in alts if id(cc) in done and done[id(cc)].get("accepted")]
    if not rows:
        return None
    pool = rows if blocked else [best, *rows]
    _open_loop_costs(sel, pool)
    win = min(pool, key=lambda r: r["open_loop_cost"])
    if win is best:
        return None
    if blocked:
        win["why"] += f"; the alternative to {c.variant}, which the open-loop verdict refused"
        return win
    win["why"] += (f"; lower open-loop validation error than {c.variant} (pooled score "
                   f"{win['open_loop_cost']:.4g} against {best['open_loop_cost']:.4g})")
    return win


def simplest_sufficient(sel, best, st, val_cur):
    """Among the winning effect's variants simpler than the winner, the simplest whose
    validation cost is within :data:`MIN_RELATIVE` of the winner's (fitted here); None to
    keep the winner.  The bound is on the point estimate: the winner nests the simpler
    variant, so a fit that explains 5 % more of the validation runs is a real gain even
    when a few validation windows cannot make the bootstrap significant (benchmark seed
    91: a cable-drag tether replaced by the pull-only one, 26 % worse)."""
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
        ok, why = judge(row, val_cur)
        st["fitted"].append(row)
        worse = row["val"]["cost"] / best["val"]["cost"] - 1.0
        if ok and worse <= MIN_RELATIVE:
            row["accepted"], row["why"] = True, why + f"; simplest variant as good as {c.variant}"
            return row
        row["accepted"] = False
        row["why"] = why if not ok else (f"simpler variant, but its validation cost is {100 * worse:.1f} % above "
                                         f"{c.variant}'s (needs <= {100 * MIN_RELATIVE:.0f} %)")
    return None


def blocked_fallback(sel, st, val_cur):
    """When no candidate of a step is accepted: for each one that passed every test but the
    open-loop verdict (``guard_blocked``, lowest windowed validation cost first), its richer
    variants (a ballast piece's own mass: :func:`inertia_challenger`; a richer tether:
    :func:`richer_challenger`), its simpler ones (:func:`simplest_sufficient`: a horizontal pull
    where a 3-D one traded depth for position, the foreign suite's case b) and its alternatives
    (a lag from rest: :func:`alternative_challenger`) get their chance, each judged by the verdict
    too.  Returns the first accepted one, or None.  A challenger fitted here and accepted but not
    returned (a richer variant that is not significantly better than the refused row it was
    measured against) still competes: the step's accepted rows go to :func:`parsimonious`."""
    for row in sorted([r for r in st["fitted"] if r.get("guard_blocked")], key=lambda r: r["val"]["cost"]):
        best = (inertia_challenger(sel, row, st, val_cur) or richer_challenger(sel, row, st, val_cur)
                or simplest_sufficient(sel, row, st, val_cur)
                or alternative_challenger(sel, row, st, val_cur, blocked=True))
        if best is not None:
            return best
        best = parsimonious([r for r in st["fitted"] if r.get("accepted")])
        if best is not None:
            best["why"] += f"; in place of {row['candidate'].label}, which the verdict refused"
            return best
    return None


def inertia_challenger(sel, best, st, val_cur):
    """The winner's richer variant whose extra parameters act through inertia (tagged
    ``open_loop``: a ballast piece's own mass), fitted from the winner's values; it wins
    when accepted (:func:`judge`) and its open-loop validation cost is lower than the
    winner's by at least :data:`MIN_RELATIVE`.

    Why open loop: a 10 g piece adds a ``m_p y_p u_dot`` yaw moment of ~5e-4 N m that
    neither the equation error (the piece's mass at the origin is the re-tuned added mass)
    nor the windowed cost (each window restarts from estimated velocities) can see, but on
    a run whose heading nothing holds it decides which way the vehicle turns (benchmark
    seed 38: windowed costs within 0.04 %, open-loop position RMSE 96 mm massless against
    28 mm with the fitted 7 +- 5 g).  Returns the new winner or None."""
    c = best["candidate"]
    rows = _fitted_with_open_loop(sel, best, st, val_cur, [
        (cc, {"values": {**best["all_values"], **inertia_start(cc, best["values"], st["cur"]["vehicle"].g)}})
        for cc in st.get("held", []) if cc.effect == c.effect and set(c.free) < set(cc.free)])
    if not rows:
        return None
    win = min(rows, key=lambda r: r["open_loop_cost"])
    # the pooled scores are mean log MSEs: their difference is the log of the (geometric-mean) MSE ratio
    ratio = float(np.exp(win["open_loop_cost"] - best["open_loop_cost"]))
    if not (np.isfinite(win["open_loop_cost"]) and ratio <= 1.0 - MIN_RELATIVE):
        win["why"] += (f"; open-loop validation MSE {100 * (ratio - 1):+.1f} % against {c.variant}'s "
                       f"(needs {100 * MIN_RELATIVE:.0f} % lower)")
        return None
    win["why"] += f"; open-loop validation MSE {100 * (1 - ratio):.0f} % below {c.variant}'s"
    return win


def _fitted_with_open_loop(sel, best, st, val_cur, todo) -> list:
    """Fit each ``(candidate, screening result or seed)`` of ``todo`` in turn, judge it
    (:func:`judge`) and report it in ``st["fitted"]``; the accepted rows, and then the winner
    ``best`` (unless None), get their open-loop validation cost (:meth:`Selector.open_loop_cost`).
    Returns the accepted rows."""
    rows = []
    for cc, s in todo:
        row = sel.fit_candidate(cc, s, st["cur"], val_cur)
        if "compare" not in row:
            continue
        ok, why = judge(row, val_cur)
        row["accepted"], row["why"] = ok, why
        st["fitted"].append(row)
        if ok:
            rows.append(row)
    if rows:
        _open_loop_costs(sel, ([] if best is None else [best]) + rows)
    return rows


def _open_loop_costs(sel, rows) -> None:
    """Each row's open-loop validation cost (:meth:`Selector.open_loop_cost`), where it has none yet."""
    for row in rows:
        if "open_loop_cost" not in row:
            row["open_loop_cost"] = sel.open_loop_cost(row["vehicle"], row["all_values"])


def base_effect_challenge(base_row, effect_row) -> str | None:
    """Whether the catalogue's best effect on the *given* model (``effect_row``, the winner of a
    forward step without the base model) replaces the base model's variant accepted in step 0
    (``base_row``): it does when its validation cost is clearly lower (:func:`clearly_better`: the
    block bootstrap at :data:`LEVEL` and by at least :data:`MIN_RELATIVE`).  Returns why, or None
    to keep the base model.

    Why: step 0 fits the thrust curve first so that a curve mismatch is not taken for per-thruster
    faults (issue 22), but a global scale also absorbs part of what a single fault does, and once
    accepted it pre-empts that fault (field-log benchmark, issue 48: a dead thruster 6 under an
    autopilot, the thrust scale accepted on its 0.5 bound with a validation cost of 6786 squared
    noise sigmas per residual, where thruster 6 at gain 0 on the given model gives 489).  A curve
    mismatch keeps the base model: one scale explains it as well as the units' gains, so no effect
    is clearly better."""
    if effect_row is None:
        return None
    if not clearly_better(base_row["val"]["windows"], effect_row["val"]["windows"]):
        return None
    b, e = base_row["val"]["per_entry"], effect_row["val"]["per_entry"]
    return (f"{effect_row['candidate'].label} on the given model explains the validation runs clearly better "
            f"(validation cost {e:.4g} against {b:.4g} squared noise sigmas per residual)")


def base_effect_kept(base_row, effect_row) -> str:
    """The reason :func:`base_effect_challenge` kept the base model, in a few words."""
    if effect_row is None:
        return "no effect accepted without it"
    return (f"the best of them, {effect_row['candidate'].label}, validation cost {effect_row['val']['per_entry']:.4g} "
            f"against {base_row['val']['per_entry']:.4g}, is not clearly better")


def outlying_unit(effect_row) -> int | None:
    """The unit whose fitted gain is farthest from the median of all the gains, when ``effect_row``
    is the every-gain variant of ``thruster_gain`` (None otherwise): the one fault that
    :func:`unit_beside_base` tries beside the base model's common thrust curve."""
    if effect_row is None:
        return None
    c = effect_row["candidate"]
    if c.effect != "thruster_gain" or "unit" in c.tags or len(c.free) < 3:
        return None
    return int(farthest_from_median({n: float(effect_row["values"][n]) for n in c.free}).rsplit("_", 1)[1])


def unit_beside_base(sel, base_row, effect_row, screened):
    """When the every-gain variant (``effect_row``) won :func:`base_effect_challenge` against the
    base model's thrust-curve variant (``base_row``, step 0), the nested model "the base model's
    common curve plus one unit's gain" (the unit farthest from the others, :func:`outlying_unit`)
    is fitted on the base model and replaces the winner when it is accepted (:func:`judge`, against
    the base model) and its validation cost is within :data:`MIN_RELATIVE` of the winner's (the
    rule of :func:`simplest_sufficient`: the winner nests it).  Returns the unit's row (fitted on
    the base model, ``row["accepted"]`` whether it replaces the winner, ``row["nested_in"]`` the
    winner's label), or None when there is nothing to fit.

    Why: every gain with all but one near a common value is a thrust curve off for every unit and
    one unit's fault: two parameters, not eight, and the fault is the unit's (field-log benchmark,
    issue 48, dead case seed 21: thruster 7 at 0.00, the other seven 0.55-0.67, named
    ``thruster_gain:all``).  ``screened``: the challenge step's ``all_screened`` (where the unit's
    candidate is)."""
    k = outlying_unit(effect_row)
    if k is None:
        return None
    cc = next((c for c, _ in screened if c.effect == "thruster_gain" and c.variant == f"unit_{k}"), None)
    if cc is None:
        return None
    c_all = effect_row["candidate"]
    g = {n: float(effect_row["values"][n]) for n in c_all.free}
    name = f"thruster_gain_{k}"
    common = float(np.median([v for n, v in g.items() if n != name]))
    start = {name: float(np.clip(g[name] / common, *cc.bounds[name])) if common > 0 else cc.start[name]}
    base_c = base_row["candidate"]
    if "thrust_scale_scale" in base_c.free and common > 0:  # the given model's scale is 1: the common gain is the scale
        start["thrust_scale_scale"] = float(np.clip(common, *base_c.bounds["thrust_scale_scale"]))
    cur = sel.current([base_c], base_row["all_values"])
    row = sel.fit_candidate(cc, {"values": start}, cur, base_row["val"])
    if "compare" not in row:
        return None
    ok, why = judge(row, base_row["val"])
    worse = row["val"]["cost"] / effect_row["val"]["cost"] - 1.0
    row["nested_in"] = c_all.label
    if ok and worse <= MIN_RELATIVE:
        row["accepted"] = True
        row["why"] = why + (f"; beside {base_c.label}, as good as {c_all.label} on the given model (validation "
                            f"cost {100 * worse:+.1f} %), which nests it")
        return row
    row["accepted"] = False
    row["why"] = why if not ok else (f"beside {base_c.label}: validation cost {100 * worse:.1f} % above "
                                     f"{c_all.label}'s on the given model (needs <= {100 * MIN_RELATIVE:.0f} %)")
    return row
