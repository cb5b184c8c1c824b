"""The independent truth model and scenario generator (``uvsim.scenarios``).

The truth model is checked against physics (closed-form results) and against the project's
simulator: two implementations written apart that agree.  This is the one test file that
uses both; the generator itself must not import the simulator (first test).
"""
from __future__ import annotations

import ast
import dataclasses
import filecmp
import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.spatial.transform import Rotation

from uvsim.errors import UvsimError
from uvsim.logs import read_dataset
from uvsim.scenarios import ScenarioError, ScenarioSpec, generate, load_truth, sample_scenario, simulate_truth
from uvsim.scenarios.dynamics import Context, Plant, integrate, rotation
from uvsim.scenarios.effects import (Ballast, CoupledDamping, Current, PeriodicForce, Tether, ThrustAsymmetry,
                                     ThrusterLag, WeakThruster)
from uvsim.scenarios.sensors import measure
from uvsim.scenarios.truth import base_parts, equilibrium_attitude
from uvsim.scenarios.vehicle_data import LINEAR_NAMES, QUADRATIC_NAMES, load_vehicle_data

SRC = Path(__file__).resolve().parents[1] / "src" / "uvsim"
FORBIDDEN = ("model", "simulate", "forces", "effects", "rigid_body", "bilinear", "kinematics", "thrusters",
             "vehicle", "metrics", "calibration", "diagnosis", "synthetic", "sam")
ZERO_DAMPING = {k: 0.0 for k in LINEAR_NAMES + QUADRATIC_NAMES}


@pytest.fixture(scope="module")
def veh():
    return load_vehicle_data()


def neutral(veh, **coeffs):
    """BlueROV2 Heavy (Table 5) with B = W (CB still 0.024 m above the CG)."""
    return veh.with_coefficients(coeffs).with_rigid_body(buoyancy=veh.weight)


# ----------------------------------------------------------------------------- isolation
def _imported_modules(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    pkg = path.parent.relative_to(SRC.parent).as_posix().replace("/", ".")
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = pkg.split(".")[: len(pkg.split(".")) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out.append(mod)
            out += [f"{mod}.{a.name}" for a in node.names]
    return out


def test_scenarios_share_no_code_with_the_simulator():
    """No module of uvsim.scenarios (nor its CLI command) imports the model, simulator, force
    terms, effects, vehicle loader, metrics, calibration, diagnosis, synthetic data or SAM."""
    files = sorted((SRC / "scenarios").glob("*.py")) + [SRC / "commands" / "scenario.py"]
    assert len(files) >= 8
    bad = []
    for f in files:
        for mod in _imported_modules(f):
            parts = mod.split(".")
            if parts[0] == "uvsim" and len(parts) > 1 and parts[1] in FORBIDDEN:
                bad.append(f"{f.name}: {mod}")
    assert not bad, bad


def test_import_check_catches_a_forbidden_import(tmp_path):
    """The checker itself works: it sees absolute, from- and relative imports."""
    d = SRC / "scenarios"
    probe = d / "_probe_for_test.py"
    try:
        probe.write_text("from uvsim.simulate import simulate\nfrom .. import model\nimport uvsim.forces.damping\n")
        mods = _imported_modules(probe)
    finally:
        probe.unlink()
    assert "uvsim.simulate" in mods and "uvsim.model" in mods and "uvsim.forces.damping" in mods


# ----------------------------------------------------------------------------- physics
def test_rotation_matrix_matches_scipy():
    q = Rotation.random(20, random_state=3).as_quat()          # x, y, z, w
    R = rotation(q[:, [3, 0, 1, 2]].T)
    np.testing.assert_allclose(R.transpose(2, 0, 1), Rotation.from_quat(q).as_matrix(), atol=1e-14)


def test_terminal_velocity_matches_the_damping_law(veh):
    """Constant surge force F, neutral buoyancy: F + X_u u + X_uu u^2 = 0 at steady state, so
    u_inf = (-X_u - sqrt(X_u^2 - 4 X_uu F)) / (2 X_uu) (seed 000 eq. 7-9, Table 5)."""
    v = neutral(veh)
    F = 20.0
    t = np.arange(0, 60.0 + 1e-9, 0.05)
    U = np.zeros((t.size, 6))
    U[:, 0] = F
    res = simulate_truth(v, t, U, "force", max_step=0.05)
    Xu, Xuu = v.coefficients["X_u"], v.coefficients["X_uu"]
    u_inf = (-Xu - np.sqrt(Xu**2 - 4 * Xuu * F)) / (2 * Xuu)
    assert res["nu"][0, -1, 0] == pytest.approx(u_inf, rel=1e-9)
    assert np.abs(res["nu"][0, -1, 1:]).max() < 1e-12


def test_small_roll_oscillation_period_from_metacentric_height(veh):
    """Neutral vehicle, CB 0.024 m above the CG, no damping: small roll oscillates with
    omega^2 = B |z_b| / (I_xx + K_pdot) (restoring K = -B |z_b| sin(phi), seed 000 eq. 10)."""
    v = neutral(veh, **ZERO_DAMPING)
    phi0 = 0.01
    t = np.arange(0, 20.0, 0.01)
    q0 = Rotation.from_euler("x", phi0).as_quat()[[3, 0, 1, 2]]
    res = simulate_truth(v, t, np.zeros((t.size, 6)), "force", quat0=[q0], max_step=0.01)
    roll = Rotation.from_quat(res["quat"][0][:, [1, 2, 3, 0]]).as_euler("ZYX")[:, 2]
    up = np.flatnonzero((roll[:-1] < 0) & (roll[1:] >= 0))
    tc = t[up] - roll[up] * (t[up + 1] - t[up]) / (roll[up + 1] - roll[up])   # interpolated crossings
    period = np.mean(np.diff(tc))
    expected = 2 * np.pi * np.sqrt((v.coefficients["I_xx"] + v.coefficients["K_pdot"]) / (v.buoyancy * 0.024))
    assert len(tc) > 5
    assert period == pytest.approx(expected, rel=2e-4)   # amplitude effect (phi0^2/16 ~ 6e-6) and sampling


def _general_plant(n=1, restoring=False):
    """A body with CG offset, products of inertia and a full symmetric M_A; no damping.
    With ``restoring``, weight at r_g and a larger buoyancy at r_b."""
    rng = np.random.default_rng(11)
    A = rng.normal(size=(6, 6))
    MA = A @ A.T * 0.4 + np.diag([8, 12, 15, 0.3, 0.4, 0.3])
    I = np.array([[0.5, -0.02, 0.03], [-0.02, 0.7, -0.01], [0.03, -0.01, 0.6]])
    r_g = np.array([0.01, -0.02, 0.03])
    W, B, r_b = 20 * 9.81, 20 * 9.81 * (1.02 if restoring else 1.0), np.array([0.0, 0.01, -0.05])
    rep = lambda a: np.repeat(np.asarray(a, dtype=float)[..., None], n, axis=-1)  # noqa: E731
    return Plant(mass=np.full(n, 20.0), r_g=rep(r_g), inertia=rep(I), added_mass=rep(MA),
                 linear=np.zeros((6, n)), quadratic=np.zeros((6, n)),
                 load=np.full(n, W - B if restoring else 0.0),
                 load_moment=rep(W * r_g - B * r_b) if restoring else np.zeros((3, n)),
                 current=np.zeros((3, n)), allocation=rep(np.eye(6)), lag_time=np.zeros((6, n)))


def _tumble(plant, nu0, duration, renormalize=True):
    """Unforced motion of ``plant`` from rest attitude with body velocity ``nu0``; states (n_t, 19)."""
    y0 = np.zeros((19, 1))
    y0[3] = 1.0
    y0[7:13, 0] = nu0
    t = np.arange(0, duration + 1e-9, 0.05)
    return integrate(plant, t, np.zeros((t.size, 6, 1)), y0, max_step=0.002, renormalize=renormalize)[0][:, :, 0]


def test_energy_is_conserved_without_damping_and_restoring():
    """Tumbling free body (general M_RB with CG offset and products of inertia, full M_A):
    T = 1/2 nu^T (M_RB + M_A) nu is constant (the Coriolis terms do no work)."""
    plant = _general_plant()
    nu = _tumble(plant, [0.4, -0.3, 0.2, 1.5, -2.0, 1.0], 10.0)[:, 7:13]
    T = 0.5 * np.einsum("ti,ij,tj->t", nu, plant.M[:, :, 0], nu)
    assert np.abs(nu[-1] - nu[0]).max() > 0.1              # it really tumbled
    assert np.abs(T / T[0] - 1).max() < 1e-10


def test_energy_with_restoring_is_kinetic_plus_potential():
    """With restoring forces on (weight at r_g, buoyancy at r_b, B > W) and no damping, the
    kinetic energy plus the potential of the loads, -(W - B) z - (W r_g - B r_b) . R^T e_3 ...
    i.e. V = -sum F_i (z + (R r_i)_z), is conserved."""
    plant = _general_plant(restoring=True)
    Y = _tumble(plant, [0.3, -0.2, 0.1, 0.8, -0.6, 0.5], 10.0)
    nu = Y[:, 7:13]
    R = rotation(Y[:, 3:7].T)                              # (3, 3, n_t)
    kin = 0.5 * np.einsum("ti,ij,tj->t", nu, plant.M[:, :, 0], nu)
    pot = -(plant.load[0] * Y[:, 2] + np.einsum("jt,j->t", R[2], plant.load_moment[:, 0]))
    E = kin + pot
    assert np.ptp(pot) > 0.1
    assert np.ptp(E) / np.ptp(pot) < 1e-8


def test_quaternion_stays_unit():
    """Without renormalization RK4 keeps |q| = 1 to ~1e-10 over 5 s of tumbling; with it (the
    default) to round-off."""
    plant = _general_plant()
    for renorm, tol in ((False, 1e-9), (True, 1e-14)):
        Y = _tumble(plant, [0.4, -0.3, 0.2, 1.5, -2.0, 1.0], 5.0, renormalize=renorm)
        assert np.abs(np.linalg.norm(Y[:, 3:7], axis=1) - 1).max() < tol


def test_integration_error_by_step_halving(veh):
    """A generated 4-s spiral with a tether (cable drag) and a thruster lag: RK4 at the default
    2 ms step and at 1 ms agree to far below 1 mm (measured ~1e-10 m; docs/scenarios.md has
    the 49-run check)."""
    spec = sample_scenario(4, "diagnose", n_runs=1, n_validation=1, duration=4.0, input_kind="pwm", rate_hz=50.0,
                           effects=[{"type": "tether", "variant": "3d_drag"}, {"type": "thruster_lag"}])
    from uvsim.scenarios.generate import simulate_spec

    pos = [simulate_spec(dataclasses.replace(spec, max_step=h), with_snr=False)["sim"]["pos"] for h in (0.002, 0.001)]
    assert np.ptp(pos[0][:, :, :2]) > 0.5                     # it moved
    assert np.abs(pos[0] - pos[1]).max() < 1e-7


# ----------------------------------------------------------------------------- cross-check
def _cross_inputs(t):
    U = np.zeros((t.size, 6))
    U[:, 0] = 15 * (t < 6)
    U[:, 2] = 5 * np.sin(t)
    U[:, 3] = 0.5 * (t > 4)
    U[:, 5] = 1.0 * (t > 2)
    return U


@pytest.mark.parametrize("case", ["force", "current", "pwm"])
def test_truth_agrees_with_the_project_simulator(veh, case):
    """No effects, no perturbation: the truth model and uvsim.simulate (both RK4 at 5 ms) give
    the same 10-s trajectory of the BlueROV2 Heavy (Table 5, B > W) to far below 1 mm
    (measured ~1e-10 m): two implementations written apart, same equations."""
    import uvsim

    t = np.arange(0, 10.0 + 1e-9, 0.02)
    kind, current = "force", None
    U = _cross_inputs(t)
    effects = []
    if case == "current":
        current = [0.1, -0.05, 0.03]
        effects = [Current(variant="with_vertical", magnitude=0.12, velocity_ned=current)]
    if case == "pwm":
        kind = "pwm"
        U = np.full((t.size, 8), 1500.0)
        U[:, 0], U[:, 1], U[:, 6] = 1600, 1580, 1650
        U[:, 4] = 1400 + 100 * (t > 3)
    mine = simulate_truth(veh, t, U, kind, effects=effects, pos0=[[0, 0, 1]], max_step=0.005)
    theirs = uvsim.simulate(uvsim.load_vehicle("bluerov2_heavy"), t, U, input_kind=kind, substeps=4,
                            pos0=[0, 0, 1], current=current)
    assert np.ptp(mine["pos"][0], axis=0).max() > 0.5
    assert np.abs(theirs.position - mine["pos"][0]).max() < 1e-6
    assert np.abs(theirs.quaternion - mine["quat"][0]).max() < 1e-6


# ----------------------------------------------------------------------------- effects
def _ctx(pos=(0, 0, 0), yaw=0.0, nu=None):
    q = Rotation.from_euler("z", yaw).as_quat()[[3, 0, 1, 2]]
    nu = np.zeros(6) if nu is None else np.asarray(nu, dtype=float)
    return Context(0.0, np.asarray(pos, dtype=float)[:, None], rotation(q[:, None]), nu[:, None], nu[:, None])


def test_tether_pull_direction_magnitude_and_moment():
    """Anchor at (3, 4, 0) NED, vehicle at the origin: a 2 N tension pulls along (3, 4, 0)/5;
    with yaw 90 deg the body sees R^T F; the attachment offset gives r_a x f."""
    ra = [-0.2, 0.05, -0.1]
    t = Tether(variant="3d", magnitude=2.0, law="tension", anchor_ned=[3, 4, 0], attach_body=ra, tension=2.0)
    w = t.wrench({}, np.array([True]))
    ctx = _ctx(pos=np.array([0, 0, 0]) - rotation(np.array([[1.0], [0], [0], [0]]))[:, :, 0] @ ra)
    tau = w(ctx)[:, 0]
    np.testing.assert_allclose(tau[:3], [1.2, 1.6, 0.0], atol=1e-12)
    np.testing.assert_allclose(tau[3:], np.cross(ra, [1.2, 1.6, 0.0]), atol=1e-12)
    ctx = _ctx(pos=np.array([0, 0, 0]) - np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]]) @ ra, yaw=np.pi / 2)
    np.testing.assert_allclose(w(ctx)[:3, 0], [1.6, -1.2, 0.0], atol=1e-12)     # R^T (1.2, 1.6, 0)


def test_tether_elastic_horizontal_and_slack():
    """Elastic law k (L - L_s) beyond the slack length, none inside it; the horizontal variant
    drops the vertical part of the line to the anchor."""
    t = Tether(variant="horizontal", magnitude=0.5, law="elastic", anchor_ned=[3, 4, -2], stiffness=0.5,
               slack_length=4.0)
    tau = t.wrench({}, np.array([True]))(_ctx())[:, 0]
    np.testing.assert_allclose(tau[:3], 0.5 * (5 - 4) * np.array([0.6, 0.8, 0]), atol=1e-12)
    t.slack_length = 6.0
    assert np.abs(t.wrench({}, np.array([True]))(_ctx())).max() == 0.0


def test_tether_cable_drag():
    """Moving at v = 0.5 m/s east, normal to a cable running north: drag -1/8 rho C_d D l |v| v
    with l = max(L, L_s) (the vehicle end's share of a straight pinned cable's drag)."""
    t = Tether(variant="3d_drag", magnitude=1e-9, law="tension", anchor_ned=[5, 0, 0], tension=0.0,
               slack_length=6.0)
    tau = t.wrench({}, np.array([True]))(_ctx(nu=[0, 0.5, 0, 0, 0, 0]))[:, 0]
    expected = -0.125 * 1000 * 1.2 * 0.0076 * 6.0 * 0.5 * 0.5
    np.testing.assert_allclose(tau[:3], [0, expected, 0], atol=1e-12)


def test_ballast_moment_sign_mass_and_equilibrium(veh):
    """A 1 N lead weight 0.1 m to starboard: positive (starboard-down) roll moment 0.1 N m on a
    level vehicle; its mass (1 N / g / (1 - 1000/11340)) joins the rigid body; the vehicle rests
    at tan(phi) = 0.1 w / (B |z_b|)."""
    b = Ballast.sample(np.random.default_rng(0), "lead", 1.0, g=veh.g)
    b.position = [0.0, 0.1, 0.0]
    parts = base_parts(neutral(veh), 1, 6)
    m0 = parts["mass"][0]
    b.modify(parts, np.array([True]))
    assert parts["mass"][0] - m0 == pytest.approx(1.0 / veh.g / (1 - 1000 / 11340))
    plant = Plant(allocation=np.eye(6)[:, :, None], **parts)
    y = np.zeros((19, 1))
    y[3] = 1.0
    dnu = plant.rhs(0.0, y, np.zeros((6, 1)))[7:13, 0]
    assert dnu[3] > 0
    tau = plant.M[:, :, 0] @ dnu
    assert tau[3] == pytest.approx(0.1, rel=1e-12)
    assert tau[2] == pytest.approx(1.0, rel=1e-12)
    roll, pitch = equilibrium_attitude(parts["load_moment"][:, 0])
    assert np.tan(roll) == pytest.approx(0.1 / (veh.weight * 0.024), rel=1e-9) and abs(pitch) < 1e-12


def test_thruster_lag_step_response(veh):
    """First-order lag: a thrust step reaches 1 - 1/e of its value after T (start at rest);
    started at the command it is there at once."""
    T = 0.1
    t = np.arange(0, 1.0 + 1e-9, 0.01)
    U = np.zeros((t.size, 8))
    U[:, 0] = 10.0
    for variant, at_T in (("rest", 10 * (1 - np.exp(-1))), ("command", 10.0)):
        lag = ThrusterLag(variant=variant, magnitude=T, time_constant=T)
        res = simulate_truth(neutral(veh), t, U, "thrust", effects=[lag], max_step=0.001)
        assert res["thrust"][0, 10, 0] == pytest.approx(at_T, rel=1e-9)


def test_thrust_asymmetry_and_weak_thruster(veh):
    """Reverse thrust scaled by the ratio, forward untouched; a weak thruster's thrust scaled by
    its gain; with force inputs the controller's allocation spreads the command and
    A diag(g) A^+ tau is delivered."""
    t = np.arange(0, 0.1, 0.01)
    U = np.tile([5.0, -5.0, 3, -3, 1, -1, 2, -2], (t.size, 1))
    asym = ThrustAsymmetry(variant="per_thruster", magnitude=0.3, ratio=0.7)
    weak = WeakThruster(variant="vertical", magnitude=0.6, thruster=6, gain=0.4)
    res = simulate_truth(veh, t, U, "thrust", effects=[asym, weak])
    expected = np.where(U[0] < 0, 0.7 * U[0], U[0])
    expected[5] *= 0.4
    np.testing.assert_allclose(res["thrust"][0, 0], expected, atol=1e-12)
    tau = np.array([10.0, -5, 8, 0.5, -0.3, 1.0])
    res = simulate_truth(veh, t, np.tile(tau, (t.size, 1)), "force", effects=[weak])
    A = veh.allocation()
    g = np.ones(8)
    g[5] = 0.4
    np.testing.assert_allclose(res["thrust"][0, 0], A @ np.diag(g) @ np.linalg.pinv(A) @ tau, atol=1e-12)
    per_dof = ThrustAsymmetry(variant="per_dof", magnitude=0.3, ratio=0.7)
    res = simulate_truth(veh, t, np.tile(tau, (t.size, 1)), "force", effects=[per_dof])
    np.testing.assert_allclose(res["thrust"][0, 0], np.where(tau < 0, 0.7 * tau, tau), atol=1e-12)


def test_coupled_damping_derivatives(veh):
    """Drag centre 0.05 m below the origin: sway drag Y = Y_v v + Y_vv |v| v gives
    K = -z_cp Y (K_v = -z_cp Y_v, K_vv = -z_cp Y_vv); surge drag gives M = z_cp X."""
    c = CoupledDamping(variant="vertical_offset", magnitude=0.05, offset=[0, 0, 0.05])
    c.with_derivatives(dict(zip(LINEAR_NAMES, veh.linear_damping())), dict(zip(QUADRATIC_NAMES,
                                                                              veh.quadratic_damping())))
    parts = base_parts(veh, 1, 6)
    w = c.wrench(parts, np.array([True]))
    v, u = 0.4, -0.3
    tau = w(_ctx(nu=[u, v, 0, 0, 0, 0]))[:, 0]
    d = c.derivatives
    assert tau[3] == pytest.approx(d["K_v"] * v + d["K_vv"] * abs(v) * v, rel=1e-12)
    assert tau[4] == pytest.approx(d["M_u"] * u + d["M_uu"] * abs(u) * u, rel=1e-12)
    assert d["K_vv"] == pytest.approx(-0.05 * veh.coefficients["Y_vv"]) and d["K_vv"] > 0
    np.testing.assert_allclose(tau[:3], 0.0)


def test_current_is_a_galilean_change_of_frame(veh):
    """A constant current v_c: a run that starts moving with the water (nu_0 = [R^T v_c; 0])
    is the still-water run carried along, p_c(t) = p(t) + v_c t, with the same attitude, while
    the vehicle turns and rolls (this is what the nu_c_dot = -omega x R^T v_c term ensures)."""
    vc = np.array([0.12, -0.08, 0.03])
    t = np.arange(0, 8.0 + 1e-9, 0.05)
    U = _cross_inputs(t)
    still = simulate_truth(veh, t, U, "force", max_step=0.005)
    moving = simulate_truth(veh, t, U, "force", max_step=0.005, nu0=[np.r_[vc, 0, 0, 0]],
                            effects=[Current(variant="with_vertical", magnitude=0.15, velocity_ned=vc.tolist())])
    assert np.ptp(still["nu"][0, :, 5]) > 0.5
    np.testing.assert_allclose(moving["pos"][0], still["pos"][0] + t[:, None] * vc, atol=1e-9)
    np.testing.assert_allclose(moving["quat"][0], still["quat"][0], atol=1e-9)


def test_periodic_force_is_a_sine():
    p = PeriodicForce(variant="body_force", magnitude=1.0, amplitude=1.0, frequency=0.25, phase=0.0,
                      direction=[0, 1, 0], point=[0.1, 0, 0])
    w = p.wrench({}, np.array([True]))
    ctx = _ctx()
    ctx.t = 1.0                                            # sin(pi/2) = 1
    np.testing.assert_allclose(w(ctx)[:, 0], [0, 1, 0, 0, 0, 0.1], atol=1e-12)


# ----------------------------------------------------------------------------- sensors
def test_accelerometer_reads_minus_g_at_rest_and_centripetal_when_spinning():
    """Level and at rest: (0, 0, -g).  Spinning at r about z with the IMU at x = 0.1 m:
    the centripetal acceleration -r^2 x appears on acc_x."""
    n = 5
    truth = {"t": np.arange(n) * 0.01, "pos": np.zeros((n, 3)), "quat": np.tile([1.0, 0, 0, 0], (n, 1)),
             "nu": np.zeros((n, 6)), "nu_dot": np.zeros((n, 6)), "g": 9.81, "rate_hz": 100.0}
    s = {"imu": {"position": [0.1, 0, 0], "gyro_sigma": 0.01, "acc_sigma": 0.01}}
    f = measure(truth, s, {}, None)["acceleration"]
    np.testing.assert_allclose(f, np.tile([0, 0, -9.81], (n, 1)), atol=1e-12)
    truth["nu"][:, 5] = 2.0
    f = measure(truth, s, {}, None)["acceleration"]
    np.testing.assert_allclose(f[:, 0], -4.0 * 0.1, atol=1e-12)


def test_depth_is_the_sensor_point_and_euler_lags():
    """Pitched nose-up by 0.1 rad, a sensor 0.15 m aft is deeper by 0.15 sin(0.1); the filter's
    pitch follows a step in attitude with its time constant."""
    n = 101
    q = np.tile(Rotation.from_euler("y", 0.1).as_quat()[[3, 0, 1, 2]], (n, 1))
    q[:50] = [1, 0, 0, 0]
    truth = {"t": np.arange(n) * 0.01, "pos": np.tile([0, 0, 1.0], (n, 1)), "quat": q, "nu": np.zeros((n, 6)),
             "nu_dot": np.zeros((n, 6)), "g": 9.81, "rate_hz": 100.0}
    s = {"depth": {"position": [-0.15, 0, 0], "rate_hz": 10.0, "mode": "native", "sigma": 0.01},
         "euler": {"time_constant": 0.1, "sigma": 0.005, "yaw": False}}
    out = measure(truth, s, {}, None)
    assert out["depth"][100, 0] == pytest.approx(1.0 + 0.15 * np.sin(0.1), abs=1e-12)
    assert np.isnan(out["depth"][1, 0]) and out["euler"].shape == (n, 2)
    assert out["euler"][60, 1] == pytest.approx(0.1 * (1 - np.exp(-11 * 0.01 / 0.1)), rel=1e-9)


# ----------------------------------------------------------------------------- datasets
@pytest.fixture(scope="module")
def small_diagnose(tmp_path_factory):
    spec = sample_scenario(7, "diagnose", n_runs=3, n_validation=1, duration=4.0, rate_hz=25.0,
                           effects=["tether"], input_kind="thrust")
    return spec, generate(spec, tmp_path_factory.mktemp("diag"))


def test_generated_dataset_reads_and_carries_its_truth(small_diagnose):
    import uvsim

    spec, out = small_diagnose
    ds = read_dataset(out)
    assert [r.name for r in ds.runs] == [r["name"] for r in spec.runs]
    assert [r.split for r in ds.runs].count("validation") == 1 and ds.validation[0].dof == "mixed"
    assert ds.runs[0].input_kind == "thrust" and ds.runs[0].has_position and ds.runs[0].has_quaternion
    manifest = yaml.safe_load((out / "manifest.yaml").read_text())
    assert set(manifest) == {"vehicle", "description", "runs"}              # no truth in it
    model = uvsim.load_vehicle(ds.vehicle_file)
    assert ds.vehicle_file.name == "myrov.yaml"
    truth = load_truth(out)
    assert model.parameters()["X_uu"] == pytest.approx(truth["coefficients"]["nominal"]["X_uu"])
    assert model.parameters()["X_uu"] != pytest.approx(truth["coefficients"]["truth"]["X_uu"])
    uvsim.vehicle.vehicle_from_dict(truth["vehicle"])                      # the truth is a valid vehicle
    (eff,) = truth["effects"]
    assert eff["type"] == "tether" and eff["effect_snr"] > 0 and "variant" in eff
    assert truth["effect_snr"] == {"tether": eff["effect_snr"]}
    assert truth["runs"][0]["initial_state"]["position"] == spec.runs[0]["pos0"]
    # the spec in truth.yaml regenerates the same thing
    assert truth["spec"] == yaml.safe_load(yaml.safe_dump(spec.to_dict()))


def test_generation_is_reproducible(small_diagnose, tmp_path):
    spec, out = small_diagnose
    again = generate(sample_scenario(7, "diagnose", n_runs=3, n_validation=1, duration=4.0, rate_hz=25.0,
                                     effects=["tether"], input_kind="thrust"), tmp_path / "again")
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(p.name for p in again.iterdir())
    match, mismatch, errors = filecmp.cmpfiles(out, again, names, shallow=False)
    assert not mismatch and not errors


@pytest.mark.parametrize("mode", ["native", "held", "interpolated"])
def test_realsensor_dataset(tmp_path, mode):
    spec = sample_scenario(2, "realsensor", n_runs=1, n_validation=1, duration=2.0, rate_hz=100.0,
                           depth_mode=mode, effects=["weak_thruster"])
    out = generate(spec, tmp_path / mode)
    ds = read_dataset(out)
    run = ds.runs[0]
    assert not run.has_position and run.input_kind == "pwm" and run.has_acceleration and run.has_depth
    assert list(run.euler_mask) == [True, True, False]
    d = run.data["depth"].to_numpy()
    native = np.arange(0, d.size, 10)
    if mode == "native":
        assert np.all(np.isfinite(d[native])) and np.all(np.isnan(np.delete(d, native)))
    elif mode == "held":
        assert np.all(np.isfinite(d)) and np.all(d[1:10] == d[0]) and d[10] != d[0]
    else:
        assert np.all(np.isfinite(d[: native[-1] + 1]))
        np.testing.assert_allclose(d[5], 0.5 * (d[0] + d[10]), atol=1e-12)
    truth = load_truth(out)
    assert len(truth["runs"][0]["gyro_bias"]) == 3 and max(abs(b) for b in truth["runs"][0]["gyro_bias"]) <= 0.02
    model = yaml.safe_load((out / "myrov.yaml").read_text())
    assert model["sensors"]["pressure"]["position"] == [-0.15, 0.0, 0.0] and "imu" in model["sensors"]
    assert truth["effects"][0]["type"] == "weak_thruster"


def test_gyro_bias_shows_in_the_log(tmp_path):
    """The logged rates minus the truth's rates average to the recorded bias."""
    spec = sample_scenario(5, "realsensor", n_runs=1, n_validation=1, duration=3.0, rate_hz=200.0, effects=[])
    from uvsim.scenarios.generate import simulate_spec

    out = generate(spec, tmp_path / "rs")
    sim = simulate_spec(spec, with_snr=False)["sim"]
    run = read_dataset(out).runs[0]
    bias = np.mean(run.data[["p", "q", "r"]].to_numpy() - sim["nu"][0, : len(run.data), 3:], axis=0)
    gs = spec.sensors["imu"]["gyro_sigma"]
    np.testing.assert_allclose(bias, load_truth(out)["runs"][0]["gyro_bias"], atol=5 * gs / np.sqrt(len(run.data)))


def test_profiles_shape():
    """The fixed issue-10 timing configuration and the profile defaults."""
    s = sample_scenario(0, "issue10_timing")
    assert len(s.runs) == 49 and s.rate_hz == 50.0 and s.input_kind == "force" and len(s.effects) == 1
    assert {r["duration"] for r in s.runs} == {14.0}
    assert [r["shape"]["shape"] for r in s.runs if r["split"] == "validation"] == ["spiral"]
    assert {r["shape"]["shape"] for r in s.runs if r["split"] == "train"} == {"step_reverse"}
    assert all(r["shape"]["t_on"] == 0.0 and r["shape"]["t_reverse"] < r["shape"]["t_off"] < 14 for r in s.runs[:48])
    assert s.vehicle["buoyancy"] == "trimmed" and s.vehicle["net_buoyancy"] == pytest.approx(3.34, abs=0.01)
    assert s.sensors == {"mocap": {"sigma_position": 0.003, "sigma_attitude": 0.003}}
    for seed in range(6):
        d = sample_scenario(seed, "diagnose")
        assert 20 <= sum(r["split"] == "train" for r in d.runs) <= 30 and len(d.effects) <= 2
        assert 10 <= d.rate_hz <= 100 and all(8 <= r["duration"] <= 15 for r in d.runs)
        assert d.runs[-2]["shape"]["shape"] == "spiral" and d.runs[-2]["split"] == "validation"
        r = sample_scenario(seed, "realsensor")
        assert "mocap" not in r.sensors and all(x["dof"] == "mixed" for x in r.runs)
    assert json.loads(json.dumps(sample_scenario(3, "realsensor", dvl=True).to_dict()))   # plain data
    assert sample_scenario(3, "diagnose").to_dict() == sample_scenario(3, "diagnose").to_dict()
    assert sample_scenario(3, "diagnose").to_dict() != sample_scenario(4, "diagnose").to_dict()
    assert len(sample_scenario(1, "diagnose", n_effects=2).effects) == 2


def test_bad_requests_are_named():
    with pytest.raises(ScenarioError, match="unknown override"):
        sample_scenario(0, "diagnose", n_run=3)
    with pytest.raises(ScenarioError, match="profile"):
        sample_scenario(0, "tank")
    with pytest.raises(ScenarioError, match="variant"):
        sample_scenario(0, "diagnose", input_kind="pwm", effects=[{"type": "thrust_asymmetry", "variant": "per_dof"}])
    with pytest.raises(ScenarioError, match="effect 'rope'"):
        sample_scenario(0, "diagnose", effects=["rope"])
    with pytest.raises(UvsimError, match="duration"):
        sample_scenario(0, "diagnose", duration=-1)
    d = sample_scenario(0, "realsensor").to_dict()
    d["sensors"]["imu"].pop("gyro_sigma")
    with pytest.raises(ScenarioError, match="sensors.imu.gyro_sigma"):
        ScenarioSpec.from_dict(d)
    d = sample_scenario(0, "diagnose").to_dict()
    del d["runs"][2]["shape"]
    with pytest.raises(ScenarioError, match=r"runs\[2\]: missing \['shape'\]"):
        ScenarioSpec.from_dict(d)


def test_cli_generate(tmp_path, capsys):
    from uvsim.cli import main

    spec = sample_scenario(1, "diagnose", n_runs=1, n_validation=1, duration=2.0, effects=["ballast"])
    (tmp_path / "spec.yaml").write_text(yaml.safe_dump(spec.to_dict()))
    assert main(["scenario", "generate", "--spec", str(tmp_path / "spec.yaml"), "--out", str(tmp_path / "d")]) == 0
    assert "effect ballast" in capsys.readouterr().out
    assert read_dataset(tmp_path / "d").runs
    assert main(["scenario", "generate", "--profile", "nope", "--out", str(tmp_path / "e")]) == 2
    assert "profile 'nope'" in capsys.readouterr().err


@pytest.mark.slow
def test_issue10_timing_dataset_generates(tmp_path):
    out = generate(sample_scenario(0, "issue10_timing"), tmp_path / "i10")
    ds = read_dataset(out)
    assert len(ds.runs) == 49 and len(ds.runs[0].t) == 701
    assert load_truth(out)["effects"][0]["effect_snr"] > 0


def test_payload_pod_and_truth_curve_voltage():
    """Issue 22's generator classes: a payload pod adds a moment and no net force; the truth
    may follow the T200 curve measured at another voltage (less thrust at 12 V)."""
    from uvsim.scenarios.effects import EFFECTS, UNCATALOGUED
    from uvsim.scenarios.generate import vehicles
    from uvsim.scenarios.truth import base_parts
    from uvsim.scenarios import sample_scenario
    from uvsim.scenarios.effects import ScenarioError

    assert "payload_pod" in UNCATALOGUED and "payload_pod" in EFFECTS
    spec = sample_scenario(3, profile="diagnose", effects=[{"type": "payload_pod", "magnitude": 5.0}], n_runs=2)
    pod = EFFECTS["payload_pod"](**{k: v for k, v in spec.effects[0].items()
                                    if k in EFFECTS["payload_pod"].__dataclass_fields__ and k != "type"})
    _, veh = vehicles(spec)
    parts = base_parts(veh, 1, 1)
    load0, m0 = parts["load"].copy(), parts["load_moment"].copy()
    pod.modify(parts, np.array([True]))
    assert np.array_equal(parts["load"], load0)
    d = np.asarray(pod.weight_at) - np.asarray(pod.float_at)
    assert np.allclose(parts["load_moment"][:, 0] - m0[:, 0], 5.0 * d) and np.linalg.norm(d) > 0.05
    spec = sample_scenario(3, profile="diagnose", curve_voltage=12, n_runs=2)
    nominal, truth = vehicles(spec)
    assert spec.input_kind == "pwm" and truth.curve.name == "t200_12v_measured"
    pwm = np.array([1300.0, 1700.0])
    assert np.all(np.abs(truth.curve.thrust(pwm)) < 0.8 * np.abs(nominal.curve.thrust(pwm)))
    with pytest.raises(ScenarioError, match="curve_voltage"):
        sample_scenario(3, profile="diagnose", curve_voltage=15)
