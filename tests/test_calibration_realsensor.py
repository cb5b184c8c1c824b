"""The issue-14 benchmark as a test: a dataset from the independent scenario generator
(uvsim.scenarios, profile realsensor) calibrates with one command and recovers the
identifiable parameters within 10 % (docs/calibration.md, "Real sensors")."""
import json

import numpy as np
import pytest
import yaml

pytest.importorskip("uvsim.scenarios")

from uvsim.benchmarks import realsensor  # noqa: E402
from uvsim.cli import main  # noqa: E402


@pytest.mark.slow
def test_realsensor_benchmark_recovers_identifiable_parameters(tmp_path):
    d = realsensor.make_dataset(tmp_path / "data")
    truth = yaml.safe_load((d / "truth.yaml").read_text())
    manifest = yaml.safe_load((d / "manifest.yaml").read_text())
    assert all(r["dof"] == "mixed" for r in manifest["runs"]) and (d / f"{manifest['vehicle']}.yaml").is_file()
    weak, gain = realsensor.weak_thruster(truth)
    # one command, no reshaping: the vehicle file beside the manifest, z_b and the weak thruster free
    out = tmp_path / "out"
    assert main(["calibrate", "--data", str(d), "--free", f"z_b,{weak}", "--out", str(out / "fitted.yaml"),
                 "--json", str(out / "report.json")]) == 0
    rep = json.loads((out / "report.json").read_text())
    assert rep["parameters"][weak] == pytest.approx(gain, rel=0.10)
    assert rep["parameters"]["z_b"] == pytest.approx(truth["buoyancy"]["z_b_truth"], rel=0.10)
    cal = realsensor.calibrate(d, truth)  # the same through the API, for the truth comparison
    assert cal.params_ == {k: pytest.approx(v, rel=1e-12) for k, v in rep["parameters"].items()}
    err = realsensor.truth_errors(cal, truth)
    assert realsensor.worst_identifiable(err) < 10.0, err
    assert err["gyro_bias_rms_error_pct_of_rms_bias"] < 10.0
    assert abs(err["attitude_lag"]) < 10.0
    # noise of the interpolated 10 Hz depth within a factor 2 of the truth
    sig = np.median([m["depth"]["sigma"] for m in rep["noise"].values()])
    assert 0.5 < sig / truth["sensors"]["depth"]["sigma"] < 2.0
    for c in ("depth", "roll", "pitch", "p", "q", "r", "acc_x", "acc_y"):
        assert rep["validation_fit_percent"][c] > 80.0, c


@pytest.mark.slow
def test_diagnose_names_the_undeclared_weak_thruster_on_the_realsensor_benchmark(tmp_path):
    """Issue 14: ``uvsim diagnose`` on the same data (gyro, lagged roll/pitch without yaw,
    interpolated 10 Hz stern depth, accelerometer, PWM; base coefficients and z_b off by up
    to 10 %, re-tuned) names the weak thruster, and its noise level for the interpolated
    depth is within a factor 2 of the truth."""
    from uvsim.benchmarks.scenarios import BASE_RETUNE
    from uvsim.diagnosis import diagnose

    d = realsensor.make_dataset(tmp_path / "data")
    truth = yaml.safe_load((d / "truth.yaml").read_text())
    weak, gain = realsensor.weak_thruster(truth)
    rep = diagnose(d, retune=[*BASE_RETUNE, "z_b"], workers=2).report
    assert [e["effect"] for e in rep["effects"]] == ["thruster_gain"], rep["message"]
    params = rep["effects"][0]["parameters"]
    assert list(params) == [weak]
    assert params[weak]["value"] == pytest.approx(gain, rel=0.10)
    assert rep["rmse_after"]["depth_m"] <= 0.5 * rep["rmse_before"]["depth_m"]
    for run in rep["noise"].values():
        assert run["depth"]["sampling"] == "interpolated"
        assert 0.5 < run["depth"]["sigma"] / truth["sensors"]["depth"]["sigma"] < 2.0
