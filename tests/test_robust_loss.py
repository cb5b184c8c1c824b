"""The Huber loss of the windowed fit (``loss="huber"``, issue 21 item 4): its residual form
costs what Huber's rho says, and a fit on a log with sensor dropouts (the pressure sensor
reading 0 for a few samples, as real logs do) recovers the coefficients that least squares
loses to the dropouts."""
from __future__ import annotations

import numpy as np
import pytest

import uvsim
from uvsim.calibration import Calibrator
from uvsim.errors import CalibrationError
from uvsim.fitting import fit, make_space
from uvsim.fitting.objective import HUBER_SCALE, robust_residuals
from uvsim.logs import Run
from uvsim.synthetic import generate_runs


def test_huber_residuals_cost_rho_and_are_smooth():
    r = np.linspace(-20, 20, 4001)
    k = HUBER_SCALE
    rho = np.where(np.abs(r) <= k, 0.5 * r * r, k * np.abs(r) - 0.5 * k * k)     # Huber 1964
    rt = robust_residuals(r, "huber")
    assert np.allclose(0.5 * rt * rt, rho) and np.all(np.sign(rt) == np.sign(r))
    assert np.max(np.abs(np.diff(rt))) < 1.01 * (r[1] - r[0])                    # slope <= 1, no jump
    assert np.array_equal(robust_residuals(r, "linear"), r)
    with pytest.raises(CalibrationError, match="loss 'cauchy'"):
        robust_residuals(r, "cauchy")


def test_huber_fit_survives_depth_dropouts_that_least_squares_does_not():
    v = uvsim.load_vehicle("bluerov2_heavy")
    P = v.parameters()
    truth = {"Z_ww": P["Z_ww"] * 1.3, "Z_w": P["Z_w"] * 0.7}
    runs, _ = generate_runs("bluerov2_heavy", dofs=("heave",), runs_per_dof=3, validation_per_dof=0, seed=2,
                            overrides=truth)
    rng = np.random.default_rng(5)
    bad = []
    for r in runs:  # three bursts of 5 samples (0.1 s) per run where the depth reads 0
        d = r.data.copy()
        for _ in range(3):
            a = int(rng.integers(20, len(d) - 10))
            d.loc[d.index[a:a + 5], "z"] = 0.0
        bad.append(Run(r.name, None, d, dof=r.dof, split=r.split))
    space = make_space(P, ["Z_ww", "Z_w", "Z_wdot"])
    ls = fit(v, bad, space)
    hub = fit(v, bad, space, loss="huber")
    assert abs(ls.values["Z_ww"] / truth["Z_ww"] - 1) > 0.1          # least squares: lost to the dropouts
    assert hub.values["Z_ww"] == pytest.approx(truth["Z_ww"], rel=0.01)
    assert hub.values["Z_wdot"] == pytest.approx(P["Z_wdot"], rel=0.02)
    assert "Z_ww" not in hub.at_bounds and "Z_wdot" not in hub.at_bounds


def test_calibrator_names_an_unknown_loss():
    runs, _ = generate_runs("bluerov2_heavy", dofs=("heave",), runs_per_dof=1, validation_per_dof=0, seed=1)
    with pytest.raises(CalibrationError, match="loss 'l1'"):
        Calibrator(loss="l1").fit(runs, "bluerov2_heavy")
