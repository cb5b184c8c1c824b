"""Tests of uvsim.thrust_curves and uvsim.thrusters: tabulated/linear thrust curves, their
inverse and loading."""
from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

from uvsim.errors import SimulationError, VehicleError
from uvsim.thrusters import (
    DATA_DIR,
    KGF_TO_N,
    LinearThrustCurve,
    TabulatedThrustCurve,
    ThrustCurve,
    ThrustCurveSet,
    available_tables,
    load_thrust_curve,
)

# A small table with a deadband, asymmetric branches and a flat stretch (1800-1850).
PWM = [1100.0, 1300.0, 1450.0, 1480.0, 1520.0, 1550.0, 1700.0, 1800.0, 1850.0, 1900.0]
THR = [-30.0, -12.0, -1.0, 0.0, 0.0, 1.0, 15.0, 30.0, 30.0, 40.0]


@pytest.fixture(scope="module")
def t200():
    return load_thrust_curve("t200_16v")


@pytest.fixture()
def small():
    return TabulatedThrustCurve(PWM, THR, name="small")


def _raw_t200_table():
    """The shipped CSV read without uvsim (numpy only), to test against."""
    a = np.loadtxt(DATA_DIR / "t200_16v.csv", delimiter=",", skiprows=1)
    return a[:, 0], a[:, 1]


# ----------------------------------------------------------------------- shipped data
def test_shipped_t200_table_matches_published_spot_values():
    """Spot values of Blue Robotics' 16 V sheet (kgf) converted with g = 9.80665 (SOURCE.md)."""
    pwm, thr = _raw_t200_table()
    assert pwm.size == 201 and pwm[0] == 1100 and pwm[-1] == 1900
    spot = {1100: -4.07, 1300: -1.44, 1468: -0.04, 1500: 0.0, 1532: 0.04, 1700: 1.82, 1900: 5.25}
    for p, kgf in spot.items():
        assert thr[pwm == p][0] == pytest.approx(kgf * KGF_TO_N, abs=1e-9)


def test_t200_deadband_and_asymmetric_branches(t200):
    assert "t200_16v" in available_tables()
    assert t200.deadband == (1472.0, 1528.0)
    assert t200.neutral == 1500.0
    assert t200.max_forward == pytest.approx(5.25 * KGF_TO_N)
    assert t200.max_reverse == pytest.approx(-4.07 * KGF_TO_N)
    # Reverse maximum is smaller in magnitude than forward (data: about 78 %).
    assert 0.7 < -t200.max_reverse / t200.max_forward < 0.85
    # Same distance from neutral gives less thrust in reverse than forward.
    d = np.array([50.0, 150.0, 250.0, 400.0])
    assert np.all(-t200.thrust(1500 - d) < t200.thrust(1500 + d))


# ----------------------------------------------------------------------- evaluation
def test_interpolation_hits_table_points_exactly(t200, small):
    pwm, thr = _raw_t200_table()
    np.testing.assert_array_equal(t200.thrust(pwm), thr)
    np.testing.assert_array_equal(small.thrust(PWM), THR)


def test_uniform_grid_path_equals_np_interp(t200):
    """Large arrays on the uniform 4 us T200 grid take a search-free path; it must agree
    with np.interp (the reference) and be exact at the table points for small arrays too."""
    pwm, thr = _raw_t200_table()
    x = np.random.default_rng(3).uniform(1100, 1900, size=(500, 8))
    np.testing.assert_allclose(t200.thrust(x), np.interp(x, pwm, thr), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(t200.thrust(pwm[::37]), thr[::37])  # small array: np.interp path
    assert t200.thrust(np.full(100, 1900.0))[0] == thr[-1]


def test_interpolation_between_points_is_linear(small):
    assert small.thrust(1200.0) == pytest.approx(-21.0)  # midway -30 .. -12
    assert small.thrust(1625.0) == pytest.approx(8.0)    # midway 1 .. 15
    assert small.thrust(1825.0) == 30.0                  # flat stretch


def test_deadband_gives_exactly_zero(t200, small):
    x = np.linspace(1472.0, 1528.0, 1001)
    out = t200.thrust(x)
    assert np.all(out == 0.0)
    assert not np.any(np.signbit(out))  # no -0.0
    assert np.all(small.thrust(np.linspace(1480, 1520, 101)) == 0.0)
    # Just outside the deadband the thrust is non-zero with the branch's sign.
    assert t200.thrust(1471.0) < 0 < t200.thrust(1529.0)


def test_explicit_deadband_inserts_zero_knots():
    c = TabulatedThrustCurve([1100, 1400, 1600, 1900], [-40, -5, 5, 50], deadband=(1450, 1550))
    assert c.thrust(1450.0) == 0.0 and c.thrust(1500.0) == 0.0 and c.thrust(1550.0) == 0.0
    assert c.thrust(1425.0) == pytest.approx(-2.5)  # linear from (1400, -5) to (1450, 0)
    assert c.thrust(1575.0) == pytest.approx(2.5)
    assert c.neutral == 1500.0


def test_shape_broadcasting(t200):
    rng = np.random.default_rng(0)
    x = rng.uniform(1100, 1900, size=(7, 5, 8))
    out = t200.thrust(x)
    assert out.shape == x.shape
    np.testing.assert_array_equal(out.ravel(), t200.thrust(x.ravel()))
    assert np.ndim(t200.thrust(1600.0)) == 0
    assert t200.thrust(np.empty((0, 8))).shape == (0, 8)
    assert t200.pwm(out).shape == x.shape


@pytest.mark.parametrize("bad", [1099.9, 1900.5, 2000.0, 900.0, np.nan, np.inf])
def test_out_of_range_pwm_raises_naming_value_and_range(t200, bad):
    x = np.full((3, 8), 1500.0)
    x[1, 4] = bad
    with pytest.raises(SimulationError) as exc:
        t200.thrust(x)
    msg = str(exc.value)
    assert "t200_16v" in msg and "[1100, 1900]" in msg and "(1, 4)" in msg
    assert f"{bad:g}" in msg


def test_inverse_out_of_range_raises(t200):
    with pytest.raises(SimulationError, match="thrust 60"):
        t200.pwm([0.0, 60.0])
    with pytest.raises(SimulationError, match="thrust -45"):
        t200.pwm(-45.0)


# ----------------------------------------------------------------------- inverse
def test_inverse_round_trip_thrust(t200, small):
    for c in (t200, small):
        T = np.linspace(c.max_reverse, c.max_forward, 2001)
        p = c.pwm(T)
        assert np.all((p >= c.pwm_min) & (p <= c.pwm_max))
        np.testing.assert_allclose(c.thrust(p), T, rtol=0, atol=1e-9)


def test_inverse_round_trip_pwm_outside_deadband(t200):
    # The T200 table is strictly increasing outside the deadband, so pwm -> thrust -> pwm
    # returns the command.
    p = np.concatenate([np.linspace(1100, 1471.5, 300), np.linspace(1528.5, 1900, 300)])
    np.testing.assert_allclose(t200.pwm(t200.thrust(p)), p, rtol=0, atol=1e-6)


def test_inverse_zero_maps_to_neutral_and_flat_stretch_to_nearest(t200, small):
    assert t200.pwm(0.0) == 1500.0
    assert small.pwm(0.0) == 1500.0
    # 30 N is produced anywhere in 1800..1850; the inverse picks the command nearest neutral.
    assert small.pwm(30.0) == 1800.0
    c = TabulatedThrustCurve([1100, 1450, 1500, 1900], [-5, 0, 0, 5], neutral=1460.0)
    assert c.pwm(0.0) == 1460.0


# ----------------------------------------------------------------------- validation
@pytest.mark.parametrize(
    "pwm, thrust, kw, match",
    [
        ([1100, 1500, 1500, 1900], [-1, 0, 0, 1], {}, "strictly increasing"),
        ([1100, 1400, 1300, 1900], [-1, 0, 0, 1], {}, "strictly increasing"),
        ([1100, 1400, 1500, 1900], [-1, 0, -0.5, 1], {}, "non-decreasing"),
        ([1100, 1500, 1900], [-1, np.nan, 1], {}, "finite"),
        ([1100, np.inf, 1900], [-1, 0, 1], {}, "finite"),
        ([1100, 1500, 1900], [-1, 0], {}, "same length"),
        ([1500], [0], {}, "at least 2"),
        ([[1100, 1900]], [[0, 1]], {}, "1-D"),
        ([1100, 1400, 1600, 1900], [-2, -1, 1, 2], {}, "deadband cannot be inferred"),
        ([1100, 1400, 1600, 1900], [-2, 0, 0, 2], {"deadband": (1550, 1450)}, "lo <= hi"),
        ([1100, 1400, 1600, 1900], [-2, 0, 0, 2], {"deadband": (1000, 1600)}, "inside the table"),
        ([1100, 1400, 1600, 1900], [-2, -1, 1, 2], {"deadband": (1300, 1700)}, "must be 0 inside"),
        ([1100, 1400, 1600, 1900], [1, 2, 2, 3], {"deadband": (1100, 1100)}, "must be 0 inside"),
        ([1100, 1400, 1600, 1900], [0, 1, 2, 3], {"deadband": (1100, 1100)}, None),
        ([1100, 1400, 1600, 1900], [-3, -2, -1, 0], {}, None),
        ([1100, 1400, 1600, 1900], [-2, 0, 0, 2], {"deadband": (1400, 1600), "neutral": 1700}, "neutral"),
    ],
)
def test_table_validation(pwm, thrust, kw, match):
    if match is None:  # valid edge cases: forward-only / reverse-only tables
        c = TabulatedThrustCurve(pwm, thrust, **kw)
        assert c.thrust(np.array(pwm, float)).tolist() == [float(t) for t in thrust]
        return
    with pytest.raises(VehicleError, match=match):
        TabulatedThrustCurve(pwm, thrust, source="vehicles/x.yaml: thrusters[2].curve", **kw)


def test_sign_rules_of_branches():
    with pytest.raises(VehicleError, match="<= 0 below the deadband"):
        TabulatedThrustCurve([1100, 1300, 1600, 1900], [0.5, 0.6, 1, 2], deadband=(1400, 1500))
    with pytest.raises(VehicleError, match=">= 0 above the deadband"):
        TabulatedThrustCurve([1100, 1300, 1600, 1900], [-3, -2, -1.5, -1], deadband=(1400, 1500))
    with pytest.raises(VehicleError, match="must be 0 inside"):
        # monotone but the zero crossing is not where the deadband says
        TabulatedThrustCurve([1100, 1400, 1600, 1900], [-2, -1, 0, 2], deadband=(1400, 1600))


def test_validation_error_names_the_field():
    with pytest.raises(VehicleError, match=r"thrusters\[2\]\.curve"):
        load_thrust_curve({"pwm": [1100, 1900], "thrust": [1, -1]}, field="thrusters[2].curve")


# ----------------------------------------------------------------------- loading
def test_load_forms_agree(t200, tmp_path):
    pwm, thr = _raw_t200_table()
    assert load_thrust_curve("t200_16v") is t200  # shared read-only instance
    assert load_thrust_curve({"table": "t200_16v"}) == t200
    inline = load_thrust_curve({"pwm": pwm.tolist(), "thrust": thr.tolist()})
    assert inline == t200
    f = tmp_path / "curve.csv"
    f.write_text("# my own copy\npwm_us,thrust_N\n" + "".join(f"{p},{t}\n" for p, t in zip(pwm, thr)))
    from_file = load_thrust_curve({"csv": "curve.csv"}, base_dir=tmp_path)
    assert from_file == t200
    assert load_thrust_curve(t200.to_mapping()) == t200
    assert load_thrust_curve(inline.to_mapping()) == t200
    # A deadband override inside the zero-thrust stretch keeps the data and the function.
    narrow = load_thrust_curve({"table": "t200_16v", "deadband": [1480, 1520]})
    assert narrow.deadband == (1480.0, 1520.0) and narrow != t200
    np.testing.assert_array_equal(narrow.thrust(pwm), thr)
    # One that would declare measured non-zero thrust to be zero is refused, not applied.
    with pytest.raises(VehicleError, match="must be 0 inside the deadband"):
        load_thrust_curve({"table": "t200_16v", "deadband": [1468, 1532]})


@pytest.mark.parametrize(
    "spec, match",
    [
        ("t300_16v", "unknown thrust curve 't300_16v'"),
        ({"table": "nope"}, r"curve\.table: unknown thrust curve"),
        ({"table": "t200_16v", "scale": 2}, r"unknown key 'scale'; expected"),
        ({"pwm": [1100, 1900]}, "exactly one of"),
        ({"table": "t200_16v", "pwm": [1, 2], "thrust": [0, 1]}, "exactly one of"),
        ({"type": "quadratic"}, "unknown thrust curve type"),
        ({"type": "linear", "forward_gain": 0.1}, "reverse_gain"),
        ({"type": "linear", "forward_gain": 0.1, "reverse_gain": -0.1}, "reverse_gain must be > 0"),
        ({"table": "t200_16v", "deadband": [1480]}, "two numbers"),
        ({"csv": "does_not_exist.csv"}, "does not exist"),
        (42, "expected a shipped curve name"),
    ],
)
def test_bad_specs_raise_vehicle_error(spec, match):
    with pytest.raises(VehicleError, match=match):
        load_thrust_curve(spec)


def test_csv_missing_column_and_bad_value(tmp_path):
    f = tmp_path / "c.csv"
    f.write_text("pwm,thrust_N\n1100,-1\n1900,1\n")
    with pytest.raises(VehicleError, match=r"missing column.*pwm_us"):
        TabulatedThrustCurve.from_csv(f)
    f.write_text("pwm_us,thrust_N\n1100,-1\n1500,x\n1900,1\n")
    with pytest.raises(VehicleError, match=r"thrust_N row 2 is 'x'"):
        TabulatedThrustCurve.from_csv(f)


# ----------------------------------------------------------------------- linear
def test_linear_curve_asymmetric_with_deadband():
    c = LinearThrustCurve(0.1, 0.08, neutral=1500, deadband=(1475, 1525))
    assert c.thrust(1500.0) == 0.0 and c.thrust(1475.0) == 0.0 and c.thrust(1525.0) == 0.0
    assert c.thrust(1625.0) == pytest.approx(10.0)    # 0.1 N/us * 100 us past the edge
    assert c.thrust(1375.0) == pytest.approx(-8.0)
    assert c.max_forward == pytest.approx(37.5) and c.max_reverse == pytest.approx(-30.0)
    T = np.linspace(-30, 37.5, 101)
    np.testing.assert_allclose(c.thrust(c.pwm(T)), T, atol=1e-12)
    assert c.pwm(0.0) == 1500.0
    with pytest.raises(SimulationError):
        c.thrust([1500, 1950])
    z = LinearThrustCurve(0.1, 0.1)  # no deadband: gain * (pwm - neutral)
    assert z.thrust(1600.0) == pytest.approx(10.0) and z.thrust(1400.0) == pytest.approx(-10.0)
    assert load_thrust_curve(c.to_mapping()) == c


# ----------------------------------------------------------------------- sets / pickling
def test_curve_set_per_thruster(t200):
    lin = LinearThrustCurve(0.1, 0.08)
    s = ThrustCurveSet([t200, lin, t200, load_thrust_curve("t200_16v")])
    x = np.random.default_rng(1).uniform(1100, 1900, size=(6, 3, 4))
    out = s.thrust(x)
    for j, c in enumerate(s.curves):
        np.testing.assert_array_equal(out[..., j], c.thrust(x[..., j]))
    np.testing.assert_allclose(s.thrust(s.pwm(out)), out, atol=1e-9)
    with pytest.raises(SimulationError, match="length 4"):
        s.thrust(np.full((2, 3), 1500.0))


def test_curves_pickle(t200):
    x1 = np.array([1100.0, 1500.0, 1900.0])
    x2 = np.array([[1100.0, 1900.0], [1500.0, 1700.0]])
    for c, x in ((t200, x1), (LinearThrustCurve(0.1, 0.05), x1), (ThrustCurveSet([t200, t200]), x2)):
        c2 = pickle.loads(pickle.dumps(c))
        np.testing.assert_array_equal(c2.thrust(x), c.thrust(x))
    assert isinstance(t200, ThrustCurve)


def test_code_reads_no_shared_paths():
    for name in ("thrusters.py", "thrust_curves.py"):
        text = (Path(__file__).resolve().parents[1] / "src" / "uvsim" / name).read_text()
        assert "/work/shared" not in text and "../shared" not in text


def test_curve_names_stay_importable_from_uvsim_thrusters():
    """The curve classes live in uvsim.thrust_curves; uvsim.thrusters re-exports the same
    objects (so old imports and pickles naming uvsim.thrusters keep working)."""
    import uvsim.thrust_curves as tc
    import uvsim.thrusters as th

    for name in ("DATA_DIR", "DEFAULT_CURVE", "KGF_TO_N", "LinearThrustCurve", "TabulatedThrustCurve",
                 "ThrustCurve", "available_tables", "shipped_curve"):
        assert getattr(th, name) is getattr(tc, name), name
    assert th.shipped_curve("t200_16v") is tc.shipped_curve("t200_16v")
    old = pickle.dumps(tc.LinearThrustCurve(0.1, 0.05), protocol=0).replace(b"uvsim.thrust_curves", b"uvsim.thrusters")
    assert b"uvsim.thrusters" in old and pickle.loads(old) == tc.LinearThrustCurve(0.1, 0.05)
