"""Issue 48, a faulty thruster unit's two forms: its gain (``unit_K``) and its gain with a reverse
ratio (``fouled_K``, a line or weed round the propeller), judged against each other and against every
unit's gain (uvsim.diagnosis.units, uvsim.diagnosis.unit_choice).  Units on made-up rows; the field-log
benchmark (docs/records/diagnose.md) is the end-to-end check."""
from __future__ import annotations

import numpy as np

from uvsim.diagnosis.candidates import _gain, catalogue, plain_answer, reported_variant, search_bound_hits
from uvsim.diagnosis.decision import clearly_better


def test_a_fouled_unit_is_a_catalogue_variant_named_as_the_unit_with_its_reverse_ratio():
    cands = {c.variant: c for c in _gain(8)}
    f = cands["fouled_3"]
    assert f.free == ["thruster_gain_3", "thruster_reverse_3"] and f.complexity == 2
    assert f.null == {"thruster_gain_3": 1.0, "thruster_reverse_3": 1.0}
    assert f.bounds["thruster_gain_3"] == (0.0, 1.5) and f.bounds["thruster_reverse_3"] == (0.1, 1.5)
    vals = {"thruster_gain_3": 0.6, "thruster_reverse_3": 0.55}
    assert reported_variant(f, vals) == "unit_3"      # the report names the unit; fitted_as keeps the form
    assert plain_answer(f, vals).startswith("thruster 3 delivers 0.60 of its curve forward and 0.33 in reverse")
    assert "dead" in plain_answer(f, {"thruster_gain_3": 0.0, "thruster_reverse_3": 0.7})
    assert search_bound_hits(f, {"thruster_gain_3": 0.0}, ["thruster_gain_3"]) == []   # dead: physical floor
    assert search_bound_hits(f, {"thruster_reverse_3": 0.1}, ["thruster_reverse_3"]) == ["thruster_reverse_3"]
    # the order the existing variants keep (tests/test_thruster_faults.py indexes it)
    assert [c.variant for c in _gain(1)] == ["unit_1", "reversed_1", "all", "fouled_1"]
    variants = {c.variant for c in catalogue(input_kind="pwm", n_thrusters=8, dt=0.05, p_ref=np.zeros(3),
                                             has_position=True, z_max=None) if c.effect == "thruster_gain"}
    assert {f"fouled_{i}" for i in range(1, 9)} <= variants


# ---------------------------------------------------------------------------- the choice among forms
def _row(c, windows, *, guard_ok=True, accepted=None):
    w = np.asarray(windows, float)
    cmp = {"wald": {"p": 1e-9}, "relative": 0.5, "p_better": 1.0,
           "guard": {"ok": guard_ok, "why": "better" if guard_ok else "trade-off: worse in depth +40 %"}}
    row = {"candidate": c, "effect": c.effect, "variant": c.variant, "free": c.free, "compare": cmp, "problem": None,
           "values": {n: 0.6 for n in c.free}, "at_bounds": [], "val": {"windows": w, "cost": float(w.sum())}}
    if accepted is not None:
        row["accepted"] = accepted
    if not guard_ok:
        row["guard_blocked"] = True
    return row


class _Sel:
    """What unit_forms asks of a Selector: fit_candidate, from prepared rows by variant."""

    def __init__(self, rows):
        self.rows, self.fitted = rows, []

    def fit_candidate(self, c, s, cur, val_cur):
        self.fitted.append(c.variant)
        return self.rows[c.variant]


def _step(screened_red: dict, fitted: list) -> dict:
    cands = {c.variant: c for c in _gain(8)}
    return {"all_screened": [(c, {"reduction": screened_red.get(v, 0.1), "values": {}}) for v, c in cands.items()],
            "fitted": fitted, "cur": {}}, cands


def _windows(seed, n=24, scale=1.0, spread=0.0):
    rng = np.random.default_rng(seed)
    base = rng.gamma(2.0, 10.0, n)
    return base * scale * (1.0 + spread * rng.standard_normal(n)).clip(0.2)


def test_a_fouled_unit_not_clearly_worse_than_every_gain_is_named_in_its_place():
    """Every gain (8 parameters) won the step; the screening's best unit form is thruster 3's.  Its
    fouled form (2 parameters, not nested in every gain) is 15 % above every gain on validation but
    not clearly (block bootstrap at 99 %): the alternative with fewer parameters is named
    (decision.parsimonious's rule).  Before, every gain was named (field-log fouled seeds 14, 44)."""
    from uvsim.diagnosis.unit_choice import unit_forms

    w_all = _windows(1)
    w_foul = _windows(1, scale=1.15, spread=0.6)
    assert not clearly_better(w_foul, w_all)
    st, c = _step({"fouled_3": 0.9, "unit_3": 0.8, "all": 0.95}, [])
    best = _row(c["all"], w_all, accepted=True)
    st["fitted"].append(best)
    sel = _Sel({"unit_3": _row(c["unit_3"], w_all * 2.0), "fouled_3": _row(c["fouled_3"], w_foul)})
    win = unit_forms(sel, best, st, None)
    assert win is not None and win["variant"] == "fouled_3" and win["accepted"]
    assert "in place of thruster_gain:all" in win["why"]
    assert sorted(sel.fitted) == ["fouled_3", "unit_3"]
    # every gain clearly better (3 times lower on every window): it stays
    st, c = _step({"fouled_3": 0.9, "unit_3": 0.8}, [])
    best = _row(c["all"], w_all, accepted=True)
    sel = _Sel({"unit_3": _row(c["unit_3"], w_all * 3.0), "fouled_3": _row(c["fouled_3"], w_all * 3.0)})
    assert unit_forms(sel, best, st, None) is None


def test_the_fouled_form_replaces_the_units_gain_only_when_clearly_lower_on_validation():
    """``fouled_K`` nests ``unit_K``: it is the answer only with a validation cost more than 5 % below
    (decision.simplest_sufficient's rule)."""
    from uvsim.diagnosis.unit_choice import unit_forms

    w = _windows(2)
    st, c = _step({"unit_5": 0.9, "fouled_5": 0.92}, [])
    best = _row(c["unit_5"], w, accepted=True)
    st["fitted"].append(best)
    sel = _Sel({"fouled_5": _row(c["fouled_5"], w * 0.97)})
    assert unit_forms(sel, best, st, None) is None            # 3 % lower: the unit's gain stays
    st, c = _step({"unit_5": 0.9, "fouled_5": 0.92}, [])
    best = _row(c["unit_5"], w, accepted=True)
    st["fitted"].append(best)
    sel = _Sel({"fouled_5": _row(c["fouled_5"], w * 0.6)})
    win = unit_forms(sel, best, st, None)
    assert win["variant"] == "fouled_5" and "below unit_5's" in win["why"]


def test_when_the_verdict_refuses_every_gain_the_screened_units_forms_get_their_chance():
    """Nothing accepted in the step: every gain was refused by the open-loop verdict alone (a trade-off
    in depth) and thruster 1's gain, fitted as its simpler variant, was refused for a validation cost
    63 % above the refused row's.  Thruster 1's fouled form passes every test: it is named (field-log
    fouled seed 34; before, nothing was named)."""
    from uvsim.diagnosis.unit_choice import unit_forms

    w = _windows(3)
    st, c = _step({"all": 0.87, "unit_1": 0.6, "fouled_1": 0.8, "unit_4": 0.3}, [])
    blocked = _row(c["all"], w, guard_ok=False, accepted=False)
    unit = _row(c["unit_1"], w * 1.63, accepted=False)
    st["fitted"] += [blocked, unit]
    sel = _Sel({"fouled_1": _row(c["fouled_1"], w * 0.9)})
    win = unit_forms(sel, None, st, None)
    assert win is not None and win["variant"] == "fouled_1" and win["accepted"]
    assert "refused by the open-loop verdict" in win["why"]
    assert sel.fitted == ["fouled_1"]                          # unit_1 was fitted in the step already
    # and without a refused every-gain row (nothing thruster-like fitted) nothing is tried
    st, c = _step({"fouled_1": 0.8}, [])
    assert unit_forms(_Sel({}), None, st, None) is None
