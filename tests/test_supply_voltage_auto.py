"""``Calibrator(supply_voltage="auto")`` / ``--supply-voltage auto`` (uvsim.calibration.supply_voltage):
the refit on the T200 voltage family is kept only when the verdict on the training runs calls it
better than the first fit.  The data come from the independent scenario generator (uvsim.scenarios), whose truth runs
on Blue Robotics' sheet at another voltage: a curve shape the start model's t200_16v table lacks."""
import numpy as np
import pytest

from uvsim.calibration import Calibrator
from uvsim.calibration import supply_voltage as supply
from uvsim.errors import CalibrationError
from uvsim.scenarios import generate, sample_scenario
from uvsim.vehicle import load_vehicle, vehicle_from_dict


def test_the_rule_keeps_the_refit_only_when_the_training_verdict_is_better_in_every_channel():
    lower, higher = {"rmse_change": -0.2}, {"rmse_change": 0.004}
    assert supply.choose({"status": "better", "channels": {"depth": lower, "r": lower}})
    # better pooled, one channel a little higher within the noise: one more parameter in-sample is not enough
    assert not supply.choose({"status": "better", "channels": {"depth": lower, "r": higher}})
    assert not supply.choose({"status": "trade-off", "channels": {"depth": lower}})   # a channel worse
    assert not supply.choose({"status": "worse", "channels": {"depth": lower}})


def test_the_family_vehicle_keeps_every_value_and_adds_the_file_s_voltage():
    v = load_vehicle("bluerov2_heavy").with_parameters({"X_u": -5.0, "thruster_gain_3": 0.8}).with_latency(0.03)
    fam = supply.on_voltage_family(v)
    p, q = v.parameters(), fam.parameters()
    assert q.pop("supply_voltage") == 16.0 and p == q
    assert fam.sensor_latency == 0.03
    assert supply.not_applicable(v) is None
    assert "t200_16v" in supply.not_applicable(fam)               # already on the family: free it with --free


def test_auto_is_refused_where_it_cannot_apply_before_any_fitting(tmp_path):
    ds = generate(sample_scenario(4, profile="realsensor", n_runs=1, n_validation=1, duration=6.0, rate_hz=50.0),
                  tmp_path / "ds")
    with pytest.raises(CalibrationError, match="supply_voltage 'yes'"):
        Calibrator(supply_voltage="yes").fit(ds)
    with pytest.raises(CalibrationError, match="needs refine=True"):
        Calibrator(supply_voltage="auto", refine=False, generations=1, population=4).fit(ds)
    d = load_vehicle("bluerov2_heavy").to_dict()
    d["thrusters"]["curve"] = {"type": "linear", "forward_gain": 0.1, "reverse_gain": 0.08}
    with pytest.raises(CalibrationError, match="needs the vehicle's thrusters on the shipped 't200_16v' curve"):
        Calibrator(supply_voltage="auto").fit(ds, vehicle_from_dict(d, source="linear.yaml"))


@pytest.mark.slow
def test_auto_keeps_the_voltage_fit_of_a_truth_on_another_sheet_and_reports_the_choice(tmp_path):
    # a truth on the 20 V sheet, its coefficients 20 % off the start model's: two joint fits
    spec = sample_scenario(9, profile="realsensor", curve_voltage=20, n_runs=2, n_validation=1, duration=20.0,
                           rate_hz=50.0, perturbation=0.2, n_effects=0)
    ds = generate(spec, tmp_path / "ds")
    cal = Calibrator(free="z_b,thruster_gain_*,thruster_reverse_*", supply_voltage="auto", workers=2).fit(ds)
    rec = cal.report_["supply_voltage_auto"]
    assert rec["how"] == "auto" and rec["value"] == pytest.approx(20.0, abs=0.5)
    assert rec["used"] and rec["training_verdict"]["status"] == "better"
    assert cal.params_["supply_voltage"] == rec["value"]           # the kept fit is the refit's
    assert cal.vehicle_.parameters()["supply_voltage"] == pytest.approx(rec["value"])
    assert np.isfinite(cal.report_["refinement"]["cost"])
