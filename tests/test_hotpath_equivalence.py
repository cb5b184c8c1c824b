"""The optimized hot paths of the windowed fit give the values of straightforward
reference code: the down axis (third row of R), the accelerometer and DVL models, the
windowed gather of a run's samples, and the normal-equation pieces of the solver."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from uvsim.fitting.objective import WindowedProblem
from uvsim.kinematics import quat_to_euler, cross_components, down_axis_components, quat_down_axis, quat_to_rotation
from uvsim.measurements import Group, RunMeasurements, specific_force
from uvsim.signals import GROUPS

SHAPES = [(1,), (7,), (3, 50), (2, 4, 25)]  # one sample, a run, a batch of runs, batches of batches


def _quats(rng, shape):
    q = rng.normal(size=shape + (4,))
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def _states(rng, shape):
    y = rng.normal(size=shape + (15,))  # 13 vehicle states and 2 term states
    y[..., 3:7] = _quats(rng, shape)
    return y


# ---------------------------------------------------------------- references
def _ref_specific_force(y, nu_dot, r_imu, g):
    """The accelerometer model with a full rotation matrix and np.cross."""
    v, w = y[..., 7:10], y[..., 10:13]
    R = quat_to_rotation(y[..., 3:7])
    f = nu_dot[..., :3] + np.cross(w, v) - g * R[..., 2, :]
    if r_imu is not None and np.any(r_imu):
        r = np.broadcast_to(np.asarray(r_imu, float), v.shape)
        f = f + np.cross(nu_dot[..., 3:], r) + np.cross(w, np.cross(w, r))
    return f


def _meas(groups, sensors, n, g=9.81):
    """A RunMeasurements with the given groups (all channels logged) and sensor positions."""
    grp = {}
    for name in groups:
        k = len(GROUPS[name])
        grp[name] = Group(name, np.zeros((n, k)), np.ones(k, bool), np.ones((n, k), bool), np.ones(k), [None] * k,
                          "quaternion" if name == "attitude" else "")
    return RunMeasurements("r", np.arange(n) * 0.01, grp, sensors, g)


# ---------------------------------------------------------------- kinematics
@pytest.mark.parametrize("shape", SHAPES)
def test_down_axis_is_the_third_row_of_the_rotation_matrix(shape):
    rng = np.random.default_rng(1)
    q = _quats(rng, shape)
    k = quat_down_axis(q)
    assert k.shape == shape + (3,)
    np.testing.assert_array_equal(k, quat_to_rotation(q)[..., 2, :])
    # also from a strided view (the quaternion inside a state array) and from components
    y = _states(rng, shape)
    np.testing.assert_array_equal(quat_down_axis(y[..., 3:7]), quat_to_rotation(y[..., 3:7])[..., 2, :])
    comps = down_axis_components(*np.moveaxis(y[..., 3:7], -1, 0))
    np.testing.assert_array_equal(np.stack(comps, -1), quat_to_rotation(y[..., 3:7])[..., 2, :])
    # it is R^T e_3: unit length, and R k = e_3
    np.testing.assert_allclose(np.linalg.norm(k, axis=-1), 1.0, rtol=1e-14)
    np.testing.assert_allclose(np.einsum("...ij,...j->...i", quat_to_rotation(q), k),
                               np.broadcast_to([0.0, 0.0, 1.0], k.shape), atol=1e-14)


def test_down_axis_of_a_single_quaternion():
    q = np.array([np.cos(0.3), np.sin(0.3), 0.0, 0.0])  # roll 0.6 rad
    np.testing.assert_allclose(quat_down_axis(q), [0.0, np.sin(0.6), np.cos(0.6)], atol=1e-15)
    np.testing.assert_array_equal(quat_down_axis(q), quat_to_rotation(q)[2])


@pytest.mark.parametrize("shape", SHAPES)
def test_cross_components_equal_np_cross(shape):
    rng = np.random.default_rng(2)
    a, b = rng.normal(size=shape + (3,)), rng.normal(size=shape + (3,))
    c = cross_components(np.moveaxis(a, -1, 0), np.moveaxis(b, -1, 0))
    np.testing.assert_array_equal(np.stack(c, -1), np.cross(a, b))
    r = rng.normal(size=3)  # a constant vector, as a sensor position
    c = cross_components(np.moveaxis(a, -1, 0), r)
    np.testing.assert_array_equal(np.stack(c, -1), np.cross(a, np.broadcast_to(r, a.shape)))


# ---------------------------------------------------------------- measurement models
@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("r_imu", [None, np.zeros(3), np.array([0.021513, -0.027687, -0.009385]),
                                   np.array([0.3, 0.0, -0.1])])
def test_specific_force_equals_the_reference(shape, r_imu):
    rng = np.random.default_rng(3)
    y = _states(rng, shape)
    nu_dot = rng.normal(size=shape + (6,))
    f = specific_force(y, nu_dot, r_imu, 9.81)
    assert f.shape == shape + (3,)
    np.testing.assert_array_equal(f, _ref_specific_force(y, nu_dot, r_imu, 9.81))


@pytest.mark.parametrize("shape", [(1, 13), (1, 1, 13), (5, 40, 13), (2, 3, 40, 13)])
def test_predict_equals_the_reference(shape):
    """predict on (..., n, n_y) states: depth, attitude, DVL velocity, gyro and accelerometer
    against full-matrix / np.cross formulas (bit for bit)."""
    rng = np.random.default_rng(4)
    *lead, n, _ = shape
    y = _states(rng, tuple(lead) + (n,))
    nu_dot = rng.normal(size=tuple(lead) + (n, 6))
    sensors = {"pressure": np.array([-0.15, 0.02, 0.07]), "dvl": np.array([0.1, -0.05, 0.2]),
               "imu": np.array([0.021513, -0.027687, -0.009385])}
    m = _meas(["position", "depth", "attitude", "velocity", "rates", "acceleration"], sensors, n, g=9.80665)
    gb = rng.normal(size=tuple(lead) + (3,))
    pred = m.predict(y, nu_dot, gyro_bias=gb)
    R = quat_to_rotation(y[..., 3:7])
    w = y[..., 10:13]
    np.testing.assert_array_equal(pred["position"], y[..., 0:3])
    np.testing.assert_array_equal(pred["depth"][..., 0],
                                  y[..., 2] + np.einsum("...j,j->...", R[..., 2, :], sensors["pressure"]))
    np.testing.assert_array_equal(pred["attitude"], quat_to_euler(y[..., 3:7]))  # Euler angles in every mode
    np.testing.assert_array_equal(pred["velocity"],
                                  y[..., 7:10] + np.cross(w, np.broadcast_to(sensors["dvl"], w.shape)))
    np.testing.assert_array_equal(pred["rates"], w + gb[..., None, :])
    np.testing.assert_array_equal(pred["acceleration"], _ref_specific_force(y, nu_dot, sensors["imu"], 9.80665))
    for g, v in pred.items():
        assert v.shape == tuple(lead) + (n, len(GROUPS[g])), g


def test_predict_with_sensors_at_the_origin():
    rng = np.random.default_rng(5)
    y = _states(rng, (3, 20))
    nu_dot = rng.normal(size=(3, 20, 6))
    m = _meas(["depth", "velocity", "acceleration"], {"imu": np.zeros(3)}, 20)
    pred = m.predict(y, nu_dot)
    np.testing.assert_array_equal(pred["depth"][..., 0], y[..., 2])
    np.testing.assert_array_equal(pred["velocity"], y[..., 7:10])
    np.testing.assert_array_equal(pred["acceleration"], _ref_specific_force(y, nu_dot, None, 9.81))


# ---------------------------------------------------------------- windowed gather
@pytest.mark.parametrize("P", [1, 4])
def test_run_prediction_equals_two_fancy_indices(P):
    rng = np.random.default_rng(6)
    W, L = 5, 9
    own_win = [np.repeat(np.arange(3), 8)[:20], np.repeat(np.arange(3, 5), 8)]
    own_pos = [np.tile(np.arange(8), 3)[:20], np.tile(np.arange(8), 2)]
    prob = SimpleNamespace(lay=SimpleNamespace(own_win=own_win, own_pos=own_pos))
    Y, A = rng.normal(size=(P, W, L, 15)), rng.normal(size=(P, W, L, 6))
    for r in range(2):
        y, a = WindowedProblem.run_prediction(prob, Y, A, r)
        np.testing.assert_array_equal(y, Y[:, own_win[r], own_pos[r]])
        np.testing.assert_array_equal(a, A[:, own_win[r], own_pos[r]])
        y, a = WindowedProblem.run_prediction(prob, Y, None, r)
        assert a is None and y.shape == (P, own_win[r].size, 15)


# ---------------------------------------------------------------- normal equations
def _ref_normal_pieces(r, Jz, Jn, cluster, nw, scores):
    """The solver's former code (np.add.at for the window sums)."""
    sse = np.zeros(nw)
    np.add.at(sse, cluster, r * r)
    D, B, gn = Jn.T @ Jn, Jn.T @ Jz, Jn.T @ r
    sc = None
    if scores:
        Jt = Jz - Jn @ np.linalg.solve(D, B) if Jn.shape[1] else Jz
        sc = np.zeros((nw, Jz.shape[1]))
        np.add.at(sc, cluster, Jt * r[:, None])
    return dict(rss=float(r @ r), n=r.size, A=Jz.T @ Jz, gz=Jz.T @ r, D=D, B=B, gn=gn, window_sse=sse, scores=sc)


#: The products with the nuisance Jacobian go block by block (linearization.structured_normal_pieces):
#: the same sums in another order, equal to round-off (the window sums and Jz's products stay bit for bit)
SPARSE_RTOL = 1e-12


def _assert_pieces_match(out, ref, rtol=SPARSE_RTOL):
    for name, v in ref.items():
        got = getattr(out, name)
        if v is None:
            assert got is None, name
            continue
        v, got = np.asarray(v, float), np.asarray(got, float)
        assert got.shape == v.shape, name
        scale = max(np.abs(v).max(initial=0.0), 1e-300)
        err = np.abs(got - v).max(initial=0.0) / scale
        assert err <= rtol, f"{name}: relative difference {err:.2e}"


def _random_run_jacobian(rng, nw, k, nb, per_window, p, empty_window=None):
    """A RunJacobian shaped like the solver's (channel-major measurement rows), with Jz, r, clusters."""
    from uvsim.fitting.linearization import RunJacobian

    own = np.tile(np.repeat(np.arange(nw), per_window), 3)
    if empty_window is not None:
        own = own[own != empty_window]
    m_meas = own.size
    dm = rng.normal(size=(m_meas, k))
    if k > 1:
        dm[:, 1] = 0.0  # a component read by nothing
    db = rng.normal(size=(m_meas, nb)) * (rng.random((m_meas, 1)) < 0.5)
    J = RunJacobian(nw, own, dm, rng.normal(size=(nw - 1, k, k)), rng.normal(size=(nw - 1, k, k)),
                    1.0 + rng.random(nw * k), db, 1.0 + rng.random(nb))
    m = m_meas + (nw - 1) * k + nw * k + nb
    Jz, r = rng.normal(size=(m, p)), rng.normal(size=m)
    Jz[m_meas + (nw - 1) * k:] = 0.0  # the priors do not depend on the parameters
    cluster = np.concatenate([own, np.repeat(np.arange(1, nw), k), np.repeat(np.arange(nw), k), np.zeros(nb, int)])
    return r, Jz, J, cluster


@pytest.mark.parametrize("nw,k,nb,per_window,p,empty", [(1, 3, 0, 10, 2, None), (6, 4, 3, 30, 5, None),
                                                        (18, 12, 5, 40, 34, None), (3, 2, 2, 1, 1, None),
                                                        (5, 6, 8, 20, 4, 2), (4, 0, 3, 10, 2, None),
                                                        (3, 0, 0, 5, 2, None)])
@pytest.mark.parametrize("scores", [False, True])
def test_normal_pieces_by_blocks_equal_the_whole_matrix_products(nw, k, nb, per_window, p, empty, scores):
    """The linearization's block-by-block products against the whole nuisance Jacobian's (dense)."""
    from uvsim.fitting.linearization import structured_normal_pieces

    rng = np.random.default_rng(11 + nw + k)
    r, Jz, J, cluster = _random_run_jacobian(rng, nw, k, nb, per_window, p, empty)
    Jn = J.to_sparse().toarray()
    assert Jn.shape == (r.size, nw * k + nb)
    out = structured_normal_pieces(r, Jz, J, cluster, scores)
    ref = _ref_normal_pieces(r, Jz, Jn, cluster, nw, scores)
    _assert_pieces_match(out, ref)
    np.testing.assert_array_equal(out.window_sse, ref["window_sse"])
    np.testing.assert_array_equal(out.D, out.D.T)


def test_wrap_equals_the_remainder_formula_bit_for_bit():
    # wrap() takes the remainder only outside [0, 2 pi) after the shift: the same values, signs,
    # dtypes and scalar types as (a + pi) % 2 pi - pi everywhere, the input untouched
    from uvsim.kinematics import wrap

    def ref(a):
        return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi

    rng = np.random.default_rng(5)
    edges = np.array([-np.pi, np.pi, 0.0, -0.0, np.nan, 2 * np.pi, -2 * np.pi, np.nextafter(np.pi, 0),
                      np.nextafter(np.pi, 4), np.nextafter(-np.pi, 0), np.nextafter(-np.pi, -4), 1e300, -1e-320])
    with np.errstate(invalid="ignore"):
        for a in [rng.normal(0, 1, (3, 50, 3)), rng.normal(0, 30, 1000), edges, np.append(edges, [np.inf, -np.inf]),
                  rng.normal(0, 5, (4, 5)).astype(np.float32), np.arange(-9, 9), [1.0, 5.0, -7.0]]:
            keep = np.array(a, copy=True)
            got, want = wrap(a), ref(a)
            assert got.dtype == want.dtype and got.shape == want.shape
            assert np.array_equal(got, want, equal_nan=True) and np.array_equal(np.signbit(got), np.signbit(want))
            assert np.array_equal(np.asarray(a), keep, equal_nan=True)
        for a in [3.5, -7.0, np.float64(2.0), np.pi, -np.pi, np.nan]:
            got, want = wrap(a), ref(a)
            assert type(got) is type(want) and (got == want or (np.isnan(got) and np.isnan(want)))
