"""Issue 48, diagnosis on field logs.

* What an autopilot hides is not a reason to stop: a model flown open loop against a log of a
  vehicle under depth or heading hold drifts away from the data; the diagnosis still tries the
  catalogue, judges the corrected model against the given one, and says where the given model
  left the data, as a caveat, not a refusal.
* Clocks as they are: jittered stamps keep the equation-error screening on."""
from __future__ import annotations

import numpy as np
import pytest

from contract_data import SHIPPED_DATASET
from uvsim.commands.checks import EXPLODE_FACTOR, _spread, diagnosis_caveats, diagnosis_problems
from uvsim.logs import read_dataset


def _reports():
    val = [r for r in read_dataset(SHIPPED_DATASET).runs if r.split == "validation"]
    spread = _spread(val)
    drift = {k: 3 * EXPLODE_FACTOR * v for k, v in spread.items()}      # the given model drifts away
    fixed = {k: 0.5 * v for k, v in spread.items()}                     # the corrected one follows
    return val, drift, fixed


def test_a_given_model_that_leaves_the_data_is_a_caveat_not_a_refusal():
    """Before: 'validation RMSE of the given model ... (the simulation diverged)' made the
    diagnosis exit 2 whatever it found (a lead weight under depth hold, issue 48)."""
    val, drift, fixed = _reports()
    rep = {"rmse_before": drift, "rmse_after": fixed, "steps": []}
    assert diagnosis_problems(rep, val) == []
    (caveat,) = diagnosis_caveats(rep, val)
    assert "the given model's free simulation leaves the validation data" in caveat and "stays with it" in caveat
    both = {"rmse_before": drift, "rmse_after": drift, "steps": []}
    assert diagnosis_problems(both, val) == [] and "still does in" in diagnosis_caveats(both, val)[0]


def test_a_corrected_model_that_leaves_the_data_where_the_given_one_did_not_is_refused():
    val, drift, fixed = _reports()
    rep = {"rmse_before": fixed, "rmse_after": drift, "steps": []}
    probs = diagnosis_problems(rep, val)
    assert probs and all("where the starting model's did not" in p for p in probs)
    assert diagnosis_caveats(rep, val) == []


def _jittered(tmp_path, jitter=0.008):
    from uvsim.scenarios import generate, sample_scenario

    spec = sample_scenario(5, profile="diagnose", n_runs=10, duration=[8, 10], rate_hz=20.0, input_kind="pwm",
                           effects=[{"type": "current", "magnitude": 0.15}], time_jitter=jitter)
    return generate(spec, tmp_path / "jit")


def test_jittered_stamps_keep_the_equation_error_on(tmp_path):
    """Before: 'time stamps are not uniform ... the Savitzky-Golay derivative needs uniform
    sampling' for every run, and the screening was off (issue 48, clocks as they are)."""
    from uvsim.fitting.equation_error import motion_or_why

    ds = read_dataset(_jittered(tmp_path))
    assert not np.allclose(np.diff(ds.runs[0].t), np.median(np.diff(ds.runs[0].t)), rtol=0.01)
    for run in ds.runs:
        motion, why = motion_or_why(run)
        assert motion is not None and why is None, why


@pytest.mark.slow
def test_a_current_under_jittered_stamps_is_named_by_the_screening(tmp_path):
    """8 ms of stamp jitter at 20 Hz: before, the screening was off and the diagnosis named
    current (horizontal) + a spurious ballast; now the screening runs and names the 3-D current."""
    from uvsim.diagnosis import diagnose
    from uvsim.scenarios import load_truth

    out = _jittered(tmp_path)
    truth = load_truth(out)["effects"][0]["velocity_ned"]
    rep = diagnose(out).report
    assert all(st["screening"]["available"] for st in rep["steps"])
    (e,) = rep["effects"]
    assert e["effect"] == "current"
    got = [e["parameters"][f"current_{c}"]["value"] for c in "ned" if f"current_{c}" in e["parameters"]]
    assert np.allclose(got, truth[:len(got)], atol=0.01) and len(got) == 3


def test_an_effect_on_its_bounds_is_judged_by_the_final_fit_and_a_dead_units_gain_is_no_bound():
    """The sanity check behind exit 2 reads the corrected model's own fit (``at_bound`` of each
    parameter of ``effects`` and ``base_model``): field logs, dead case seed 21, exited 2 for the
    thrust scale step 0 had put on its 0.5 bound (0.61 in the final fit beside the dead unit) and
    for the dead unit's gain 0 (a physical floor).  A parameter really on its bound still counts."""
    val, _, fixed = _reports()

    def rep(scale_at_bound, gain_at_bound):
        return {"rmse_before": fixed, "rmse_after": fixed,
                "steps": [{"candidates": [{"chosen": True, "effect": "base_model", "variant": "thrust_scale",
                                           "free": ["thrust_scale_scale"], "at_bounds": ["thrust_scale_scale"]}]}],
                "base_model": {"variant": "thrust_scale", "parameters": {
                    "thrust_scale_scale": {"value": 0.5 if scale_at_bound else 0.61, "at_bound": scale_at_bound}}},
                "effects": [{"effect": "thruster_gain", "variant": "unit_7", "parameters": {
                    "thruster_gain_7": {"value": 1.5 if gain_at_bound else 0.0, "at_bound": gain_at_bound}}}]}

    assert diagnosis_problems(rep(False, False), val) == []
    (p,) = diagnosis_problems(rep(True, False), val)
    assert "base_model:thrust_scale" in p and "ended on a bound" in p
    assert "thrust_scale_scale 0.5" in p and "not an answer" in p  # the value, and how to read it
    (p,) = diagnosis_problems(rep(False, True), val)
    assert "thruster_gain:unit_7" in p
    old = rep(False, False)
    for f in [old["base_model"], *old["effects"]]:  # a report without at_bound: each step's own fit
        for d in f["parameters"].values():
            del d["at_bound"]
    (p,) = diagnosis_problems(old, val)
    assert "base_model:thrust_scale" in p


def test_a_base_model_on_its_search_edge_is_not_told_to_be_calibrated():
    """Field tether seeds: the thrust scale stops on its 0.5 floor because the autopilot pushes against
    a tether the model lacks; the message must not send the user to calibrate a scale of 0.5."""
    from uvsim.diagnosis.summary import summary_message

    def msg(at_bound):
        base = {"variant": "thrust_scale", "notes": "every thruster's curve scaled",
                "parameters": {"thrust_scale_scale": {"value": 0.5 if at_bound else 0.8, "before": 1.0,
                                                      "at_bound": at_bound}}}
        cost = {"per_entry": 100.0}
        return summary_message([], {}, base, cost, cost, 1.5, None, [], [])

    assert "calibrate it (uvsim calibrate)" in msg(False) and "stands in for" not in msg(False)
    on_edge = msg(True)
    assert "calibrate it (uvsim calibrate)" not in on_edge and "on the edge of its search range" in on_edge
    assert "thrust_scale_scale 1 -> 0.5" in on_edge


def test_a_random_angle_is_off_by_pi_over_root_3():
    """The reference of a lost angle (uvsim.fitting.evaluate.RANDOM_ANGLE_RMSE): the wrapped error of
    angles drawn at random against a logged series, by sampling."""
    from uvsim.fitting.evaluate import RANDOM_ANGLE_RMSE

    rng = np.random.default_rng(3)
    logged = np.cumsum(rng.normal(0, 0.05, 200_000))          # any heading history
    drawn = rng.uniform(-np.pi, np.pi, logged.size)
    err = np.angle(np.exp(1j * (logged - drawn)))
    assert np.sqrt(np.mean(err ** 2)) == pytest.approx(RANDOM_ANGLE_RMSE, rel=0.01)
    assert RANDOM_ANGLE_RMSE == pytest.approx(1.8138, abs=1e-4)


def test_a_lost_heading_over_whole_runs_is_a_caveat(tmp_path):
    """A compass-less heading hold (the field generator, written apart from the fitting code) leaves the
    given model's free-simulated yaw as far off as a random angle, which the spread rule cannot see
    for a wrapped angle: on a log that does not say it was flown in closed loop the verdict still
    compares whole runs, says the heading is lost and how to declare the autopilot; declared, the
    runs are judged over windows; the shipped tank data lose nothing."""
    import copy
    from pathlib import Path

    from uvsim.fitting.evaluate import judged_prediction
    from uvsim.measurements import measurements_for
    from uvsim.scenarios.field import generate_field, sample_field

    d = generate_field(sample_field(0, "clean", duration=40.0, n_train=1, n_validation=1), tmp_path / "field")
    declared = [r for r in read_dataset(d).runs if r.split == "validation"]
    veh = str(Path(d) / "myrov.yaml")
    meas = [measurements_for(r, veh) for r in declared]
    val = [copy.copy(r) for r in declared]
    for r in val:
        r.closed_loop = None                    # a topside log that does not record the flight mode
    judged = judged_prediction(veh, val, meas)
    assert judged["prediction"] == "whole runs"
    assert set(judged["lost_angles"]) == {"yaw"} and judged["lost_angles"]["yaw"] > 1.0
    assert "has lost yaw" in judged["why"]
    (caveat,) = diagnosis_caveats({"judged": judged, "rmse_before": {}, "rmse_after": {}}, val)
    assert "has lost yaw (RMS error" in caveat and "closed_loop: true" in caveat and "--judge-horizon" in caveat
    assert judged_prediction(veh, declared, meas)["horizon_s"] == 1.0
    tank = [r for r in read_dataset(SHIPPED_DATASET).runs if r.split == "validation"]
    calm = judged_prediction("bluerov2_heavy", tank, [measurements_for(r, "bluerov2_heavy") for r in tank])
    assert "lost_angles" not in calm and diagnosis_caveats({"judged": calm, "rmse_before": {}}, tank) == []


def test_calibrate_says_a_lost_angle_of_the_runs_it_judged():
    """calibrate's caveats name the runs its verdict compared (the training runs when there are no
    validation runs) and say nothing of a verdict judged over windows."""
    from uvsim.commands.checks import calibration_caveats

    ds = read_dataset(SHIPPED_DATASET)
    judged = {"prediction": "whole runs", "lost_angles": {"yaw": 1.5}, "split": "train"}
    (caveat,) = [c for c in calibration_caveats({"judged": judged}, ds) if "has lost" in c]
    assert caveat.startswith("the starting model's free simulation of the training runs has lost yaw (RMS error 1.5 rad")
    windows = {"prediction": "windows", "horizon_s": 5.0, "lost_angles": {"yaw": 1.5}}
    assert not [c for c in calibration_caveats({"judged": windows}, ds) if "has lost" in c]
