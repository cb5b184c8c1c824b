"""How the runs of a fit become simulated rows: windows of about one horizon
(:class:`Layout`, :func:`layout`), whole runs padded into one batch and simulated
(:func:`padded_runs`, :func:`whole_runs`), and the 12 tangent coordinates of a 13-element
state (position, rotation vector, velocities: :func:`apply_tangent`,
:func:`tangent_difference`) in which nodes are moved and defects measured
(:mod:`uvsim.fitting.objective`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from uvsim.initial_state import INITIAL_WINDOW_S, initial_state_from_run
from uvsim.kinematics import quat_multiply
from uvsim.latency import runs_for
from uvsim.measurements import rotation_vector_error
from uvsim.model import Model
from uvsim.simulate import _rk4_loop


def _expmap(dtheta: np.ndarray) -> np.ndarray:
    """Unit quaternion (..., 4) of a rotation vector (..., 3)."""
    a = np.linalg.norm(dtheta, axis=-1, keepdims=True)
    s = np.where(a > 1e-12, np.sin(0.5 * a) / np.where(a > 1e-12, a, 1.0), 0.5)
    return np.concatenate([np.cos(0.5 * a), dtheta * s], axis=-1)


def apply_tangent(x: np.ndarray, d: np.ndarray) -> np.ndarray:
    """State(s) (..., 13) moved by tangent perturbation(s) (..., 12): position + dp,
    q (x) exp(dtheta), nu + dnu."""
    shape = np.broadcast_shapes(x.shape[:-1], d.shape[:-1]) + (13,)
    out = np.array(np.broadcast_to(x, shape), float, copy=True)
    out[..., 0:3] = x[..., 0:3] + d[..., 0:3]
    out[..., 3:7] = quat_multiply(x[..., 3:7], _expmap(d[..., 3:6]))
    out[..., 7:13] = x[..., 7:13] + d[..., 6:12]
    return out


def tangent_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a - b`` in tangent coordinates (..., 12) for states (..., 13)."""
    return np.concatenate([a[..., 0:3] - b[..., 0:3], rotation_vector_error(b[..., 3:7], a[..., 3:7]),
                           a[..., 7:13] - b[..., 7:13]], axis=-1)


@dataclass
class Layout:
    """Windows of all runs.  ``bounds[r]``: list of (start, end) sample rows of run r's
    windows; ``win_run`` (W,), ``first`` (W,) index of the first window of each run in
    the global list, ``length`` (W,) samples per window, ``T``/``U`` (W, L[, k]) padded
    times and inputs, and per run the owner window ``own_win`` and position ``own_pos``
    of every sample."""

    bounds: list
    win_run: np.ndarray
    first: np.ndarray
    length: np.ndarray
    T: np.ndarray
    U: np.ndarray
    own_win: list
    own_pos: list
    V: np.ndarray | None = None   # (W, L) battery voltage (NaN: nominal), None when no run logs one

    @property
    def W(self) -> int:
        return self.win_run.size


def layout(runs, horizon: float | None) -> Layout:
    """Cut runs into windows of about ``horizon`` seconds (module docstring); a last
    piece shorter than half a horizon joins the previous window."""
    bounds, win_run, first = [], [], []
    for r, run in enumerate(runs):
        t = run.t
        n = t.size
        if horizon is None or t[-1] - t[0] <= horizon * 1.5:
            cuts = [0, n - 1]
        else:
            cuts = [0]
            while True:
                nxt = int(np.searchsorted(t, t[cuts[-1]] + horizon - 1e-9))
                if nxt >= n - 1 or t[-1] - t[nxt] < 0.5 * horizon:
                    cuts.append(n - 1)
                    break
                cuts.append(nxt)
        first.append(len(win_run))
        bounds.append(list(zip(cuts[:-1], cuts[1:])))
        win_run += [r] * (len(cuts) - 1)
    win_run = np.array(win_run, int)
    length = np.array([e - s + 1 for b in bounds for s, e in b], int)
    L = int(length.max())
    k = len(runs[0].input_columns)
    T = np.empty((win_run.size, L))
    U = np.empty((win_run.size, L, k))
    V = np.full((win_run.size, L), np.nan) if any(r.voltage is not None for r in runs) else None
    own_win, own_pos = [], []
    w = 0
    for r, run in enumerate(runs):
        t, u, v = run.t, run.inputs, run.voltage
        ow = np.empty(t.size, int)
        op = np.empty(t.size, int)
        for j, (s, e) in enumerate(bounds[r]):
            m = e - s + 1
            T[w, :m], T[w, m:] = t[s:e + 1], t[e]
            U[w, :m], U[w, m:] = u[s:e + 1], u[e]
            if V is not None and v is not None:
                V[w, :m], V[w, m:] = v[s:e + 1], v[e]
            last = j == len(bounds[r]) - 1
            rows = np.arange(s, e + 1 if last else e)
            ow[rows], op[rows] = w, rows - s
            w += 1
        own_win.append(ow)
        own_pos.append(op)
    return Layout(bounds, win_run, np.array(first, int), length, T, U, own_win, own_pos, V)


def padded_runs(runs):
    """Whole runs padded to one length (the last sample held): T (R, n), U (R, n, k) and
    V (R, n) (NaN where not logged) or None when no run logs a voltage."""
    R = len(runs)
    n = max(r.t.size for r in runs)
    T = np.empty((R, n))
    U = np.empty((R, n, len(runs[0].input_columns)))
    V = np.full((R, n), np.nan) if any(r.voltage is not None for r in runs) else None
    for i, run in enumerate(runs):
        t, u, v = run.t, run.inputs, run.voltage  # (each is read from the run's table)
        m = t.size
        T[i, :m], T[i, m:] = t, t[-1]
        U[i, :m], U[i, m:] = u, u[-1]
        if V is not None and v is not None:
            V[i, :m], V[i, m:] = v, v[-1]
    return T, U, V


def whole_runs(vehicle, runs, sensors, space, z, *, initial_velocity: str = "zero", nu0=None, accel: bool = False,
               pos0=None):
    """Whole-run simulations of ``runs`` (one input kind) with the parameters ``z`` of
    ``space``, from the runs' estimated initial states (``sensors``: per run, what its
    measurement model reads); all runs in one batch.  Returns (states (R, n_max, n_y),
    accelerations (R, n_max, 6) or None, the model).  The inputs act as late as the vehicle's
    sensors read (``sensor_latency``, :mod:`uvsim.latency`).  ``pos0`` (R, 3), where finite,
    replaces the estimated initial positions (a window's dead-reckoned start, :func:`uvsim.fitting.evaluate.windowed`)."""
    runs = runs_for(vehicle, runs)
    R = len(runs)
    T, U, V = padded_runs(runs)
    P0, Q0, N0 = [], [], []
    for run, sens in zip(runs, sensors):
        p, q, v, _ = initial_state_from_run(run, initial_velocity=initial_velocity, window_s=INITIAL_WINDOW_S,
                                            sensors=sens)
        P0.append(p), Q0.append(q), N0.append(v)
    P0 = np.array(P0)
    if pos0 is not None:
        pos0 = np.asarray(pos0, float)
        P0 = np.where(np.isfinite(pos0), pos0, P0)
    model = Model(vehicle, space.overrides(np.atleast_2d(np.asarray(z, float)), R), n=R,
                  input_kind=runs[0].input_kind)
    model.check_inputs(U.shape[2], where=f"run {runs[0].name}")
    y0 = model.initial_state(P0, np.array(Q0), np.array(N0) if nu0 is None else nu0, U[:, 0])
    acc = np.empty((R, T.shape[1], 6)) if accel else None
    Y = _rk4_loop(model, T, U, y0, 1, "nan", accel=acc, V=V)
    return Y, acc, model
