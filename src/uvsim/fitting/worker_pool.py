"""Worker processes kept for a whole diagnosis: the fits' linearizations without a new pool per fit,
and the screening's independent candidate fits (:meth:`WorkerPool.map`).

A diagnosis makes dozens of fits, each a few Levenberg-Marquardt iterations long.  A process pool
made for each fit (:class:`uvsim.fitting.evaluators.PoolEvaluator`) pays, every fit, for starting
its processes and for their first linearization, which runs several times slower than the next
ones in a fresh process (its memory is new; on the shipped tank tether 0.11 s against 0.02 s,
docs/performance.md): with two workers the diagnosis took as long as with one.  A
:class:`WorkerPool` starts its processes once; each fit sends them its problems (pickled, about
1 MB per problem of four 14-s runs at 50 Hz) and then only the points to linearize at
(:class:`PersistentEvaluator`).

Each problem is linearized by one worker, whole, exactly as :class:`~uvsim.fitting.evaluators.SerialEvaluator`
does it, so the results do not depend on the number of workers or on which worker took a problem.
Problems go to the worker with the least work so far (samples times parameter sets), largest first.

Use it as a context manager (the processes stop at the end, also on an error or Ctrl-C)::

    with WorkerPool(2) as pool:
        fit(vehicle, runs, space, workers=pool)
"""
from __future__ import annotations

import functools
import multiprocessing as mp
import os
import traceback
import weakref

import numpy as np

from uvsim.errors import CalibrationError
from uvsim.fitting.evaluators import SerialEvaluator, _split


#: prctl(2) option asking the kernel to signal this process when its parent dies (Linux).
_PR_SET_PDEATHSIG = 1


def die_with_parent(parent_pid: int) -> None:
    """Make this (worker) process end with its parent, whatever ends the parent.

    On Linux the kernel sends SIGKILL to the worker when the parent dies, even by
    SIGKILL (``prctl(PR_SET_PDEATHSIG)``); if the parent is already gone (it died
    between the fork and this call) the worker exits now.  SIGTERM gets its default
    action back (a forked worker inherits the parent's Python handler) and SIGINT is
    ignored: a Ctrl-C reaches the whole process group, and the parent, which receives it
    too, stops the workers itself (:meth:`uvsim.calibration.evaluation.ProcessMap.close`, :meth:`WorkerPool.close`)."""
    import signal
    import sys

    if sys.platform.startswith("linux"):
        import ctypes

        try:
            ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - no prctl in this libc
            pass
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if os.getppid() != parent_pid:
        os._exit(1)


def _serve(conn, parent_pid: int) -> None:
    """A worker's loop: ``("load", {index: problem})`` keeps a fit's problems (replacing the last
    fit's); ``("linearize", [(index, nus)], z, jacobian, scores)`` answers with their blocks;
    ``("map", fn, shared, items)`` with ``[fn(shared, item) for item in items]``; ``("stop",)``
    ends.  Errors are sent back to be raised in the parent."""
    from uvsim.blas import single_thread
    from uvsim.fitting.linearization import linearize
    from uvsim.heap import keep_freed_memory

    die_with_parent(parent_pid)  # whatever ends the parent (SIGKILL included); Ctrl-C is the parent's
    keep_freed_memory()  # a linearization's arrays served from a heap kept mapped (uvsim.heap)
    probs: dict = {}
    while True:
        try:
            msg = conn.recv()
        except (EOFError, OSError):
            return
        if msg[0] == "stop":
            return
        try:
            if msg[0] == "load":
                probs = msg[1]
                conn.send(("ok", None))
            elif msg[0] == "map":
                _, fn, shared, items = msg
                with single_thread():
                    conn.send(("ok", [fn(shared, it) for it in items]))
            else:
                _, items, z, jacobian, scores = msg
                with single_thread():
                    out = [linearize(probs[i], z, nus, jacobian=jacobian, scores=scores) for i, nus in items]
                conn.send(("ok", out))
        except Exception as exc:  # noqa: BLE001 -- sent to the parent, which raises it
            tb = traceback.format_exc()
            try:
                conn.send(("error", exc, tb))
            except Exception:  # noqa: BLE001 -- an exception that does not pickle: its text
                conn.send(("error", CalibrationError(f"{type(exc).__name__}: {exc}"), tb))


def _stop(procs, conns) -> None:
    for c in conns:
        try:
            c.send(("stop",))
        except (OSError, ValueError):
            pass
    for p in procs:
        p.join(timeout=2.0)
        if p.is_alive():
            p.terminate()
            p.join(timeout=2.0)
    for c in conns:
        c.close()


class WorkerPool:
    """``workers`` local processes (started at the first use) that linearize the problems of one
    fit after another (module docstring)."""

    def __init__(self, workers: int):
        if not (isinstance(workers, (int, np.integer)) and workers >= 2):
            raise CalibrationError(f"WorkerPool: need 2 or more workers, got {workers!r}")
        self.workers = int(workers)
        self._procs: list = []
        self._conns: list = []
        self._finalizer = None

    def _start(self) -> None:
        if self._procs:
            return
        ctx = mp.get_context("fork" if "fork" in mp.get_all_start_methods() else "spawn")
        for _ in range(self.workers):
            parent, child = ctx.Pipe()
            p = ctx.Process(target=_serve, args=(child, os.getpid()), daemon=True)
            p.start()
            child.close()
            self._procs.append(p)
            self._conns.append(parent)
        self._finalizer = weakref.finalize(self, _stop, self._procs, self._conns)

    def _lost(self, w: int) -> CalibrationError:
        self.close()
        return CalibrationError(f"worker process {w + 1} of {self.workers} ended unexpectedly (out of memory?); "
                                "run with fewer workers")

    def _send(self, w: int, msg) -> None:
        try:
            self._conns[w].send(msg)
        except (BrokenPipeError, EOFError, OSError):
            raise self._lost(w) from None

    def _gather(self, busy: list[int]) -> dict:
        """The replies of the workers ``busy`` (every one read before an error is raised, so that
        none is left in a pipe for the next call)."""
        got, error = {}, None
        for w in busy:
            try:
                reply = self._conns[w].recv()
            except (EOFError, OSError):
                raise self._lost(w) from None
            if reply[0] == "error":
                if error is None:
                    error = reply[1]
                    error.add_note(f"raised in worker process {w + 1} of {self.workers}:\n{reply[2]}")
            else:
                got[w] = reply[1]
        if error is not None:
            raise error
        return got

    def load(self, probs: list) -> list[list[int]]:
        """Send the problems of a fit to the workers; returns each worker's problem indices."""
        self._start()
        load = [0.0] * self.workers
        owned: list[list[int]] = [[] for _ in range(self.workers)]
        size = [sum(r.t.size for r in p.runs) * (p.space.p + 13) for p in probs]
        for i in sorted(range(len(probs)), key=lambda i: -size[i]):
            w = int(np.argmin(load))
            owned[w].append(i)
            load[w] += size[i]
        for w in range(self.workers):
            self._send(w, ("load", {i: probs[i] for i in owned[w]}))
        self._gather(list(range(self.workers)))
        return owned

    def linearize(self, owned: list[list[int]], z, nus_split: list, *, jacobian: bool, scores: bool) -> list:
        """Each problem's blocks (in problem order) at ``z`` with its runs' nuisance ``nus_split[i]``."""
        busy = []
        for w, idx in enumerate(owned):
            if idx:
                self._send(w, ("linearize", [(i, nus_split[i]) for i in idx], z, jacobian, scores))
                busy.append(w)
        out: list = [None] * len(nus_split)
        for w, res in self._gather(busy).items():
            for i, blocks in zip(owned[w], res):
                out[i] = blocks
        return out

    def map(self, fn, shared, items: list, *, meanwhile=None) -> tuple[list, object]:
        """``[fn(shared, item) for item in items]`` in the workers (``fn`` a module-level function;
        ``shared`` sent once to each worker, the items dealt out in turn), while this process runs
        ``meanwhile()`` (None: nothing); returns (the results in order, what ``meanwhile`` returned)."""
        self._start()
        owned = [list(range(w, len(items), self.workers)) for w in range(self.workers)]
        busy = [w for w in range(self.workers) if owned[w]]
        for w in busy:
            self._send(w, ("map", fn, shared, [items[i] for i in owned[w]]))
        try:
            extra = None if meanwhile is None else meanwhile()
        finally:
            got = self._gather(busy)  # read every reply, also when meanwhile() raised
        out: list = [None] * len(items)
        for w, res in got.items():
            for i, v in zip(owned[w], res):
                out[i] = v
        return out, extra

    def close(self) -> None:
        """Stop the processes (also done when the pool is garbage-collected)."""
        if self._finalizer is not None:
            self._finalizer()
        self._procs, self._conns, self._finalizer = [], [], None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


class PersistentEvaluator(SerialEvaluator):
    """Linearizes one fit's problems in a :class:`WorkerPool` (the same results as serially)."""

    def __init__(self, probs, pool: WorkerPool):
        super().__init__(probs)
        self.pool = pool
        self.owned = pool.load(self.probs)

    def linearize(self, z, nus, *, jacobian=True, scores=False) -> list:
        per = self.pool.linearize(self.owned, z, _split(nus, self.sizes), jacobian=jacobian, scores=scores)
        return [b for blocks in per for b in blocks]

    def close(self):
        pass  # the pool outlives the fit


def with_worker_pool(fn):
    """``fn`` (which takes a keyword ``workers``) run with ``workers`` > 1 turned into a
    :class:`WorkerPool` of that many processes, kept for all of its fits and stopped when it
    returns or raises; a pool already given is used as it is (an outer call owns it)."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        w = kwargs.get("workers", 1)
        if isinstance(w, (int, np.integer)) and not isinstance(w, bool) and w >= 2:
            with WorkerPool(int(w)) as pool:
                return fn(*args, **{**kwargs, "workers": pool})
        return fn(*args, **kwargs)
    return wrapper
