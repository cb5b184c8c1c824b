"""GA mechanics: determinism, workers identical to serial, checkpoint/resume, settings errors."""
import importlib.util

import numpy as np
import pytest

from calibration_data import tank_runs
from uvsim.calibration import Calibrator
from uvsim.calibration import ga as ga_mod
from uvsim.errors import CalibrationError

SMALL = dict(dofs="surge,yaw", population=8, generations=3, refine=False, batch_rows=24)


def _runs():
    return tank_runs(dofs=("surge", "yaw"))[0]


def _fit(**kw):
    return Calibrator(**{**SMALL, **kw}).fit(_runs(), "bluerov2_heavy_initial")


@pytest.fixture(scope="module")
def serial():
    return _fit(seed=5)


def test_same_seed_identical_result(serial):
    again = _fit(seed=5)
    assert again.params_ == serial.params_
    assert [dict(r) for r in again.logbook_["surge"]] == [
        {**dict(r), "wall_s": dict(again.logbook_["surge"][i])["wall_s"]} for i, r in enumerate(serial.logbook_["surge"])]
    other = _fit(seed=6)
    assert other.params_ != serial.params_


def test_workers_identical_to_serial(serial):
    par = _fit(seed=5, workers=2)
    assert par.params_ == serial.params_
    assert par.evaluations_ == serial.evaluations_


def test_refinement_with_workers_identical_to_serial():
    kw = dict(dofs="surge,yaw", population=8, generations=2, seed=5, max_iter=6)
    a = Calibrator(**kw).fit(_runs(), "bluerov2_heavy_initial")
    b = Calibrator(workers=2, **kw).fit(_runs(), "bluerov2_heavy_initial")
    assert a.params_ == b.params_ and a.uncertainty_ == b.uncertainty_


def test_first_generation_seeded_with_initial_values(serial):
    # generation 0 contains the initial values: the best fitness can only improve on them
    lb = serial.logbook_["surge"]
    assert lb[0]["gen"] == 0 and lb[0]["nevals"] == 8
    # gen 0 holds an exact copy of the initial values: its best is at least as good as them
    init = serial.initial_vehicle_.parameters()
    assert lb[0]["min"] <= lb[0]["max"]
    assert min(r["min"] for r in lb) <= lb[0]["min"]
    assert serial.ga_params_ != {k: init[k] for k in serial.ga_params_}
    assert serial.report_["logbook"]["yaw"][-1]["gen"] == 3


def test_checkpoint_and_resume_identical(tmp_path, monkeypatch, serial):
    ckpt = tmp_path / "fit.ckpt"
    real_save = ga_mod._save_checkpoint

    def save_then_interrupt(path, state):
        real_save(path, state)
        if state["generation"] == 1:
            raise KeyboardInterrupt  # the machine went down after generation 1

    monkeypatch.setattr(ga_mod, "_save_checkpoint", save_then_interrupt)
    with pytest.raises(KeyboardInterrupt):
        _fit(seed=5, checkpoint=ckpt)
    monkeypatch.setattr(ga_mod, "_save_checkpoint", real_save)
    assert ga_mod.load_checkpoint(ckpt)["generation"] == 1
    resumed = _fit(seed=5, resume=ckpt, checkpoint=ckpt)
    assert resumed.params_ == serial.params_
    assert resumed.evaluations_ == serial.evaluations_
    assert ga_mod.load_checkpoint(ckpt)["generation"] == 3
    with pytest.raises(CalibrationError, match="different settings"):
        _fit(seed=6, resume=ckpt)


def test_bad_settings_and_inputs(tmp_path):
    with pytest.raises(CalibrationError, match="dof"):
        Calibrator(dofs="surge,flip").fit(_runs(), "bluerov2_heavy_initial")
    with pytest.raises(CalibrationError, match="no training runs for dof"):
        Calibrator(dofs="heave").fit(_runs(), "bluerov2_heavy_initial")
    with pytest.raises(CalibrationError, match="population"):
        _fit(population=1)
    with pytest.raises(CalibrationError, match="probability"):
        _fit(crossover=1.5)
    with pytest.raises(CalibrationError, match="do not contain"):
        _fit(bounds={"X_u": (-0.1, -0.05)})
    with pytest.raises(CalibrationError, match="positive damping"):
        _fit(bounds={"X_u": (-0.3, 0.1)})
    with pytest.raises(CalibrationError, match="unknown signal"):
        _fit(signal_weights={"dept": 1.0})
    with pytest.raises(CalibrationError, match="does not exist"):
        _fit(resume=tmp_path / "nope.ckpt")
    bad = tmp_path / "bad.ckpt"
    bad.write_bytes(b"not a pickle")
    with pytest.raises(CalibrationError, match="cannot be read"):
        _fit(resume=bad)


def test_dask_missing_is_a_clear_error(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "dask.distributed", None)  # as if not installed
    with pytest.raises(CalibrationError, match=r"uvsim\[dask\]"):
        _fit(dask="local")


@pytest.mark.skipif(importlib.util.find_spec("distributed") is None, reason="needs dask.distributed")
@pytest.mark.slow  # end to end: starts a local dask cluster (make test-all)
def test_dask_local_identical_to_serial(serial):
    par = _fit(seed=5, dask="local", workers=2)
    assert par.params_ == serial.params_


def test_deap_creator_not_used():
    import deap.creator

    assert issubclass(ga_mod.FitnessMin, ga_mod.base.Fitness)
    assert not hasattr(deap.creator, "FitnessMin")
    assert ga_mod.GASettings().population == 60 and ga_mod.GASettings().generations == 30
    s = ga_mod.GASettings()
    assert (s.tournament, s.crossover, s.mutation) == (5, 0.5, 0.25)
    assert np.isfinite(s.mutation_sigma)


def test_initial_population_is_partly_seeded():
    import random

    random.seed(0)
    s = ga_mod.GASettings(population=20, seeded_fraction=0.2)
    genes = np.array([0.5, 0.25, 0.75])
    pop = ga_mod.initial_population("surge", 3, genes, s)
    assert len(pop) == 20 and all(ind.dof == "surge" for ind in pop)
    assert list(pop[0]) == [0.5, 0.25, 0.75]  # exact initial values
    near = [np.max(np.abs(np.array(ind) - genes)) for ind in pop[1:4]]
    assert max(near) < 0.1  # the other seeded ones close to them
    assert all(0 <= g <= 1 for ind in pop for g in ind)
