"""The generator's truth model compiled by numba equals its numpy form (the reference)."""
import numpy as np
import pytest

from uvsim.errors import SimulationError
from uvsim.scenarios import dynamics
from uvsim.scenarios.dynamics import Plant, integrate

pytest.importorskip("numba")


def _plant(n=3, a=8, seed=0, current=True):
    """Every trajectory with its own parameters: CG offset, full M_A, lags on half the actuators,
    drag along the relative velocity."""
    rng = np.random.default_rng(seed)
    MA = np.stack([(lambda B: B @ B.T + 6 * np.eye(6))(rng.normal(size=(6, 6))) for _ in range(n)], axis=2)
    I = np.repeat((np.diag([0.3, 0.4, 0.5]) + 0.01)[:, :, None], n, axis=2) + rng.normal(size=(3, 3, n)) * 1e-3
    return Plant(mass=rng.uniform(10, 14, n), r_g=rng.normal(size=(3, n)) * 0.01, inertia=I, added_mass=MA,
                 linear=-rng.uniform(1, 5, (6, n)), quadratic=-rng.uniform(1, 20, (6, n)), load=rng.normal(size=n),
                 load_moment=rng.normal(size=(3, n)), current=rng.normal(size=(3, n)) * 0.2 * current,
                 allocation=rng.normal(size=(6, a, n)), lag_time=np.where(rng.random((a, n)) < 0.5, 0.1, 0.0),
                 along_flow=-rng.uniform(5, 30, (3, n)))


def _state(rng, n, a):
    y = rng.normal(size=(13 + a, n))
    y[3:7] /= np.linalg.norm(y[3:7], axis=0)
    return y


@pytest.mark.parametrize("current", [True, False])
def test_the_compiled_derivative_equals_the_numpy_one_with_and_without_wrenches(current):
    plant, rng = _plant(current=current), np.random.default_rng(1)
    y, f = _state(rng, 3, 8), rng.normal(size=(8, 3)) * 10
    ref = plant.rhs_numpy(0.3, y, f)
    assert np.abs(plant.rhs(0.3, y, f) - ref).max() <= 1e-12 * np.abs(ref).max()
    seen = []

    def wrench(ctx):                      # what a wrench reads: position, rotation, relative velocity
        seen.append((ctx.R.copy(), ctx.nu_r.copy()))
        return np.concatenate((ctx.R[:, 0] * ctx.nu_r[0], ctx.pos))

    plant.wrenches = [wrench]
    ref = plant.rhs_numpy(0.3, y, f)
    assert np.abs(plant.rhs(0.3, y, f) - ref).max() <= 1e-12 * np.abs(ref).max()
    (R_fast, nu_r_fast), (R_ref, nu_r_ref) = seen
    assert np.abs(R_fast - R_ref).max() <= 1e-15 and np.abs(nu_r_fast - nu_r_ref).max() <= 1e-15


def test_the_compiled_integration_equals_the_numpy_one():
    plant, rng = _plant(), np.random.default_rng(2)
    t = np.r_[np.arange(0.0, 2.0, 0.01), 2.013, 2.05]                 # a non-uniform interval too
    U = rng.normal(size=(t.size, 8, 3)) * 5
    y0 = np.zeros((21, 3))
    y0[3] = 1.0
    Y, A = integrate(plant, t, U, y0)
    previous = dynamics.use_compiled(False)
    try:
        Y0, A0 = integrate(plant, t, U, y0)
    finally:
        dynamics.use_compiled(previous)
    assert np.abs(Y - Y0).max() <= 1e-10 * np.abs(Y0).max()
    assert np.abs(A - A0).max() <= 1e-10 * np.abs(A0).max()


def test_a_compiled_blow_up_is_an_error_naming_the_time():
    plant = _plant(n=1, a=8)
    plant.packed[dynamics.dynamics_compiled.O_DQ:dynamics.dynamics_compiled.O_DQ + 6] = 1e6   # drag that feeds
    t = np.arange(0.0, 1.0, 0.1)
    y0 = np.zeros((21, 1))
    y0[3], y0[7] = 1.0, 1.0
    with pytest.raises(SimulationError, match=r"diverged at t = \d"):
        integrate(plant, t, np.zeros((t.size, 8, 1)), y0)
