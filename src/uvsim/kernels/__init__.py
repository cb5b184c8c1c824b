"""Kernels for the fixed-step RK4 (issue 46): which one runs a model, and running it.

Two kernels, chosen by name (as ``scipy.integrate.solve_ivp`` chooses methods):

``"numpy"``
    :func:`uvsim.simulate._rk4_steps` over :meth:`uvsim.model.Model.rhs`: every model, every
    plug-in; the reference.
``"numba"``
    :mod:`uvsim.kernels.rk4_equations` compiled by numba (the optional extra ``uvsim[fast]``):
    models whose terms have a compiled form (restoring, diagonal or coupled damping, thrusters
    and generalized-force inputs, a constant current; :func:`uvsim.kernels.plan.why_not_compiled`
    says why another model is not), 100-400x the numpy path's speed per trajectory.

``"auto"`` (the default) is numba where it is installed and the model allows, else numpy.  Set
it with :func:`use` (also a context manager) or the environment variable ``UVSIM_KERNEL``.
"""
from __future__ import annotations

import functools
import importlib.util
import os

from uvsim.errors import SimulationError
from uvsim.schema import did_you_mean

KERNELS = ("auto", "numpy", "numba")
_choice: str | None = None


def _check(name) -> str:
    if name not in KERNELS:
        raise SimulationError(f"kernel {name!r}: unknown{did_you_mean(str(name), list(KERNELS))}; expected one of "
                              f"{', '.join(KERNELS)}")
    return name


@functools.lru_cache(maxsize=None)
def numba_installed() -> bool:
    """True when numba can be imported (without importing it; looked up once per process: every
    integration asks)."""
    return importlib.util.find_spec("numba") is not None


def current() -> str:
    """The kernel setting in force: :func:`use`'s, else ``UVSIM_KERNEL``, else "auto"."""
    if _choice is not None:
        return _choice
    env = os.environ.get("UVSIM_KERNEL", "auto").strip().lower() or "auto"
    if env not in KERNELS:
        raise SimulationError(f"environment variable UVSIM_KERNEL={env!r}: expected one of {', '.join(KERNELS)}")
    return env


class use:
    """Set the kernel: ``uvsim.kernels.use("numpy")``, or for a block ``with uvsim.kernels.use("numpy"):``.
    ``"numba"`` refuses when numba is not installed."""

    def __init__(self, name: str):
        global _choice
        _check(name)
        if name == "numba" and not numba_installed():
            raise SimulationError("kernel 'numba': numba is not installed; pip install 'uvsim[fast]' (or numba)")
        self._previous, _choice = _choice, name

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        global _choice
        _choice = self._previous
        return False


def describe() -> str:
    """Which kernel runs the models it can, in words: ``"numba 0.68.1"`` or ``"numpy (...)"``."""
    choice = current()
    if choice == "numpy":
        return "numpy (the setting says numpy)"
    if not numba_installed():
        return "numpy (numba is not installed: pip install 'uvsim[fast]')"
    from importlib.metadata import version

    return f"numba {version('numba')} (models it cannot run: numpy)"


def _numba_allowed() -> bool:
    """True unless the setting or the install says numpy."""
    return current() != "numpy" and numba_installed()


def _compiled(name: str):
    """The compiled function ``name`` of :mod:`uvsim.kernels.numba_rk4`, or None when the setting
    or the install says numpy."""
    if not _numba_allowed():
        return None
    from uvsim.kernels import numba_rk4

    return getattr(numba_rk4, name)


def compiled_advance():
    """The compiled :func:`rk4_equations.advance`, or None when the setting or the install says numpy."""
    return _compiled("advance")


def compiled_accelerations():
    """The compiled :func:`rk4_equations.accelerations` (the equation error's accelerations along a
    measured motion), or None when the setting or the install says numpy."""
    return _compiled("accelerations")


@functools.lru_cache(maxsize=None)
def _jitted(module: str, name: str):
    import importlib

    import numba

    return numba.njit(getattr(importlib.import_module(f"uvsim.kernels.{module}"), name), cache=True, nogil=True,
                      error_model="numpy")


def compiled_uniform_table():
    """The compiled :func:`uvsim.kernels.table_lookup.uniform_table` (a thrust table on uniform knots),
    or None when the setting or the install says numpy."""
    return _jitted("table_lookup", "uniform_table") if _numba_allowed() else None


def compiled_voltage_table():
    """The compiled :func:`uvsim.kernels.table_lookup.voltage_table` (thrust tables per supply voltage),
    or None when the setting or the install says numpy."""
    return _jitted("table_lookup", "voltage_table") if _numba_allowed() else None


def compiled_window_sums():
    """The compiled :func:`uvsim.kernels.window_sums.window_sums` (a fit's window scores), or None
    when the setting or the install says numpy."""
    return _jitted("window_sums", "window_sums") if _numba_allowed() else None


def compiled_unwrapped_lag():
    """The compiled :func:`uvsim.kernels.attitude_lag.unwrapped_lag` (the attitude filter's lag on
    predicted angles), or None when the setting or the install says numpy."""
    return _jitted("attitude_lag", "unwrapped_lag") if _numba_allowed() else None
