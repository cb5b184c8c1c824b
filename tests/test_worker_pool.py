"""The worker processes a diagnosis keeps for all its fits (uvsim.fitting.worker_pool)."""
import numpy as np
import pytest

import uvsim
from uvsim.errors import CalibrationError
from uvsim.fitting import fit, make_space
from uvsim.fitting.evaluators import SerialEvaluator
from uvsim.fitting.fitter import build_problems
from uvsim.fitting.worker_pool import PersistentEvaluator, WorkerPool
from uvsim.measurements import measurements_for
from uvsim.synthetic import generate_runs


@pytest.fixture(scope="module")
def problems():
    runs, _ = generate_runs("bluerov2_heavy", dofs=("surge", "heave", "yaw"), runs_per_dof=1, validation_per_dof=0,
                            duration=6.0, rate=25.0, seed=5, off=5.0)
    v = uvsim.load_vehicle("bluerov2_heavy")
    space = make_space(v.parameters(), ["X_uu", "N_rr"])
    meas = [measurements_for(r, v) for r in runs]
    import uvsim.fitting.fitter as F

    old = F.RUNS_PER_PROBLEM
    F.RUNS_PER_PROBLEM = 1  # one problem per run: work for every worker
    try:
        probs, _ = build_problems(v, runs, meas, space, 2.0, space.z0)
    finally:
        F.RUNS_PER_PROBLEM = old
    return v, runs, space, probs


def _blocks_equal(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert x.rss == y.rss
        for name in ("A", "gz", "D", "B", "gn", "window_sse", "scores"):
            u, w = getattr(x, name), getattr(y, name)
            assert (u is None) == (w is None), name
            if u is not None:
                np.testing.assert_array_equal(u, w, err_msg=name)


def test_kept_workers_linearize_exactly_as_in_this_process(problems):
    _, _, space, probs = problems
    assert len(probs) == 3
    nus = [n for p in probs for n in p.zero_nuisance()]
    z = space.z0 * 1.1
    serial = SerialEvaluator(probs).linearize(z, nus, scores=True)
    with WorkerPool(2) as pool:
        ev = PersistentEvaluator(probs, pool)
        assert sorted(i for idx in ev.owned for i in idx) == [0, 1, 2]
        assert all(ev.owned)  # both workers have a problem
        _blocks_equal(serial, ev.linearize(z, nus, scores=True))
        # a second fit's problems replace the first's in the same processes
        pids = [p.pid for p in pool._procs]
        ev2 = PersistentEvaluator(probs[:2], pool)
        _blocks_equal(SerialEvaluator(probs[:2]).linearize(z, nus[:2]), ev2.linearize(z, nus[:2]))
        assert [p.pid for p in pool._procs] == pids
        procs = list(pool._procs)
    assert not any(p.is_alive() for p in procs)  # stopped at the end of the block


def test_a_fit_gives_the_same_answer_with_a_kept_pool(problems):
    v, runs, space, _ = problems
    import uvsim.fitting.fitter as F

    old = F.RUNS_PER_PROBLEM
    F.RUNS_PER_PROBLEM = 1
    try:
        a = fit(v, runs, space, horizons=(3.0, 2.0), max_iter=3)
        with WorkerPool(2) as pool:
            b = fit(v, runs, space, horizons=(3.0, 2.0), max_iter=3, workers=pool)
            c = fit(v, runs, space, horizons=(3.0,), max_iter=3, workers=pool)  # the same processes again
        d = fit(v, runs, space, horizons=(3.0,), max_iter=3)
    finally:
        F.RUNS_PER_PROBLEM = old
    assert a.values == b.values and a.cost == b.cost
    assert c.values == d.values and c.cost == d.cost


def test_a_worker_error_reaches_the_caller_and_leaves_the_pool_usable(problems):
    _, _, space, probs = problems
    nus = [n for p in probs for n in p.zero_nuisance()]
    with WorkerPool(2) as pool:
        ev = PersistentEvaluator(probs, pool)
        # damping of the wrong sign: the model's own error, raised in a worker, reaches the caller
        with pytest.raises(ValueError, match="X_uu .* would feed energy into the motion"):
            ev.linearize(-space.z0, nus)
        # every reply of the failed call was read: the next call gets its own
        _blocks_equal(SerialEvaluator(probs).linearize(space.z0, nus), ev.linearize(space.z0, nus))


def test_a_worker_that_dies_is_named(problems):
    _, _, space, probs = problems
    nus = [n for p in probs for n in p.zero_nuisance()]
    with WorkerPool(2) as pool:
        ev = PersistentEvaluator(probs, pool)
        pool._procs[0].kill()
        pool._procs[0].join()
        with pytest.raises(CalibrationError, match="worker process 1 of 2 ended unexpectedly"):
            ev.linearize(space.z0, nus)


@pytest.mark.parametrize("n", [1, 0, 2.5, "2"])
def test_a_pool_needs_two_or_more_workers(n):
    with pytest.raises(CalibrationError, match="2 or more workers"):
        WorkerPool(n)


def _square_plus(shared, x):
    if x < 0:
        raise ValueError(f"item {x} refused")
    return shared + x * x


def test_map_deals_the_items_out_and_keeps_their_order():
    with WorkerPool(2) as pool:
        out, extra = pool.map(_square_plus, 100, list(range(7)), meanwhile=lambda: "parent's part")
        assert out == [100 + x * x for x in range(7)] and extra == "parent's part"
        with pytest.raises(ValueError, match="item -3 refused"):
            pool.map(_square_plus, 0, [1, -3, 2])
        assert pool.map(_square_plus, 1, [2])[0] == [5]  # usable after an error; one worker idle


def test_screening_in_the_pool_equals_the_screening_here(tmp_path):
    """The screening's candidates outside the tether chain, fitted in the workers while this
    process fits the chain, give the numbers of the screening in one process."""
    from uvsim.diagnosis.candidates import catalogue
    from uvsim.diagnosis.selector import Selector
    from uvsim.latency import runs_for
    from uvsim.logs import read_dataset
    from uvsim.scenarios import generate, sample_scenario

    out = generate(sample_scenario(3, profile="diagnose", n_runs=6, duration=[6, 8], rate_hz=20.0,
                                   effects=[{"type": "current", "magnitude": 0.05}]), tmp_path / "d")
    ds = read_dataset(out)
    veh = uvsim.load_vehicle(ds.vehicle_file or ds.vehicle)
    train, val = runs_for(veh, ds.train), runs_for(veh, ds.validation)
    results = []
    for workers in (1, WorkerPool(2)):
        sel = Selector(veh, train, val, retune=None, noise=None, weights=None, horizon=3.0, max_iter=5,
                       workers=workers, say=None)
        has_pos, p_ref, z_max, has_depth = sel.signals()
        cands = catalogue(input_kind=train[0].input_kind, n_thrusters=veh.n_thrusters, dt=0.05, p_ref=p_ref,
                          has_position=has_pos, z_max=z_max, has_depth=has_depth, base=veh.parameters())
        screened, info = sel.screen(sel.current([], {}), cands)
        results.append([(c.label, s) for c, s in screened])
        if isinstance(workers, WorkerPool):
            workers.close()
    assert info["available"] and len(results[0]) > 10
    assert sum(lab.startswith("tether") for lab, _ in results[0]) >= 2  # a chain beside the pool's part
    assert results[0] == results[1]


class _Unpicklable(Exception):
    def __init__(self):
        super().__init__("holds a lambda")
        self.f = lambda: 0


def _raises_unpicklable(shared, x):
    raise _Unpicklable()


def test_an_error_that_does_not_pickle_arrives_as_its_text():
    with WorkerPool(2) as pool:
        with pytest.raises(CalibrationError, match="_Unpicklable: holds a lambda") as got:
            pool.map(_raises_unpicklable, None, [1, 2])
        assert any("raised in worker process" in n for n in got.value.__notes__)
        assert pool.map(_square_plus, 0, [3])[0] == [9]  # the workers live on
