"""Issue 21 "bounds are physical limits only": with the start model as a prior, the joint
stage's bounds on masses, inertias, added masses and damping are their signs and a factor of
:data:`uvsim.fitting.parameters.PHYSICAL_FACTOR` (the prior, not a +-50 % box, keeps a
coefficient near the file's value), so a truth beyond the old box is reachable; without
priors the ``margin`` box is kept. Data from the independent generator (:mod:`uvsim.scenarios`)."""
from __future__ import annotations

import pytest

from uvsim.calibration import Calibrator
from uvsim.errors import CalibrationError
from uvsim.fitting.parameters import PHYSICAL_FACTOR, default_bounds, physical_bounds
from uvsim.scenarios import generate, sample_scenario
from uvsim.vehicle import load_vehicle


def test_physical_bounds_are_signs_and_a_factor():
    assert PHYSICAL_FACTOR == 10.0
    assert physical_bounds("Z_ww", -40.0, 0.5) == (-400.0, 0.0)        # dissipative: <= 0
    assert physical_bounds("K_p", -0.2, 0.5) == (-2.0, 0.0)
    assert physical_bounds("Z_wdot", 20.0, 0.5) == (0.0, 200.0)        # added mass: >= 0
    assert physical_bounds("I_xx", 0.3, 0.5) == pytest.approx((0.03, 3.0))
    assert physical_bounds("m", 11.5, 0.5) == pytest.approx((1.15, 115.0))
    # families whose ranges are not relative to the file's value keep them
    for name, value in (("z_b", -0.02), ("thruster_gain_3", 1.0), ("current_n", 0.0)):
        assert physical_bounds(name, value, 0.5) == default_bounds(name, value, 0.5)
    with pytest.raises(CalibrationError, match="X_u is 0"):
        physical_bounds("X_u", 0.0, 0.5)


@pytest.fixture(scope="module")
def heave_data(tmp_path_factory):
    """Telegraph-PWM runs of the generator's exact BlueROV2 Heavy (IMU, lagged attitude, 10 Hz
    depth aft); the start model is the dataset's vehicle file with half the truth's quadratic
    heave damping, beyond the +-50 % box."""
    spec = sample_scenario(4, profile="realsensor", n_runs=2, n_validation=1, duration=[10, 12], rate_hz=100.0,
                           perturbation=0.0, perturb_z_b=False, n_effects=0)
    d = generate(spec, tmp_path_factory.mktemp("heave") / "ds")
    truth = load_vehicle(d / "myrov.yaml")          # the model file, with the pressure sensor's position
    P = truth.parameters()
    start = truth.with_parameters({"Z_ww": 0.5 * P["Z_ww"]}, name="half_heave_damping")
    return d, P, start


def _calibrate(d, start, **kw):
    return Calibrator(dofs="heave", seed=0, **kw).fit(d, vehicle=start)


def test_with_priors_the_fit_reaches_a_truth_beyond_the_margin_box(heave_data):
    d, P, start = heave_data
    S = start.parameters()
    cal = _calibrate(d, start)
    assert cal.report_["bounds"]["Z_ww"] == [PHYSICAL_FACTOR * S["Z_ww"], 0.0]
    # the truth is 2x the start: outside the default box (start * 1.5), reached with priors
    assert cal.params_["Z_ww"] < 1.5 * S["Z_ww"] * 1.05, cal.params_
    assert "Z_ww" not in cal.fit_.at_bounds
    # the prior still pulls toward the start: -60.3 against the truth's -70.2 when written
    assert cal.params_["Z_ww"] == pytest.approx(P["Z_ww"], rel=0.2), cal.params_
    plain = _calibrate(d, start, prior=False)
    assert plain.report_["bounds"]["Z_ww"] == pytest.approx(sorted([0.5 * S["Z_ww"], 1.5 * S["Z_ww"]]))
    assert "Z_ww" in plain.fit_.at_bounds           # the box stops it at 1.5x the start (-52.7)
