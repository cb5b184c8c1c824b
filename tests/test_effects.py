"""Effects catalogue: forces by hand computation, validation, vehicle-file round
trip, and simulate() with the effect in the vehicle file."""
from __future__ import annotations

import numpy as np
import pytest

import uvsim
from uvsim.effects import CATALOGUE
from uvsim.errors import VehicleError
from uvsim.forces import make_term
from uvsim.kinematics import quat_to_rotation
from uvsim.model import Model

VEH = uvsim.load_vehicle("bluerov2_heavy")


def effect_force(effect, *, pos=(0, 0, 1.0), q=(1, 0, 0, 0), nu=(0, 0, 0, 0, 0, 0), u=None, kind="force",
                 states=None):
    """Generalized force the effect adds, from the model's accelerations:
    ``M (nu_dot_with - nu_dot_without)`` at the same state (inertia and Coriolis cancel)."""
    u = np.zeros(6 if kind == "force" else 8) if u is None else np.asarray(u, float)
    base = Model(VEH, input_kind=kind)
    with_eff = Model(VEH.with_effects([effect]), input_kind=kind)
    y0 = base.initial_state(pos, q, nu)
    y1 = with_eff.initial_state(pos, q, nu, u[None])
    if states is not None:
        y1[0, 13:13 + len(states)] = states
    d = with_eff.rhs(0.0, y1, u[None])[0, 7:13] - base.rhs(0.0, y0, u[None])[0, 7:13]
    return VEH.M @ d


def test_catalogue_names_registered():
    from uvsim.forces import registered

    for name in ("current", "tether", "thruster_lag", "ballast", "thrust_asymmetry", "coupled_damping",
                 "bottom_effect"):
        assert name in registered()
        assert name in CATALOGUE


def test_ballast_force_and_moment_by_hand():
    tau = effect_force({"type": "ballast", "weight": 2.0, "x": 0.1, "y": -0.05})
    # f = w k, k = [0, 0, 1] level; m = r x f = [y w, -x w, 0]
    np.testing.assert_allclose(tau, [0, 0, 2.0, -0.05 * 2.0, -0.1 * 2.0, 0], atol=1e-9)
    # rolled 90 deg to starboard: NED down is body -y ... k = R^T e3 = [0, sin(phi), cos(phi)] -> [0, 1, 0]
    phi = np.pi / 2
    q = [np.cos(phi / 2), np.sin(phi / 2), 0, 0]
    tau = effect_force({"type": "ballast", "weight": 2.0, "x": 0.1}, q=q)
    np.testing.assert_allclose(tau[:3], [0, 2.0, 0], atol=1e-9)
    np.testing.assert_allclose(tau[3:], np.cross([0.1, 0, 0], [0, 2.0, 0]), atol=1e-9)


def test_ballast_piece_mass_is_inertia_only():
    """A piece's own mass joins M_RB as a point mass at r_p (parallel axis); its weight
    stays the net ``weight`` (restoring unchanged), and it changes the accelerations."""
    from uvsim.rigid_body import rigid_body_mass_matrix

    r = np.array([-0.02, 0.1, -0.05])
    massless = {"type": "ballast", "weight": -0.2, "x": r[0], "y": r[1], "z": r[2]}
    m0, m1 = Model(VEH.with_effects([massless])), Model(VEH.with_effects([{**massless, "mass": 0.01}]))
    dI = 0.01 * ((r @ r) * np.eye(3) - np.outer(r, r))
    np.testing.assert_allclose(m1.M - m0.M, rigid_body_mass_matrix(0.01, dI, r), atol=1e-15)
    # the same generalized force at rest (weight and buoyancy unchanged), other accelerations
    q = np.array([np.cos(0.1), np.sin(0.1), 0.0, 0.0])
    y = m0.initial_state(np.zeros(3), q)
    a0, a1 = m0.rhs(0.0, y, np.zeros((1, 6)))[0, 7:13], m1.rhs(0.0, y, np.zeros((1, 6)))[0, 7:13]
    np.testing.assert_allclose(m1.M @ a1, m0.M @ a0, atol=1e-12)
    assert np.max(np.abs(a1 - a0)) > 1e-6
    # per-row masses in one batch; the vehicle file round trip keeps the mass
    mb = Model(VEH.with_effects([massless]), {"ballast_mass": np.array([0.0, 0.01])})
    np.testing.assert_allclose(mb.M[1], m1.M, atol=1e-15)
    np.testing.assert_allclose(mb.M[0], m0.M, atol=1e-15)
    assert make_term({**massless, "mass": 0.01}).to_dict()["mass"] == 0.01
    with pytest.raises(VehicleError, match="mass"):
        make_term({**massless, "mass": -1.0})


def test_ballast_piece_mass_reproduces_the_independent_truth(tmp_path):
    """Benchmark scenario 38 (``uvsim.scenarios``, written apart from the effects): a 10 g foam
    block.  On its telegraph validation run uvsim with the piece's mass follows the log to
    about the noise; the massless load turns the vehicle the other way (> 100 mm)."""
    from uvsim.kinematics import euler_to_quat
    from uvsim.logs import read_dataset
    from uvsim.scenarios import generate, load_truth, sample_scenario

    out = generate(sample_scenario(38, profile="diagnose", n_effects=1), tmp_path / "ds")
    truth = load_truth(out)
    (e,) = truth["effects"]
    assert e["type"] == "ballast" and 0.005 < e["mass"] < 0.02
    model = uvsim.load_vehicle(out / truth["model_vehicle_file"])
    base = model.with_parameters({k: v for k, v in truth["coefficients"]["truth"].items() if k in model.parameters()})
    load = {"type": "ballast", "weight": e["weight"], **dict(zip("xyz", e["position"]))}
    start = {r["file"].removesuffix(".csv"): r["initial_state"] for r in truth["runs"]}
    run = [r for r in read_dataset(out).validation if "telegraph" in r.name][0]
    s = start[run.name]
    rmse = {}
    for label, veh in (("mass", base.with_effects([{**load, "mass": e["mass"]}])), ("massless", base.with_effects([load]))):
        res = uvsim.simulate(veh, run.t, run.inputs, input_kind=run.input_kind, pos0=np.array(s["position"]),
                             q0=euler_to_quat(np.array([s["roll"], s["pitch"], s["yaw"]])),
                             nu0=np.array(s["nu"]), substeps=4)
        err = res.position - run.data[["x", "y", "z"]].to_numpy()
        rmse[label] = float(np.sqrt(np.mean(np.sum(err ** 2, axis=1))))
    sigma = truth["noise"]["mocap.sigma_position"]
    assert rmse["mass"] < 3 * np.sqrt(3) * sigma, rmse
    assert rmse["massless"] > 0.1, rmse


@pytest.mark.parametrize("input_kind", [pytest.param("thrust", marks=pytest.mark.slow),
                                        pytest.param("pwm", marks=pytest.mark.slow), "force"])
def test_a_weak_thruster_s_lag_lags_its_weak_thrust_as_in_the_independent_truth(tmp_path, input_kind):
    """Benchmark pair 118 (``uvsim.scenarios``, written apart from the effects): a weak
    horizontal thruster and a lag from rest.  uvsim stating both (``thruster_gain_4`` and a
    ``thruster_lag`` with ``start: zero``) follows the generator's noise-free truth to 1e-6
    in every state channel; with the lag acting on the curve's thrust instead of the weak
    unit's (the effects before 2026-11-27) depth was 10 mm and r 0.033 rad/s off."""
    import dataclasses

    from uvsim.benchmarks.calibration_structural import truth_errors
    from uvsim.scenarios import generate, load_truth, sample_scenario
    from uvsim.vehicle import vehicle_from_dict

    spec = sample_scenario(118, profile="diagnose", n_effects=2)
    spec = dataclasses.replace(spec, input_kind=input_kind, runs=[r for r in spec.runs if r["split"] == "validation"])
    truth = load_truth(generate(spec, tmp_path / "ds"))
    weak, lag = truth["effects"]
    assert weak["type"] == "weak_thruster" and lag["type"] == "thruster_lag" and lag["variant"] == "rest"
    veh = vehicle_from_dict(truth["vehicle"], source="truth.yaml").with_effects(
        [{"type": "thruster_lag", "time_constant": lag["time_constant"], "start": "zero"}])
    err = truth_errors(spec, {"both": veh.with_parameters({f"thruster_gain_{weak['thruster']}": weak["gain"]})})
    assert max(err["both"].values()) < 1e-6, err


def test_tether_pull_and_moment_by_hand():
    eff = {"type": "tether", "anchor_n": -3.0, "anchor_d": 1.0, "stiffness": 2.0, "slack_length": 1.0,
           "attach_z": -0.1, "length": 0.0}
    tau = effect_force(eff, pos=(0, 0, 1.1))  # attachment at NED (0, 0, 1.0): 3 m from the anchor
    # pull = k (L - L_s) = 2 (3 - 1) = 4 N towards -x; moment r_a x f = [0, 0, -0.1] x [-4, 0, 0] = [0, 0.4, 0]
    np.testing.assert_allclose(tau, [-4.0, 0, 0, 0, 0.4, 0], atol=1e-9)
    # constant tension only, slack: 5 N towards the anchor
    tau = effect_force({"type": "tether", "anchor_n": -3.0, "anchor_d": 1.0, "tension": 5.0, "slack_length": 10.0})
    np.testing.assert_allclose(tau, [-5.0, 0, 0, 0, 0, 0], atol=1e-9)


@pytest.mark.parametrize("horizontal", [False, True])
def test_tether_at_any_attitude_matches_the_ned_formulas(horizontal):
    """The tether is evaluated in the body frame; at random attitudes, positions and
    velocities it equals the NED-frame formulas of its docstring written out here."""
    rng = np.random.default_rng(7)
    eff = {"type": "tether", "anchor_n": -3.0, "anchor_e": 1.0, "anchor_d": 0.5, "stiffness": 2.0,
           "slack_length": 1.0, "tension": 0.5, "length": 5.0, "attach_x": 0.1, "attach_y": -0.05,
           "attach_z": -0.1, "horizontal": horizontal}
    c = 0.5 * 1000.0 * 1.2 * 0.0076 * 5.0 / 3.0
    r_a, p0 = np.array([0.1, -0.05, -0.1]), np.array([-3.0, 1.0, 0.5])
    for _ in range(5):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        pos, nu = rng.normal(size=3), rng.normal(0, 0.5, size=6)
        R = quat_to_rotation(q)
        d = p0 - (pos + R @ r_a)
        if horizontal:
            d[2] = 0.0
        L = np.linalg.norm(d)
        e = d / L
        F = (0.5 + 2.0 * max(0.0, L - 1.0)) * e
        v_a = R @ (nu[:3] + np.cross(nu[3:], r_a))
        v_n = v_a - (v_a @ e) * e
        F = F - c * np.linalg.norm(v_n) * v_n
        f = R.T @ F
        tau = effect_force(eff, pos=pos, q=q, nu=nu)
        np.testing.assert_allclose(tau, np.r_[f, np.cross(r_a, f)], atol=1e-9)


def test_tether_drag_by_hand():
    # cable along x, vehicle moving in sway at 0.5 m/s: normal speed 0.5
    eff = {"type": "tether", "anchor_n": -3.0, "anchor_d": 1.0, "length": 6.0, "cd": 1.2, "diameter": 0.0076}
    tau = effect_force(eff, nu=(0, 0.5, 0, 0, 0, 0))
    expected = -0.5 * 1000 * 1.2 * 0.0076 * (6.0 / 3) * 0.5 * 0.5
    np.testing.assert_allclose(tau, [0, expected, 0, 0, 0, 0], atol=1e-9)
    # motion along the cable: no cross-flow drag
    tau = effect_force(eff, nu=(0.5, 0, 0, 0, 0, 0))
    np.testing.assert_allclose(tau, 0, atol=1e-9)


def test_current_acts_through_relative_velocity():
    # at rest in a 0.2 m/s northward current, heading north: u_r = -0.2, so the damping pushes forward
    tau = effect_force({"type": "current", "n": 0.2})
    p = VEH.parameters()
    ur = -0.2
    expected = p["X_u"] * ur + p["X_uu"] * abs(ur) * ur  # damping on the relative velocity (paper sign)
    assert expected > 0
    np.testing.assert_allclose(tau, [expected, 0, 0, 0, 0, 0], atol=1e-6)
    assert VEH.with_effects([{"type": "current", "e": 0.1}]).parameters()["current_e"] == 0.1


def test_thruster_lag_force_and_states():
    B = VEH.actuators.matrix
    f_c = np.array([10.0, 10, 10, 10, 0, 0, 0, 0])
    eff = {"type": "thruster_lag", "time_constant": 0.5, "start": "zero"}
    tau = effect_force(eff, u=f_c, kind="thrust")
    np.testing.assert_allclose(tau, -B @ f_c, atol=1e-9)  # lagged thrust 0: cancels the command
    lagged = np.array([4.0, 4, 4, 4, 0, 0, 0, 0])
    tau = effect_force(eff, u=f_c, kind="thrust", states=lagged)
    np.testing.assert_allclose(tau, B @ (lagged - f_c), atol=1e-9)
    m = Model(VEH.with_effects([eff]), input_kind="thrust")
    y = m.initial_state([0, 0, 1], None, None, f_c[None])
    y[0, 13:21] = lagged
    dx = m.rhs(0.0, y, f_c[None])[0, 13:21]
    np.testing.assert_allclose(dx, (f_c - lagged) / 0.5)
    # steady start: no effect at t0
    tau = effect_force({"type": "thruster_lag", "time_constant": 0.5}, u=f_c, kind="thrust")
    np.testing.assert_allclose(tau, 0, atol=1e-9)
    # force inputs: lags tau itself
    tau_c = np.array([5.0, 0, 2, 0, 0, 1])
    tau = effect_force(eff, u=tau_c, kind="force")
    np.testing.assert_allclose(tau, -tau_c, atol=1e-9)


def test_thrust_asymmetry_by_hand():
    B = VEH.actuators.matrix
    f = np.array([-10.0, 10, 0, 0, -4, 0, 0, 0])
    tau = effect_force({"type": "thrust_asymmetry", "ratio": 0.7}, u=f, kind="thrust")
    np.testing.assert_allclose(tau, B @ ((0.7 - 1) * np.minimum(f, 0)), atol=1e-9)
    tau = effect_force({"type": "thrust_asymmetry", "ratio": 0.7}, u=[-5.0, 3, 0, 0, 0, 0], kind="force")
    np.testing.assert_allclose(tau, [1.5, 0, 0, 0, 0, 0], atol=1e-9)


def test_coupled_damping_by_hand():
    tau = effect_force({"type": "coupled_damping", "K_vv": -2.0, "M_u": 0.5}, nu=(0.2, 0.5, 0, 0, 0, 0))
    np.testing.assert_allclose(tau, [0, 0, 0, -2.0 * 0.25, 0.5 * 0.2, 0], atol=1e-9)


def test_bottom_effect_by_hand():
    eff = {"type": "bottom_effect", "floor_d": 2.0, "damping": -100.0, "decay_length": 0.25}
    # 0.5 m above the floor, sinking at 0.3 m/s: F = -100 exp(-0.5 / 0.25) 0.3^2 (upwards)
    tau = effect_force(eff, pos=(0, 0, 1.5), nu=(0, 0, 0.3, 0, 0, 0))
    np.testing.assert_allclose(tau, [0, 0, -100 * np.exp(-2.0) * 0.09, 0, 0, 0], atol=1e-9)
    # below the floor level: full strength; rising: pushes down (opposes the motion)
    tau = effect_force(eff, pos=(0, 0, 2.5), nu=(0, 0, -0.3, 0, 0, 0))
    np.testing.assert_allclose(tau, [0, 0, 100 * 0.09, 0, 0, 0], atol=1e-9)
    # horizontal motion: nothing
    np.testing.assert_allclose(effect_force(eff, pos=(0, 0, 1.9), nu=(0.5, 0.2, 0, 0, 0, 0)), 0, atol=1e-12)


@pytest.mark.parametrize("spec, field", [
    ({"type": "thruster_lag", "time_constant": 0.0}, "time_constant"),
    ({"type": "thruster_lag", "time_constant": 100.0}, "time_constant"),
    ({"type": "thruster_lag"}, "time_constant"),
    ({"type": "thruster_lag", "time_constant": 0.2, "start": "later"}, "start"),
    ({"type": "current", "n": 50.0}, ".n"),
    ({"type": "ballast", "weight": 1e5}, "weight"),
    ({"type": "ballast", "weight": "heavy"}, "weight"),
    ({"type": "tether", "stiffness": -1.0}, "stiffness"),
    ({"type": "tether", "diameter": 0.5}, "diameter"),
    ({"type": "tether", "anchr_n": 1.0}, "anchr_n"),
    ({"type": "thrust_asymmetry", "ratio": 0.0}, "ratio"),
    ({"type": "thrust_asymmetry", "ratio": float("nan")}, "ratio"),
    ({"type": "coupled_damping", "K_pp": -1.0}, "K_pp"),
    ({"type": "coupled_damping", "Q_u": 1.0}, "Q_u"),
    ({"type": "coupled_damping", "K_v": 1e9}, "K_v"),
    ({"type": "bottom_effect", "floor_d": 2.0, "damping": 50.0}, "damping"),
    ({"type": "bottom_effect", "floor_d": 2.0, "damping": -50.0, "decay_length": 0.0}, "decay_length"),
    ({"type": "bottom_effect", "damping": -50.0}, "floor_d"),
])
def test_absurd_values_rejected_naming_the_field(spec, field):
    with pytest.raises(VehicleError, match=field.replace(".", r"\.")):
        make_term(spec)


EXAMPLES = [
    {"type": "current", "n": 0.05, "e": -0.03, "d": 0.0},
    {"type": "tether", "anchor_n": -3.0, "stiffness": 2.0, "tension": 1.0, "length": 5.0, "attach_z": -0.1},
    {"type": "thruster_lag", "time_constant": 0.3, "start": "zero"},
    {"type": "thrust_asymmetry", "ratio": 0.75},
    {"type": "ballast", "weight": 1.5, "x": 0.1, "y": 0.0, "z": 0.05},
    {"type": "coupled_damping", "K_vv": -2.0, "M_u": 0.4},
    {"type": "bottom_effect", "floor_d": 1.5, "damping": -200.0, "decay_length": 0.3},
]


@pytest.mark.parametrize("spec", EXAMPLES, ids=[e["type"] for e in EXAMPLES])
def test_vehicle_file_round_trip(spec, tmp_path):
    veh = VEH.with_effects([spec])
    path = uvsim.save_vehicle(veh, tmp_path / "v.yaml")
    back = uvsim.load_vehicle(path)
    assert [e.to_dict() for e in back.effects] == [e.to_dict() for e in veh.effects]
    term = back.effects[0]
    for k, v in spec.items():
        if k != "type":
            assert term.to_dict()[k] == v
    assert back.parameters() == veh.parameters()
    # named parameters can be changed like any other (what calibration / diagnosis do)
    name = next(iter(term.parameters()))
    newval = term.parameters()[name] * 0.9 + 0.01
    changed = back.with_parameters({name: newval})
    assert changed.parameters()[name] == pytest.approx(newval)


def _surge_pwm(t, level=80.0, sign=1.0):
    pwm = np.full((t.size, 8), 1500.0)
    on = (t >= 1.0) & (t < 6.0)
    pwm[on, :4] = 1500.0 + sign * level
    return pwm


def _sim(veh, t, pwm, **kw):
    return uvsim.simulate(veh, t, pwm, input_kind="pwm", pos0=[0, 0, 1.0], **kw)


def test_simulate_with_effects_in_vehicle_file(tmp_path):
    t = np.arange(0, 10, 0.02)
    fwd, rev = _surge_pwm(t), _surge_pwm(t, sign=-1)
    base_f, base_r = _sim(VEH, t, fwd), _sim(VEH, t, rev)

    def load(spec):
        return uvsim.load_vehicle(uvsim.save_vehicle(VEH.with_effects([spec]), tmp_path / f"{spec['type']}.yaml"))

    # current: the vehicle at rest drifts with the water (north)
    rest = np.full((t.size, 8), 1500.0)
    r = _sim(load({"type": "current", "n": 0.1}), t, rest)
    assert 0.3 < r.position[-1, 0] < 1.0 and abs(r.position[-1, 1]) < 1e-6
    # tether anchored behind: surges less far than without
    r = _sim(load({"type": "tether", "anchor_n": -3.0, "anchor_d": 1.0, "stiffness": 2.0}), t, fwd)
    assert r.position[-1, 0] < base_f.position[-1, 0] - 0.05
    # thruster lag: slower start of the surge motion, similar end speed
    r = _sim(load({"type": "thruster_lag", "time_constant": 0.5}), t, fwd)
    i = np.searchsorted(t, 1.5)
    assert r.nu[i, 0] < 0.8 * base_f.nu[i, 0]
    # reverse weaker: the reverse run goes less far, the forward run is unchanged
    v = load({"type": "thrust_asymmetry", "ratio": 0.7})
    # (the base vehicle may run on the compiled kernel and the one with the effect on numpy:
    # equal to round-off, not bit for bit)
    np.testing.assert_allclose(_sim(v, t, fwd).y, base_f.y, rtol=1e-7, atol=1e-12)
    assert abs(_sim(v, t, rev).position[-1, 0]) < 0.9 * abs(base_r.position[-1, 0])
    # extra weight: sinks relative to the baseline (positively buoyant BlueROV2 rises)
    r = _sim(load({"type": "ballast", "weight": 5.0, "x": 0.05}), t, rest)
    assert r.position[-1, 2] > base_f.position[0, 2] + 0.1
    assert r.euler[-1, 1] < -0.01  # weight forward of the CG: nose down (negative pitch)
    # floor 0.5 m below the start: a heave-down run stops short of where it went without
    heave = np.full((t.size, 8), 1500.0)
    heave[(t >= 1.0) & (t < 6.0), 4:] = 1650.0
    base_h = _sim(VEH, t, heave)
    r = _sim(load({"type": "bottom_effect", "floor_d": 1.5, "damping": -500.0}), t, heave)
    assert base_h.position[-1, 2] > 2.0 and r.position[-1, 2] < base_h.position[-1, 2] - 0.2
    # coupled damping: surge motion now pitches the vehicle
    r = _sim(load({"type": "coupled_damping", "M_uu": 3.0}), t, fwd)
    assert r.euler[:, 1].max() > base_f.euler[:, 1].max() + 0.01
