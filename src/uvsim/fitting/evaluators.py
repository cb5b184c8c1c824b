"""Evaluators: what linearizes the problems of a fit at a point (:mod:`uvsim.fitting.solver`
calls ``ev.linearize(z, nus)`` and gets one :class:`uvsim.fitting.linearization.RunNormal` per run).

:class:`SerialEvaluator` linearizes in this process, :class:`PoolEvaluator` in local
processes (one problem per task: the same result as serially), :class:`PriorEvaluator`
weighs a data evaluator's blocks and adds the prior's (maximum a posteriori,
:mod:`uvsim.fitting.priors`).
"""
from __future__ import annotations

import numpy as np

from uvsim.blas import single_thread
from uvsim.fitting.linearization import RunNormal, linearize, reduced_system
from uvsim.fitting.priors import data_weight
from uvsim.heap import keep_freed_memory


def _split(seq, sizes):
    out, i = [], 0
    for n in sizes:
        out.append(list(seq[i:i + n]))
        i += n
    return out


class SerialEvaluator:
    """Linearizes every problem in this process (problems in order, their runs in order)."""

    def __init__(self, probs):
        self.probs = list(probs)
        self.sizes = [len(p.runs) for p in self.probs]

    def linearize(self, z, nus, *, jacobian=True, scores=False) -> list:
        out = []
        for p, n in zip(self.probs, _split(nus, self.sizes)):
            out += linearize(p, z, n, jacobian=jacobian, scores=scores)
        return out

    def close(self):
        pass


_WORKER_PROBS = None


def _init_worker(probs):
    global _WORKER_PROBS
    keep_freed_memory()  # uvsim.heap
    _WORKER_PROBS = probs


def _worker_linearize(args):
    i, z, nus, jacobian, scores = args
    with single_thread():
        return linearize(_WORKER_PROBS[i], z, nus, jacobian=jacobian, scores=scores)


class PoolEvaluator(SerialEvaluator):
    """Linearizes the problems in ``workers`` local processes, one problem per task.
    The problems (chunks of runs) do not depend on the number of workers, so the
    results equal the serial ones."""

    def __init__(self, probs, workers: int):
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        super().__init__(probs)
        method = "fork" if "fork" in mp.get_all_start_methods() else "spawn"
        self._pool = ProcessPoolExecutor(max_workers=workers, mp_context=mp.get_context(method),
                                         initializer=_init_worker, initargs=(self.probs,))

    def linearize(self, z, nus, *, jacobian=True, scores=False) -> list:
        tasks = [(i, z, n, jacobian, scores) for i, n in enumerate(_split(nus, self.sizes))]
        out = []
        for res in self._pool.map(_worker_linearize, tasks):
            out += res
        return out

    def close(self):
        self._pool.shutdown(wait=True, cancel_futures=True)


class PriorEvaluator:
    """An evaluator whose blocks are the data's, weighted by the data weight ``w``
    (:func:`uvsim.fitting.priors.data_weight`, re-estimated at every linearization with
    window scores), plus one block for the prior's residuals (no nuisance, no windows).
    ``raw`` keeps the data's own blocks of the last such linearization."""

    def __init__(self, ev, prior):
        self.ev, self.prior, self.w, self.raw = ev, prior, 1.0, None
        #: the data weight changes at every fresh linearization (the solver then re-evaluates its cost);
        #: holding it after the first 10 was tried and left more fits unfinished (9 against 7 of the
        #: structural benchmark's 50 at 80 iterations, docs/calibration.md)
        self.reweighs = bool(prior.temper)

    def linearize(self, z, nus, *, jacobian=True, scores=False) -> list:
        raw = self.ev.linearize(z, nus, jacobian=jacobian, scores=scores)
        if scores:
            self.raw = raw
            if self.reweighs:
                S, _, _ = reduced_system(raw, 0.0)
                self.w = data_weight(S, sum(b.scores.T @ b.scores for b in raw))
        w = self.w
        out = [RunNormal(w * b.rss, b.n) if b.A is None else
               RunNormal(w * b.rss, b.n, w * b.A, w * b.gz, w * b.D, w * b.B, w * b.gn, w * b.window_sse,
                         None if b.scores is None else w * b.scores) for b in raw]
        r = self.prior.residual(z)
        p = r.size
        if not jacobian:
            return out + [RunNormal(float(r @ r), 0)]
        inv = 1.0 / self.prior.sd_z
        return out + [RunNormal(float(r @ r), 0, np.diag(inv * inv), inv * r, np.zeros((0, 0)), np.zeros((0, p)),
                                np.zeros(0), np.zeros(0), np.zeros((0, p)) if scores else None)]

    def close(self):
        self.ev.close()
