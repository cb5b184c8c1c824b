"""What of a :class:`uvsim.model.Model` the compiled RK4 can run, packed for it.

:func:`compiled_plan` returns a :class:`CompiledPlan` (one parameter row per trajectory, the
layout of :mod:`uvsim.kernels.rk4_equations`) or None with :func:`why_not_compiled` saying
why; the model then runs on the numpy path, which is the reference in any case.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from uvsim.kernels import rk4_equations as eq


@dataclass
class CompiledPlan:
    """A model packed for :func:`uvsim.kernels.rk4_equations.advance`.

    Attributes
    ----------
    TH : (n, N_TH) one parameter row per trajectory.
    parts : the kernel's optional parts, a bit mask (``rk4_equations.CURRENT`` ...).
    held : [(term, prep)] the terms whose force is held over each sample interval.
    """

    TH: np.ndarray
    parts: int
    held: list = field(default_factory=list)

    def held_forces(self, U: np.ndarray, kind: str, V: np.ndarray | None, rows=None) -> np.ndarray:
        """The held terms' generalized force (n, m, 6) for inputs ``U`` (n, m, k) and battery
        voltages ``V`` (n, m) or None, by the terms' own numpy code; ``rows``:
        :func:`uvsim.forces.actuators.distinct_histories` of the whole run, or None."""
        tau = np.zeros(U.shape[:2] + (6,))
        for term, prep in self.held:
            tau += term.held_along(U, kind, prep, V, rows)
        return tau


#: The forms of ``ForceTerm.kernel_part`` the kernel knows.
KNOWN_PARTS = ("restoring", "diagonal", "coupled", "tether", "held", "none")


def _parts(model):
    """``(parts, None)``: each term's :meth:`~uvsim.forces.ForceTerm.kernel_part` (computed once),
    or ``(None, reason)`` when the compiled kernel cannot run ``model``."""
    if model.n_y != 13:
        return None, "a term has its own states (" + ", ".join(model.state_names[13:]) + ")"
    if model.changes_mass:
        return None, "a term changes the mass properties"
    if model.current_fn is not None:
        return None, "the current varies with time"
    parts = []
    for term, prep in zip(model.terms, model.preps):
        part = term.kernel_part(prep)
        if part is None or part[0] not in KNOWN_PARTS:
            return None, f"the term {type(term).__name__} has no compiled form"
        parts.append(part)
    if sum(part[0] == "tether" for part in parts) > 1:
        return None, "the compiled kernel has one tether"
    return parts, None


def why_not_compiled(model) -> str | None:
    """Why ``model`` runs on the numpy path (None: the compiled kernel can run it)."""
    return _parts(model)[1]


def _rows(a, n: int, shape: tuple) -> np.ndarray:
    """``a`` (shape) shared or (n, *shape) per row, as (n, prod(shape))."""
    a = np.asarray(a, float)
    return np.broadcast_to(a, (n,) + shape).reshape(n, -1)


def compiled_plan(model) -> CompiledPlan | None:
    """``model`` packed for the compiled RK4, or None when :func:`why_not_compiled` says why not."""
    parts_of_terms, why = _parts(model)
    if why is not None:
        return None
    n = model.n
    TH = np.zeros((n, eq.N_TH))
    TH[:, eq.O_MINV:eq.O_MINV + 36] = _rows(model.Minv, n, (6, 6))
    TH[:, eq.O_M:eq.O_M + 36] = _rows(model.M, n, (6, 6))
    TH[:, eq.O_MRB:eq.O_MRB + 36] = _rows(model.M_RB, n, (6, 6))
    TH[:, eq.O_MA:eq.O_MA + 36] = _rows(model.M_A, n, (6, 6))
    parts = eq.CURRENT if model.has_current else 0
    held = []
    for term, prep, part in zip(model.terms, model.preps, parts_of_terms):
        if part[0] == "restoring":
            TH[:, eq.O_G:eq.O_G + 18] += _rows(part[1], n, (3, 6))
        elif part[0] == "diagonal":
            TH[:, eq.O_DL:eq.O_DL + 6] += _rows(part[1], n, (6,))
            TH[:, eq.O_DQ:eq.O_DQ + 6] += _rows(part[2], n, (6,))
        elif part[0] == "coupled":
            TH[:, eq.O_CL:eq.O_CL + 36] += _rows(part[1], n, (6, 6))
            TH[:, eq.O_CQ:eq.O_CQ + 36] += _rows(part[2], n, (6, 6))
            parts |= eq.COUPLED
        elif part[0] == "tether":
            TH[:, eq.O_TE:eq.O_TE + 12] = _rows(part[1], n, (12,))
            parts |= eq.TETHER
        elif part[0] == "held":
            held.append((term, prep))
    TH[:, eq.O_VC:eq.O_VC + 3] = _rows(model.current_ned, n, (3,))
    return CompiledPlan(np.ascontiguousarray(TH), parts, held)
