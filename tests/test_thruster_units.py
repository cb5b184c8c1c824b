"""Issue 48, a faulty thruster unit's two forms: its gain (``unit_K``) and its gain with a reverse
ratio (``fouled_K``, a line or weed round the propeller), judged against each other and against every
unit's gain (uvsim.diagnosis.units, uvsim.diagnosis.unit_choice).  Units on made-up rows; the field-log
benchmark (docs/records/diagnose.md) is the end-to-end check."""
from __future__ import annotations

import numpy as np
import pytest

from uvsim.diagnosis.candidates import _gain, catalogue, search_bound_hits
from uvsim.diagnosis.units import plain_answer, reported_variant
from uvsim.diagnosis.decision import clearly_better


def test_a_fouled_unit_is_a_catalogue_variant_named_as_the_unit_with_its_reverse_ratio():
    cands = {c.variant: c for c in _gain(8)}
    f = cands["fouled_3"]
    assert f.free == ["thruster_gain_3", "thruster_reverse_3"] and f.complexity == 2
    assert f.null == {"thruster_gain_3": 1.0, "thruster_reverse_3": 1.0}
    assert f.bounds["thruster_gain_3"] == (0.0, 1.5) and f.bounds["thruster_reverse_3"] == (0.1, 1.0)
    vals = {"thruster_gain_3": 0.6, "thruster_reverse_3": 0.55}
    assert reported_variant(f, vals) == "unit_3"      # the report names the unit; fitted_as keeps the form
    assert plain_answer(f, vals).startswith("thruster 3 delivers 0.60 of its curve forward and 0.33 in reverse")
    assert "dead" in plain_answer(f, {"thruster_gain_3": 0.0, "thruster_reverse_3": 0.7})
    assert search_bound_hits(f, {"thruster_gain_3": 0.0}, ["thruster_gain_3"]) == []   # dead: physical floor
    assert search_bound_hits(f, {"thruster_reverse_3": 0.1}, ["thruster_reverse_3"]) == ["thruster_reverse_3"]
    # stronger in reverse than the curve is no fouling: a fit at 1 is on the edge, not named (field seed 15)
    assert search_bound_hits(f, {"thruster_reverse_3": 1.0}, ["thruster_reverse_3"]) == ["thruster_reverse_3"]
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
    (step_choice.parsimonious's rule).  Before, every gain was named (field-log fouled seeds 14, 44)."""
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
    (step_choice.simplest_sufficient's rule)."""
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


# ---------------------------------------------------------------------------- every gain, re-examined
class _FinalSel:
    """What unit_in_every_gain asks of a Selector: the model's parts (as Selector.current), a fit of
    the model without the unit, validation costs and the unit's fits, from prepared numbers."""

    def __init__(self, unit_windows, fouled_windows, reduced_windows):
        from types import SimpleNamespace

        from uvsim.vehicle import load_vehicle

        self.base_vehicle = load_vehicle("bluerov2_heavy")
        self.train = [SimpleNamespace(input_kind="pwm")]
        self.w = {"unit_7": unit_windows, "fouled_7": fouled_windows}
        self.reduced = reduced_windows
        self.fitted, self.trained = [], []

    def current(self, accepted, values):
        free = [n for a in accepted for n in a.free]
        return {"vehicle": self.base_vehicle, "values": dict(values), "free": free,
                "bounds": {n: a.bounds[n] for a in accepted for n in a.free}, "accepted": list(accepted)}

    def space(self, veh, free, bounds, start, fixed):
        return {"free": list(free), "start": dict(start)}

    def fit_train(self, veh, sp, label):
        from types import SimpleNamespace

        self.trained.append(label)
        return SimpleNamespace(values={n: sp["start"].get(n, 1.0) for n in sp["free"]})

    def validation(self, veh, vals):
        return {"windows": self.reduced, "cost": float(self.reduced.sum())}

    def fit_candidate(self, c, s, cur, vc):
        self.fitted.append((c.variant, [a.label for a in cur["accepted"]], dict(s["values"])))
        row = _row(c, self.w[c.variant])
        row["all_values"], row["result"] = {**cur["values"], **{n: 0.5 for n in c.free}}, "the fit"
        return row


def _final_model(n=8, k=7):
    from uvsim.diagnosis.candidates import _base_model

    sel_v = _FinalSel(np.ones(3), np.ones(3), np.ones(3)).base_vehicle
    hydro = {c.variant: c for c in _base_model(sel_v.parameters(), n, "pwm")}["hydrodynamics"]
    c_all = {c.variant: c for c in _gain(n)}["all"]
    gains = {f"thruster_gain_{i + 1}": 0.7 + 0.02 * ((i % 3) - 1) for i in range(n)}
    gains[f"thruster_gain_{k}"] = 0.35
    values = {**gains, **{p: sel_v.parameters()[p] * 1.2 for p in hydro.free}}
    return [c_all, hydro], values


def test_every_gain_beside_a_later_base_model_is_replaced_by_its_unit_when_as_good():
    """The final model names every gain (thruster 7 at 0.35, the other seven near 0.7) and the
    hydrodynamics re-tuned after it; the re-tune with the thrust scale free plus thruster 7 alone is
    within 5 % of it on validation (it nests that model): the unit is named, the scale started at the
    other gains' median and thruster 7 at its share of it (field-log weak seed 13; before, every gain)."""
    from uvsim.diagnosis.unit_choice import unit_in_every_gain

    accepted, values = _final_model()
    w = _windows(4)
    sel = _FinalSel(w * 1.03, w * 1.5, w * 20.0)
    out = unit_in_every_gain(sel, accepted, values, {"windows": w, "cost": float(w.sum())})
    assert out is not None and out["chosen"]["variant"] == "unit_7"
    assert [c.label for c in out["accepted"]] == ["base_model:hydrodynamics_thrust", "thruster_gain:unit_7"]
    assert not any(n.startswith("thruster_gain_") and n != "thruster_gain_7" for n in out["values"])
    variant, model, seed = sel.fitted[0]
    assert model == ["base_model:hydrodynamics_thrust"] and seed["thrust_scale_scale"] == pytest.approx(0.7)
    assert seed["thruster_gain_7"] == pytest.approx(0.5)
    assert "as good as the model with thruster_gain:all" in out["chosen"]["why"]


def test_every_gain_stays_when_its_unit_beside_the_base_model_is_worse_or_absent():
    from uvsim.diagnosis.unit_choice import unit_in_every_gain

    accepted, values = _final_model()
    w = _windows(5)
    sel = _FinalSel(w * 1.2, w * 1.2, w * 20.0)                  # 20 % above: every gain explains more
    out = unit_in_every_gain(sel, accepted, values, {"windows": w, "cost": float(w.sum())})
    assert out is not None and "accepted" not in out and len(out["rows"]) == 2
    assert "needs <= 5 %" in out["rows"][0]["why"]
    # no every-gain variant in the model: nothing to try
    assert unit_in_every_gain(sel, [accepted[1]], values, {"windows": w, "cost": float(w.sum())}) is None
