"""One BLAS thread inside the batched simulations and fits.

The fits evaluate many small matrix products per call, and a multi-threaded BLAS only adds
synchronisation to them (worker processes give the parallelism instead).  ``threadpoolctl``'s
``threadpool_limits`` finds the loaded BLAS libraries anew at every call (it scans the
process's shared objects): about 3 ms a call and 4 % of a diagnosis' time
(docs/performance.md).  :func:`single_thread` reuses one ``ThreadpoolController`` per process.
"""
from __future__ import annotations

import os

import scipy.linalg  # noqa: F401  (scipy's own BLAS is loaded before the controller looks)
from threadpoolctl import ThreadpoolController

_CONTROLLER: tuple[int, ThreadpoolController] | None = None


def _controller() -> ThreadpoolController:
    """The process's controller (a forked worker inherits the parent's libraries, but makes
    its own controller so that the parent's bookkeeping is not shared)."""
    global _CONTROLLER
    pid = os.getpid()
    if _CONTROLLER is None or _CONTROLLER[0] != pid:
        _CONTROLLER = (pid, ThreadpoolController())
    return _CONTROLLER[1]


def single_thread():
    """Context manager limiting the BLAS libraries to one thread (restored on exit)."""
    return _controller().limit(limits=1, user_api="blas")
