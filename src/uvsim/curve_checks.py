"""The value checks of thrust-curve specifications (tables, deadbands, gains): each returns
the value or raises :class:`uvsim.errors.VehicleError` naming the field and what was expected
(:mod:`uvsim.thrust_curves`).
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import VehicleError
from uvsim import schema
from uvsim.schema import check_keys


def as_1d(x, what) -> np.ndarray:
    """``x`` as a 1-D array of finite numbers; a VehicleError naming ``what`` otherwise."""
    try:
        a = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise VehicleError(f"{what}: expected a list of numbers, got {x!r}") from None
    if a.ndim != 1:
        raise VehicleError(f"{what}: expected a 1-D list of numbers, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        i = int(np.flatnonzero(~np.isfinite(a))[0])
        raise VehicleError(f"{what}: entry {i} is {a[i]}, expected a finite number")
    return a


def number_pair(x, what) -> tuple[float, float]:
    """``x`` as two finite numbers ``(lo, hi)``; a VehicleError naming ``what`` otherwise."""
    a = as_1d(x, what)
    if a.size != 2:
        raise VehicleError(f"{what}: expected two numbers [lo, hi], got {list(a)}")
    return float(a[0]), float(a[1])


def finite_number(x, what) -> float:
    """``x`` as a finite float; a VehicleError naming ``what`` otherwise (:func:`uvsim.schema.finite_number`)."""
    return schema.finite_number(x, what, error=VehicleError)


def check_curve_keys(d, allowed, field):
    """Unknown keys of a curve specification ``d``: a VehicleError naming ``field`` (:func:`uvsim.schema.check_keys`)."""
    check_keys(d, sorted(allowed), field, error=VehicleError)


def readonly_array(a: np.ndarray) -> np.ndarray:
    """A read-only float copy of ``a`` (a curve's tables cannot be changed after its checks)."""
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a
