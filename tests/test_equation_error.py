"""The equation error (uvsim.fitting.equation_error): batching over runs and what it estimates."""
from __future__ import annotations

import numpy as np

import uvsim
from uvsim.fitting import make_space
from uvsim.fitting.equation_error import EquationError, measured_motion
from uvsim.logs import Run
from uvsim.synthetic import generate_runs


def _cut(run, n):
    return Run(name=f"{run.name}_cut{n}", path=None, data=run.data.iloc[:n].reset_index(drop=True), dof=run.dof,
               weight=run.weight, split=run.split)


def test_runs_evaluated_together_give_each_runs_own_residuals():
    """Runs of equal length share one smoothing call, others do not; either way each run's
    residual is what it is when the run is evaluated alone (its own time axis only)."""
    runs, _ = generate_runs("bluerov2_heavy", dofs=("surge", "yaw", "heave"), runs_per_dof=2, validation_per_dof=0,
                            duration=8.0, rate=25.0, seed=4, off=4.0)
    runs = runs + [_cut(runs[0], 150), _cut(runs[3], 131)]
    v = uvsim.load_vehicle("bluerov2_heavy")
    p = v.parameters()
    space = make_space(p, ["X_uu", "N_rr", "Z_w"])
    motions = [measured_motion(r) for r in runs]
    Z = space.z0[None] * np.array([[1.0, 1.0, 1.0], [1.2, 0.9, 1.1]])
    together = EquationError(v, motions, space, scale=np.ones(6)).forces(Z)
    for m, f in zip(motions, together):
        alone = EquationError(v, [m], space, scale=np.ones(6)).forces(Z)[0]
        np.testing.assert_allclose(f, alone, rtol=1e-12, atol=1e-12, equal_nan=True)
        assert np.isnan(f[:, ~m.valid_sub]).all() and np.isfinite(f[:, m.valid_sub][..., m.have]).all()


def test_the_equation_error_recovers_a_damping_coefficient_from_a_wrong_start():
    """Noisy surge runs of the truth: Gauss-Newton on the equation error from a start 40 %
    off lands within 5 % of the truth's quadratic surge damping (0.4 % on this seed; the smoothing biases it a
    little; diagnosis uses it to rank and seed, not to decide)."""
    runs, _ = generate_runs("bluerov2_heavy", dofs=("surge",), runs_per_dof=4, validation_per_dof=0, duration=10.0,
                            rate=50.0, seed=7, off=5.0)
    v = uvsim.load_vehicle("bluerov2_heavy")
    truth = v.parameters()["X_uu"]
    space = make_space(v.parameters(), ["X_uu"], start={"X_uu": 0.6 * truth})
    ee = EquationError(v, [measured_motion(r) for r in runs], space)
    out = ee.gauss_newton(iterations=4)
    assert abs(out["values"]["X_uu"] / truth - 1) < 0.05
    assert out["rss"] < out["rss0"]


def test_the_compiled_path_is_kept_per_vehicle_and_goes_with_it():
    """EquationError._compiled looks up once per vehicle object whether its models run compiled (the
    screening builds an evaluation per Gauss-Newton step); the answer is the same as a fresh look-up,
    the residuals are the same with and without the kept answer, and the entry goes with the vehicle."""
    import gc

    from uvsim.fitting import equation_error as ee

    runs, _ = generate_runs("bluerov2_heavy", dofs=("surge",), runs_per_dof=1, validation_per_dof=0, duration=6.0,
                            rate=25.0, seed=2, off=4.0)
    v = uvsim.load_vehicle("bluerov2_heavy").with_effects([{"type": "current"}])
    space = make_space(v.parameters(), ["X_uu", "current_n"])
    motions = [measured_motion(r) for r in runs]
    first = EquationError(v, motions, space, scale=np.ones(6))
    r1 = first.residuals(space.z0[None])
    assert id(v) in ee._COMPILED_VEHICLES or not first._compiled()
    again = EquationError(v, motions, space, scale=np.ones(6))
    assert again._compiled() == first._compiled()
    np.testing.assert_array_equal(again.residuals(space.z0[None]), r1)
    key = id(v)
    del v, first, again
    gc.collect()
    assert key not in ee._COMPILED_VEHICLES
