"""The functions of :mod:`uvsim.kernels.rk4_equations` compiled by numba, as they are.

numba compiles a function with the globals it sees; the equations module's own globals are
plain Python functions, so each function is rebuilt from its code object over a copy of the
module's globals in which its helpers are the compiled ones (the text is the one in
``rk4_equations.py``; nothing is written twice).  Compiled once per machine: numba keeps the
machine code in its cache (``__pycache__`` beside the module, or ``NUMBA_CACHE_DIR``).
"""
from __future__ import annotations

import types

import numba

from uvsim.kernels import rk4_equations as eq


def _compile():
    g = dict(eq.__dict__)
    for name in eq.KERNEL_FUNCTIONS:
        f = getattr(eq, name)
        g[name] = numba.njit(types.FunctionType(f.__code__, g, name, f.__defaults__), cache=True, nogil=True)
    return g


_compiled = _compile()
advance = _compiled["advance"]
accelerations = _compiled["accelerations"]
