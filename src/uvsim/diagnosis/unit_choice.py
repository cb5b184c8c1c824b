"""Which form of a thruster-unit fault a step names: :func:`unit_forms`.

The catalogue has two forms of one faulty unit ``K`` (:mod:`uvsim.diagnosis.units`): ``unit_K`` (its
gain) and ``fouled_K`` (its gain and its reverse ratio), beside ``all`` (every unit's gain).  The
screening picks one variant per effect (the simplest within ``VARIANT_SHARE`` of the best), and the
challengers of :mod:`uvsim.diagnosis.decision` fit one richer and one simpler variant, so the unit's
other form may never be fitted: on a fouled unit the screening ranks ``all`` first, ``unit_K`` is
fitted as its simpler variant and ``fouled_K``, which neither nests nor is nested in ``all``, is not
(field-log benchmark, issue 48, fouled seed 34: ``all`` refused as a trade-off in depth, ``unit_1``
62.9 % above it, nothing named, where ``fouled_1`` alone passes every test including the verdict).

The rule, applied to a step's winner (or to a step without one whose every-gain row the open-loop
verdict alone refused, as :func:`uvsim.diagnosis.decision.blocked_fallback` does for the other
effects):

1. the unit is the one whose form removed most of the equation error in the screening;
2. both forms are fitted (unless fitted already in the step) and judged (:func:`judge`); of the
   accepted ones, ``fouled_K`` is the unit's answer only when its validation cost is more than
   :data:`MIN_RELATIVE` below ``unit_K``'s (it nests ``unit_K``: the rule of
   :func:`uvsim.diagnosis.decision.simplest_sufficient`);
3. against ``all``: ``unit_K`` is nested in it, and keeps :func:`simplest_sufficient`'s rule (within
   :data:`MIN_RELATIVE`); ``fouled_K`` is not (its reverse ratio is no gain), so the two are
   alternatives, compared as the step's alternatives are (:func:`parsimonious`): the one with fewer
   parameters wins unless the other is clearly better on validation (:func:`clearly_better`, the
   block bootstrap at :data:`LEVEL` and by at least :data:`MIN_RELATIVE`).
"""
from __future__ import annotations

from uvsim.diagnosis.decision import MIN_RELATIVE, clearly_better, judge

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
    else:  # the every-gain row the verdict alone refused (decision.blocked_fallback's rows)
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
    gain = next((r for r in rows if not r["candidate"].tags.get("fouled")), None)
    fouled = next((r for r in rows if r["candidate"].tags.get("fouled")), None)
    answer = gain
    if fouled is not None and (gain is None or fouled["val"]["cost"] < (1.0 - MIN_RELATIVE) * gain["val"]["cost"]):
        answer = fouled
    note = ""
    if gain is not None and answer is fouled:
        note = (f"; validation cost {100 * (1 - fouled['val']['cost'] / gain['val']['cost']):.0f} % below "
                f"{gain['candidate'].variant}'s, which it nests")
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
