"""The starting model as a prior (uvsim.fitting.priors): an unexcited coefficient stays at its
prior with the prior's width, an excited one moves as far as the data say, the data weight
falls under structural mismatch, and the vehicle file's uncertainty sets the width."""
from __future__ import annotations

import numpy as np
import pytest

import uvsim
from uvsim.errors import CalibrationError
from uvsim.fitting import fit, make_space
from uvsim.fitting.priors import data_weight, default_prior_sd, make_prior
from uvsim.synthetic import generate_runs

NAMES = ["X_uu", "X_u", "N_rr", "K_pp"]


@pytest.fixture(scope="module")
def surge_only():
    """Surge runs only: N_rr and K_pp are not excited; truth X_uu, X_u 30 % off the file."""
    v = uvsim.load_vehicle("bluerov2_heavy")
    P = v.parameters()
    truth = {"X_uu": P["X_uu"] * 1.3, "X_u": P["X_u"] * 0.7}
    runs, _ = generate_runs("bluerov2_heavy", dofs=("surge",), runs_per_dof=3, validation_per_dof=0, seed=2,
                            overrides=truth)
    return v, P, truth, runs


def test_an_unexcited_coefficient_stays_at_its_prior_and_an_excited_one_follows_the_data(surge_only):
    v, P, truth, runs = surge_only
    space = make_space(P, NAMES)
    plain = fit(v, runs, space)
    # without the prior the unexcited coefficients run to a search bound (what issue 21 reports)
    assert {"N_rr", "K_pp"} & set(plain.at_bounds)
    res = fit(v, runs, space, prior_mean={k: P[k] for k in NAMES})
    assert res.at_bounds == []
    for k in ("N_rr", "K_pp"):
        assert abs(res.values[k] - P[k]) < 0.02 * res.prior_sd[k], k
        assert res.std[k] == pytest.approx(res.prior_sd[k], rel=0.05), k   # the prior alone
    # X_uu: determined by the data (posterior sd far below the prior's) and recovered
    assert res.std["X_uu"] < 0.05 * res.prior_sd["X_uu"]
    assert res.values["X_uu"] == pytest.approx(truth["X_uu"], rel=0.01)
    assert res.prior_sd["X_uu"] == pytest.approx(0.5 * abs(P["X_uu"]))
    assert 0.0 < res.data_weight <= 1.0


def test_the_vehicle_files_uncertainty_sets_the_prior_width(surge_only):
    v, P, _, runs = surge_only
    space = make_space(P, NAMES)
    res = fit(v, runs, space, prior_mean={k: P[k] for k in NAMES}, prior_sd={"N_rr": 0.01})
    assert res.prior_sd["N_rr"] == pytest.approx(0.01)
    assert res.std["N_rr"] == pytest.approx(0.01, rel=0.05)
    d = v.to_dict()
    d["uncertainty"] = {"N_rr": 0.01}
    assert uvsim.vehicle.vehicle_from_dict(d).uncertainty == {"N_rr": 0.01}


def test_prior_widths_and_their_errors():
    assert default_prior_sd("X_uu", -35.0) == pytest.approx(17.5)
    assert default_prior_sd("z_b", -0.024) == pytest.approx(0.05)       # positions: not relative
    # gains: the T200's thrust per volt of supply (priors.THRUSTER_GAIN_SD), not half the 0.05-1.5 range
    assert default_prior_sd("thruster_gain_1", 1.0) == pytest.approx(0.1)
    assert default_prior_sd("thruster_gain_8", 0.6) == pytest.approx(0.1)
    # reverse ratios: the T200 sheets' reverse/forward ratio over 10-20 V (priors.THRUSTER_REVERSE_SD)
    assert default_prior_sd("thruster_reverse_1", 1.0) == pytest.approx(0.1)
    assert default_prior_sd("force_reverse_1", 1.0) == pytest.approx(0.7)     # not a T200: half its range
    with pytest.raises(CalibrationError, match="X_u is 0"):
        default_prior_sd("X_u", 0.0)
    P = uvsim.load_vehicle("bluerov2_heavy").parameters()
    space = make_space(P, ["X_uu"])
    with pytest.raises(CalibrationError, match="prior standard deviation of X_uu"):
        make_prior(space, P, {"X_uu": -1.0})
    with pytest.raises(CalibrationError, match="no prior mean"):
        make_prior(space, {})


def test_data_weight_is_one_for_white_residuals_and_small_for_correlated_ones():
    rng = np.random.default_rng(0)
    W, n, p = 400, 50, 3
    # smooth sensitivities within a window (a slow motion sampled fast), as trajectories have
    J = rng.normal(size=(W, 1, p)) + 0.1 * rng.normal(size=(W, n, p))
    S = sum(j.T @ j for j in J)
    white = [j.T @ rng.normal(size=n) for j in J]                  # independent unit residuals
    assert data_weight(S, sum(np.outer(s, s) for s in white)) == pytest.approx(1.0, abs=0.15)
    corr = [j.T @ np.full(n, rng.normal()) for j in J]             # one shared error per window
    assert data_weight(S, sum(np.outer(s, s) for s in corr)) < 0.05  # ~1/n: n samples, one error


def test_a_structural_mismatch_lowers_the_data_weight(surge_only):
    """Truth with a 8 cm/s current the fitted model lacks: the data count for much less."""
    v, P, truth, _ = surge_only
    runs, _ = generate_runs("bluerov2_heavy", dofs=("surge",), runs_per_dof=3, validation_per_dof=0, seed=2,
                            overrides=truth, effects=[{"type": "current", "n": 0.08, "e": 0.03}])
    res = fit(v, runs, make_space(P, NAMES), prior_mean={k: P[k] for k in NAMES})
    assert res.data_weight < 0.1


def test_the_imu_spec_sets_the_gyro_bias_prior_and_a_large_bias_is_flagged():
    from types import SimpleNamespace

    from uvsim.calibration.report import gyro_bias_flags
    from uvsim.errors import VehicleError
    from uvsim.fitting.objective import GYRO_BIAS_SIGMA
    from uvsim.vehicle import vehicle_from_dict

    d = uvsim.load_vehicle("bluerov2_heavy").to_dict()
    d["sensors"] = {"imu": {"gyro_bias_sd": 0.005}}
    v = vehicle_from_dict(d)
    assert v.gyro_bias_sd == 0.005 and vehicle_from_dict(v.to_dict()).gyro_bias_sd == 0.005
    for bad, msg in (({"imu": {"gyro_bias_sd": 2.0}}, "expected rad/s"),
                     ({"pressure": {"position": [0, 0, 0], "gyro_bias_sd": 0.01}}, "only the imu"),
                     ({"imu": {"gyro_bias_sd": -0.01}}, "positive")):
        d["sensors"] = bad
        with pytest.raises(VehicleError, match=msg):
            vehicle_from_dict(d, source="f.yaml")
    res = SimpleNamespace(gyro_bias={"run_1": [0.001, -0.004, 0.081]})
    flags = gyro_bias_flags(res, GYRO_BIAS_SIGMA)
    assert len(flags) == 1 and "run run_1: gyro bias in r +0.0810" in flags[0]
    assert gyro_bias_flags(res, 0.05) == []


def test_the_gyro_bias_prior_reaches_the_fit(surge_only):
    """The vehicle's IMU spec is the windowed problem's gyro-bias prior (default 0.02 rad/s)."""
    from uvsim.fitting.objective import WindowedProblem

    v, P, _, runs = surge_only
    space = make_space(P, ["X_uu"])
    meas = [uvsim.measurements.measurements_for(r, v) for r in runs]
    tight = v.with_parameters({})
    tight.gyro_bias_sd = 1e-4
    assert WindowedProblem(tight, runs, meas, space, 2.0).gyro_bias_sd == 1e-4
    assert WindowedProblem(v, runs, meas, space, 2.0).gyro_bias_sd == 0.02


def test_a_fit_with_priors_resumed_from_any_step_gives_the_same_result(surge_only):
    """The data weight is part of the saved state: resuming after an accepted step of a MAP fit
    ends where the uninterrupted fit ends."""
    from uvsim.fitting.objective import WindowedProblem
    from uvsim.fitting.solver import solve

    v, P, _, runs = surge_only
    space = make_space(P, NAMES)
    meas = [uvsim.measurements.measurements_for(r, v) for r in runs]
    prob = WindowedProblem(v, runs, meas, space, 2.0)
    prior = make_prior(space, P)
    states = []
    full = solve(prob, space.z0, max_iter=30, prior=prior, on_step=states.append)
    assert len(states) >= 2 and all("data_weight" in s for s in states)
    again = solve(prob, space.z0, max_iter=30, prior=prior, state=states[1])
    np.testing.assert_array_equal(again["z"], full["z"])
    assert again["data_weight"] == full["data_weight"]


def test_a_zero_valued_coefficient_gets_its_default_width_or_a_quarter_of_its_bounds():
    P = uvsim.load_vehicle("bluerov2_heavy").parameters()
    assert P["y_g"] == 0.0 and P["current_n"] == 0.0 and P["X_u"] != 0.0
    space = make_space(P, ["y_g", "current_n"])
    pr = make_prior(space, P)
    sd = pr.sd_z * space.scale
    assert sd[0] == pytest.approx(default_prior_sd("y_g", 0.0)) and sd[1] == pytest.approx(1.0)
    P0 = {**P, "X_u": 0.0}  # no default width at 0: a quarter of the explicit bounds
    space = make_space(P0, ["X_u"], bounds={"X_u": (-2.0, 0.0)})
    assert make_prior(space, P0).sd_z[0] * space.scale[0] == pytest.approx(0.5)
