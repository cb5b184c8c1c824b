"""The functions of :mod:`uvsim.kernels.rk4_equations` compiled by numba, as they are.

numba compiles a function with the globals it sees; the equations module's own globals are
plain Python functions, so each function is rebuilt from its code object over a copy of the
module's globals in which its helpers are the compiled ones (the text is the one in
``rk4_equations.py``; nothing is written twice).  Compiled once per machine: numba keeps the
machine code in its cache (``__pycache__`` beside the module, or ``NUMBA_CACHE_DIR``).

Options: the equations (``rk4_equations.INLINED``) are compiled into their callers by LLVM
(``forceinline``; numba's own ``inline="always"`` gave the same code but took 70 s to compile),
so that the loops over a block's lanes of :func:`~uvsim.kernels.rk4_equations.rk4_block` and
:func:`~uvsim.kernels.rk4_equations.rhs_block` are single loop bodies that LLVM vectorises
(8 trajectories per AVX-512 instruction); they and the two block functions run without numba's
reference counting (they allocate nothing, and the counting's calls inside a loop stop the
vectoriser); ``error_model="numpy"``: a division by zero gives inf or NaN, which the blow-up
check catches, instead of a check and a branch at every division (which also stops the
vectoriser).  No ``fastmath``: the operations and their order are the
text's, so the numbers are the same bit for bit as one trajectory at a time.

numba's cache is keyed on ``rk4_equations.py`` (the functions' source file) and the machine, not on
the options above: after changing only an option here, delete ``kernels/__pycache__/*.nbi`` and
``*.nbc`` (or edit ``rk4_equations.py``), or the old machine code is loaded.
"""
from __future__ import annotations

import types

import numba

from uvsim.kernels import rk4_equations as eq


def _compile():
    g = dict(eq.__dict__)
    for name in eq.KERNEL_FUNCTIONS:
        f = getattr(eq, name)
        options = {"forceinline": True, "_nrt": False} if name in eq.INLINED else {}
        if name in ("rk4_block", "rhs_block"):
            options = {"_nrt": False}
        g[name] = numba.njit(types.FunctionType(f.__code__, g, name, f.__defaults__), cache=True, nogil=True,
                             error_model="numpy", **options)
    return g


_compiled = _compile()
advance = _compiled["advance"]
accelerations = _compiled["accelerations"]
