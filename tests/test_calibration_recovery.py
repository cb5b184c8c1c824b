"""Calibration recovers seed 000 Table 5 from Table 2 on simulated tank data (issue 5),
and works on rates-only and depth-only datasets (issue 7)."""
import numpy as np
import pytest

from calibration_data import tank_runs, truth_rmse
from uvsim.calibration import Calibrator
from uvsim.calibration.params import EFFECTIVE_INERTIA, QUADRATIC_DAMPING
from uvsim.metrics import fit_percent, rmse
from uvsim.vehicle import load_vehicle

TRUTH = load_vehicle("bluerov2_heavy").parameters()


def _eff(p, dof):
    a, b = EFFECTIVE_INERTIA[dof]
    return p[a] + p[b]


@pytest.fixture(scope="module")
def six_dof():
    runs, truth = tank_runs()
    cal = Calibrator(population=16, generations=5, seed=1, max_iter=12).fit(runs, "bluerov2_heavy_initial")
    return runs, cal


@pytest.mark.slow
def test_clean_tank_data_of_the_paper_s_kind_get_the_verdict_better_every_time(six_dof):
    """Issue 45: the paper's workflow on clean tank data (seed 000's kind, from the same start model)
    is *better* than the model it started from, on this dataset and on two more drawn with other
    seeds, each of them: no stability rule refuses a fit that validates better."""
    runs, cal = six_dof
    assert cal.report_["verdict"]["status"] == "better", cal.report_["verdict"]["message"]
    for seed in (7, 8):
        more, _ = tank_runs(seed=seed)
        v = Calibrator(population=8, generations=3, seed=seed, max_iter=12).fit(more, "bluerov2_heavy_initial")
        assert v.report_["verdict"]["status"] == "better", (seed, v.report_["verdict"]["message"])
        assert v.report_["verdict"]["pooled"]["rmse_change"] < -0.3


def test_six_dof_identifiable_quantities(six_dof):
    runs, cal = six_dof
    p = cal.vehicle_.parameters()
    for dof in EFFECTIVE_INERTIA:
        # effective mass / inertia (m + X_udot, I_xx + K_pdot, ...) within 2 %
        assert _eff(p, dof) == pytest.approx(_eff(TRUTH, dof), rel=0.02), dof
    for dof in ("surge", "sway", "heave", "pitch", "yaw"):
        k = QUADRATIC_DAMPING[dof]
        assert p[k] == pytest.approx(TRUTH[k], rel=0.05), k
    # roll quadratic damping: the roll runs are small (restoring-limited)
    assert p["K_pp"] == pytest.approx(TRUTH["K_pp"], rel=0.15)
    # the report says what is identifiable: the rigid-body inertias stay at the GA's split
    ident = cal.report_["identifiability"]
    for dof, pair in (("roll", "I_xx + K_pdot"), ("pitch", "I_yy + M_qdot"), ("yaw", "I_zz + N_rdot")):
        assert any(c.startswith(pair) for c in ident["effective_inertia"]), ident["effective_inertia"]
        assert cal.uncertainty_[EFFECTIVE_INERTIA[dof][0]] is None
        assert cal.report_["effective_inertia_uncertainty"][dof] > 0
    assert ident["not_identifiable"] == []
    assert set(cal.report_["free_parameters"]) == {k for d in ("surge", "sway", "heave", "roll", "pitch", "yaw")
                                                   for k in cal.report_["parameters"] if k not in
                                                   ("I_xx", "I_yy", "I_zz")}


def test_six_dof_validation_rmse_at_noise_floor(six_dof):
    runs, cal = six_dof
    floor = truth_rmse(runs)
    got = cal.report_["validation_rmse"]
    init = cal.report_["initial_validation_rmse"]
    assert got["position_m"] < 1.5 * floor["position_m"]
    assert got["attitude_rad"] < 1.5 * floor["attitude_rad"]
    assert got["position_m"] < 0.5 * init["position_m"]
    rep = cal.report_
    for key in ("parameters", "uncertainty", "effective_inertia", "linear_damping", "quadratic_damping",
                "validation_rmse", "training_rmse", "per_run", "evaluations", "wall_seconds", "identifiability",
                "validation_fit_percent", "gyro_bias", "free_parameters", "at_bounds", "physical_limit"):
        assert key in rep
    assert set(rep["effective_inertia"]) == set(EFFECTIVE_INERTIA)
    assert rep["linear_damping"]["surge"] == cal.params_["X_u"]
    assert rep["evaluations"] > 16 * 6


def test_rates_only_dataset_and_fit_numbers():
    # gyro + IMU attitude + PWM, no position (issue 7)
    runs, _ = tank_runs(dofs=("yaw",), signals=("imu_attitude", "rates"))
    assert all("position" not in r.signals() for r in runs)
    cal = Calibrator(population=12, generations=4, seed=3).fit(runs, "bluerov2_heavy_initial")
    p = cal.vehicle_.parameters()
    assert _eff(p, "yaw") == pytest.approx(_eff(TRUTH, "yaw"), rel=0.03)
    assert p["N_rr"] == pytest.approx(TRUTH["N_rr"], rel=0.05)
    # report numbers against a hand computation on one run (its gyro bias from the fit)
    run = runs[0]
    ev = cal.predict([run])[run.name]
    r_meas = run.velocity[:, 5]
    r_pred = ev["pred"]["rates"][:, 2]
    assert ev["gyro_bias"] == cal.report_["gyro_bias"][run.name]
    rep = cal.report_["per_run"][run.name]
    assert rep["fit_percent"]["r"] == pytest.approx(
        100 * (1 - np.linalg.norm(r_meas - r_pred) / np.linalg.norm(r_meas - r_meas.mean())), rel=1e-9)
    assert rep["channels"]["r"]["rmse"] == pytest.approx(np.sqrt(np.mean((r_meas - r_pred) ** 2)), rel=1e-9)
    assert "position_m" not in rep["rmse"]


def test_depth_only_heave_dataset():
    runs, _ = tank_runs(dofs=("heave",), signals=("depth",))
    assert all(r.measured_columns == {"position": ["z"]} for r in runs)
    cal = Calibrator(population=12, generations=4, seed=2).fit(runs, "bluerov2_heavy_initial")
    p = cal.vehicle_.parameters()
    assert _eff(p, "heave") == pytest.approx(_eff(TRUTH, "heave"), rel=0.02)
    assert p["Z_ww"] == pytest.approx(TRUTH["Z_ww"], rel=0.03)
    run = [r for r in runs if r.split == "validation"][0]
    zh = cal.predict([run])[run.name]["pred"]["position"][:, 2]
    z = run.position[:, 2]
    rep = cal.report_["per_run"][run.name]
    assert rep["rmse"]["position_m"] == pytest.approx(float(rmse(z - zh)), rel=1e-9)
    assert rep["fit_percent"]["z"] == pytest.approx(fit_percent(z, zh), rel=1e-9)
    assert rep["nrmse"]["z"] == pytest.approx(float(rmse(z - zh)) / np.ptp(z), rel=1e-9)
    # noise floor: what the true model reaches on the same noisy validation run
    floor = truth_rmse(runs)["position_m"]
    assert cal.report_["validation_rmse"]["position_m"] < 1.5 * floor


@pytest.mark.slow
def test_paper_setup_full_size():
    """The paper's whole setup: 6 DOFs x 8 runs, 14 s at 50 Hz, 60 individuals x 30 generations."""
    from uvsim.synthetic import generate_runs

    runs, _ = generate_runs("bluerov2_heavy", runs_per_dof=8, validation_per_dof=2, seed=0)
    cal = Calibrator(seed=0, workers=2).fit(runs, "bluerov2_heavy_initial")
    p = cal.vehicle_.parameters()
    for dof in EFFECTIVE_INERTIA:
        assert _eff(p, dof) == pytest.approx(_eff(TRUTH, dof), rel=0.02), dof
    floor = truth_rmse(runs)
    assert cal.report_["validation_rmse"]["position_m"] < 1.5 * floor["position_m"]


def test_runs_starting_in_motion():
    # depth-only heave runs cut at t = 3 s, while moving: a zero initial velocity is wrong,
    # but the joint stage estimates every window's start state, the first one included
    from uvsim.logs import Run

    runs, _ = tank_runs(dofs=("heave",), signals=("depth",))
    cut = [Run(name=r.name, path=None, data=r.data[r.data.t >= 3.0].reset_index(drop=True), dof=r.dof,
               weight=r.weight, split=r.split) for r in runs]
    kw = dict(population=12, generations=4, seed=2)
    ga_only = Calibrator(refine=False, **kw).fit(cut, "bluerov2_heavy_initial").vehicle_.parameters()
    cal = Calibrator(**kw).fit(cut, "bluerov2_heavy_initial")
    truth = _eff(TRUTH, "heave")
    assert abs(_eff(ga_only, "heave") / truth - 1) > 0.05  # the GA's free simulations from rest are biased
    assert _eff(cal.vehicle_.parameters(), "heave") == pytest.approx(truth, rel=0.01)
    assert cal.vehicle_.parameters()["Z_ww"] == pytest.approx(TRUTH["Z_ww"], rel=0.02)
