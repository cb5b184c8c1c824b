"""Issue 22: the open-loop guard, the "not explained" verdict, effects on search bounds
and the lag floor, and the depth-only tether (units here; end-to-end cases on data made
by the independent truth generator of uvsim.scenarios)."""
from __future__ import annotations

import numpy as np
import pytest

from uvsim.diagnosis import diagnose
from uvsim.diagnosis.candidates import catalogue, observability, search_bound_hits
from uvsim.diagnosis.decision import judge
from uvsim.fitting.verdict import score
from verdict_data import errors, logged_run, model, prediction
from uvsim.diagnosis.residual import UNEXPLAINED, verdict
from uvsim.scenarios import generate, load_truth, sample_scenario


def _open_loop(scale: dict, seed: int = 3) -> dict:
    """What :meth:`Selector.open_loop_blocks` returns for a model whose validation errors are the
    base errors of tests/verdict_data.py times ``scale`` per channel (two runs)."""
    runs = [logged_run(seed + i, name=f"val_{i:02d}") for i in range(2)]
    ms = [model(r) for r in runs]
    preds = [prediction(m, errors(m, seed + 10 + i), scale) for i, m in enumerate(ms)]
    return {"meas": ms, "preds": preds, "score": score(ms, preds)}


def _row(c, values, at_bounds=(), guard_ok=True):
    cmp = {"wald": {"p": 1e-9}, "relative": 0.3, "p_better": 1.0,
           "guard": {"ok": guard_ok, "why": "trade-off: pooled error -20 %, but worse in depth +40 %"}}
    return {"candidate": c, "compare": cmp, "problem": None, "values": values, "at_bounds": list(at_bounds)}


def test_judge_needs_the_guard_and_parameters_inside_their_search_range():
    cands = {c.label: c for c in catalogue(input_kind="pwm", n_thrusters=8, dt=0.02, p_ref=np.zeros(3),
                                           has_position=True, z_max=None)}
    bal = cands["ballast:xy"]
    ok_vals = {"ballast_weight": 1.0, "ballast_x": 0.1, "ballast_y": 0.0}
    assert judge(_row(bal, ok_vals), None)[0]
    ok, why = judge(_row(bal, ok_vals, guard_ok=False), None)
    assert not ok and "trade-off" in why and "depth" in why
    # a weight at the edge of the frame's search range is not named
    ok, why = judge(_row(bal, {**ok_vals, "ballast_x": 0.5}, at_bounds=["ballast_x"]), None)
    assert not ok and "ballast_x" in why and "search range" in why
    # a tether without stiffness sits on a physical floor, not on a search bound
    teth = cands["tether:3d"]
    assert search_bound_hits(teth, {"tether_stiffness": 0.0}, ["tether_stiffness"]) == []
    assert search_bound_hits(teth, {"tether_anchor_d": 51.0}, ["tether_anchor_d"]) == ["tether_anchor_d"]


def test_a_lag_of_half_a_sample_is_the_input_timing_not_an_actuator():
    """A zero-order hold delays a command by dt / 2 (Franklin, Powell & Workman sec. 4.3.1),
    so a lag's floor and the Wald test's null are dt / 2."""
    lag = catalogue(input_kind="force", n_thrusters=8, dt=0.02, p_ref=np.zeros(3), has_position=True, z_max=None,
                    only=["thruster_lag"])[0]
    assert lag.bounds["thruster_lag_time_constant"][0] == pytest.approx(0.01)
    assert lag.null == {"thruster_lag_time_constant": pytest.approx(0.01)}
    ok, why = judge(_row(lag, {"thruster_lag_time_constant": 0.01}, at_bounds=["thruster_lag_time_constant"]), None)
    assert not ok and "timing of the logged inputs" in why
    assert judge(_row(lag, {"thruster_lag_time_constant": 0.2}), None)[0]


def test_a_thrust_scale_on_its_bound_and_every_gain_below_it_stand_in_for_a_missing_force():
    """Issue 48: under an autopilot the thrusters hold against a pull the model lacks, and a model
    without it wants less thrust than any supply voltage gives (field logs, tether seed 7: every gain
    0.08-0.18; seeds 17, 37, 47: the thrust scale on its 0.5 floor).  Neither is named; a scale inside
    its range or on its ceiling, every gain with one unit at or above the floor, and a dead unit still
    are."""
    from uvsim.diagnosis.candidates import THRUST_SCALE_RANGE

    cands = {c.label: c for c in catalogue(input_kind="pwm", n_thrusters=8, dt=0.1, p_ref=np.zeros(3),
                                           has_position=True, z_max=None, base={"X_uu": 1.0})}
    lo = THRUST_SCALE_RANGE[0]
    scale = cands["base_model:thrust_scale"]
    ok, why = judge(_row(scale, {"thrust_scale_scale": lo}, at_bounds=["thrust_scale_scale"]), None)
    assert not ok and f"thrust scale on its floor {lo:g}" in why and "stands in" in why
    assert judge(_row(scale, {"thrust_scale_scale": 0.63}), None)[0]
    # the ceiling is a curve at 20 V (the structural benchmark's curve_mismatch), not a held force
    hi = THRUST_SCALE_RANGE[1]
    assert judge(_row(scale, {"thrust_scale_scale": hi}, at_bounds=["thrust_scale_scale"]), None)[0]
    both = cands["base_model:damping_thrust"]   # a re-tuned damping on its bound is no reason to refuse ...
    vals = {n: 1.0 for n in both.free}
    assert judge(_row(both, {**vals, "X_uu": 1.5}, at_bounds=["X_uu"]), None)[0]
    # ... the scale on its bound is
    assert not judge(_row(both, {**vals, "thrust_scale_scale": lo}, at_bounds=["thrust_scale_scale"]), None)[0]
    every = cands["thruster_gain:all"]
    gains = {n: g for n, g in zip(every.free, [0.16, 0.11, 0.14, 0.18, 0.08, 0.13, 0.10, 0.08])}
    row = _row(every, gains)
    ok, why = judge(row, None)
    assert not ok and "every unit at 0.08-0.18 of its curve" in why and row["bound_rejected"]
    ok, why = judge(_row(every, {**gains, every.free[3]: lo}), None)   # one unit at the floor: the units' answer
    assert ok
    dead = cands["thruster_gain:unit_6"]
    assert judge(_row(dead, {dead.free[0]: 0.0}, at_bounds=dead.free), None)[0]


def test_a_reversed_unit_fitted_to_zero_is_a_dead_unit_not_an_edge():
    """A reversed unit's range is -1.5..0 and its upper end, 0, is a dead unit (reported as unit_6,
    units.reported_variant), a physical answer like a gain's floor (field logs, dead seed 1 once the
    5 Hz DVL entered the window starts: fitted from the reversed side to -0.00 and refused before);
    its lower end stays an edge."""
    cands = {c.label: c for c in catalogue(input_kind="pwm", n_thrusters=8, dt=0.1, p_ref=np.zeros(3),
                                           has_position=True, z_max=None)}
    rev = cands["thruster_gain:reversed_6"]
    ok, _ = judge(_row(rev, {rev.free[0]: -1e-4}, at_bounds=rev.free), None)
    assert ok and search_bound_hits(rev, {rev.free[0]: -1.5}, rev.free) == rev.free


def _drift_row(c, *, wald_p, windowed, p_better, channels, ok=True):
    """A fitted candidate whose windowed validation gain is below MIN_RELATIVE, with the open-loop
    verdict's channels given as (MSE ratio, better beyond the noise) and its status ``ok``."""
    ch = {k: {"mse_ratio": r, "rmse_change": np.sqrt(r) - 1.0, "better": b} for k, (r, b) in channels.items()}
    cmp = {"wald": {"p": wald_p}, "relative": windowed, "p_better": p_better,
           "guard": {"ok": ok, "channels": ch, "why": "better: pooled error -70 %"}}
    return {"candidate": c, "compare": cmp, "problem": None, "values": {"current_n": 0.02, "current_e": 0.0},
            "at_bounds": []}


def test_a_drift_the_windows_hide_is_accepted_on_the_free_simulation():
    """Benchmark seed 85's numbers: a current removes 3.4 % of the windowed validation cost
    (below MIN_RELATIVE) and 98.5 % of the open-loop position error.  The free simulation of
    the held-out runs accepts it; each missing piece of that evidence refuses it."""
    from uvsim.diagnosis.decision import MIN_RELATIVE, OPEN_LOOP_GAIN, OPEN_LOOP_WALD_P

    cur = catalogue(input_kind="pwm", n_thrusters=8, dt=0.1, p_ref=np.zeros(3), has_position=True, z_max=None,
                    only=["current"])[0]
    seed85 = dict(wald_p=1e-12, windowed=0.034, p_better=1.0, channels={"x": (0.015, True), "yaw": (0.63, True)})
    assert seed85["windowed"] < MIN_RELATIVE
    ok, why = judge(_drift_row(cur, **seed85), None)
    assert ok and "free simulation" in why and "x -88 %" in why
    # the open-loop gain must be large ...
    small = {**seed85, "channels": {"x": (1.0 - 0.9 * OPEN_LOOP_GAIN, True), "yaw": (0.9, True)}}
    ok, why = judge(_drift_row(cur, **small), None)
    assert not ok and "does not help the validation runs" in why
    # ... and beyond the comparison's noise ...
    luck = {**seed85, "channels": {"x": (0.015, False), "yaw": (1.0, False)}}
    assert not judge(_drift_row(cur, **luck), None)[0]
    # ... the windowed cost must fall too, the training fit must be significant at 1 % ...
    assert not judge(_drift_row(cur, **{**seed85, "windowed": -0.01, "p_better": 0.2}), None)[0]
    ok, why = judge(_drift_row(cur, **{**seed85, "wald_p": 2 * OPEN_LOOP_WALD_P}), None)
    assert not ok and "Wald" in why
    # ... and the verdict must be better: no channel worse, the pooled error lower
    assert not judge(_drift_row(cur, **seed85, ok=False), None)[0]


def test_a_ballast_seed_from_the_rotations_alone_is_tried_mirrored_too():
    """Without linear velocities the equation error sees a ballast's moments w r only; the
    mirrored start (-w, -r) has the same moments and the opposite vertical force."""
    from uvsim.diagnosis.candidates import mirror_start

    cands = {c.label: c for c in catalogue(input_kind="pwm", n_thrusters=6, dt=0.01, p_ref=np.zeros(3),
                                           has_position=False, z_max=None, has_depth=True)}
    seed = {"ballast_weight": 0.37, "ballast_x": 0.24, "ballast_y": 0.24, "ballast_z": 0.02}
    for label in ("ballast:xy", "ballast:xyz"):
        c = cands[label]
        m = mirror_start(c, seed)
        assert set(m) == set(c.free) and m["ballast_weight"] == -0.37
        for ax in c.free[1:]:
            assert m["ballast_weight"] * m[ax] == pytest.approx(seed["ballast_weight"] * seed[ax])
    assert mirror_start(cands["tether:3d"], seed) == {}


class _FakeSelector:
    """What :func:`uvsim.diagnosis.step_choice.still_needed` asks of a selector, with the
    windowed validation costs and open-loop blocks of the model without an effect given."""

    def __init__(self, without_windows, without_blocks):
        self.without_windows, self.without_blocks = without_windows, without_blocks
        self.fitted = []

    def current(self, accepted, values):
        free = [n for a in accepted for n in a.free]
        return {"vehicle": tuple(a.label for a in accepted), "values": dict(values), "free": free,
                "bounds": {n: a.bounds[n] for a in accepted for n in a.free}}

    def space(self, veh, free, bounds, start, fixed):
        return {n: start[n] for n in free}

    def fit_train(self, veh, sp, label):
        self.fitted.append(veh)
        return type("R", (), {"values": dict(sp), "at_bounds": []})()

    def validation(self, veh, vals):
        w = np.asarray(self.without_windows, float)
        return {"windows": w, "cost": float(w.sum()), "per_entry": float(w.mean()), "open_loop": self.without_blocks}


def _joint(cands, values, p_of):
    """A joint fit result whose Wald test of each effect gives p ~ ``p_of[effect]``."""
    names = [n for c in cands for n in c.free]
    var = []
    for c in cands:
        # W = sum (d_i / sd_i)^2 over k parameters: sd so that W is the chi2 quantile of p
        from scipy.stats import chi2

        W = chi2.isf(p_of[c.effect], len(c.null))
        for n in c.free:
            d = values[n] - c.null.get(n, values[n])
            var.append((d * d * len(c.null) / W) if n in c.null and d else 1.0)
    return type("R", (), {"names": names, "values": dict(values), "covariance": np.diag(var), "at_bounds": []})()


def test_an_effect_chosen_first_is_dropped_when_the_later_one_explains_it():
    """Backward elimination: the tether chosen in step 1 is judged again on top of the
    model with the later ballast alone; refused there (not significant, validation no
    better), it is dropped and the model without it is the answer.  A tether that the
    later effect does not explain (validation far worse without it) stays."""
    from uvsim.diagnosis.step_choice import still_needed

    cands = {c.label: c for c in catalogue(input_kind="pwm", n_thrusters=6, dt=0.01, p_ref=np.zeros(3),
                                           has_position=True, z_max=None)}
    teth, bal = cands["tether:horizontal"], cands["ballast:xy"]
    values = {**{n: teth.start[n] for n in teth.free}, "tether_stiffness": 0.05,
              "ballast_weight": -0.57, "ballast_x": -0.2, "ballast_y": -0.12}
    rng = np.random.default_rng(3)
    w_joint = rng.uniform(90, 110, 24)
    blocks = _open_loop({})
    val_joint = {"windows": w_joint, "cost": float(w_joint.sum()), "per_entry": 1.0, "open_loop": blocks}
    # the later ballast explains it: without the tether the validation is the same
    sel = _FakeSelector(w_joint * 1.001, blocks)
    acc, vals, val, _, rows = still_needed(sel, [teth, bal], values, val_joint,
                                           _joint([teth, bal], values, {"tether": 0.2, "ballast": 1e-30}))
    assert [c.label for c in acc] == ["ballast:xy"] and sel.fitted == [("ballast:xy",)]
    assert rows[0]["effect"] == "tether" and not rows[0]["kept"] and "Wald" in rows[0]["why"]
    assert np.allclose(val["windows"], w_joint * 1.001) and vals["ballast_weight"] == -0.57
    # it does not: the tether stays
    worse = _open_loop({"x": 3.0, "y": 3.0})
    sel = _FakeSelector(w_joint * 2.0, worse)
    acc, _, val, _, rows = still_needed(sel, [teth, bal], values, val_joint,
                                        _joint([teth, bal], values, {"tether": 1e-12, "ballast": 1e-30}))
    assert [c.label for c in acc] == ["tether:horizontal", "ballast:xy"] and rows[0]["kept"]
    assert val is val_joint
    # significant beside the later effect, refused by the open-loop verdict alone: kept (the verdict is
    # the entry rule; benchmark seed 118's thruster lag beside a weak thruster)
    better = _open_loop({"x": 0.5, "y": 0.5})
    sel = _FakeSelector(w_joint * 2.0, better)
    acc, _, _, _, rows = still_needed(sel, [teth, bal], values, val_joint,
                                      _joint([teth, bal], values, {"tether": 1e-12, "ballast": 1e-30}))
    assert len(acc) == 2 and rows[0]["kept"] and "entry rule" in rows[0]["why"]


# ----------------------------------------------------------------------------- verdict
def test_verdict_says_not_explained_and_where():
    conc = {"by_channel": [{"name": "depth", "share": 0.7}, {"name": "pitch", "share": 0.2},
                           {"name": "x", "share": 0.1}],
            "by_run": [{"name": "val_1", "share": 1.0}],
            "by_part": [{"name": "end", "share": 0.6}, {"name": "middle", "share": 0.3},
                        {"name": "start", "share": 0.1}]}
    v = verdict(40.0, [], conc, 1.5)
    assert v["status"] == "not explained" and v["unexplained"]
    assert [x["name"] for x in v["where"]["by_channel"]] == ["depth", "pitch"]
    assert any(c.startswith("depth:") for c in v["check"]) and any("slowly acting" in c for c in v["check"])
    assert "not explained by the catalogue" in v["message"]
    assert verdict(40.0, ["tether"], conc, 1.5)["status"] == "partly explained"
    assert verdict(1.2, ["tether"], conc, 1.5)["status"] == "explained"
    assert verdict(1.2, [], conc, 1.5)["status"] == "at noise"
    assert verdict(0.5 * (1.5 + UNEXPLAINED), [], conc, 1.5)["status"] == "between"


def test_observability_is_reported_not_silent():
    notes = observability(has_position=False, has_depth=True, has_velocity=False, z_max=2.0, n_thrusters=8)
    assert {n["effect"] for n in notes} == {"tether", "current"}
    no_pos = {c.variant for c in catalogue(input_kind="pwm", n_thrusters=8, dt=0.01, p_ref=np.zeros(3),
                                           has_position=False, has_depth=True, z_max=2.0, only=["tether"])}
    assert "3d" in no_pos and "tension" in no_pos and not any(v.startswith("horizontal") for v in no_pos)
    assert observability(has_position=True, has_depth=True, has_velocity=False, z_max=2.0, n_thrusters=8) == []


# ----------------------------------------------------------------------------- end to end
@pytest.mark.slow
def test_an_out_of_catalogue_force_is_not_explained(tmp_path):
    """A periodic force (outside the catalogue) on otherwise exact data: the verdict says the
    residual is not explained and where it lies; whatever is named passed the guard."""
    spec = sample_scenario(7, profile="diagnose", n_runs=10, duration=[8, 10], rate_hz=20.0,
                           effects=[{"type": "periodic_force", "magnitude": 2.0}])
    out = generate(spec, tmp_path / "s7")
    assert load_truth(out)["effects"][0]["type"] == "periodic_force"
    rep = diagnose(out).report
    v = rep["verdict"]
    assert v["unexplained"] and v["status"] in ("not explained", "partly explained"), v
    assert v["where"]["by_channel"] and v["check"]
    for st in rep["steps"]:
        for c in st["candidates"]:
            if c["chosen"]:
                assert "no logged group's open-loop validation error is worse" in c["why"]


@pytest.mark.slow
def test_a_thrust_curve_at_another_voltage_is_the_base_model_not_a_thruster_fault(tmp_path):
    """Issue 22 class 5: PWM runs through the T200 curve measured at 12 V while the model's
    file says 16 V, nothing else wrong: no effect is named; the base model's thrust scale
    (not per-thruster gains) takes the curve, below 1 (less thrust at 12 V)."""
    from uvsim.benchmarks.structural import run_one

    rec = run_one("curve_mismatch", 10000, tmp=tmp_path)
    assert rec["curve"] == "t200_12v_measured" and rec["truth"] == []
    assert rec["named"] == [] and rec["correct"]
    assert rec["base_model"] == "thrust_scale"
    assert rec["worst_group_change"] is not None and rec["worst_group_change"] <= 0.10


@pytest.mark.slow
def test_a_voltage_family_vehicle_gets_the_battery_voltage_and_the_effect_beside_it(tmp_path):
    """Issue 22 class 5 with an effect: PWM runs through the T200 curve measured at 20 V, the
    model's thrusters on the voltage family at the file's 16 V, and a ballast the model lacks.
    The base model's ``supply_voltage`` takes the curve (a thrust scale cannot: the family
    differs in shape near the dead band), and the ballast is named beside it."""
    from uvsim.benchmarks.structural import run_one

    rec = run_one("curve_mismatch", 10001, supply=True, tmp=tmp_path)
    assert rec["curve"] == "t200_20v_measured" and rec["true"] == ["ballast"]
    assert rec["base_model"] == "supply_voltage"
    assert rec["named"] == ["ballast"] and rec["correct"]
    assert rec["worst_group_change"] is not None and rec["worst_group_change"] <= 0.10
