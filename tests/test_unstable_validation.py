"""The never-worse check on a validation run whose free simulation amplifies its start
(uvsim.fitting.sensitivity): the generator's own truth, directionally unstable, must not be
refused against a wrong but stable start model, and the run must be named."""
from __future__ import annotations

import yaml

from uvsim.benchmarks.calibration_structural import scenario
from uvsim.calibration.report import evaluate_runs, never_worse
from uvsim.fitting.sensitivity import initial_state_growth
from uvsim.logs import read_dataset
from uvsim.measurements import measurements_for
from uvsim.scenarios import generate, sample_scenario
from uvsim.vehicle import load_vehicle


def test_an_unstable_truth_is_not_refused_against_a_stable_start(tmp_path):
    # benchmark seed 35: truth Y_vdot - X_udot = 9.2 kg (file: 0.84 kg), a straight surge validation run
    out = generate(sample_scenario(35, profile="realsensor", **scenario(35, structure=False)), tmp_path / "ds")
    truth_file = tmp_path / "truth_vehicle.yaml"
    truth_file.write_text(yaml.safe_dump(yaml.safe_load((out / "truth.yaml").read_text())["vehicle"]))
    start, truth = load_vehicle(out / "myrov.yaml"), load_vehicle(truth_file)
    ds = read_dataset(out)
    meas = [measurements_for(r, start) for r in ds.runs]
    by_name = {r.name: m for r, m in zip(ds.runs, meas)}
    ev_truth, ev_start = evaluate_runs(truth, ds.runs, meas), evaluate_runs(start, ds.runs, meas)
    val = [r for r in ds.runs if r.split == "validation"]
    growth = initial_state_growth(truth, val, [by_name[r.name] for r in val], [ev_truth[r.name] for r in val])
    assert growth["val_04_telegraph_mixed"]["unstable"] and growth["val_04_telegraph_mixed"]["growth"] > 10
    stable = initial_state_growth(start, val, [by_name[r.name] for r in val], [ev_start[r.name] for r in val])
    assert not stable["val_05_telegraph_mixed"]["unstable"]
    # the free simulations alone refuse the truth (the test can fail) ...
    assert not never_worse(ds.runs, ev_truth, ev_start, by_name)["ok"]
    # ... with the growth test the unstable run's attitude and rates are left out and named
    nw = never_worse(ds.runs, ev_truth, ev_start, by_name, (start, truth))
    assert nw["ok"], nw["why"]
    assert set(nw["not_compared"]) == {"val_04_telegraph_mixed"}
    assert {"r", "p", "roll"} <= set(nw["not_compared"]["val_04_telegraph_mixed"]["channels"])
    assert "depth" not in nw["not_compared"]["val_04_telegraph_mixed"]["channels"]
    assert nw["fit_percent"]["r"] > nw["initial_fit_percent"]["r"]


def test_the_diagnosis_guard_leaves_out_what_either_side_marks_unstable():
    # compare_open_loop (the diagnosis' guard): a run marked unstable by either side is left out
    # for both, by signal group as diagnosis compares
    import numpy as np

    from uvsim.fitting.guard import block_costs, compare_open_loop
    from uvsim.synthetic import generate_runs

    runs, _ = generate_runs("bluerov2_heavy", dofs=("yaw",), runs_per_dof=2, validation_per_dof=0, seed=4)
    veh = load_vehicle("bluerov2_heavy")
    meas = [measurements_for(r, veh) for r in runs]
    ev = evaluate_runs(veh, runs, meas)
    good = [ev[r.name] for r in runs]
    bad = [dict(e, pred={k: (v + 0.5 if k == "attitude" and i == 0 else v) for k, v in e["pred"].items()})
           for i, e in enumerate(good)]
    before, after = block_costs(meas, good), block_costs(meas, bad)
    assert not compare_open_loop(before, after)["ok"]          # the attitude of run 0 is much worse
    # unstable for the candidate only: left out and listed; refused where asked (the calibration)
    after["unstable"] = {runs[0].name: ["roll", "pitch", "yaw"]}
    g = compare_open_loop(before, after)
    assert g["ok"] and g["newly_unstable"] == [runs[0].name]
    assert g["not_compared"] == {runs[0].name: ["pitch", "roll", "yaw"]}
    g = compare_open_loop(before, after, refuse_newly_unstable=True)
    assert not g["ok"] and "is unstable" in g["why"] and "attitude" not in g["worse"]
    # unstable for both: left out for both, and judged on the rest
    before["unstable"] = {runs[0].name: ["roll"]}
    g = compare_open_loop(before, after)
    assert g["ok"] and g["not_compared"] == {runs[0].name: ["pitch", "roll", "yaw"]} and g["newly_unstable"] == []
    assert np.isfinite(g["groups"]["attitude"]["after"])


def test_a_fit_unstable_where_the_start_is_stable_is_not_ok(tmp_path):
    # benchmark seed 30: truth and start are stable on both validation runs; a "fit" with the
    # sway added mass 15 kg above the surge one and a fifth of the yaw damping is not
    out = generate(sample_scenario(30, profile="realsensor", **scenario(30, structure=False)), tmp_path / "ds")
    start = load_vehicle(out / "myrov.yaml")
    P = start.parameters()
    bad = start.with_parameters({"Y_vdot": P["X_udot"] + 15.0, "N_r": 0.2 * P["N_r"], "N_rr": 0.2 * P["N_rr"]})
    ds = read_dataset(out)
    meas = [measurements_for(r, start) for r in ds.runs]
    by_name = {r.name: m for r, m in zip(ds.runs, meas)}
    nw = never_worse(ds.runs, evaluate_runs(bad, ds.runs, meas), evaluate_runs(start, ds.runs, meas), by_name,
                     (start, bad))
    assert nw["unstable_fit"] and not nw["ok"]
    assert "is unstable" in nw["why"] and set(nw["unstable_fit"]) <= set(nw["not_compared"])
