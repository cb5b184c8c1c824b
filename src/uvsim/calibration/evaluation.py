"""Batched fitness evaluation of GA individuals and DEAP map hooks.

:class:`DofProblem` describes one DOF's fit (its training runs, parameter
names and bounds, run weights).  :class:`BatchEvaluator` turns a
list of individuals - possibly of several DOFs at once - into one
:func:`uvsim.simulate_batch` call per *block* of rows (one row = one individual x
one run of its DOF) and returns each individual's fitness.

Blocks are formed from the list of individuals alone (at most ``batch_rows``
rows each, split evenly), never from the number of workers, so a block is
computed by exactly the same numpy operations whether it runs in this process,
in a ``multiprocessing`` worker (:class:`ProcessMap`) or on a dask.distributed
cluster (:class:`DaskMap`): results are bit-identical to the serial run for the
same seed.  These map objects are DEAP map hooks (``toolbox.register("map",
hook)``): ``hook(evaluate, individuals)`` returns the list of fitness tuples.
"""
from __future__ import annotations

import functools
import math
import os
import random
import sys
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from uvsim.calibration.batching import RunBatch, simulate_rows
from uvsim.calibration.fitness import abs_error_fitness
from uvsim.errors import CalibrationError
from uvsim.fitting.worker_pool import die_with_parent
from uvsim.heap import keep_freed_memory

#: Default largest number of simulated trajectories per batched call.  Batched
#: RK4 reaches ~90 % of its peak vehicle-steps/s from ~500 rows on (core_api.md).
DEFAULT_BATCH_ROWS = 1024


@dataclass
class DofProblem:
    """One DOF's fit.

    Attributes
    ----------
    dof : DOF name.
    names : fitted parameter names (seed 000 Table 3).
    lower, upper : (p,) search bounds.
    initial : (p,) initial values.
    run_index : (R,) indices of this DOF's training runs in the evaluator's batch.
    run_weights : (R,) fitness weight of each run (manifest weight x low-speed factor).
    signal_weights : channel -> weight of the DOF's fitness (also in its runs' measurement
        models).
    """

    dof: str
    names: tuple
    lower: np.ndarray
    upper: np.ndarray
    initial: np.ndarray
    run_index: np.ndarray
    run_weights: np.ndarray
    signal_weights: dict

    def decode(self, genes: np.ndarray) -> np.ndarray:
        """Parameter values (..., p) from genes in [0, 1] (..., p)."""
        return self.lower + np.asarray(genes, float) * (self.upper - self.lower)

    def encode(self, values: np.ndarray) -> np.ndarray:
        return (np.asarray(values, float) - self.lower) / (self.upper - self.lower)


class BatchEvaluator:
    """Fitness of individuals (seed 000 sec. 4.4 ii): for each of the DOF's runs,
    the noise-normalized mean absolute error of its logged channels through their
    measurement models (:func:`uvsim.calibration.fitness.abs_error_fitness`), times
    the run's weight, summed over runs.  Lower is better; a diverged simulation scores
    ``inf``.

    Parameters
    ----------
    vehicle : Vehicle whose non-fitted parameters are used.
    batch : all training runs of all DOFs (:class:`RunBatch`).
    problems : dof -> :class:`DofProblem`.
    meas : per run of ``batch``, its :class:`uvsim.measurements.RunMeasurements` (with
        the weights of its DOF's fitness).
    batch_rows : largest rows per simulated block.
    gyro_bias : remove each gyro channel's median residual (a sensor offset).
    """

    def __init__(self, vehicle, batch: RunBatch, problems: dict, meas: list, batch_rows: int = DEFAULT_BATCH_ROWS,
                 gyro_bias: bool = True):
        self.vehicle = vehicle
        self.batch = batch
        self.problems = problems
        self.meas = list(meas)
        self.gyro_bias = bool(gyro_bias)
        self.acceleration = any(m.needs_acceleration for m in self.meas)
        self.batch_rows = int(batch_rows)
        if self.batch_rows < 1:
            raise CalibrationError(f"batch_rows must be >= 1, got {batch_rows}")
        base = vehicle.parameters()
        self.base = {k: float(base[k]) for p in problems.values() for k in p.names}

    def __call__(self, individual):  # DEAP-style single evaluation (slow path)
        return self.evaluate_block([(individual.dof, tuple(individual))])[0]

    # -- blocks -----------------------------------------------------------------
    def make_blocks(self, items: Sequence[tuple]) -> list[list[tuple]]:
        """Split (dof, genes) items into contiguous blocks of about equal rows."""
        rows = np.array([len(self.problems[d].run_index) for d, _ in items])
        total = int(rows.sum())
        if total == 0:
            return []
        n_blocks = max(1, math.ceil(total / self.batch_rows))
        target = total / n_blocks
        blocks, cur, acc, k = [], [], 0, 1
        for item, r in zip(items, rows):
            cur.append(item)
            acc += r
            if acc >= k * target - 1e-9 and k < n_blocks:
                blocks.append(cur)
                cur, k = [], k + 1
        if cur:
            blocks.append(cur)
        return blocks

    def evaluate_block(self, block: Sequence[tuple]) -> list[tuple]:
        """Fitness tuples of (dof, genes) items, simulated in one batched call."""
        run_idx, owner = [], []
        values = {k: [] for k in self.base}
        for j, (dof, genes) in enumerate(block):
            prob = self.problems[dof]
            vals = dict(zip(prob.names, prob.decode(np.asarray(genes, float))))
            for r in prob.run_index:
                run_idx.append(r)
                owner.append(j)
                for k in self.base:
                    values[k].append(vals.get(k, self.base[k]))
        run_idx = np.asarray(run_idx, int)
        owner = np.asarray(owner, int)
        overrides = {k: np.asarray(v, float) for k, v in values.items()}
        out = simulate_rows(self.vehicle, self.batch, run_idx, overrides, acceleration=self.acceleration)
        y, acc = out if self.acceleration else (out, None)
        fit = np.zeros(len(block))
        for r in np.unique(run_idx):
            rows = np.flatnonzero(run_idx == r)
            n = self.batch.lengths[r]
            with np.errstate(all="ignore"):
                pred = self.meas[r].predict(y[rows, :n], None if acc is None else acc[rows, :n])
                e = abs_error_fitness(self.meas[r], pred, gyro_bias=self.gyro_bias)
            prob = self.problems[block[owner[rows[0]]][0]]
            w = float(prob.run_weights[np.flatnonzero(prob.run_index == r)[0]])
            np.add.at(fit, owner[rows], w * e)
        return [(float(f),) for f in fit]


def _unwrap(func):
    while isinstance(func, functools.partial):
        func = func.func
    return func


def _serial_blocks(ev, blocks):
    return [ev.evaluate_block(b) for b in blocks]


class SerialMap:
    """DEAP map hook evaluating blocks in this process."""

    n_workers = 1

    def __call__(self, func, individuals):
        individuals = list(individuals)
        ev = _unwrap(func)
        if not isinstance(ev, BatchEvaluator):
            return list(map(func, individuals))
        items = [(ind.dof, tuple(ind)) for ind in individuals]
        out = []
        # the executor (e.g. dask's client) may draw from the global random streams
        # that DEAP's operators use: keep them untouched so results match the serial run
        state, np_state = random.getstate(), np.random.get_state()
        try:
            for res in self._run(ev, ev.make_blocks(items)):
                out.extend(res)
        finally:
            random.setstate(state)
            np.random.set_state(np_state)
        return out

    def _run(self, ev, blocks):
        return _serial_blocks(ev, blocks)

    def run_tasks(self, evaluator, fn, args_list) -> list:
        """``[fn(evaluator, *args) for args in args_list]``, in the workers when
        there are any (``fn`` must be a module-level function)."""
        return [fn(evaluator, *a) for a in args_list]

    def close(self):
        pass


_WORKER_EVALUATOR = None

def _init_worker(evaluator, parent_pid=None):
    global _WORKER_EVALUATOR
    if parent_pid is not None:
        die_with_parent(parent_pid)
    keep_freed_memory()  # uvsim.heap
    _WORKER_EVALUATOR = evaluator


def _worker_block(block):
    return _WORKER_EVALUATOR.evaluate_block(block)


def _worker_task(fn_args):
    fn, args = fn_args
    return fn(_WORKER_EVALUATOR, *args)


class ProcessMap(SerialMap):
    """DEAP map hook with ``workers`` local processes (``multiprocessing``; fork on
    Linux, spawn elsewhere - there, scripts need the ``if __name__ == "__main__"`` guard).

    Each worker receives the evaluator once (pool initializer) and then only
    the blocks' genes.  Workers die with this process (:func:`die_with_parent`), and
    :meth:`close` called while an exception (KeyboardInterrupt, SIGTERM turned into one
    by the CLI, an error) is propagating kills them at once instead of waiting for
    the blocks in flight."""

    def __init__(self, evaluator: BatchEvaluator, workers: int):
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        if workers < 1:
            raise CalibrationError(f"workers must be >= 1, got {workers}")
        self.n_workers = workers
        # fork where available (Linux): no re-import of the user's __main__ module, so
        # scripts without an ``if __name__ == "__main__"`` guard work; spawn elsewhere.
        method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
        self._pool = ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context(method),
                                         initializer=_init_worker, initargs=(evaluator, os.getpid()))

    def _run(self, ev, blocks):
        return list(self._pool.map(_worker_block, blocks))

    def run_tasks(self, evaluator, fn, args_list) -> list:
        return list(self._pool.map(_worker_task, [(fn, a) for a in args_list]))

    def close(self):
        if sys.exc_info()[0] is not None:  # called from a finally clause while an exception propagates
            self.terminate()
            return
        self._pool.shutdown(wait=True, cancel_futures=True)

    def terminate(self):
        """Kill the workers now and reap them (no process is left behind)."""
        procs = list((getattr(self._pool, "_processes", None) or {}).values())
        manager = getattr(self._pool, "_executor_manager_thread", None)
        for p in procs:
            if p.is_alive():
                p.kill()
        self._pool.shutdown(wait=False, cancel_futures=True)
        for p in procs:
            p.join(timeout=5)
        # The pool's manager thread sees the dead workers and closes its wake-up pipe.
        # Wait for it: otherwise the interpreter's exit hook (concurrent.futures.process
        # ._python_exit) may write to that pipe while it is being closed, and print
        # "OSError: Bad file descriptor" after a Ctrl-C (the unlocked wakeup in _python_exit,
        # CPython gh-84176; _ThreadWakeup got its own lock in gh-125451, 3.12.8 / 3.13.1).
        if manager is not None:
            manager.join(timeout=10)


def _dask_block(evaluator, block):
    return evaluator.evaluate_block(block)


class DaskMap(SerialMap):
    """DEAP map hook on a dask.distributed cluster: ``address`` of a running
    scheduler (``tcp://host:8786``) or ``"local"`` for a LocalCluster on this
    machine.  Needs the optional extra ``uvsim[dask]``."""

    def __init__(self, evaluator: BatchEvaluator, address: str, workers: int | None = None):
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise CalibrationError(
                "--dask needs the optional package dask.distributed: pip install 'uvsim[dask]' "
                "(or pip install 'dask[distributed]')") from None
        self._cluster = None
        try:
            if address == "local":
                self._cluster = LocalCluster(n_workers=workers or 2, threads_per_worker=1, processes=True,
                                             dashboard_address=None)
                self._client = Client(self._cluster)
            else:
                self._client = Client(address, timeout=30)
        except OSError as exc:
            raise CalibrationError(f"cannot connect to the dask scheduler {address!r}: {exc}") from None
        self.n_workers = len(self._client.scheduler_info().get("workers", {})) or 1
        self._ev = self._client.scatter(evaluator, broadcast=True)

    def _run(self, ev, blocks):
        futs = [self._client.submit(_dask_block, self._ev, b, pure=False) for b in blocks]
        return self._client.gather(futs)

    def run_tasks(self, evaluator, fn, args_list) -> list:
        futs = [self._client.submit(fn, self._ev, *a, pure=False) for a in args_list]
        return self._client.gather(futs)

    def close(self):
        self._client.close()
        if self._cluster is not None:
            self._cluster.close()  # stops its worker processes (which also exit when this process dies)
