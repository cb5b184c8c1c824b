"""The accelerometer's constant offset as a per-run nuisance with a prior (issue 21 item 3:
"accelerometer and pressure sensor at their positions", a sensor bias with a prior, flagged when it
explains what the dynamics do not).

The data come from the independent generator (:mod:`uvsim.scenarios`, profile ``realsensor``),
which gives every run its own accelerometer bias (``acc_bias`` in truth.yaml, up to 0.05 m/s^2
per axis). Before the offset was fitted it stayed in the residual and the fit explained it with
whatever else it could move: on the structural benchmark's seed 22 the thruster gains by 1-4 %,
enough to turn the open-loop depth of the validation runs worse than the start model's
(docs/calibration.md, "Accelerometer bias")."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from uvsim.files import safe_load
from uvsim.calibration.report import acc_bias_flags
from uvsim.errors import VehicleError
from uvsim.fitting import fit, make_space
from uvsim.fitting.objective import ACC_BIAS_SIGMA, WindowedProblem, acc_bias_sd
from uvsim.logs import read_dataset
from uvsim.measurements import measurements_for
from uvsim.scenarios import generate, sample_scenario
from uvsim.vehicle import load_vehicle, vehicle_from_dict

#: the vertical thrusters' gains (the heavy configuration's units 5-8) and the heave damping:
#: what a constant vertical specific-force offset bends when nothing else can take it
FREE = ["thruster_gain_5", "thruster_gain_6", "thruster_gain_7", "thruster_gain_8", "Z_w", "Z_ww"]


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    # start model = truth (perturbation 0, no effect, the file's centre of buoyancy): what
    # differs is the sensors' offsets only
    spec = sample_scenario(13, profile="realsensor", n_runs=2, n_validation=1, duration=[10, 12], rate_hz=100.0,
                           perturbation=0.0, n_effects=0, perturb_z_b=False)
    return generate(spec, tmp_path_factory.mktemp("acc") / "ds")


def _truth_bias(path) -> dict:
    truth = safe_load((Path(path) / "truth.yaml").read_text())
    return {Path(r["file"]).stem: np.array(r["acc_bias"], float) for r in truth["runs"]}


def _runs(path, remove_bias=False):
    """Training runs of ``path``; ``remove_bias``: with the generator's accelerometer offset
    taken out of the logged acc_x, acc_y, acc_z (a copy; the files are not changed)."""
    bias = _truth_bias(path)
    out = []
    for r in read_dataset(path).runs:
        if r.split != "train":
            continue
        if remove_bias:
            d = r.data.copy()
            for i, c in enumerate(("acc_x", "acc_y", "acc_z")):
                d[c] = d[c] - bias[r.name][i]
            r = type(r)(r.name, r.path, d, dof=r.dof, split=r.split)
        out.append(r)
    return out


def test_the_measurement_model_adds_the_offset_to_the_accelerometer_only(dataset):
    v = load_vehicle(read_dataset(dataset).vehicle_file)
    run = _runs(dataset)[0]
    m = measurements_for(run, v)
    assert m.has_accelerometer
    y = np.zeros((2, m.n, 13))
    y[..., 3] = 1.0                                    # level, at rest
    nu_dot = np.zeros((2, m.n, 6))
    b = np.array([[0.01, -0.02, 0.03], [0.0, 0.0, 0.0]])
    plain, biased = m.predict(y, nu_dot), m.predict(y, nu_dot, acc_bias=b)
    np.testing.assert_allclose(biased["acceleration"] - plain["acceleration"], np.repeat(b[:, None], m.n, 1))
    for g in plain:
        if g != "acceleration":
            np.testing.assert_array_equal(biased[g], plain[g])


def test_the_nuisance_layout_keeps_gyro_attitude_and_accelerometer_apart(dataset):
    v = load_vehicle(read_dataset(dataset).vehicle_file)
    runs = _runs(dataset)
    meas = [measurements_for(r, v) for r in runs]
    space = make_space(v.parameters(), FREE)
    wp = WindowedProblem(v, runs, meas, space, 2.0, gyro_bias=True, attitude_bias=True, acc_bias=True)
    sd = wp.bias_sd(0)
    assert sd.size == 8 and np.all(sd[5:] == ACC_BIAS_SIGMA)
    g, a, c = wp.split_bias(0, np.arange(8.0))
    assert g.tolist() == [0, 1, 2] and a.tolist() == [3, 4] and c.tolist() == [5, 6, 7]
    off = WindowedProblem(v, runs, meas, space, 2.0)        # off unless asked for (diagnosis)
    assert off.bias_sd(0).size == 3 and off.split_bias(0, np.zeros(3))[2] is None


def test_offsets_are_recovered_and_stop_bending_the_thrusters(dataset):
    v = load_vehicle(read_dataset(dataset).vehicle_file)
    truth = _truth_bias(dataset)
    space = make_space(v.parameters(), FREE)
    with_bias = fit(v, _runs(dataset), space, attitude_bias=True, acc_bias=True)
    for name, b in with_bias.acc_bias.items():
        np.testing.assert_allclose(b, truth[name], atol=0.01)
    clean = fit(v, _runs(dataset, remove_bias=True), space, attitude_bias=True, acc_bias=True)
    for name, b in clean.acc_bias.items():                 # none invented where there is none
        assert np.max(np.abs(b)) < 0.01
    without = fit(v, _runs(dataset), space, attitude_bias=True)
    assert without.acc_bias == {}
    # the truth is the file (perturbation 0): with the offsets fitted the gains and the quadratic
    # heave damping stay there; without, the offsets bend them (what the data must show for this
    # test to mean anything; Z_w, weakly excited by these runs, moves alike in both fits)
    truth_values = v.parameters()

    def worst(res):
        return max(abs(res.values[k] / truth_values[k] - 1.0) for k in FREE if k != "Z_w")

    assert worst(with_bias) < 0.01
    assert worst(without) > 2 * worst(with_bias)


def test_a_large_offset_is_flagged():
    class R:
        acc_bias = {"run_a": [0.0, 0.01, -4 * ACC_BIAS_SIGMA], "run_b": [0.0, 0.0, 0.0]}

    flags = acc_bias_flags(R(), ACC_BIAS_SIGMA)
    assert len(flags) == 1 and "run_a" in flags[0] and " z " in flags[0]


def test_the_vehicle_file_states_the_accelerometer_offset(dataset):
    d = yaml.safe_load(Path(read_dataset(dataset).vehicle_file).read_text())
    d.setdefault("sensors", {}).setdefault("imu", {})["acc_bias_sd"] = 0.03
    v = vehicle_from_dict(d)
    assert v.acc_bias_sd == 0.03 and acc_bias_sd(v) == 0.03
    assert vehicle_from_dict(v.to_dict()).acc_bias_sd == 0.03          # written back
    d["sensors"]["imu"]["acc_bias_sd"] = 9.81                            # a g, not an offset
    with pytest.raises(VehicleError, match="acc_bias_sd"):
        vehicle_from_dict(d)
    d["sensors"]["imu"].pop("acc_bias_sd")
    d["sensors"]["pressure"] = {"position": [0.0, 0.0, 0.0], "acc_bias_sd": 0.1}
    with pytest.raises(VehicleError, match="only the imu"):
        vehicle_from_dict(d)


def test_the_bias_columns_are_the_one_bias_at_a_time_differences(dataset, monkeypatch):
    """The linearization moves the 8 sensor biases (gyro, attitude filter, accelerometer) in one
    batch of predictions; each column equals the forward difference of that bias alone, to the bit."""
    import uvsim.fitting.linearization as lin
    from uvsim.fitting.objective import FILL, robust_residuals

    v = load_vehicle(read_dataset(dataset).vehicle_file)
    runs = _runs(dataset)
    meas = [measurements_for(r, v) for r in runs]
    space = make_space(v.parameters(), FREE)
    wp = WindowedProblem(v, runs, meas, space, 2.0, gyro_bias=True, attitude_bias=True, acc_bias=True)
    rng = np.random.default_rng(4)
    nus = [rng.normal(scale=0.01, size=wp.nuisance_size(r)) for r in range(len(runs))]
    seen = []
    monkeypatch.setattr(lin, "structured_normal_pieces",
                        lambda r, Jz, J, cluster, scores: seen.append(J) or lin.RunNormal(0.0))
    lin.linearize(wp, space.z0, nus)
    D, biases = wp.assemble(nus)
    Y, A = wp.simulate(space.z0[None], D)
    for r, J in enumerate(seen):
        b = biases[r]
        assert J.db.shape[1] == 8
        m0 = wp.measurement_residuals(Y, A, r, b)[0]
        y, a = wp.run_prediction(Y, A, r)
        for j in range(8):
            b1 = b.copy()
            b1[0, j] += lin.FD_STEP_BIAS
            with np.errstate(all="ignore"):
                m1 = robust_residuals(wp.meas[r].normalized(wp.predict_run(r, y, a, b1), fill=FILL), wp.loss)[0]
            np.testing.assert_array_equal(J.db[:, j], (m1 - m0) / lin.FD_STEP_BIAS)
