"""``uvsim simulate --compare``: channels of any logged subset, depth at the pressure
sensor and accelerometer specific force at the IMU checked against a truth computed
here by finite differences of the trajectory (issue 11 item 5)."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import uvsim
from uvsim.cli import main
from uvsim.commands.simulate import channel_metrics, compare_channels
from uvsim.logs import Run, write_run
from uvsim.simulate import simulate_run
from uvsim.vehicle import load_vehicle, save_vehicle, vehicle_from_dict

R_PRESSURE = np.array([0.10, -0.05, 0.20])
R_IMU = np.array([0.30, 0.20, -0.25])  # a long lever arm, so that w_dot x r and w x (w x r) matter


def _vehicle():
    d = load_vehicle("bluerov2_heavy").to_dict()
    d["sensors"] = {"pressure": {"position": R_PRESSURE.tolist()}, "imu": {"position": R_IMU.tolist()}}
    return vehicle_from_dict(d, source="test-vehicle")


def _rot(e):
    """ZYX Euler -> rotation body->NED, written out (independent of uvsim.kinematics)."""
    phi, th, psi = e[:, 0], e[:, 1], e[:, 2]
    c, s = np.cos, np.sin
    R = np.empty((len(e), 3, 3))
    R[:, 0] = np.stack([c(psi) * c(th), c(psi) * s(th) * s(phi) - s(psi) * c(phi),
                        c(psi) * s(th) * c(phi) + s(psi) * s(phi)], -1)
    R[:, 1] = np.stack([s(psi) * c(th), s(psi) * s(th) * s(phi) + c(psi) * c(phi),
                        s(psi) * s(th) * c(phi) - c(psi) * s(phi)], -1)
    R[:, 2] = np.stack([-s(th), c(th) * s(phi), c(th) * c(phi)], -1)
    return R


@pytest.fixture(scope="module")
def truth():
    veh = _vehicle()
    rng = np.random.default_rng(7)
    dt = 0.001
    t = np.arange(0, 6.0, dt)
    U = np.zeros((t.size, 6))
    for j, amp in enumerate((25.0, 15.0, 20.0, 2.0, 2.0, 1.5)):
        U[:, j] = amp * np.sin(2 * np.pi * rng.uniform(0.2, 0.6) * t + rng.uniform(0, 6))
    res = uvsim.simulate(veh, t, U, pos0=[0.0, 0.0, 2.0])
    e = res.euler
    R = _rot(e)
    p_imu = res.position + R @ R_IMU
    a = np.gradient(np.gradient(p_imu, dt, axis=0), dt, axis=0)  # NED acceleration of the IMU point
    f = np.einsum("nji,nj->ni", R, a - np.array([0.0, 0.0, veh.g]))  # R^T (a - g e3)
    depth = res.position[:, 2] + R[:, 2, :] @ R_PRESSURE
    df = pd.DataFrame({"t": t, "depth": depth, "roll": e[:, 0], "pitch": e[:, 1],
                       "acc_x": f[:, 0], "acc_y": f[:, 1], "acc_z": f[:, 2]})
    for j, c in enumerate("XYZKMN"):
        df[c] = U[:, j]
    return veh, df


def test_depth_and_specific_force_of_the_same_model_match_the_truth(truth):
    veh, df = truth
    run = Run(name="truth", path=None, data=df)
    # the truth starts level at z = 2 m, so the body origin starts 0.2 m above the logged sensor depth
    res = simulate_run(veh, Run(name="init", path=None, data=df.assign(z=df.depth - 0.2)))
    chans = {c["name"]: c for c in compare_channels(veh, run, res)}
    assert set(chans) == {"depth", "roll", "pitch", "acc_x", "acc_y", "acc_z"}  # no yaw: not logged
    rows = {r["name"]: r for r in channel_metrics(list(chans.values()))}
    assert rows["roll"]["rmse"] < 1e-6 and rows["pitch"]["rmse"] < 1e-6
    assert rows["depth"]["rmse"] < 2e-3
    inner = slice(20, -20)  # np.gradient is one-sided at the ends
    for c in ("acc_x", "acc_y", "acc_z"):
        m, s = chans[c]["measured"][inner], chans[c]["simulated"][inner]
        assert np.sqrt(np.mean((m - s) ** 2)) < 3e-3, c
        assert rows[c]["fit_percent"] > 95.0


def test_a_wrong_sensor_position_shows_in_depth(truth):
    veh, df = truth
    d = veh.to_dict()
    d["sensors"]["pressure"]["position"] = [0.0, 0.0, 0.0]
    wrong = vehicle_from_dict(d, source="wrong")
    run = Run(name="truth", path=None, data=df)
    res = simulate_run(wrong, Run(name="init", path=None, data=df.assign(z=df.depth - 0.2)))
    depth = next(c for c in compare_channels(wrong, run, res) if c["name"] == "depth")
    err = depth["measured"] - depth["simulated"]
    assert np.sqrt(np.mean(err ** 2)) > 0.1  # the 0.2 m lever arm below the origin


def test_cli_compare_prints_only_logged_channels_and_plots(truth, tmp_path, capsys):
    veh, df = truth
    vfile = save_vehicle(veh, tmp_path / "veh.yaml")
    small = df.iloc[::40][["t", "depth", "roll", "X", "Y", "Z", "K", "M", "N"]]
    run = write_run(tmp_path / "run.csv", small)
    plot = tmp_path / "p.png"
    assert main(["simulate", "--vehicle", str(vfile), "--run", str(run), "--compare", "--plot", str(plot)]) == 0
    out = capsys.readouterr().out
    table = out.split("Fit %")[1]
    names = [line.split()[0] for line in table.strip().splitlines() if line.strip() and not line.startswith("plot")]
    assert names == ["depth", "roll"]
    assert plot.is_file() and plot.stat().st_size > 10_000
    assert main(["simulate", "--vehicle", str(vfile), "--run", str(run)]) == 2
    assert "--out: required unless --compare" in capsys.readouterr().err
    assert main(["simulate", "--run", str(run), "--compare"]) == 2
    assert "--vehicle: not given" in capsys.readouterr().err
