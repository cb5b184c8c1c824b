"""How a uvsim process's C heap keeps the memory that numpy frees (glibc only; issue 46).

A linearization allocates and frees tens of megabytes of numpy arrays: the batched trajectories
(parameter sets x windows x steps x states), the predicted measurements of every parameter set, the
Jacobian's columns.  glibc's ``malloc`` serves an array above its *mmap threshold* with a fresh
``mmap`` and gives it back to the kernel when freed, and returns the top of its heap to the kernel
once more than the *trim threshold* is free there.  Unless set, both thresholds move with what was
freed last (from 128 KiB up to 32 MiB on 64-bit; the GNU C Library manual, "Malloc Tunable
Parameters", and mallopt(3)), so a fit's alternating large and medium arrays keep being mapped and
unmapped, and every page is faulted in again by its first write.  On the docs' real-log command a
linearization of one 35-s, 100 Hz run took 132-154 ms that way and 101-108 ms with the thresholds
fixed as below (a 4-run, 14-s problem of the timing dataset 45-51 ms and 40-44 ms; records in
docs/records/performance_kernel.md).

:func:`keep_freed_memory` fixes them (``mallopt(3)``): arrays up to :data:`MMAP_THRESHOLD` come from
the heap, and up to :data:`TRIM_THRESHOLD` of freed heap stays mapped for the next allocation.  The
price is memory held by a process after its peak: at most that much.  uvsim calls it in the
processes it owns: the ``uvsim`` command and its worker processes (diagnosis, fits, the GA).  A
notebook or script that fits in its own process (``workers=1``) may call it once itself; it does
nothing where the C library is not glibc, and leaves the heap alone when the user has tuned glibc's
``malloc`` already (any ``MALLOC_*`` or ``GLIBC_TUNABLES`` variable in the environment).
"""
from __future__ import annotations

import os
import platform
import sys

#: ``mallopt(3)`` parameter numbers (glibc ``malloc.h``).
M_TRIM_THRESHOLD = -1
M_MMAP_THRESHOLD = -3
#: Arrays up to this size come from the heap, bytes: 32 MiB, the ceiling glibc's own moving
#: threshold reaches on 64-bit systems (``DEFAULT_MMAP_THRESHOLD_MAX``, mallopt(3)).
MMAP_THRESHOLD = 32 * 1024 * 1024
#: Freed heap kept mapped before any is returned to the kernel, bytes.  128 MiB to 4 GiB gave the
#: same linearization times (records); 256 MiB bounds what an idle worker holds.
TRIM_THRESHOLD = 256 * 1024 * 1024

_done: bool | None = None


def _user_tuned() -> bool:
    """True when the environment sets glibc's malloc itself (``MALLOC_TOP_PAD_``, ``MALLOC_ARENA_MAX``,
    ``GLIBC_TUNABLES``, ...)."""
    return "GLIBC_TUNABLES" in os.environ or any(k.startswith("MALLOC_") for k in os.environ)


def keep_freed_memory() -> bool:
    """Fix this process's ``malloc`` thresholds (module docstring) once; True when they are set
    (now or by an earlier call), False where nothing was changed (not glibc, ``mallopt`` missing or
    refusing, or the environment tunes ``malloc`` itself)."""
    global _done
    if _done is not None:
        return _done
    _done = False
    if not sys.platform.startswith("linux") or platform.libc_ver()[0] != "glibc" or _user_tuned():
        return False
    import ctypes

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # pragma: no cover - a glibc without mallopt
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    _done = bool(mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD))
    return _done
