"""`uvsim calibrate` end to end on a small dataset written to disk."""
import json

import pytest
import yaml

import uvsim
from calibration_data import SMALL
from uvsim.cli import main
from uvsim.synthetic import generate_dataset


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    d = tmp_path_factory.mktemp("tank")
    generate_dataset("bluerov2_heavy", d, dofs=["surge", "roll"], seed=4, **SMALL)
    return d


def test_calibrate_command_outputs(dataset, tmp_path, capsys):
    out, rep, plots = tmp_path / "fitted.yaml", tmp_path / "report.json", tmp_path / "plots"
    code = main(["calibrate", "--data", str(dataset), "--vehicle", "bluerov2_heavy_initial", "--population", "8",
                 "--generations", "2", "--seed", "3", "--out", str(out), "--json", str(rep), "--plots", str(plots)])
    assert code == 0
    text = capsys.readouterr().out
    assert "I_xx + K_pdot" in text
    veh = uvsim.load_vehicle(out)  # complete and loadable
    r = json.loads(rep.read_text())
    for key in ("parameters", "uncertainty", "effective_inertia", "linear_damping", "quadratic_damping",
                "validation_rmse", "training_rmse", "per_run", "evaluations", "wall_seconds", "identifiability",
                "logbook"):
        assert key in r, key
    assert veh.parameters()["X_udot"] == pytest.approx(r["parameters"]["X_udot"])
    assert r["uncertainty"]["I_xx"] is None and r["uncertainty"]["K_p"] > 0
    assert set(r["validation_rmse"]) >= {"position_m", "attitude_rad"}
    run = next(iter(r["per_run"].values()))
    assert {"rmse", "nrmse", "fit_percent"} <= set(run)
    y = out.read_text()
    assert "previous 0.344" in y and "X_udot: fitted" in y  # I_xx line and the added-mass row annotated
    assert yaml.safe_load(y)["name"] == "bluerov2_heavy_initial_calibrated"
    assert "only I_xx + K_pdot =" in y
    assert (plots / "ga_convergence.png").is_file() and (plots / "error_boxplots.png").is_file()
    assert len(list((plots / "runs").glob("*.png"))) == 10
    assert not list(tmp_path.glob("*.ckpt*"))  # a finished run leaves no checkpoint (issue 47)


@pytest.mark.parametrize("args, msg", [
    (["--dof", "flip"], "dof"),
    (["--dof", "heave"], "no training runs for dof"),
    (["--weights", "x"], "--weights"),
    (["--vehicle", "no_such_vehicle"], "unknown vehicle"),
])
def test_calibrate_bad_input(dataset, tmp_path, capsys, args, msg):
    base = ["calibrate", "--data", str(dataset), "--out", str(tmp_path / "f.yaml"), "--population", "4",
            "--generations", "1"]
    assert main(base + args) == 2
    assert msg in capsys.readouterr().err


def test_calibrate_missing_dataset(tmp_path, capsys):
    assert main(["calibrate", "--data", str(tmp_path / "none"), "--out", str(tmp_path / "f.yaml")]) == 2
    assert "manifest" in capsys.readouterr().err
