"""Dataset batching: padding, partial initial states, residuals (shared with diagnosis)."""
import numpy as np
import pandas as pd
import pytest

import uvsim
from calibration_data import tank_runs
from uvsim.calibration import prepare_runs, simulate_dataset
from uvsim.calibration.batching import initial_state
from uvsim.errors import CalibrationError
from uvsim.logs import Run


def _cut(run, n, name=None):
    return Run(name=name or f"{run.name}_cut", path=None, data=run.data.iloc[:n].reset_index(drop=True),
               dof=run.dof, weight=run.weight, split=run.split)


def test_padded_batch_equals_single_simulations():
    runs, _ = tank_runs(dofs=("surge", "yaw"))
    sel = [runs[0], _cut(runs[1], 120), _cut(runs[6], 77)]
    b = prepare_runs(sel)
    assert list(b.lengths) == [len(r.t) for r in sel]
    pred = simulate_dataset("bluerov2_heavy", b)
    for r, p, i in zip(sel, pred, range(3)):
        single = uvsim.simulate("bluerov2_heavy", r.t, r.inputs, input_kind=r.input_kind, pos0=b.pos0[i],
                                q0=b.q0[i], nu0=b.nu0[i])
        assert p["states"].shape[0] == len(r.t)
        np.testing.assert_allclose(p["states"][:, :13], single.y[:, :13], rtol=1e-9, atol=1e-12)


def test_partial_initial_state():
    runs, _ = tank_runs(dofs=("heave",), signals=("depth",))
    r = runs[0]
    pos0, q0, nu0, known = initial_state(r)
    assert pos0[0] == 0 and pos0[1] == 0 and abs(pos0[2] - r.position[0, 2]) < 0.05
    assert np.allclose(q0, [1, 0, 0, 0]) and not known.any() and np.all(nu0 == 0)
    # a run logging rates starts from them
    runs, _ = tank_runs(dofs=("yaw",), signals=("imu_attitude", "rates"))
    r = runs[3]
    data = r.data.copy()
    data.loc[0, ["p", "q", "r"]] = [0.01, -0.02, 0.3]
    r2 = Run(name="x", path=None, data=data)
    pos0, q0, nu0, known = initial_state(r2)
    assert list(known) == [False, False, False, True, True, True]
    assert nu0[5] == 0.3 and nu0[0] == 0.0
    # "differentiate": unknown velocities from smoothed logged signals
    runs, _ = tank_runs(dofs=("surge",))
    d = runs[3].data.iloc[200:].reset_index(drop=True)  # starts while moving
    moving = Run(name="moving", path=None, data=d)
    _, _, nu0, _ = initial_state(moving, initial_velocity="differentiate")
    assert abs(nu0[0]) > 0.05
    with pytest.raises(CalibrationError, match="initial_velocity"):
        initial_state(moving, initial_velocity="guess")


def test_mixed_input_kinds_rejected_and_empty():
    runs, _ = tank_runs(dofs=("surge",))
    r = runs[0]
    t = r.t
    f = pd.DataFrame({"t": t, "x": r.position[:, 0], **{c: np.zeros_like(t) for c in "XYZKMN"}})
    with pytest.raises(CalibrationError, match="mix input kinds"):
        prepare_runs([r, Run(name="force", path=None, data=f)])
    with pytest.raises(CalibrationError, match="no runs"):
        prepare_runs([])
