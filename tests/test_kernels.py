"""The compiled RK4 (uvsim.kernels) against the numpy path, the reference (issue 46, item 3).

Random parameter sets, inputs of every kind, currents, coupled damping, per-row time grids,
substeps and voltages: states and accelerations equal to 1e-10.  The uncompiled text of the
equations is checked the same way, so the packing is tested where numba is not installed.
"""
from __future__ import annotations

import numpy as np
import pytest

import uvsim
from uvsim import kernels
from uvsim.errors import SimulationError
from uvsim.kernels import rk4_equations
from uvsim.kernels.plan import compiled_plan, why_not_compiled
from uvsim.model import Model
from uvsim.vehicle import load_vehicle, vehicle_from_dict

needs_numba = pytest.mark.skipif(not kernels.numba_installed(), reason="numba not installed (uvsim[fast])")

TOL = 1e-10


def _random_overrides(rng, n, k):
    """Parameter sets that differ in every part the kernel packs (inertia, added mass, CG/CB,
    damping, thruster gains and reverse ratios, buoyancy)."""
    return {
        "m": rng.uniform(10, 16, n), "B": rng.uniform(125, 140, n), "z_g": rng.uniform(0.0, 0.02, n),
        "z_b": rng.uniform(-0.05, -0.02, n), "x_b": rng.uniform(-0.01, 0.01, n),
        "I_xx": rng.uniform(0.2, 0.5, n), "I_xz": rng.uniform(-0.02, 0.02, n),
        "X_u": rng.uniform(-5, -0.1, n), "Z_ww": rng.uniform(-120, -40, n),
        "N_rr": rng.uniform(-2, -0.1, n), "K_p": rng.uniform(-1, -0.1, n),
        **{f"thruster_gain_{i + 1}": rng.uniform(0.5, 1.2, n) for i in range(k)},
        **{f"thruster_reverse_{i + 1}": rng.uniform(0.6, 1.0, n) for i in range(k)},
    }


def _coupled_vehicle(rng):
    d = load_vehicle("bluerov2_heavy").to_dict()
    DL = -np.diag([3.0, 4.0, 5.0, 0.4, 0.4, 0.3]) + 0.05 * rng.standard_normal((6, 6))
    DQ = -np.diag([35.0, 43.0, 70.0, 0.4, 0.4, 0.4]) + 0.5 * rng.standard_normal((6, 6))
    d["damping"] = {"type": "coupled", "linear": DL.tolist(), "quadratic": DQ.tolist()}
    return vehicle_from_dict(d, source="test")


def _both(fn):
    out = {}
    for name in ("numpy", "numba"):
        with kernels.use(name):
            out[name] = fn()
    return out


def _close(a, b, tol=TOL):
    a, b = np.asarray(a), np.asarray(b)
    assert np.array_equal(np.isnan(a), np.isnan(b))
    ok = ~np.isnan(a)
    assert np.max(np.abs(a[ok] - b[ok]), initial=0.0) <= tol * max(1.0, np.max(np.abs(b[ok]), initial=0.0))


@needs_numba
@pytest.mark.parametrize("kind", ["pwm", "thrust", "force"])
def test_batched_states_and_accelerations_equal_numpy(kind):
    rng = np.random.default_rng(1)
    veh = load_vehicle("bluerov2_heavy")
    n, t = 7, np.arange(0.0, 6.0, 0.02)
    k = 6 if kind == "force" else 8
    lo, hi = {"pwm": (1250, 1750), "thrust": (-30, 30), "force": (-20, 20)}[kind]
    U = rng.uniform(lo, hi, (n, t.size, k))
    U[:, :, :] = np.repeat(U[:, ::25], 25, axis=1)[:, :t.size]  # steps held 0.5 s: the vehicle moves
    ov = _random_overrides(rng, n, 8)
    if kind == "force":
        ov = {k_: v for k_, v in ov.items() if not k_.startswith("thruster_")}
    nu0 = rng.uniform(-0.3, 0.3, (n, 6))
    r = _both(lambda: uvsim.simulate_batch(veh, t, U, input_kind=kind, overrides=ov, nu0=nu0,
                                           return_acceleration=True))
    assert np.abs(r["numpy"].y[:, -1, 7:]).max() > 0.05  # something happened
    _close(r["numba"].y, r["numpy"].y)
    _close(r["numba"].nu_dot, r["numpy"].nu_dot)


@needs_numba
def test_current_coupled_damping_substeps_and_per_row_grids():
    rng = np.random.default_rng(2)
    veh = _coupled_vehicle(rng)
    n = 5
    T = np.empty((n, 300))
    for j in range(n):  # runs of different lengths, padded by repeating the last time
        L = 200 + 20 * j
        T[j, :L] = np.cumsum(rng.uniform(0.015, 0.025, L))
        T[j, L:] = T[j, L - 1]
    U = rng.uniform(-25, 25, (n, 300, 8))
    ov = {"current_n": rng.uniform(-0.3, 0.3, n), "current_e": rng.uniform(-0.3, 0.3, n),
          "current_d": rng.uniform(-0.1, 0.1, n), "D_L[0,0]": rng.uniform(-3, -0.1, n),
          "D_Q[2,4]": rng.uniform(-1, 1, n)}
    q0 = np.tile([0.95, 0.1, -0.2, 0.2], (n, 1))
    q0 /= np.linalg.norm(q0, axis=1, keepdims=True)
    r = _both(lambda: uvsim.simulate_batch(veh, T, U, input_kind="thrust", overrides=ov, q0=q0, substeps=3,
                                           return_acceleration=True))
    _close(r["numba"].y, r["numpy"].y)
    _close(r["numba"].nu_dot, r["numpy"].nu_dot)


@needs_numba
def test_voltage_dependent_curve_and_fitted_supply():
    d = load_vehicle("bluerov2_heavy").to_dict()
    d["thrusters"] = dict(d["thrusters"], curve={"voltage_table": "t200", "nominal_voltage": 16.0})
    veh = vehicle_from_dict(d, source="test")
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 4.0, 0.02)
    U = np.repeat(rng.uniform(1300, 1700, (3, 8, 8)), 25, axis=1)[:, :t.size]
    V = rng.uniform(13, 17, (3, t.size))
    V[1, 50:90] = np.nan  # not logged there: the fitted supply
    ov = {"supply_voltage": np.array([14.0, 15.0, 16.5])}
    r = _both(lambda: uvsim.simulate_batch(veh, t, U, input_kind="pwm", overrides=ov, voltage=V))
    _close(r["numba"].y, r["numpy"].y)


@needs_numba
def test_shared_input_histories_give_the_same_numbers():
    """A fit's rows share their runs' inputs: the curves are evaluated once per distinct history."""
    rng = np.random.default_rng(4)
    veh = load_vehicle("bluerov2_heavy")
    t = np.arange(0.0, 3.0, 0.02)
    runs = np.repeat(rng.uniform(1300, 1700, (2, 6, 8)), 25, axis=1)[:, :t.size]
    idx = np.array([0, 1, 0, 1, 1, 0])
    ov = _random_overrides(rng, idx.size, 8)
    r = _both(lambda: uvsim.simulate_batch(veh, t, runs[idx], input_kind="pwm", overrides=ov))
    _close(r["numba"].y, r["numpy"].y)


@needs_numba
def test_single_simulate_and_blowup_messages_agree():
    veh = load_vehicle("bluerov2_heavy")
    t = np.arange(0.0, 10.0, 0.05)
    U = np.full((t.size, 6), 0.0)
    U[:, 0] = 1e9  # absurd surge force: blows up
    msgs = {}
    for name in ("numpy", "numba"):
        with kernels.use(name), pytest.raises(SimulationError, match="blew up") as exc:
            uvsim.simulate(veh, t, U, input_kind="force")
        msgs[name] = str(exc.value)
    assert msgs["numba"] == msgs["numpy"]
    # "nan": the blown-up row is NaN from the same check on (the 16th interval), the other
    # row untouched.  Between the blow-up and the check the two may differ in which
    # components of an infinite state are NaN (numpy's bilinear form multiplies zeros by inf)
    UU = np.stack([U, np.zeros_like(U)])
    r = _both(lambda: uvsim.simulate_batch(veh, t, UU, input_kind="force", on_blowup="nan"))
    _close(r["numba"].y[1], r["numpy"].y[1])
    a, b = r["numba"].y[0], r["numpy"].y[0]
    assert np.isnan(a[17:]).all() and np.isnan(b[17:]).all()
    both = np.isfinite(a) & np.isfinite(b)
    assert both[0].all() and np.array_equal(a[both], b[both])


def test_uncompiled_equations_match_the_numpy_path():
    """The text numba compiles, run as plain Python: the packing is checked without numba."""
    rng = np.random.default_rng(5)
    veh = _coupled_vehicle(rng)
    n, t = 3, np.arange(0.0, 0.6, 0.02)
    U = rng.uniform(-20, 20, (n, t.size, 8))
    ov = {k: v for k, v in _random_overrides(rng, n, 8).items() if k[0] not in "XYZKMN"}
    ov.update({"current_n": rng.uniform(-0.3, 0.3, n), "D_Q[5,5]": rng.uniform(-1, -0.1, n)})
    model = Model(veh, ov, n=n, input_kind="thrust")
    plan = compiled_plan(model)
    y0 = model.initial_state(nu=rng.uniform(-0.2, 0.2, (n, 6)))
    with kernels.use("numpy"):
        ref = uvsim.simulate_batch(veh, t, U, input_kind="thrust", y0=y0, model=model, return_acceleration=True)
    from uvsim.kernels.run import rk4_compiled

    acc = np.empty((n, t.size, 6))
    assert plan.parts == rk4_equations.CURRENT | rk4_equations.COUPLED
    Y = rk4_compiled(rk4_equations.advance, plan, model, np.tile(t, (n, 1)), U, y0, 1, "nan", None, None, acc,
                     1e3)
    _close(Y, ref.y)
    _close(acc, ref.nu_dot)


def test_models_the_kernel_cannot_run_say_why_and_run_on_numpy():
    veh = load_vehicle("bluerov2_heavy").with_effects([{"type": "thruster_lag", "time_constant": 0.1}])
    model = Model(veh, input_kind="pwm")
    assert "states" in why_not_compiled(model) and compiled_plan(model) is None
    floor = load_vehicle("bluerov2_heavy").with_effects([{"type": "bottom_effect", "floor_d": 3.0, "damping": -10.0}])
    assert "BottomEffect" in why_not_compiled(Model(floor, input_kind="pwm"))
    two = load_vehicle("bluerov2_heavy").with_effects([{"type": "tether", "stiffness": 1.0},
                                                      {"type": "tether", "tension": 2.0}])
    assert "one tether" in why_not_compiled(Model(two, input_kind="pwm")) and compiled_plan(Model(two)) is None
    sam = Model("sam")
    assert why_not_compiled(sam) is not None
    assert why_not_compiled(Model("bluerov2_heavy", input_kind="pwm")) is None
    t = np.arange(0.0, 1.0, 0.02)
    res = uvsim.simulate(veh, t, np.full((t.size, 8), 1600.0), input_kind="pwm")  # whatever the setting
    assert np.isfinite(res.y).all()


def test_kernel_names_are_checked(monkeypatch):
    with pytest.raises(SimulationError, match="unknown.*did you mean 'numba'"):
        kernels.use("numbaa")
    monkeypatch.setenv("UVSIM_KERNEL", "fortran")
    with pytest.raises(SimulationError, match="UVSIM_KERNEL"):
        kernels.current()
    monkeypatch.setenv("UVSIM_KERNEL", "numpy")
    assert kernels.current() == "numpy" and kernels.compiled_advance() is None
    assert kernels.describe().startswith("numpy (the setting")
    with kernels.use("auto"):
        assert kernels.current() == "auto"
    assert kernels.current() == "numpy"


@needs_numba
@pytest.mark.parametrize("kind,horizontal", [("pwm", False), ("force", False), ("pwm", True)])
def test_effects_with_a_compiled_form_equal_numpy(kind, horizontal):
    """Ballast (a force linear in the down axis), current (through nu_r), the thrust scale
    and asymmetry (held over each interval), named coupled-damping terms and a tether (3-D or horizontal, attached off
    the origin, taut and slack) run compiled, with per-row effect parameters."""
    rng = np.random.default_rng(6 + horizontal)
    veh = load_vehicle("bluerov2_heavy").with_effects([
        {"type": "ballast", "weight": 3.0, "x": 0.05, "z": 0.1, "mass": 0.3},
        {"type": "current", "n": 0.1, "e": -0.05},
        {"type": "thrust_scale", "scale": 0.9},
        {"type": "thrust_asymmetry", "ratio": 0.7},
        {"type": "coupled_damping", "K_vv": -2.0, "M_u": 0.5, "X_qq": 0.3},
        {"type": "tether", "attach_x": -0.2, "attach_z": -0.05, "anchor_n": -1.0, "anchor_e": 0.5,
         "anchor_d": -0.3, "tension": 2.0, "stiffness": 5.0, "slack_length": 1.2, "length": 5.0,
         "lumped_drag": 2.0, "horizontal": horizontal}])
    n, t = 4, np.arange(0.0, 4.0, 0.02)
    k = 8 if kind == "pwm" else 6
    lo, hi = (1300, 1700) if kind == "pwm" else (-20, 20)
    U = np.repeat(rng.uniform(lo, hi, (n, 8, k)), 25, axis=1)[:, :t.size]
    names = uvsim.Model(veh).params
    ov = {nm: rng.uniform(0.6, 1.1, n) for nm in names if nm.endswith(("scale", "ratio"))}
    ov.update({nm: rng.uniform(1.0, 4.0, n) for nm in names if nm.endswith(("weight", "stiffness"))})
    ov.update({nm: rng.uniform(0.5, 2.0, n) for nm in names if nm.endswith("slack_length")})
    ov.update({nm: rng.uniform(-3.0, -1.0, n) for nm in names if nm.endswith("K_vv")})
    assert len(ov) == 6 and why_not_compiled(Model(veh, ov, n=n, input_kind=kind)) is None
    r = _both(lambda: uvsim.simulate_batch(veh, t, U, input_kind=kind, overrides=ov, return_acceleration=True))
    _close(r["numba"].y, r["numpy"].y)
    _close(r["numba"].nu_dot, r["numpy"].nu_dot)


def test_without_numba_everything_runs_on_numpy(monkeypatch):
    """An installation without the extra: 'auto' falls back, 'numba' is refused by name."""
    monkeypatch.setattr(kernels, "numba_installed", lambda: False)
    monkeypatch.delenv("UVSIM_KERNEL", raising=False)
    assert kernels.compiled_advance() is None and "not installed" in kernels.describe()
    with pytest.raises(SimulationError, match="numba is not installed.*uvsim\\[fast\\]"):
        kernels.use("numba")
    t = np.arange(0.0, 1.0, 0.02)
    res = uvsim.simulate("bluerov2_heavy", t, np.full((t.size, 8), 1600.0), input_kind="pwm")
    assert np.isfinite(res.y).all() and res.y[-1, 7] > 0.0


@needs_numba
@pytest.mark.parametrize("kind", ["pwm", "force"])
def test_equation_error_accelerations_equal_numpy(kind):
    """The equation error's accelerations along measured motions (uvsim.fitting.equation_error,
    rk4_equations.accelerations: one parameter row per set, the held forces once for the shared
    inputs) equal the numpy path's (one model row per set and sample) for parameter sets that
    differ in mass, added mass, damping, thruster gains and the effects' parameters."""
    from uvsim.fitting import make_space
    from uvsim.fitting.equation_error import EquationError, measured_motion
    from uvsim.synthetic import generate_runs

    veh = load_vehicle("bluerov2_heavy").with_effects([
        {"type": "ballast", "weight": 3.0, "x": 0.05, "z": 0.1, "mass": 0.3},
        {"type": "current", "n": 0.1, "e": -0.05},
        {"type": "thrust_asymmetry", "ratio": 0.7},
        {"type": "coupled_damping", "K_vv": -2.0, "M_u": 0.5},
        {"type": "tether", "attach_x": -0.2, "attach_z": -0.05, "anchor_n": -1.0, "anchor_e": 0.5,
         "anchor_d": -0.3, "tension": 2.0, "stiffness": 5.0, "slack_length": 1.2, "length": 5.0,
         "lumped_drag": 2.0}])
    runs, _ = generate_runs("bluerov2_heavy", dofs=("surge", "yaw", "heave"), runs_per_dof=1, validation_per_dof=0,
                            duration=6.0, rate=25.0, seed=3, off=3.0, input_kind=kind)
    motions = [measured_motion(r) for r in runs]
    p = Model(veh).params
    free = ["m", "X_udot", "X_uu", "N_r", "tether_stiffness", "tether_slack_length", "tether_attach_x", "ballast_weight",
            "ballast_mass", "K_vv"]
    free = [nm for nm in free if nm in p] + (["thruster_gain_1", "thruster_gain_5"] if kind == "pwm" else [])
    assert len(free) == 10 + 2 * (kind == "pwm")
    space = make_space(p, free)
    rng = np.random.default_rng(8)
    Z = space.z0[None] * rng.uniform(0.8, 1.2, (5, space.p))
    assert why_not_compiled(Model(veh, space.overrides(Z), n=5, input_kind=kind)) is None
    r = _both(lambda: EquationError(veh, motions, space, scale=np.ones(6)).forces(Z))
    for a, b in zip(r["numba"], r["numpy"]):
        assert np.isfinite(b).any()
        _close(a, b)
    # the uncompiled text gives the same numbers (the packing without numba)
    model = Model(veh, space.overrides(Z[:2]), n=2, input_kind=kind)
    plan = compiled_plan(model)
    m0 = motions[0]
    Y, U = m0.y_sub[:20], m0.U_sub[:20]
    tau = plan.held_forces(np.broadcast_to(U, (2,) + U.shape), kind, None)
    acc = np.empty((2, 20, 6))
    rk4_equations.accelerations(Y, tau, plan.TH, plan.parts, acc)
    ref = Model(veh, space.overrides(Z[:2], 20), n=40, input_kind=kind).rhs(0.0, np.tile(Y, (2, 1)),
                                                                             np.tile(U, (2, 1)))[:, 7:13]
    _close(acc.reshape(40, 6), ref)


def _table_inputs(curve):
    rng = np.random.default_rng(46)
    pwm = rng.uniform(curve.pwm_min, curve.pwm_max, (4000, 8))
    pwm[::5] = curve._xp[rng.integers(0, curve._xp.size, pwm[::5].shape)]   # exactly on knots
    pwm[0, :2] = curve.pwm_min, curve.pwm_max
    pwm[1, :2] = curve.deadband                                             # the deadband's edges
    return pwm


def _voltage_sheet(volts):
    from uvsim.vehicle import load_vehicle

    d = load_vehicle("bluerov2_heavy").to_dict()
    d["thrusters"]["curve"] = {"voltage_table": "t200", "nominal_voltage": 16.0}
    return vehicle_from_dict(d, source="test").actuators.curves[0].at_voltage(volts)


@needs_numba
@pytest.mark.parametrize("volts", [None, 18.5])
def test_the_compiled_thrust_table_equals_numpy_to_the_bit(volts):
    from uvsim.thrust_curves import shipped_curve

    curve = shipped_curve("t200_16v") if volts is None else _voltage_sheet(volts)
    assert curve._step is not None                      # the uniform-knot path
    pwm = _table_inputs(curve)
    got = _both(lambda: curve.thrust(pwm))
    assert got["numba"].shape == pwm.shape and np.array_equal(got["numba"], got["numpy"])
    assert np.array_equal(_both(lambda: curve.thrust(pwm[:, 3].copy()))["numba"], got["numpy"][:, 3])  # 1-D
    with kernels.use("numba"):
        with pytest.raises(SimulationError):           # the range check comes first, as before
            curve.thrust(np.where(pwm == pwm.max(), np.nan, pwm))


def test_the_uncompiled_table_lookup_equals_numpy():
    from uvsim.kernels.table_lookup import uniform_table
    from uvsim.thrust_curves import shipped_curve

    curve = shipped_curve("t200_16v")
    pwm = _table_inputs(curve)[:50].ravel()
    out = np.empty(pwm.size)
    uniform_table(pwm, float(curve._xp[0]), curve._step, curve._fp, out)   # the text, run by Python
    with kernels.use("numpy"):
        assert np.array_equal(out, curve.thrust(pwm))


def _voltage_curve():
    from uvsim.vehicle import load_vehicle

    d = load_vehicle("bluerov2_heavy").to_dict()
    d["thrusters"]["curve"] = {"voltage_table": "t200", "nominal_voltage": 16.0}
    return vehicle_from_dict(d, source="test").actuators.curves[0]


def _voltage_inputs(curve):
    rng = np.random.default_rng(47)
    pwm = rng.uniform(curve.pwm_min, curve.pwm_max, (3000, 8))
    pwm[::5] = curve.table_pwm[rng.integers(0, curve.table_pwm.size, pwm[::5].shape)]  # on knots
    volts = rng.uniform(curve.voltages[0], curve.voltages[-1], (3000, 1))
    volts[::7] = curve.voltages[rng.integers(0, curve.voltages.size, volts[::7].shape)]   # on sheets
    volts[0], volts[1], volts[2] = curve.voltages[0], curve.voltages[-1], np.nan          # ends; nominal
    return pwm, volts


@needs_numba
def test_the_compiled_voltage_table_equals_numpy_to_the_bit():
    curve = _voltage_curve()
    pwm, volts = _voltage_inputs(curve)
    got = _both(lambda: curve.thrust(pwm, volts))
    assert got["numba"].shape == pwm.shape and np.array_equal(got["numba"], got["numpy"])
    assert np.array_equal(_both(lambda: curve.thrust(pwm))["numba"], _both(lambda: curve.thrust(pwm))["numpy"])
    with kernels.use("numba"):
        with pytest.raises(SimulationError, match="supply voltage"):  # the range checks come first, as before
            curve.thrust(pwm, volts + 100.0)


def test_the_uncompiled_voltage_table_equals_numpy():
    from uvsim.kernels.table_lookup import voltage_table

    curve = _voltage_curve()
    pwm, volts = _voltage_inputs(curve)
    pwm, volts = pwm[:40], np.where(np.isnan(volts[:40]), curve.nominal_voltage, volts[:40])
    v = np.broadcast_to(volts, pwm.shape)
    out = np.empty(pwm.size)
    voltage_table(pwm.ravel(), np.ascontiguousarray(v).ravel(), float(curve.table_pwm[0]), curve._step,
                  curve.voltages, curve.table_thrust, out)                    # the text, run by Python
    with kernels.use("numpy"):
        assert np.array_equal(out.reshape(pwm.shape), curve.thrust(pwm, volts))


def _lag_inputs():
    """Predicted angles shaped like a windowed fit's (sets, windows, L, 3): smooth motion with wraps
    through +-pi, jumps of exactly pi and beyond, a constant stretch."""
    rng = np.random.default_rng(48)
    t = np.arange(60) * 0.02
    base = rng.uniform(-np.pi, np.pi, (5, 4, 1, 3)) + rng.normal(0, 3.0, (5, 4, 1, 3)) * t[:, None]
    e = (base + np.pi) % (2 * np.pi) - np.pi                    # wrapped into (-pi, pi]
    e[0, 0, :10, 0], e[0, 0, 10:, 0] = 0.0, np.pi               # a jump of exactly +pi (kept: numpy.unwrap)
    e[0, 1, :10, 0], e[0, 1, 10:, 0] = 0.0, -np.pi              # and of exactly -pi
    e[1, 2, 30:, 1] -= 4.0                                      # beyond pi
    e[2, 1, :, 2] = 0.5                                         # constant
    start = rng.uniform(-np.pi, np.pi, (5, 4, 3))
    start[3, 0, 1] = np.nan                                     # no logged start: the prediction's own
    return t, e, start


@needs_numba
def test_the_compiled_attitude_lag_equals_unwrap_and_lfilter_to_the_bit():
    from uvsim.measurements import RunMeasurements

    t, e, start = _lag_inputs()
    m = object.__new__(RunMeasurements)  # _lag_segments reads the lag only
    m.attitude_lag = 0.15
    got = _both(lambda: RunMeasurements._lag_segments(m, e, start, t))
    assert got["numba"].shape == e.shape and np.array_equal(got["numba"], got["numpy"])
    e2 = e.copy()
    e2[4, 3, 7, 0] = np.nan                                     # a diverged sample: numpy's path
    got = _both(lambda: RunMeasurements._lag_segments(m, e2, start, t))
    assert np.array_equal(got["numba"], got["numpy"], equal_nan=True)


def test_the_uncompiled_attitude_lag_text_equals_numpy():
    from uvsim.estimation.lag import first_order_lag
    from uvsim.kernels.attitude_lag import unwrapped_lag
    from uvsim.kinematics import unwrap_angles

    t, e, start = _lag_inputs()
    flat = e.reshape(-1, t.size, 3)[:6]
    y0 = np.nan_to_num(start.reshape(-1, 3)[:6])
    a = float(np.exp(-(t[1] - t[0]) / 0.15))
    out = np.empty_like(flat)
    unwrapped_lag(flat, y0, 1.0 - a, a, out)                    # the text, run by Python
    assert np.array_equal(out, first_order_lag(t, unwrap_angles(flat, axis=-2), 0.15, y0))


def _window_sum_case(seed, m, p, nw):
    rng = np.random.default_rng(seed)
    J = rng.normal(size=(m, p)) * 10.0 ** rng.integers(-6, 6, size=(m, 1))  # magnitudes that round
    r = rng.normal(size=m)
    cluster = rng.integers(0, nw, size=m)
    if nw > 2:
        cluster[cluster == 1] = 0  # a window with no entries
    return J, r, cluster


@needs_numba
@pytest.mark.parametrize("m,p,nw", [(500, 7, 5), (3000, 35, 18), (1, 1, 1), (0, 3, 2)])
def test_the_compiled_window_sums_equal_bincount_to_the_bit(m, p, nw):
    """The window scores' sums (uvsim.kernels.window_sums) against the numpy form
    (linearization._window_sums: bincount per column), to the bit."""
    from uvsim.fitting.linearization import _scores, _window_sums

    J, r, cluster = _window_sum_case(m + p, m, p, nw)
    ref = _window_sums(J * r[:, None], cluster, nw)
    with kernels.use("numba"):
        got = _scores(J, r, cluster, nw)
    np.testing.assert_array_equal(got, ref)
    with kernels.use("numpy"):
        np.testing.assert_array_equal(_scores(J, r, cluster, nw), ref)


def test_the_uncompiled_window_sums_text_equals_bincount():
    from uvsim.fitting.linearization import _window_sums
    from uvsim.kernels.window_sums import window_sums

    J, r, cluster = _window_sum_case(3, 400, 6, 7)
    out = np.zeros((7, 6))
    window_sums(J, r, cluster, out)
    np.testing.assert_array_equal(out, _window_sums(J * r[:, None], cluster, 7))
