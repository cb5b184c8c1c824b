"""SAM actuator subsystems: propulsion and thrust vectoring, servo limits/rates, mass changes."""
import math

import numpy as np
import pytest
from scipy.optimize import brentq

import uvsim
from uvsim.errors import SimulationError
from uvsim.rigid_body import rigid_body_mass_matrix
from uvsim.sam.model import make_model
from uvsim.sam.vehicle import NEUTRAL, SAM_INPUTS, commands, load_sam
from uvsim.vehicle import inertia_tensor


@pytest.fixture(scope="module")
def veh():
    return load_sam()


def _term(model, kind):
    for i, t in enumerate(model.terms):
        if t.kind == kind:
            return i, t
    raise KeyError(kind)


def _tau(model, kind, y, u):
    """Generalized force of one term at state y (1, n_y) and commands u (1, 7)."""
    from uvsim.forces.base import Context
    from uvsim.kinematics import quat_to_rotation

    i, term = _term(model, kind)
    R = quat_to_rotation(y[:, 3:7])
    ctx = Context(0.0, y[:, :3], y[:, 3:7], R, y[:, 7:13], y[:, 7:13], u, "thrust", model.weight, model.mass,
                  model.r_g, {j: y[:, s] for j, s in model.state_slices.items()}, model.params)
    return term.forces(ctx, model.preps[i])


def test_counter_rotating_propellers_cancel_roll(veh):
    m = make_model(veh)
    u = commands(1, rpm_1=1200, rpm_2=1200)
    y = m.initial_state(nu=[1.0, 0, 0, 0, 0, 0], u0=u)
    f = _tau(m, "sam_propulsion", y, u)[0]
    assert f[0] > 0 and abs(f[3]) < 1e-12 and abs(f[4]) < 1e-12 and abs(f[5]) < 1e-12
    u2 = commands(1, rpm_1=1200, rpm_2=600)
    y2 = m.initial_state(nu=[1.0, 0, 0, 0, 0, 0], u0=u2)
    f2 = _tau(m, "sam_propulsion", y2, u2)[0]
    assert abs(f2[3]) > 0.1  # unequal rpm leave a reaction torque in roll


@pytest.mark.parametrize("col, dof, sign", [("tv_pitch", 4, 1), ("tv_yaw", 5, 1)])
def test_thrust_vector_signs(veh, col, dof, sign):
    m = make_model(veh)
    u = commands(1, rpm_1=1000, rpm_2=1000, **{col: 0.1})
    y = m.initial_state(u0=u)
    f = _tau(m, "sam_propulsion", y, u)[0]
    assert np.sign(f[dof]) == sign
    T = f[0] / math.cos(0.1)
    assert abs(f[dof]) == pytest.approx(0.78 * T * math.sin(0.1), rel=1e-6)  # arm 0.78 m (sam.yaml)


def test_batch_and_scalar_propulsion_agree(veh):
    m1 = make_model(veh, n=1)
    m3 = make_model(veh, n=3)
    u = commands(3, rpm_1=[-800, 300, 1500], rpm_2=[-800, 900, 1400], tv_pitch=[0.1, -0.05, 0.0], tv_yaw=[0, 0.1, -0.1])
    y = m3.initial_state(nu=np.array([[0.5, 0, 0, 0, 0, 0]] * 3), u0=u)
    fb = _tau(m3, "sam_propulsion", y, u)
    fs = np.vstack([_tau(m1, "sam_propulsion", y[i:i + 1], u[i:i + 1]) for i in range(3)])
    np.testing.assert_allclose(fs, fb, rtol=1e-12, atol=1e-12)


def test_servo_limits_and_rates(veh):
    t = np.arange(0.0, 2.0, 0.01)
    u = commands(t.size)
    u[t >= 0.2, SAM_INPUTS.index("tv_yaw")] = 0.5  # beyond +7 deg
    u[t >= 0.2, SAM_INPUTS.index("lcg")] = 100.0
    res = uvsim.simulate(veh, t, u, input_kind="thrust", model=make_model(veh))
    df = res.to_pandas()
    tv = df["tv_yaw_act"].to_numpy()
    assert tv.max() <= math.radians(7) + 1e-9
    assert tv.max() == pytest.approx(math.radians(7), abs=1e-4)
    rate = np.abs(np.diff(tv) / np.diff(t)).max()
    assert rate <= math.radians(40) * 1.001
    lcg = df["lcg_act"].to_numpy()
    assert np.abs(np.diff(lcg) / np.diff(t)).max() <= 15.0 * 1.001  # %/s
    assert lcg[-1] == pytest.approx(50 + 15.0 * 1.8, abs=0.5)        # still rate-limited after 1.8 s


def test_commands_need_thrust_kind_and_seven_columns(veh):
    t = np.arange(0, 0.1, 0.01)
    with pytest.raises(SimulationError, match="thrust"):
        uvsim.simulate(veh, t, np.zeros((t.size, 6)), input_kind="force")
    with pytest.raises(SimulationError, match="7"):
        uvsim.simulate(veh, t, np.zeros((t.size, 6)), input_kind="thrust")


def test_vbs_changes_weight_cg_and_mass_matrix_consistently(veh):
    m = make_model(veh)
    u = commands(1, vbs=100.0)
    y = m.initial_state(u0=u)  # actuator starts at the command
    vbs = next(t for t in veh.effects if t.kind == "sam_vbs")
    dm = vbs.full_mass * 0.5
    assert dm == pytest.approx(1026 * math.pi * 0.0425 ** 2 * 0.045 / 2)
    R = np.eye(3)[None]
    mass, r_g, M_RB, Minv = m._mass_update(0.0, y, y[:, :3], R, y[:, 7:13], y[:, 7:13], u)
    m_tot = veh.mass + dm
    assert mass[0] == pytest.approx(m_tot)
    r_expect = (veh.mass * veh.r_g + dm * vbs.position) / m_tot
    np.testing.assert_allclose(r_g[0], r_expect, atol=1e-12)
    I = inertia_tensor(*(veh.inertia[k] for k in ("I_xx", "I_yy", "I_zz", "I_xy", "I_xz", "I_yz")))
    p = vbs.position
    I = I + dm * (p @ p * np.eye(3) - np.outer(p, p))
    np.testing.assert_allclose(M_RB[0], rigid_body_mass_matrix(m_tot, I, r_expect), atol=1e-12)
    # at rest, level: net heave force = extra weight, pitch moment = its lever (restoring term)
    f = _tau(m, "restoring", y, u)
    y_ctx = y
    from uvsim.forces.base import Context

    ctx = Context(0.0, y_ctx[:, :3], y_ctx[:, 3:7], R, y_ctx[:, 7:13], y_ctx[:, 7:13], u, "thrust", mass * 9.81,
                  mass, r_g, {}, m.params, True)
    i, rest = _term(m, "restoring")
    f = rest.forces(ctx, m.preps[i])[0]
    assert f[2] == pytest.approx(m_tot * 9.81 - veh.buoyancy, rel=1e-9)
    assert f[2] == pytest.approx(dm * 9.81, rel=1e-3)
    assert f[4] == pytest.approx(-9.81 * (m_tot * r_expect[0]), rel=1e-9)
    assert f[4] > 0  # VBS aft (x < 0): nose-up moment  # VBS aft (x < 0): nose-up moment
    # the simulator sinks it with that net force
    res = uvsim.simulate(veh, np.arange(0, 1.0, 0.01), np.tile(u, (100, 1)), input_kind="thrust",
                         model=make_model(veh))
    assert res.position[-1, 2] > 0.0


def test_lcg_static_trim_matches_hand_computation(veh):
    """Zero of the pitch moment at rest, LCG all forward, vs atan(dx_g / z_g)."""
    m = make_model(veh)
    lcg = next(t for t in veh.effects if t.kind == "sam_lcg")
    u = commands(1, lcg=100.0)
    dx = lcg.mass * 0.5 * lcg.stroke / veh.mass
    theta_hand = -math.atan2(dx, veh.r_g[2])

    def qdot(theta):
        q = np.array([math.cos(theta / 2), 0.0, math.sin(theta / 2), 0.0])
        y = m.initial_state(q=q, u0=u)
        return m.rhs(0.0, y, u)[0, 11]

    theta = brentq(qdot, -math.pi / 2 + 1e-3, 0.0)
    assert math.degrees(theta) == pytest.approx(math.degrees(theta_hand), abs=0.05)
    assert math.degrees(theta) < -75.0  # close to vertical (seed 003 Fig. 29)


def test_tcg_rolls_the_vehicle_statically(veh):
    m = make_model(veh)
    tcg = next(t for t in veh.effects if t.kind == "sam_tcg")
    u = commands(1, tcg=math.pi / 2)
    dy = tcg.mass * tcg.radius / veh.mass
    dz = -tcg.mass * tcg.radius / veh.mass
    phi_hand = math.atan2(dy, veh.r_g[2] + dz)

    def pdot(phi):
        q = np.array([math.cos(phi / 2), math.sin(phi / 2), 0.0, 0.0])
        y = m.initial_state(q=q, u0=u)
        return m.rhs(0.0, y, u)[0, 10]

    phi = brentq(pdot, 0.0, math.pi / 2 - 1e-3)
    assert phi == pytest.approx(phi_hand, abs=1e-4)


def test_neutral_commands_keep_sam_at_rest(veh):
    t = np.arange(0, 5.0, 0.02)
    res = uvsim.simulate(veh, t, np.tile(NEUTRAL, (t.size, 1)), input_kind="thrust", model=make_model(veh))
    assert np.abs(res.y[:, 7:13]).max() < 1e-3
    assert np.abs(res.position).max() < 1e-3


def test_cached_mass_model_is_identical_to_core_model(veh):
    t = np.arange(0.0, 3.0, 0.02)
    u = commands(t.size, rpm_1=800, rpm_2=800, tv_yaw=0.1)
    u[t > 1.0, SAM_INPUTS.index("lcg")] = 80.0
    u[t > 1.5, SAM_INPUTS.index("vbs")] = 30.0
    a = uvsim.simulate(veh, t, u, input_kind="thrust")
    b = uvsim.simulate(veh, t, u, input_kind="thrust", model=make_model(veh))
    np.testing.assert_array_equal(a.y, b.y)


# ----------------------------------------------------------------------------- review (issue 12)
def _prop(veh):
    return next(e for e in veh.effects if e.kind == "sam_propulsion")


def test_reverse_thrust_ratio_is_the_cited_number(veh):
    """Reverse / forward bollard thrust at equal |rpm| = reverse_thrust_ratio = 0.797, the T200
    equal-rpm K_T ratio cited in sam.yaml; the shipped T200 thrust table (src/uvsim/data/thrusters,
    which we did not write) gives 0.775 at full reverse / full forward command, consistent."""
    from uvsim.thrusters import shipped_curve

    prop = _prop(veh)
    assert prop.coef["reverse_thrust_ratio"] == 0.797
    rpm = np.array([[1000.0, 1400.0], [-1000.0, -1400.0]])
    T, Q = prop.thrust_torque(rpm, np.zeros(2), prop.prepare({}, 2))
    np.testing.assert_allclose(-T[1] / T[0], 0.797, rtol=1e-12)
    np.testing.assert_allclose(-Q[1] / Q[0], 0.797, rtol=1e-12)
    rev, fwd = shipped_curve("t200_16v").thrust(np.array([1100.0, 1900.0]))
    assert -rev / fwd == pytest.approx(0.797, abs=0.03)


def test_thrust_deduction_reduces_the_hull_force_not_the_torque(veh):
    """Fossen's remus100.py: tau_X = (1 - t) X_prop with t = 0.1."""
    m = make_model(veh)
    prop = _prop(veh)
    assert prop.coef["thrust_deduction"] == 0.1
    u = commands(1, rpm_1=1200, rpm_2=-900)
    y = m.initial_state(nu=[0.7, 0, 0, 0, 0, 0], u0=u)
    f = _tau(m, "sam_propulsion", y, u)[0]
    T, Q = prop.thrust_torque(np.array([[1200.0, -900.0]]), np.array([0.7]), prop.prepare({}, 1))
    assert f[0] == pytest.approx(0.9 * T.sum(), rel=1e-12)
    assert f[3] == pytest.approx(-(Q[0, 0] - Q[0, 1]), rel=1e-12)  # spins +1, -1


@pytest.mark.parametrize("key, value, match", [("reverse_thrust_ratio", 2.0, r"\(0, 1.5\]"),
                                               ("reverse_thrust_ratio", 0.0, "positive"),
                                               ("thrust_deduction", 0.6, r"\[0, 0.5\)"),
                                               ("reverse_factor", 5.0, "replaced by reverse_thrust_ratio")])
def test_bad_propulsion_numbers_are_named(key, value, match):
    from uvsim.errors import VehicleError
    from uvsim.forces import make_term

    spec = {"type": "sam_propulsion", key: value}
    with pytest.raises(VehicleError, match=match):
        make_term(spec)


def test_added_mass_is_lamb_k_factors_times_the_displaced_water(veh):
    """M_A = Lamb's k-factors x (rho V, I_f) of the water displaced by the hull envelope (the V of
    the hull tables), not x the vehicle mass.  k1, k2, k' from Lamb (1932) sec. 373 written here;
    V and I_f integrated here with scipy over the piecewise-linear station profile."""
    from scipy.integrate import quad

    from uvsim.hydro.geometry import hull_from_stations

    st = veh.raw["damping"]["components"][0]["hull"]["stations"]
    x, r = np.asarray(st["x"], float), np.asarray(st["r"], float)
    rho = veh.damping.rho
    a, b = 0.75, 0.095
    e = math.sqrt(1 - (b / a) ** 2)
    lg = math.log((1 + e) / (1 - e))
    a0 = 2 * (1 - e * e) / e ** 3 * (0.5 * lg - e)
    b0 = 1 / e ** 2 - (1 - e * e) / (2 * e ** 3) * lg
    k1, k2 = a0 / (2 - a0), b0 / (2 - b0)
    kp = e ** 4 * (b0 - a0) / ((2 - e * e) * (2 * e * e - (2 - e * e) * (b0 - a0)))
    V = hull_from_stations(x, r).volume                  # the hull tables' V (their Munk terms)
    rf = lambda s: np.interp(s, x, r)  # noqa: E731
    pts = list(x[1:-1])
    Vq = quad(lambda s: math.pi * rf(s) ** 2, 0, 1.5, points=pts, limit=200)[0]
    xb = quad(lambda s: math.pi * rf(s) ** 2 * s, 0, 1.5, points=pts, limit=200)[0] / Vq
    I_f = rho * quad(lambda s: math.pi * rf(s) ** 2 * ((s - xb) ** 2 + rf(s) ** 2 / 4), 0, 1.5,
                     points=pts, limit=200)[0]
    Ixx_f = rho * quad(lambda s: math.pi * rf(s) ** 4 / 2, 0, 1.5, points=pts, limit=200)[0]
    assert V == pytest.approx(Vq, rel=2e-3)              # stations' trapezoid vs exact profile
    MA = np.diag(veh.added_mass_matrix)
    np.testing.assert_allclose(MA[:3], [k1 * rho * V, k2 * rho * V, k2 * rho * V], rtol=1e-5)
    np.testing.assert_allclose(MA[3:], [0.3 * Ixx_f, kp * I_f, kp * I_f], rtol=1e-4)
    # the Munk factor of the hull tables is the same k2 - k1
    assert veh.damping.components[0].table.meta["munk_k2_minus_k1"] == pytest.approx(k2 - k1, rel=1e-9)


def test_batched_runs_on_their_own_time_grids_match_single_runs(veh):
    """Rows with different time grids (issue 12 item 6): the SAM terms use no time themselves, so
    each row of a batch equals a single run on its grid (batch numpy path vs scalar path)."""
    from uvsim.simulate import simulate_batch

    grids = [np.arange(0.0, 3.0 + 1e-9, 0.02), np.linspace(0.5, 2.9, 151)]
    n_t = max(g.size for g in grids)
    T = np.stack([np.concatenate([g, np.full(n_t - g.size, g[-1])]) for g in grids])
    U = np.stack([commands(n_t, rpm_1=1000 * np.sign(np.sin(3 * T[i])), rpm_2=900,
                           tv_yaw=0.1 * np.cos(2 * T[i]), lcg=50 + 20 * (T[i] > 1.5)) for i in range(2)])
    batch = simulate_batch(veh, T, U, input_kind="thrust", model=make_model(veh, n=2),
                           nu0=np.array([[0.5, 0, 0, 0, 0, 0.1], [0.2, 0.1, 0, 0, 0, 0]]))
    for i, g in enumerate(grids):
        single = uvsim.simulate(veh, g, U[i, :g.size], input_kind="thrust", model=make_model(veh),
                                nu0=[[0.5, 0, 0, 0, 0, 0.1], [0.2, 0.1, 0, 0, 0, 0]][i])
        np.testing.assert_allclose(batch.y[i, :g.size], single.y, rtol=1e-8, atol=1e-9)
