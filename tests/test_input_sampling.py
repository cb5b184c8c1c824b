"""Inputs that change like noise from row to row (uvsim.input_sampling): the statistic on seeded
sequences of known form, the project's field logs (an autopilot at 50 Hz logged at 10 Hz: written
apart from this code, uvsim.scenarios.field), the shipped tank tests, and the note the commands print."""
from __future__ import annotations

from pathlib import Path

import numpy as np

import uvsim
from uvsim.input_sampling import CHATTER_AUTOCORR, MIN_CHANGES, change_autocorrelation, chattering_input_notes
from uvsim.logs import read_dataset

TANK = Path(uvsim.__file__).parent / "data" / "datasets" / "bluerov2_tank"


def test_the_statistic_separates_independent_values_from_resolved_inputs():
    rng = np.random.default_rng(7)
    n = 600
    iid = 1500 + 20 * rng.standard_normal(n)                 # a snapshot of a chattering command per row
    held = np.repeat(1500 + 100 * rng.standard_normal(n // 6), 6)   # steps held over six rows
    sweep = 1500 + 200 * np.sin(np.linspace(0, 12, n))       # a smooth sweep
    r_iid, r_held, r_sweep = (change_autocorrelation(x) for x in (iid, held, sweep))
    assert abs(r_iid + 0.5) < 0.1 and r_iid < CHATTER_AUTOCORR
    assert abs(r_held) < 0.15 and r_held > CHATTER_AUTOCORR
    assert r_sweep > 0.9
    # a slow drift under the chatter still reads as chatter: what the log cannot resolve is the chatter
    assert change_autocorrelation(iid + np.linspace(0, 300, n)) < CHATTER_AUTOCORR
    assert change_autocorrelation(iid[:MIN_CHANGES]) is None      # too few changes to tell
    assert change_autocorrelation(np.full(n, 1500.0)) is None     # a constant input


def test_field_logs_flag_the_depth_hold_thrusters_and_the_tank_tests_nothing(tmp_path):
    from uvsim.scenarios.field import generate_field, sample_field

    spec = sample_field(0, "clean")
    assert spec["log_hz"] == 10.0
    ds = read_dataset(generate_field(spec, tmp_path / "field"))
    notes = chattering_input_notes(ds.runs)
    assert len(notes) == 1
    note = notes[0]
    # the vertical units (5-8 of the Heavy's mixer) chatter under depth hold; the horizontal ones follow sticks
    assert "pwm_5" in note and "pwm_6" in note and "pwm_8" in note
    assert not any(f"pwm_{i}," in note or f"pwm_{i} " in note for i in (1, 2, 3, 4))
    assert "10 Hz" in note and "log the inputs at the autopilot's rate" in note
    assert chattering_input_notes(read_dataset(TANK).runs) == []


def test_calibrate_and_diagnose_say_it_at_the_door(tmp_path):
    from uvsim.commands.checks import check_runs_at_door
    from uvsim.vehicle import load_vehicle

    rng = np.random.default_rng(3)
    ds = read_dataset(TANK)
    run = ds.runs[0]
    data = run.data.copy()
    col = run.input_columns[0]
    data[col] = 1500 + 30 * rng.standard_normal(len(data))   # a chattering command held at 50 Hz rows
    noisy = run.derived(data)
    veh = load_vehicle("bluerov2_heavy")
    lines = check_runs_at_door("diagnose", [noisy], veh, None)
    assert any(line.startswith("note: ") and f"{col} of {run.name} change like noise" in line for line in lines)
    assert not any("change like noise" in line for line in
                   check_runs_at_door("diagnose", ds.runs[:3], veh, None))
