"""Vehicle files: loading, validation errors that name file and field, round trips."""
from __future__ import annotations

import copy
import json

import numpy as np
import pytest
import yaml

from uvsim.files import safe_load
import uvsim
from uvsim.cli import main
from uvsim.errors import SimulationError, VehicleError
from uvsim.vehicle import builtin_vehicles, load_vehicle, vehicle_path


@pytest.fixture
def rov_dict():
    return safe_load(vehicle_path("bluerov2_heavy").read_text())


def write(tmp_path, d, name="veh.yaml"):
    p = tmp_path / name
    p.write_text(yaml.safe_dump(d))
    return p


def test_builtins_load_and_have_the_papers_numbers():
    assert {"bluerov2_heavy", "bluerov2_heavy_initial", "chin2018_rov"} <= set(builtin_vehicles())
    fit = load_vehicle("bluerov2_heavy").parameters()
    init = load_vehicle("bluerov2_heavy_initial").parameters()
    # seed 000 Table 5 (optimized) and Table 2 (initial)
    assert fit["I_xx"] == 0.371 and init["I_xx"] == 0.344
    assert fit["X_udot"] == 15.638 and init["X_udot"] == 13.272
    assert fit["N_rr"] == -0.425 and init["N_rr"] == -0.471
    assert fit["m"] == init["m"] == 13.17 and fit["B"] == 132.537 and fit["z_b"] == -0.024
    chin = load_vehicle("chin2018_rov").parameters()
    assert chin["Z_wdot"] == 126.144 and chin["Z_ww"] == -273.8 and chin["N_rr"] == -6.079


def test_thruster_allocation_reproduces_seed000_eq12():
    """Equal thrust T on the four horizontal thrusters gives X = 4 T cos(pi/4) (seed 000 eq. 12),
    no sway, heave, roll or yaw, and the pitch moment of thrust acting 0.085 m below the CG:
    M = z F_x = 0.085 * 4 T cos(pi/4)."""
    v = load_vehicle("bluerov2_heavy")
    tau = v.actuators.matrix @ np.array([1.0, 1, 1, 1, 0, 0, 0, 0])
    assert tau[0] == pytest.approx(4 * np.cos(np.pi / 4))
    assert np.abs(tau[[1, 2, 3, 5]]).max() < 1e-6
    assert tau[4] == pytest.approx(0.085 * 4 * np.cos(np.pi / 4))
    assert np.linalg.matrix_rank(v.actuators.matrix) == 6


def test_chin_configuration_matrix_is_eq9():
    v = load_vehicle("chin2018_rov")
    B = v.actuators.matrix
    c = np.cos(np.pi / 4)
    assert B.shape == (6, 6)
    assert B[4, 0] == pytest.approx(0.394 * c) and B[5, 4] == pytest.approx(-0.660 * c) and B[3, 2] == -0.275


@pytest.mark.parametrize(
    "mutate, field",
    [
        (lambda d: d["rigid_body"].__setitem__("mass", -1), "rigid_body.mass"),
        (lambda d: d["rigid_body"].__setitem__("mass", float("nan")), "rigid_body.mass"),
        (lambda d: d["rigid_body"].__setitem__("buoyancy", 13.25), "rigid_body.buoyancy"),
        (lambda d: d["rigid_body"]["inertia"].__setitem__("I_zz", 5.0), "rigid_body.inertia"),
        (lambda d: d["rigid_body"].__setitem__("r_b", [0, 0]), "rigid_body.r_b"),
        (lambda d: d["added_mass"].__setitem__("X_udot", -3.0), "added_mass"),
        (lambda d: d["added_mass"].__setitem__("Xudot", 3.0), "added_mass"),
        (lambda d: d["damping"]["linear"].__setitem__("X_u", 0.5), "damping.linear.X_u"),
        (lambda d: d["damping"]["quadratic"].__setitem__("Y_vv", "a lot"), "damping.quadratic.Y_vv"),
        (lambda d: d["damping"].__setitem__("type", "magic"), "damping"),
        (lambda d: d["thrusters"].__setitem__("curve", "t999"), "curve"),
        (lambda d: d["thrusters"]["units"][2].__setitem__("position", [0, 1]), "thrusters.units[2].position"),
        (lambda d: d["thrusters"]["units"][0].__setitem__("direction", [0, 0, 0]), "thrusters.units[0].direction"),
        (lambda d: d.pop("rigid_body"), "rigid_body"),
    ],
)
def test_bad_vehicle_files_name_file_and_field(tmp_path, rov_dict, mutate, field):
    d = copy.deepcopy(rov_dict)
    mutate(d)
    p = write(tmp_path, d)
    with pytest.raises(VehicleError) as exc:
        load_vehicle(p)
    msg = str(exc.value)
    assert str(p) in msg and field in msg, msg


def test_non_positive_definite_mass_matrix_rejected(tmp_path, rov_dict):
    d = copy.deepcopy(rov_dict)
    d["added_mass"] = {"matrix": (np.diag([1.0] * 6) + 60 * (np.ones((6, 6)) - np.eye(6))).tolist()}
    with pytest.raises(VehicleError, match="not positive (semi-)?definite"):
        load_vehicle(write(tmp_path, d))


def test_unknown_vehicle_and_missing_file():
    with pytest.raises(VehicleError, match="unknown vehicle 'nautilus'"):
        load_vehicle("nautilus")
    with pytest.raises(VehicleError, match="does not exist"):
        load_vehicle("no/such/file.yaml")


def test_with_parameters_and_save_round_trip(tmp_path):
    v = load_vehicle("bluerov2_heavy_initial")
    v2 = v.with_parameters({"X_u": -0.2, "I_xx": 0.4, "Z_wdot": 20.0})
    p = uvsim.save_vehicle(v2, tmp_path / "fit.yaml", header="fitted", annotations={"X_u": "previous -0.161"})
    text = p.read_text()
    assert "# previous -0.161" in text
    v3 = load_vehicle(p)
    for k, val in v2.parameters().items():
        assert v3.parameters()[k] == pytest.approx(val)
    assert v3.n_thrusters == 8
    with pytest.raises(VehicleError, match="unknown parameter"):
        v.with_parameters({"X_uuu": 1})


def test_absurd_override_rejected():
    with pytest.raises(VehicleError, match="I_xx = -1: expected a positive value"):
        uvsim.Model("bluerov2_heavy", {"I_xx": -1.0})
    with pytest.raises(VehicleError, match="non-finite"):
        uvsim.Model("bluerov2_heavy", {"X_u": np.nan})


def test_blowup_is_reported():
    t = np.arange(0, 2.0, 0.5)
    U = np.zeros((t.size, 6))
    U[:, 0] = 1e9
    with pytest.raises(SimulationError, match="blew up"):
        uvsim.simulate("bluerov2_heavy", t, U)
    res = uvsim.simulate("bluerov2_heavy", t, U, on_blowup="nan")
    assert np.isnan(res.y[-1]).all()


def test_bad_simulation_inputs():
    t = np.array([0.0, 0.1, 0.1, 0.2])
    with pytest.raises(SimulationError, match="strictly increasing"):
        uvsim.simulate("bluerov2_heavy", t, np.zeros((4, 6)))
    t = np.arange(4) * 0.1
    U = np.zeros((4, 6))
    U[2, 1] = np.nan
    with pytest.raises(SimulationError, match="row 2"):
        uvsim.simulate("bluerov2_heavy", t, U)
    with pytest.raises(SimulationError, match="8 thrusters"):
        uvsim.simulate("bluerov2_heavy", t, np.full((4, 6), 1500.0), input_kind="pwm")
    with pytest.raises(SimulationError, match="no thrust curves"):
        uvsim.simulate("chin2018_rov", t, np.full((4, 6), 1500.0), input_kind="pwm")


def test_vehicle_show_json(capsys):
    assert main(["vehicle", "show", "bluerov2_heavy", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    for key in ("mass", "buoyancy", "r_g", "r_b", "inertia", "added_mass", "linear_damping", "quadratic_damping"):
        assert key in d
    assert np.array(d["added_mass"]).shape == (6, 6) and np.all(np.diag(d["added_mass"]) > 0)
    assert np.array(d["inertia"]).shape == (3, 3)
    assert d["linear_damping"][0] == -0.153 and d["quadratic_damping"][5] == -0.425
    assert main(["vehicle", "show", "nautilus"]) == 2


def test_coupled_damping_parameters_round_trip(tmp_path):
    """Named entries D_L[i,j] of a coupled damping model are overridable and written back."""
    from uvsim.vehicle import vehicle_from_dict

    d = yaml.safe_load(vehicle_path("bluerov2_heavy").read_text())
    DL = np.diag([-0.15, -0.18, -0.24, -0.38, -0.2, -0.13])
    DL[5, 1] = -0.05
    d["damping"] = {"type": "coupled", "linear": DL.tolist(), "quadratic": np.diag([-35, -43, -70, -0.39, -0.43, -0.43]).tolist()}
    v = vehicle_from_dict(d, source="coupled")
    assert v.parameters()["D_L[5,1]"] == -0.05
    v2 = v.with_parameters({"D_L[5,1]": -0.08, "D_Q[0,0]": -30.0})
    assert v2.parameters()["D_L[5,1]"] == -0.08 and v2.parameters()["D_Q[0,0]"] == -30.0
    v3 = load_vehicle(uvsim.save_vehicle(v2, tmp_path / "c.yaml"))
    assert v3.parameters()["D_L[5,1]"] == -0.08


def test_sensor_positions_load_validate_and_round_trip():
    """Issue 14: a vehicle file declares sensor positions (pressure sensor aft, IMU)."""
    from uvsim.vehicle import vehicle_from_dict

    d = uvsim.load_vehicle("bluerov2_heavy").to_dict()
    d["sensors"] = {"pressure": {"position": [-0.15, 0.0, 0.0], "source": "measured"}, "imu": {"position": [0, 0, 0.02]}}
    v = vehicle_from_dict(d)
    np.testing.assert_array_equal(v.sensors["pressure"], [-0.15, 0.0, 0.0])
    assert vehicle_from_dict(v.to_dict()).sensors.keys() == v.sensors.keys()
    assert v.with_parameters({"X_u": -1.0}).sensors.keys() == v.sensors.keys()
    for bad, frag in (({"presure": {"position": [0, 0, 0]}}, "unknown sensor"),
                      ({"imu": {"position": [0, 0]}}, "3 finite numbers"),
                      ({"imu": {"position": [50, 0, 0]}}, "from the body origin"),
                      ({"imu": [0, 0, 0]}, "expected a mapping")):
        d["sensors"] = bad
        with pytest.raises(uvsim.VehicleError, match=frag):
            vehicle_from_dict(d)
