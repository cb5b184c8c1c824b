"""Which form of a thruster-unit fault a step names: :func:`unit_forms`.

The catalogue has two forms of one faulty unit ``K`` (:mod:`uvsim.diagnosis.units`): ``unit_K`` (its
gain) and ``fouled_K`` (its gain and its reverse ratio), beside ``all`` (every unit's gain).  The
screening picks one variant per effect (the simplest within ``VARIANT_SHARE`` of the best), and the
challengers of :mod:`uvsim.diagnosis.step_choice` fit one richer and one simpler variant, so the unit's
other form may never be fitted: on a fouled unit the screening ranks ``all`` first, ``unit_K`` is
fitted as its simpler variant and ``fouled_K``, which neither nests nor is nested in ``all``, is not
(field-log benchmark, issue 48, fouled seed 34: ``all`` refused as a trade-off in depth, ``unit_1``
62.9 % above it, nothing named, where ``fouled_1`` alone passes every test including the verdict).

The rule, applied to a step's winner (or to a step without one whose every-gain row the open-loop
verdict alone refused, as :func:`uvsim.diagnosis.step_choice.blocked_fallback` does for the other
effects):

1. the unit is the one whose form removed most of the equation error in the screening;
2. both forms are fitted (unless fitted already in the step) and judged (:func:`judge`); of the
   accepted ones, ``fouled_K`` is the unit's answer only when its validation cost is more than
   :data:`MIN_RELATIVE` below ``unit_K``'s (it nests ``unit_K``: the rule of
   :func:`uvsim.diagnosis.step_choice.simplest_sufficient`);
3. against ``all``: ``unit_K`` is nested in it, and keeps :func:`simplest_sufficient`'s rule (within
   :data:`MIN_RELATIVE`); ``fouled_K`` is not (its reverse ratio is no gain), so the two are
   alternatives, compared as the step's alternatives are (:func:`parsimonious`): the one with fewer
   parameters wins unless the other is clearly better on validation (:func:`clearly_better`, the
   block bootstrap at :data:`LEVEL` and by at least :data:`MIN_RELATIVE`).
"""
from __future__ import annotations

import numpy as np

from uvsim.diagnosis.candidates import BASE_MODEL, _base_model, _gain
from uvsim.diagnosis.decision import MIN_RELATIVE, clearly_better, judge
from uvsim.diagnosis.summary import row_report
from uvsim.diagnosis.units import farthest_from_median
from uvsim.errors import UvsimError
from uvsim.fitting.parameters import GAIN_RANGE

EFFECT = "thruster_gain"


def _screened_unit(st) -> int | None:
    """The unit whose form (``unit_K`` or ``fouled_K``) removed most of the equation error in the step's
    screening (``st["all_screened"]``), or None without one."""
    best, unit = 0.0, None
    for c, s in st["all_screened"]:
        if c.effect != EFFECT or "unit" not in c.tags or c.tags.get("reversed"):
            continue
        red = (s or {}).get("reduction", 0.0)
        if red > best:
            best, unit = red, c.tags["unit"]
    return unit


def _form_row(sel, st, val_cur, variant: str):
    """The step's row of ``variant`` (judged again: a challenger may have marked it not accepted for
    being worse than another row), fitted and judged when the step has none; None when the catalogue
    has no such variant or its fit failed."""
    row = next((r for r in st["fitted"] if r.get("candidate") is not None and r["candidate"].effect == EFFECT
                and r["candidate"].variant == variant), None)
    if row is None:
        cs = next(((c, s) for c, s in st["all_screened"] if c.effect == EFFECT and c.variant == variant), None)
        if cs is None:
            return None
        row = sel.fit_candidate(cs[0], cs[1], st["cur"], val_cur)
        if "compare" not in row:
            return None
        st["fitted"].append(row)
    elif "compare" not in row:
        return None
    row["unit_form_ok"], row["unit_form_why"] = judge(row, val_cur)
    if "accepted" not in row:
        row["accepted"], row["why"] = row["unit_form_ok"], row["unit_form_why"]
    return row


def unit_forms(sel, best, st, val_cur):
    """The step's answer among a faulty unit's forms (module docstring), or None to keep ``best``.

    ``best``: the step's winner after the other challengers (None: no winner); ``st``: the step
    (:meth:`uvsim.diagnosis.selector.Selector.step`); ``val_cur``: the current model's validation."""
    if best is not None:
        c = best["candidate"]
        if c.effect != EFFECT or c.tags.get("reversed"):
            return None
        blocked = None
    else:  # the every-gain row the verdict alone refused (step_choice.blocked_fallback's rows)
        blocked = next((r for r in st["fitted"] if r.get("guard_blocked") and r.get("candidate") is not None
                        and r["candidate"].effect == EFFECT and "unit" not in r["candidate"].tags), None)
        if blocked is None:
            return None
    k = best["candidate"].tags["unit"] if best is not None and "unit" in best["candidate"].tags else _screened_unit(st)
    if k is None:
        return None
    rows = [r for r in (_form_row(sel, st, val_cur, f"unit_{k}"), _form_row(sel, st, val_cur, f"fouled_{k}"))
            if r is not None and r["unit_form_ok"]]
    if not rows:
        return None
    gain, fouled = _split_forms(rows)
    answer, note = _pick(gain, fouled)
    if best is not None and "unit" in best["candidate"].tags:  # the winner is a form of the unit
        if answer is best:
            return None
        answer["accepted"], answer["why"] = True, answer["unit_form_why"] + note + f"; in place of {best['variant']}"
        return answer
    every = best if best is not None else blocked
    if answer is gain:
        # nested in every gain: simplest_sufficient's rule (it ran already when `best` is every gain)
        if best is not None and answer["val"]["cost"] > (1.0 + MIN_RELATIVE) * best["val"]["cost"]:
            return None
    elif best is not None and clearly_better(answer["val"]["windows"], best["val"]["windows"]):
        answer["accepted"] = False
        answer["why"] = (answer["unit_form_why"] + f"; not named: {best['variant']} (every gain, an alternative with "
                         f"more parameters) is clearly better on validation")
        return None
    how = ("refused by the open-loop verdict" if best is None else
           "not clearly better on validation, with more parameters" if answer is fouled else "as good")
    answer["accepted"] = True
    answer["why"] = answer["unit_form_why"] + note + f"; in place of {every['candidate'].label} ({how})"
    return answer


def _split_forms(rows):
    """The ``unit_K`` row and the ``fouled_K`` row among ``rows`` (None for a form not there)."""
    gain = next((r for r in rows if not r["candidate"].tags.get("fouled")), None)
    fouled = next((r for r in rows if r["candidate"].tags.get("fouled")), None)
    return gain, fouled


def _pick(gain, fouled):
    """The unit's answer among its accepted forms (rule 2 of the module docstring) and the note on why."""
    if fouled is not None and (gain is None or fouled["val"]["cost"] < (1.0 - MIN_RELATIVE) * gain["val"]["cost"]):
        note = "" if gain is None else (f"; validation cost {100 * (1 - fouled['val']['cost'] / gain['val']['cost']):.0f}"
                                        f" % below {gain['candidate'].variant}'s, which it nests")
        return fouled, note
    return gain, ""


def _with_scale(sel, bases):
    """The final model's base-model variants with the thrust curve's scale free: unchanged when one of
    them frees it, the re-tune's ``_thrust`` sibling (``damping`` -> ``damping_thrust``), the scale
    alone without a base-model variant; None when the base model is something else (a supply voltage)."""
    v = sel.base_vehicle
    cands = {c.variant: c for c in _base_model(v.parameters(), v.n_thrusters, sel.train[0].input_kind)}
    if any("thrust_scale_scale" in c.free for c in bases):
        return list(bases)
    if not bases:
        return [cands["thrust_scale"]] if "thrust_scale" in cands else None
    if len(bases) == 1 and bases[0].variant + "_thrust" in cands:
        return [cands[bases[0].variant + "_thrust"]]
    return None


def unit_in_every_gain(sel, accepted: list, values: dict, val_cur: dict):
    """When the final model names every unit's gain (``thruster_gain:all``), the nested model "the base
    model with the thrust curve's scale free, plus the unit farthest from the median of the gains" is
    fitted too (both of the unit's forms, after the model without them), and replaces it when that
    unit is accepted (:func:`judge`, against the model without it) and the result is as good: within
    :data:`MIN_RELATIVE` of the final model's validation cost for ``unit_K`` (nested in every gain:
    :func:`uvsim.diagnosis.step_choice.simplest_sufficient`'s rule), or not clearly worse for ``fouled_K``
    (not nested: :func:`clearly_better`).  Returns None when there is nothing to try, else a dict with
    ``rows`` (the fits, for the report) and, when it replaces the model, ``accepted``, ``values``,
    ``val``, ``fit``.

    Why: a base-model variant accepted after every gain (a hydrodynamic re-tune) explains part of what
    the seven other gains stood in for, and the unit beside a common scale was only tried against a
    thrust scale accepted in step 0 (:func:`uvsim.diagnosis.step_choice.unit_beside_base`).  Field logs,
    weak seed 13 (thruster 7 at 0.472): every gain (thruster 7 at 0.35, the others 0.67-0.77) then the
    hydrodynamics re-tuned, validation cost 25.0; the re-tune with the scale free plus ``unit_7``: 25.5 in
    the diagnosis (24.1 fitted on the given model alone: docs/records/diagnose.md).
    This is backward elimination's question (:func:`uvsim.diagnosis.step_choice.still_needed`) asked of
    the every-gain variant once the base model is in."""
    c_all = next((c for c in accepted if c.effect == EFFECT and "unit" not in c.tags and len(c.free) >= 3), None)
    if c_all is None:
        return None
    g = {n: float(values[n]) for n in c_all.free}
    name = farthest_from_median(g)
    k = int(name.rsplit("_", 1)[1])
    common = float(np.median([v for n, v in g.items() if n != name]))
    bases = _with_scale(sel, [c for c in accepted if c.effect == BASE_MODEL])
    if bases is None or common <= 0.0:
        return None
    others = [c for c in accepted if c.effect not in (BASE_MODEL, EFFECT)]
    reduced = bases + others
    start = {n: v for n, v in values.items() if n not in c_all.free}
    lo, hi = next(c for c in bases if "thrust_scale_scale" in c.free).bounds["thrust_scale_scale"]
    start["thrust_scale_scale"] = float(np.clip(start.get("thrust_scale_scale", 1.0) * common, lo, hi))
    cur = sel.current(reduced, start)
    sp = sel.space(cur["vehicle"], cur["free"], cur["bounds"], start, cur["values"])
    label = " + ".join(c.label for c in reduced)
    try:
        res = sel.fit_train(cur["vehicle"], sp, f"{label} (every gain's unit {k} beside the thrust scale)")
    except (UvsimError, np.linalg.LinAlgError) as exc:  # the model stays as it is, and the report says why
        return {"rows": [], "why": f"{label} could not be fitted ({exc})"}
    vals = {**cur["values"], **res.values}
    vc = sel.validation(cur["vehicle"], vals)
    cur = sel.current(reduced, vals)
    forms = {c.variant: c for c in _gain(sel.base_vehicle.n_thrusters)}
    seed = {f"thruster_gain_{k}": float(np.clip(g[name] / common, *GAIN_RANGE)),
            "thrust_scale_scale": start["thrust_scale_scale"]}
    rows = []
    for variant in (f"unit_{k}", f"fouled_{k}"):
        row = sel.fit_candidate(forms[variant], {"values": seed}, cur, vc)
        if "compare" not in row:
            continue
        row["accepted"], row["why"] = judge(row, vc)
        row["unit_form_ok"] = row["accepted"]
        rows.append(row)
    gain, fouled = _split_forms([r for r in rows if r["unit_form_ok"]])
    answer, note = _pick(gain, fouled)
    out = {"rows": rows, "model": label, "nested_in": c_all.label}
    for r in rows:
        r["accepted"] = False
    if answer is None:
        return out
    worse = answer["val"]["cost"] / val_cur["cost"] - 1.0
    ok = (worse <= MIN_RELATIVE if answer is gain else not clearly_better(answer["val"]["windows"], val_cur["windows"]))
    if not ok:
        answer["why"] += (f"; beside {label}: validation cost {100 * worse:+.1f} % against the model with "
                          f"{c_all.label}" + (" (needs <= 5 %)" if answer is gain else ", clearly worse"))
        return out
    answer["accepted"] = True
    answer["why"] += note + (f"; beside {label}, as good as the model with {c_all.label} (validation cost "
                             f"{100 * worse:+.1f} %), which {'nests it' if answer is gain else 'has more parameters'}")
    out.update(accepted=reduced + [answer["candidate"]], values=dict(answer["all_values"]), val=answer["val"],
               fit=answer["result"], chosen=answer)
    return out


def every_gain_step(again: dict, accepted: list, val_cur: dict, k: int) -> dict:
    """The report's step of :func:`unit_in_every_gain` (``again``) on the final model (``accepted``,
    ``val_cur``), numbered ``k``; each fitted row as :func:`uvsim.diagnosis.summary.row_report` writes it."""
    chosen = again.get("chosen")
    rep = {"step": k, "model": " + ".join(c.label for c in accepted), "before_cost_per_entry": val_cur["per_entry"],
           "screening": None, "screened": [], "chosen": None, "candidates": [row_report(r, chosen) for r in again["rows"]],
           "unit_in_every_gain": {"model": again.get("model"), "nested_in": again.get("nested_in"),
                                  "why": again.get("why")}}
    if chosen is not None:
        rep.update(chosen=chosen["candidate"].label, after_cost_per_entry=chosen["val"]["per_entry"])
    return rep
