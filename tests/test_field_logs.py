"""Issue 48, diagnosis on field logs: what an autopilot hides is not a reason to stop.

A model flown open loop against a log of a vehicle under depth or heading hold drifts away
from the data; the diagnosis still tries the catalogue and judges the corrected model against
the given one, and says where the given model left the data, as a caveat, not a refusal."""
from __future__ import annotations

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
