"""``uvsim export``: gz-sim SDF and UUV Simulator xacro round trips, the frame flip of
cross terms, and the added-mass stability warning (issue 11 item 4)."""
from __future__ import annotations

import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from uvsim.cli import main
from uvsim.errors import VehicleError
from uvsim.export import vehicle_json
from uvsim.export.gz_sim import gz_sdf, parse_gz_sdf
from uvsim.export.uuv_simulator import parse_uuv_xacro, uuv_xacro
from uvsim.vehicle import load_vehicle, vehicle_from_dict

# FRD -> FLU: the sign of a coupling term flips exactly when one of its two DOFs is
# x or roll (unchanged by a rotation of pi about x) and the other is y, z, pitch or yaw.
KEEP = {0, 3}


def _flip(i, j):
    return -1.0 if (i in KEEP) != (j in KEEP) else 1.0


@pytest.fixture(scope="module")
def coupled():
    """A vehicle with every kind of coupling: full added mass, coupled damping with
    off-diagonal quadratic terms, CG/CB off the axes, products of inertia."""
    rng = np.random.default_rng(11)
    d = load_vehicle("bluerov2_heavy").to_dict()
    A = rng.normal(size=(6, 6)) * 0.3
    d["added_mass"] = {"matrix": (np.diag([15.6, 16.5, 16.8, 0.16, 0.17, 0.13]) + 0.05 * (A + A.T)).tolist()}
    DL = -np.diag([0.15, 0.18, 0.24, 0.38, 0.20, 0.13]) + 0.02 * rng.normal(size=(6, 6))
    DQ = -np.diag([35.0, 43.0, 70.0, 0.39, 0.43, 0.43]) + 0.5 * rng.normal(size=(6, 6))
    d["damping"] = {"type": "coupled", "linear": DL.tolist(), "quadratic": DQ.tolist()}
    rb = d["rigid_body"]
    rb["r_g"], rb["r_b"] = [0.01, -0.02, 0.03], [0.005, 0.01, -0.02]
    rb["inertia"].update(I_xy=0.01, I_xz=-0.02, I_yz=0.015)
    return vehicle_from_dict(d, source="coupled-test")


def _composite(p):
    """Mass, centre of mass and inertia about the origin (file frame) of all the file's links:
    the base link and each thruster link (parallel-axis theorem, written out here)."""
    parts = [(p["mass"], np.asarray(p["cg"]), np.asarray(p["inertia_cg"]))]
    parts += [(th["mass"], np.asarray(th["position"]), np.asarray(th["inertia"])) for th in p["thrusters"]]
    m = sum(mi for mi, _, _ in parts)
    c = sum(mi * ci for mi, ci, _ in parts) / m
    J = sum(Ji + mi * (ci @ ci * np.eye(3) - np.outer(ci, ci)) for mi, ci, Ji in parts)
    return m, c, J


def _back_to_frd(p, veh):
    S6 = np.diag([1.0, -1, -1, 1, -1, -1])
    S3 = S6[:3, :3]
    m, c, J = _composite(p)
    return {"added_mass": S6 @ p["added_mass"] @ S6, "linear": S6 @ p["linear"] @ S6,
            "quadratic": S6 @ p["quadratic"] @ S6, "mass": m, "r_g": S3 @ c, "inertia": S3 @ J @ S3,
            "r_b": S3 @ p["cb"]}


def test_gz_sdf_round_trip_every_coefficient(coupled):
    from uvsim.export.frames import damping_matrices

    text, _ = gz_sdf(coupled)
    root = ET.fromstring(text)  # well-formed XML with an SDF root
    assert root.tag == "sdf" and root.find("model").get("name") == coupled.name
    p = parse_gz_sdf(text)
    back = _back_to_frd(p, coupled)
    DL, DQ = damping_matrices(coupled)
    np.testing.assert_array_equal(back["added_mass"], coupled.added_mass_matrix)
    np.testing.assert_array_equal(back["linear"], DL)
    np.testing.assert_array_equal(back["quadratic"], DQ)
    # base link + thruster links together: uvsim's inertia about the origin, CG and mass
    np.testing.assert_allclose(back["inertia"], coupled.inertia_matrix, atol=1e-14)
    np.testing.assert_allclose(back["r_g"], coupled.r_g, atol=1e-15)
    np.testing.assert_allclose(back["r_b"], coupled.r_b, atol=0)
    assert back["mass"] == pytest.approx(coupled.mass, rel=1e-14)
    assert len(p["thrusters"]) == 8 and p["mass"] < coupled.mass  # the thruster links' mass is taken out
    # buoyancy: rho g V of the collision sphere reproduces B
    assert p["water_density"] * coupled.g * p["buoyancy_volume"] == pytest.approx(coupled.buoyancy, rel=1e-12)


def test_gz_cross_terms_flip_sign_under_the_frame_change(coupled):
    text, _ = gz_sdf(coupled, added_mass="plugin")
    hyd = ET.fromstring(text).find("model/plugin")
    MA = coupled.added_mass_matrix
    for (i, j, name) in ((0, 1, "xDotV"), (1, 2, "yDotW"), (3, 4, "kDotQ"), (4, 5, "mDotR"), (0, 3, "xDotP"),
                         (0, 4, "xDotQ"), (1, 5, "yDotR"), (2, 4, "zDotQ")):
        # SNAME sign: xDotV = -M_A[0, 1] in FRD, then the frame flip
        assert float(hyd.find(name).text) == _flip(i, j) * -MA[i, j], name
    DL, DQ = (np.array(coupled.damping.DL), np.array(coupled.damping.DQ))
    assert float(hyd.find("xV").text) == -DL[0, 1]
    assert float(hyd.find("yW").text) == DL[1, 2]
    assert float(hyd.find("kQabsQ").text) == -DQ[3, 4]
    assert float(hyd.find("nRabsR").text) == DQ[5, 5]
    # diagonal damping stays negative (paper sign) and added mass is negative (SNAME)
    assert float(hyd.find("xU").text) < 0 and float(hyd.find("xDotU").text) < 0


def test_bluerov2_heavy_gz_export_and_warning():
    veh = load_vehicle("bluerov2_heavy")
    assert gz_sdf(veh)[1] == []  # the default (fluid added mass) needs no warning
    text, warnings = gz_sdf(veh, added_mass="plugin")
    heavy = [w for w in warnings if "#1923" in w]
    assert len(heavy) == 1 and "surge: added mass 15.64 >= rigid 13.17" in heavy[0]
    hyd = ET.fromstring(text).find("model/plugin")
    # Orjales et al. 2025 Table 5 values with the gz-sim signs
    assert float(hyd.find("xDotU").text) == -15.638 and float(hyd.find("zWabsW").text) == -70.209
    thr = parse_gz_sdf(text)["thrusters"]
    assert len(thr) == 8
    # T5 (front right, vertical, pushes down in FRD) -> FLU: left is -y, up is +z
    np.testing.assert_allclose(thr[4]["position"], [0.120, -0.218, 0.0])
    np.testing.assert_allclose(thr[4]["axis"], [0.0, 0.0, -1.0])


def test_fluid_added_mass_replaces_the_plugin_terms(coupled):
    text, warnings = gz_sdf(coupled, added_mass="fluid")
    assert not any("#1923" in w for w in warnings)
    root = ET.fromstring(text)
    fam = root.find("model/link/inertial/fluid_added_mass")
    assert fam is not None and len(list(fam)) == 21
    hyd = root.find("model/plugin")
    assert not [e.tag for e in hyd if "Dot" in e.tag]  # never both
    assert float(fam.find("xx").text) == coupled.added_mass_matrix[0, 0] > 0  # positive sign
    assert float(fam.find("xy").text) == -coupled.added_mass_matrix[0, 1]
    back = _back_to_frd(parse_gz_sdf(text), coupled)
    np.testing.assert_array_equal(back["added_mass"], coupled.added_mass_matrix)


def test_uuv_round_trip_and_signs():
    veh = load_vehicle("bluerov2_heavy")
    text, _ = uuv_xacro(veh)
    p = parse_uuv_xacro(text)
    assert p["type"] == "fossen"
    np.testing.assert_array_equal(p["added_mass"], veh.added_mass_matrix)  # positive, FRD
    assert np.all(np.diag(p["linear"]) < 0) and np.all(np.diag(p["quadratic"]) < 0)
    np.testing.assert_array_equal(np.diag(p["quadratic"]), [-34.972, -43.118, -70.209, -0.389, -0.427, -0.425])
    assert p["volume"] * veh.rho * veh.g == pytest.approx(veh.buoyancy, rel=1e-12)
    # CB above the CG: +z in FLU, written from the base link's centre of mass (Gazebo classic's ODE)
    np.testing.assert_allclose(p["cg"] + p["cb"], [0.0, 0.0, 0.024], atol=1e-15)
    assert p["fluid_density"] == veh.rho
    m, c, J = _composite(p)
    assert m == pytest.approx(veh.mass, rel=1e-14) and np.allclose(c, 0.0, atol=1e-15)
    t1 = p["thrusters"][0]
    curve = veh.actuators.curves[0]
    np.testing.assert_array_equal(t1["thrust"], curve.thrust(t1["pwm"]))
    np.testing.assert_allclose(t1["axis"], [np.sqrt(0.5), np.sqrt(0.5), 0.0])  # (fwd, starboard) -> (fwd, left)


def test_uuv_rejects_off_diagonal_quadratic_damping(coupled):
    with pytest.raises(VehicleError, match="only the diagonal of the quadratic"):
        uuv_xacro(coupled)


def test_uuv_full_linear_damping_round_trips():
    d = load_vehicle("bluerov2_heavy").to_dict()
    DL = -np.eye(6) + 0.01 * np.arange(36).reshape(6, 6)
    d["damping"] = {"type": "coupled", "linear": DL.tolist(), "quadratic": (-np.eye(6)).tolist()}
    p = parse_uuv_xacro(uuv_xacro(vehicle_from_dict(d, source="x"))[0])
    np.testing.assert_array_equal(p["linear"], DL)


def test_cli_export_all_targets(tmp_path, capsys):
    for to, name in (("gz-sim", "m.sdf"), ("uuv-simulator", "m.xacro"), ("json", "m.json")):
        assert main(["export", "bluerov2_heavy", "--to", to, "--out", str(tmp_path / name)]) == 0
    err = capsys.readouterr().err
    assert "#1923" not in err  # the default gz-sim export (fluid added mass) does not warn
    assert main(["export", "bluerov2_heavy", "--to", "gz-sim", "--added-mass", "plugin",
                 "--out", str(tmp_path / "p.sdf")]) == 0
    err = capsys.readouterr().err
    assert "#1923" in err and "HydrodynamicsUtils.hh:45-72" in err
    doc = json.loads((tmp_path / "m.json").read_text())
    assert doc == json.loads(json.dumps(vehicle_json(load_vehicle("bluerov2_heavy"))))
    assert doc["damping"]["quadratic"][2][2] == -70.209
    assert main(["export", "bluerov2_heavy", "--to", "uuv-simulator", "--added-mass", "plugin",
                 "--out", str(tmp_path / "x.xacro")]) == 2
    assert "gz-sim option" in capsys.readouterr().err
    assert main(["export", "no_such_vehicle", "--to", "json", "--out", str(tmp_path / "n.json")]) == 2
