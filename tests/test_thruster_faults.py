"""Issue 48, physical ranges: a thruster's gain spans [0, 1.5] with 0 a dead unit named as
such, and a unit that pushes the wrong way is a candidate of its own, written to the
corrected vehicle with its direction reversed. The end-to-end cases diagnose data of the
independent truth model (uvsim.scenarios), where the fault is a thrust factor of 0 or -1."""
from __future__ import annotations

import numpy as np
import pytest
import yaml

import uvsim
from contract_data import shipped_vehicle_text
from uvsim.diagnosis import diagnose, save_fixed_vehicle
from uvsim.diagnosis.candidates import _gain, catalogue, search_bound_hits
from uvsim.diagnosis.units import plain_answer, reported_variant
from uvsim.scenarios import generate, load_truth, sample_scenario

SMALL = dict(n_runs=10, duration=[8, 10], rate_hz=20.0)


def test_a_dead_unit_is_a_vehicle_file_value_and_a_reversed_one_is_written_reversed(tmp_path):
    d = yaml.safe_load(shipped_vehicle_text())
    d["thrusters"]["units"][2]["gain"] = 0.0                     # before: refused, (0, 2] only
    veh = uvsim.vehicle.vehicle_from_dict(d, source="veh.yaml")
    assert veh.parameters()["thruster_gain_3"] == 0.0
    t = np.arange(0, 6, 0.02)
    pwm = np.full((t.size, 8), 1500.0)
    pwm[:, [0, 2]] = 1650.0
    rev = veh.with_parameters({"thruster_gain_3": -0.9})         # a reversed unit at 0.9 of its curve
    unit = rev.actuators.specs["units"][2]
    assert unit["gain"] == 0.9 and unit["direction"] == [-x for x in d["thrusters"]["units"][2]["direction"]]
    a = uvsim.simulate(veh, t, pwm, input_kind="pwm", overrides={"thruster_gain_3": -0.9}).to_pandas()
    b = uvsim.simulate(rev, t, pwm, input_kind="pwm").to_pandas()
    np.testing.assert_allclose(a[["x", "y", "z", "yaw"]].to_numpy(), b[["x", "y", "z", "yaw"]].to_numpy(), atol=1e-12)


def test_gain_ranges_are_physical_and_a_dead_unit_is_an_answer_not_an_edge():
    unit, reversed_, _ = _gain(1)[0], _gain(1)[1], _gain(1)[2]
    assert unit.bounds["thruster_gain_1"] == (0.0, 1.5) and reversed_.bounds["thruster_gain_1"] == (-1.5, 0.0)
    assert search_bound_hits(unit, {"thruster_gain_1": 0.0}, ["thruster_gain_1"]) == []     # dead: physical
    assert search_bound_hits(unit, {"thruster_gain_1": 1.5}, ["thruster_gain_1"]) == ["thruster_gain_1"]
    # a reversed unit at 0, the upper end of its range, is the same dead unit (reported as unit_1 below)
    assert search_bound_hits(reversed_, {"thruster_gain_1": 0.0}, ["thruster_gain_1"]) == []
    assert search_bound_hits(reversed_, {"thruster_gain_1": -1.5}, ["thruster_gain_1"]) == ["thruster_gain_1"]
    assert plain_answer(unit, {"thruster_gain_1": 0.004}) == "thruster 1 gives no thrust (gain 0.004: a dead unit)"
    assert plain_answer(unit, {"thruster_gain_1": 0.6}) is None
    assert "pushes the wrong way" in plain_answer(reversed_, {"thruster_gain_1": -1.0})
    # a reversed unit fitted at ~0 is the unit's own variant at 0: a dead unit (field-log dead case, seed 0)
    assert plain_answer(reversed_, {"thruster_gain_1": -0.004}) == "thruster 1 gives no thrust (gain -0.004: a dead unit)"
    assert reported_variant(reversed_, {"thruster_gain_1": -0.004}) == "unit_1"
    assert reported_variant(reversed_, {"thruster_gain_1": -0.9}) == "reversed_1"
    assert reported_variant(unit, {"thruster_gain_1": 0.0}) == "unit_1"
    variants = {c.variant for c in catalogue(input_kind="pwm", n_thrusters=8, dt=0.05, p_ref=np.zeros(3),
                                             has_position=True, z_max=None) if c.effect == "thruster_gain"}
    assert {"unit_8", "reversed_8", "all"} <= variants
    # every gain: the unit that stands out, in words (a dead one as dead)
    every = next(c for c in _gain(8) if c.variant == "all")
    g = {f"thruster_gain_{i}": v for i, v in enumerate([0.81, 0.8, 0.79, 0.82, 0.78, 0.8, 0.49, 0.78], start=1)}
    assert plain_answer(every, g) == "every unit's gain: thruster 7 at 0.49 of its curve, the other 7 at 0.78-0.82"
    assert plain_answer(every, {**g, "thruster_gain_7": 0.0}).startswith("thruster 7 gives no thrust (a dead unit)")


def _fault(tmp_path, magnitude, seed=3):
    spec = sample_scenario(seed, profile="diagnose", **SMALL, input_kind="pwm",
                           effects=[{"type": "weak_thruster", "magnitude": magnitude}])
    out = generate(spec, tmp_path / "data")
    return out, load_truth(out)["effects"][0]


@pytest.mark.slow
def test_a_reversed_thruster_is_named_reversed_and_the_corrected_vehicle_flies_like_the_truth(tmp_path):
    out, truth = _fault(tmp_path, 2.0)                         # the truth's gain 1 - 2 = -1
    d = diagnose(out)
    (e,) = d.report["effects"]
    assert (e["effect"], e["variant"]) == ("thruster_gain", f"reversed_{truth['thruster']}")
    assert e["answer"].startswith(f"thruster {truth['thruster']} pushes the wrong way")
    assert e["parameters"][f"thruster_gain_{truth['thruster']}"]["value"] == pytest.approx(-1.0, abs=0.05)
    assert d.report["model_verdict"]["status"] == "better"
    fixed = uvsim.load_vehicle(save_fixed_vehicle(d, tmp_path / "fixed.yaml"))
    assert fixed.parameters()[f"thruster_gain_{truth['thruster']}"] == pytest.approx(1.0, abs=0.05)


@pytest.mark.slow
def test_a_dead_thruster_is_named_dead(tmp_path):
    out, truth = _fault(tmp_path, 1.0)                         # the truth's gain 0
    d = diagnose(out)
    answers = [e.get("answer") or "" for e in d.report["effects"] if e["effect"] == "thruster_gain"]
    assert any(f"{truth['thruster']} give" in a and "no thrust" in a for a in answers), d.report["effects"]
    assert d.report["model_verdict"]["status"] == "better"
    assert uvsim.load_vehicle(save_fixed_vehicle(d, tmp_path / "fixed.yaml"))
