"""Equation-error (inverse-dynamics) fits: fast, convex-ish, used to screen and seed.

Along the *measured* motion (smoothed pose, Savitzky-Golay velocities ``nu`` and
accelerations ``nu_dot``, :mod:`uvsim.estimation.derivatives`) the model predicts an
acceleration ``f(eta, nu, u; theta)`` (:meth:`uvsim.model.Model.rhs`); the generalized
force the model misses is

    tau_res(theta) = M0 (nu_dot_meas - S f(eta, nu, u; theta))

(``M0`` the given model's mass matrix, so the residual is in N and N m; ``S`` the same
Savitzky-Golay smoothing applied twice, because the measured acceleration went through
two filters, position -> nu -> nu_dot: input steps then leave no filter artefact).  No
simulation is involved, so the cost of a parameter set is one vectorized ``rhs`` over
all samples, and for effects whose force is linear in their parameters (current to
first order, ballast, an elastic tether in stiffness and pull, gains) the fit is
linear least squares in disguise: the classical "equation error" of system
identification (Ljung 1999, sec. 7.3).  Its estimates are biased by the noise of the
differentiated data and it needs the degrees of freedom the log can differentiate
(``have``: all of u, v, w for forces, all of p, q, r for moments), so diagnosis uses it
to rank candidate effects and to start their output-error fits
(:func:`uvsim.fitting.fit`), never to decide.

Term states (a thruster lag) are integrated along the measured motion for each
parameter set (the vehicle state teacher-forced), exactly as in the windowed fits.
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.ndimage import convolve1d
from scipy.optimize import least_squares

from uvsim.estimation.savgol import is_uniform, savgol_on_stamps
from uvsim.blas import single_thread
from uvsim.errors import CalibrationError, UvsimError
from uvsim.estimation.derivatives import body_acceleration, body_velocity
from uvsim.fitting.dead_reckoning import dead_reckoned_xy
from uvsim.kernels import compiled_accelerations
from uvsim.kernels.plan import compiled_plan
from uvsim.kinematics import euler_to_quat, unwrap_angles
from uvsim.model import Model

#: Savitzky-Golay window (s) and order of the differentiation: the second derivative
#: amplifies noise, so a longer window than for initial velocities (2-5 mm position
#: noise at 20-100 Hz); still short against the 1-3 s time constants of an ROV.
WINDOW_S = 1.0
POLYORDER = 3
#: The residual is evaluated on the samples of a grid of about this rate (Hz): the
#: smoothed accelerations hold nothing faster than ~1 / WINDOW_S, so a faster log only
#: costs time (the model's acceleration is smoothed on the coarser grid with the same
#: window in seconds; term states are carried at the log's full rate).
EVAL_RATE_HZ = 12.5


@dataclass
class Motion:
    """Measured motion of one run for the equation error.

    Attributes
    ----------
    name : run name.  t : (n,) times.  U : (n, k) inputs.  input_kind.
    V : (n,) battery voltage (NaN: nominal) or None.
    y : (n, 13) states along the measured motion (smoothed pose, velocities).
    nud : (n, 6) measured accelerations.
    have : (6,) bool, which DOFs can be differentiated from the log.
    valid : (n,) bool, samples used (the filter's end segments are not).
    win : Savitzky-Golay window in samples.
    """

    name: str
    t: np.ndarray
    U: np.ndarray
    input_kind: str
    y: np.ndarray
    nud: np.ndarray
    have: np.ndarray
    valid: np.ndarray
    win: int
    V: np.ndarray | None = None
    sub: np.ndarray | None = None   # rows of the evaluation grid
    win_sub: int = 0                # Savitzky-Golay window on that grid, samples

    def __post_init__(self):
        dt = float(np.median(np.diff(self.t)))
        k = max(1, int(np.floor(1.0 / (EVAL_RATE_HZ * dt))))
        self.sub = np.arange(0, self.t.size, k)
        w = int(round(WINDOW_S / (k * dt))) | 1
        self.win_sub = max(w, POLYORDER + 2 + (POLYORDER + 1) % 2)
        # the evaluation grid's pieces, taken once (every evaluation of every candidate reads them)
        self.dt_sub = float(np.median(np.diff(self.t[self.sub])))
        self.y_sub, self.U_sub, self.nud_sub = self.y[self.sub], self.U[self.sub], self.nud[self.sub]
        self.V_sub = None if self.V is None else self.V[self.sub]
        self.valid_sub = self.valid[self.sub]


#: Model rows (parameter sets x evaluation samples) per batched equation-error evaluation.
CHUNK_ROWS = 25000
#: The same on the compiled path, which holds no (rows, ...) intermediate of the numpy ``rhs``:
#: a Jacobian's parameter sets in one call (one model, one packing; the per-set numbers are
#: the same in any chunking)
CHUNK_ROWS_COMPILED = 500000


def _sg(x, win, deriv=0, dt=1.0, axis=-2, mode="interp"):
    if mode != "interp":  # what savgol_filter does for these modes, with the coefficients cached
        return convolve1d(x, _sg_coeffs(win, deriv, float(dt)), axis=axis, mode=mode)
    from scipy.signal import savgol_filter  # here, not at import (0.6 s of every command's start)

    return savgol_filter(x, win, POLYORDER, deriv=deriv, delta=dt, axis=axis, mode=mode)


@lru_cache(maxsize=256)
def _sg_coeffs(win: int, deriv: int, dt: float) -> np.ndarray:
    from scipy.signal import savgol_coeffs

    return savgol_coeffs(win, POLYORDER, deriv=deriv, delta=dt)


def measured_motion(run, *, window_s: float = WINDOW_S) -> Motion | None:
    """The :class:`Motion` of ``run``, or None when the log allows no DOF (gaps, too short,
    or neither full velocities nor full rates; jittered stamps are fine); why:
    :func:`motion_or_why`."""
    return motion_or_why(run, window_s=window_s)[0]


def motion_or_why(run, *, window_s: float = WINDOW_S) -> tuple[Motion | None, str | None]:
    """``(Motion, None)`` for ``run``, or ``(None, why)`` naming what the log lacks for the
    equation error, so that a caller that leaves the run out can say why.

    Parameters
    ----------
    run : :class:`uvsim.logs.Run`.
    window_s : Savitzky-Golay window of the differentiation, s.
    """
    try:
        nu = body_velocity(run, window_s=window_s)
        nud = body_acceleration(run, nu, window_s=window_s)
    except CalibrationError as exc:
        return None, str(exc)
    have = np.isfinite(nu).all(axis=0) & np.isfinite(nud).all(axis=0)
    have = np.array([have[:3].all()] * 3 + [have[3:].all()] * 3)
    if not have.any():
        return None, (f"{run.name}: neither complete body velocities (u, v, w, or x, y, z with the attitude to "
                      "differentiate) nor complete rates (p, q, r, or the whole attitude to differentiate)")
    t = run.t
    n = t.size
    dt = float(np.median(np.diff(t)))
    win = int(round(window_s / dt)) | 1
    win = max(win, POLYORDER + 2 + (POLYORDER + 1) % 2)
    if win > n // 2:
        return None, (f"{run.name}: {n} samples ({t[-1] - t[0]:.3g} s); the equation error needs {2 * win}, twice "
                      f"its {window_s:g} s Savitzky-Golay window")
    y = np.zeros((n, 13))
    pos = run.position
    uniform = is_uniform(t)

    def smooth(x):  # jittered stamps: the local fits on the actual time offsets (uvsim.estimation.savgol)
        return _sg(x, win, axis=0) if uniform else savgol_on_stamps(t, x, win, POLYORDER)

    for j in range(3):
        col = pos[:, j]
        if np.isfinite(col).all():
            y[:, j] = smooth(col)
    track = dead_reckoned_xy(run)
    if track is not None:  # no x/y logged: the track from the attitude and the DVL (a tether reads it)
        y[:, :2] = track
    e = unwrap_angles(run.euler)
    e = np.where(np.isfinite(e), e, 0.0)
    y[:, 3:7] = euler_to_quat(smooth(e))
    y[:, 7:13] = np.where(np.isfinite(nu), nu, 0.0)
    valid = np.ones(n, bool)
    half = win // 2
    valid[:half] = False
    valid[n - half:] = False
    return Motion(run.name, t, run.inputs, run.input_kind, y, np.where(np.isfinite(nud), nud, 0.0), have, valid, win,
                  run.voltage), None


#: id of a vehicle object -> (a weak reference to it, the input kinds for which its models were
#: found to run compiled) (:meth:`EquationError._compiled`); an entry goes with its vehicle.
_COMPILED_VEHICLES: dict = {}


def _remember_compiled(vehicle, kinds: frozenset) -> None:
    key = id(vehicle)
    ref, known = _COMPILED_VEHICLES.get(key, (None, frozenset()))
    if ref is None or ref() is not vehicle:
        try:
            ref = weakref.ref(vehicle, lambda _r, key=key: _COMPILED_VEHICLES.pop(key, None))
        except TypeError:  # (an object that cannot be weakly referenced: looked up each time)
            return
        known = frozenset()
    _COMPILED_VEHICLES[key] = (ref, known | kinds)


class EquationError:
    """Normalized inverse-dynamics residuals of ``motions`` for batches of parameter
    sets of ``space`` (module docstring).

    Parameters
    ----------
    vehicle : the model (effects added).
    motions : :class:`Motion` list (one input kind per call of :meth:`forces`; runs of
        several kinds are handled by grouping).
    space : :class:`uvsim.fitting.parameters.ParameterSpace`.
    M0 : (6, 6) mass matrix converting accelerations to forces (default the vehicle's).
    scale : (6,) normalization per DOF (default: a robust standard deviation of the
        residual at the start values).
    """

    def __init__(self, vehicle, motions, space, *, M0=None, scale=None):
        self.vehicle, self.motions, self.space = vehicle, [m for m in motions if m is not None], space
        if not self.motions:
            raise CalibrationError("no run allows an equation-error fit (need complete position + attitude, or "
                                   "velocities and rates, without gaps)")
        self.M0 = np.asarray(vehicle.M if M0 is None else M0, float)
        self._compiled_path = None
        self.scale = None
        if scale is None:
            r = self.forces(space.z0[None])
            s = np.ones(6)
            for j in range(6):  # robust spread per DOF; a DOF the log cannot give (all NaN) keeps 1
                x = r[0][..., j]
                x = x[np.isfinite(x)]
                if x.size:
                    s[j] = 1.4826 * np.median(np.abs(x - np.median(x)))
            self.scale = np.where(np.isfinite(s) & (s > 0), s, 1.0)
        else:
            self.scale = np.asarray(scale, float)

    def _term_states(self, Z: np.ndarray, ms: list, kind: str) -> list:
        """Term states along the measured motion (vehicle state teacher-forced, RK4), all
        runs ``ms`` and parameter sets Z (P, p) at once; per run (P, n, n_term)."""
        P, R = Z.shape[0], len(ms)
        L = max(m.t.size for m in ms)
        T = np.empty((R, L))
        Y = np.empty((R, L, 13))
        U = np.empty((R, L, ms[0].U.shape[1]))
        V = np.full((R, L), np.nan) if any(m.V is not None for m in ms) else None
        for j, m in enumerate(ms):
            n = m.t.size
            T[j, :n], T[j, n:] = m.t, m.t[-1]  # padding: zero-length steps
            Y[j, :n], Y[j, n:] = m.y, m.y[-1]
            U[j, :n], U[j, n:] = m.U, m.U[-1]
            if V is not None and m.V is not None:
                V[j, :n], V[j, n:] = m.V, m.V[-1]
        model = Model(self.vehicle, self.space.overrides(Z, R), n=P * R, input_kind=kind)
        nt = model.n_y - 13
        Tt, Yt, Ut = np.tile(T, (P, 1)), np.tile(Y, (P, 1, 1)), np.tile(U, (P, 1, 1))
        Vt = None if V is None else np.tile(V, (P, 1))
        closed = model.term_states_along(Tt, Ut, Vt)
        if closed is not None:  # input-only states (a lag): exact, no integration along the motion
            closed = closed.reshape(P, R, L, nt)
            return [closed[:, j, : m.t.size] for j, m in enumerate(ms)]
        x = model.initial_state(u0=Ut[:, 0])[:, 13:]
        xs = np.empty((P * R, L, nt))
        xs[:, 0] = x

        def f(yy, xx, u, v):
            return model.rhs(0.0, np.concatenate([yy, xx], 1), u, v, states_only=True)

        for i in range(L - 1):
            h = (Tt[:, i + 1] - Tt[:, i])[:, None]
            ya, yb = Yt[:, i], Yt[:, i + 1]
            ym = 0.5 * (ya + yb)
            u = Ut[:, i]
            v = None if Vt is None else Vt[:, i]
            k1 = f(ya, x, u, v)
            k2 = f(ym, x + 0.5 * h * k1, u, v)
            k3 = f(ym, x + 0.5 * h * k2, u, v)
            k4 = f(yb, x + h * k3, u, v)
            x = x + h / 6.0 * (k1 + 2 * (k2 + k3) + k4)
            xs[:, i + 1] = x
        xs = xs.reshape(P, R, L, nt)
        return [xs[:, j, : m.t.size] for j, m in enumerate(ms)]

    def forces(self, Z: np.ndarray) -> list:
        """Per run, ``tau_res`` (P, n_eval, 6) in N / N m on the run's evaluation grid
        (:data:`EVAL_RATE_HZ`), NaN for DOFs the log cannot give and for the filter's end
        segments.  Runs of one input kind share one ``rhs`` call, and runs of one length,
        window and step share each smoothing call (each run is filtered along its own time
        axis, so the result is that of one call per run)."""
        Z = np.atleast_2d(Z)
        P = Z.shape[0]
        out: list = [None] * len(self.motions)
        groups: dict = {}
        for i, m in enumerate(self.motions):
            groups.setdefault((m.input_kind, m.U.shape[1]), []).append(i)
        with single_thread(), np.errstate(all="ignore"):
            for (kind, _), idx in groups.items():
                ms = [self.motions[i] for i in idx]
                N = sum(m.sub.size for m in ms)
                Y = np.concatenate([m.y_sub for m in ms])
                U = np.concatenate([m.U_sub for m in ms])
                V = None
                if any(m.V is not None for m in ms):
                    V = np.concatenate([m.V_sub if m.V is not None else np.full(m.sub.size, np.nan) for m in ms])
                acc = self._compiled_accelerations(Z, kind, Y, U, V)
                if acc is None:  # the numpy path: one model row per parameter set and sample
                    model = Model(self.vehicle, self.space.overrides(Z, N), n=P * N, input_kind=kind)
                    Yp = np.tile(Y, (P, 1))
                    if model.n_y > 13:  # term states per run and parameter set, stacked like Yp
                        xs = self._term_states(Z, ms, kind)
                        xs = np.concatenate([x[:, m.sub] for x, m in zip(xs, ms)], axis=1)
                        Yp = np.concatenate([Yp, xs.reshape(P * N, -1)], 1)
                    Up = np.tile(U, (P, 1))
                    Vp = None if V is None else np.tile(V, P)
                    acc = model.rhs(0.0, Yp, Up, Vp)[:, 7:13].reshape(P, N, 6)
                starts = np.cumsum([0] + [m.sub.size for m in ms])
                buckets: dict = {}
                for j, m in enumerate(ms):
                    buckets.setdefault((m.sub.size, m.win_sub, m.dt_sub), []).append(j)
                for (n, win, dt), js in buckets.items():
                    ac = np.stack([acc[:, starts[j]:starts[j] + n] for j in js], axis=1)  # (P, k, n, 6)
                    for _ in range(2):  # the ends are not used, so no polynomial fit there ("nearest")
                        ac = _sg(ac, win, dt=dt, mode="nearest")
                    for jj, j in enumerate(js):
                        m = ms[j]
                        res = (m.nud_sub[None] - ac[:, jj]) @ self.M0.T
                        res[:, :, ~m.have] = np.nan
                        res[:, ~m.valid_sub] = np.nan
                        out[idx[j]] = res
        return out

    def _compiled_accelerations(self, Z: np.ndarray, kind: str, Y, U, V) -> np.ndarray | None:
        """The accelerations (P, N, 6) of the parameter sets ``Z`` (P, p) at the states ``Y``
        (N, 13) with inputs ``U`` (N, k) and voltages ``V`` (N,) or None, by the compiled
        equations (:func:`uvsim.kernels.rk4_equations.accelerations`: one model row per
        parameter set, the actuators' held forces by their own numpy code with the thrust curves
        once for the shared inputs); None where the setting, the install or the model says numpy
        (:func:`uvsim.kernels.plan.why_not_compiled`), which :meth:`forces` then runs."""
        kernel = compiled_accelerations()
        if kernel is None:
            return None
        P = Z.shape[0]
        model = Model(self.vehicle, self.space.overrides(Z), n=P, input_kind=kind)
        plan = compiled_plan(model)
        if plan is None:
            return None
        N = Y.shape[0]
        # every parameter set sees the same inputs: distinct_histories' answer, known here
        same = (np.zeros(1, int), np.zeros(P, int))
        tau = plan.held_forces(np.broadcast_to(U, (P,) + U.shape), kind,
                               None if V is None else np.broadcast_to(V, (P, N)), same)
        acc = np.empty((P, N, 6))
        kernel(np.ascontiguousarray(Y, dtype=float), np.ascontiguousarray(tau), plan.TH, plan.parts, acc)
        return acc

    def _compiled(self) -> bool:
        """Whether :meth:`forces` takes the compiled path (:meth:`_compiled_accelerations`) for
        this model (looked up once, on a one-row model: what the chunk size depends on, and only
        that: every set's residual is the same in any chunking).  Whether a model runs compiled
        depends on its terms, not on their values, so a yes is kept per vehicle object (the
        screening builds an evaluation per Gauss-Newton step of the same candidate)."""
        if self._compiled_path is None:
            kinds = frozenset(m.input_kind for m in self.motions)
            ref, known = _COMPILED_VEHICLES.get(id(self.vehicle), (None, None))
            if ref is not None and ref() is self.vehicle and kinds <= known:
                self._compiled_path = compiled_accelerations() is not None
                return self._compiled_path
            try:
                self._compiled_path = compiled_accelerations() is not None and all(
                    compiled_plan(Model(self.vehicle, self.space.overrides(self.space.z0[None]), n=1,
                                        input_kind=kind)) is not None for kind in kinds)
            except (UvsimError, ValueError, np.linalg.LinAlgError):  # a start the model refuses: the evaluation says why
                self._compiled_path = False
            if self._compiled_path:
                _remember_compiled(self.vehicle, kinds)
        return self._compiled_path

    def residuals(self, Z: np.ndarray) -> np.ndarray:
        """Normalized residual vectors (P, m) over the valid entries.  Large batches of
        parameter sets are evaluated in chunks of about :data:`CHUNK_ROWS` model rows
        (the arrays stay in cache: 0.64 s -> 0.41 s for 61 sets of a 33-run dataset,
        docs/performance.md); every set's residual is computed alone, so the result is
        the same."""
        Z = np.atleast_2d(Z)
        rows = sum(m.sub.size for m in self.motions)
        per = max(1, (CHUNK_ROWS_COMPILED if self._compiled() else CHUNK_ROWS) // max(rows, 1))
        if Z.shape[0] > per:
            return np.concatenate([self._residuals(Z[a:a + per]) for a in range(0, Z.shape[0], per)], axis=0)
        return self._residuals(Z)

    def _residuals(self, Z: np.ndarray) -> np.ndarray:
        parts = []
        for m, r in zip(self.motions, self.forces(Z)):
            sel = m.valid_sub[:, None] & m.have[None, :]
            parts.append((r / self.scale)[:, sel])
        v = np.concatenate(parts, axis=1)
        return np.where(np.isfinite(v), v, 30.0)

    def jacobian(self, z0=None, step: float = 1e-6) -> tuple[np.ndarray, np.ndarray]:
        """Forward-difference Jacobian (p, m) with respect to the scaled variables at ``z0``
        (default the space's start) and the residual (m,) there, in one batched evaluation."""
        sp = self.space
        z = sp.z0 if z0 is None else np.asarray(z0, float)
        h = step * np.maximum(1.0, np.abs(z))
        h = np.where(z + h > sp.z_upper, -h, h)
        R = self.residuals(np.vstack([z, z + np.diag(h)]))
        return (R[1:] - R[0]) / h[:, None], R[0]

    def gauss_newton(self, z0=None, *, iterations: int = 3) -> dict:
        """A few bounded Gauss-Newton steps from ``z0`` (exact in one step for parameters
        that enter the force linearly); each step costs one batched evaluation of
        ``1 + p`` parameter sets.  Returns like :meth:`fit`."""
        sp = self.space
        lo, hi = sp.z_lower, sp.z_upper
        z = np.clip(sp.z0 if z0 is None else np.asarray(z0, float), lo, hi)
        r0 = None
        best = None
        for _ in range(max(iterations, 1)):
            h = 1e-6 * np.maximum(1.0, np.abs(z))
            h = np.where(z + h > hi, -h, h)
            R = self.residuals(np.vstack([z, z + np.diag(h)]))
            r = R[0]
            if r0 is None:
                r0 = r
            if best is None or r @ r < best[1]:
                best = (z.copy(), float(r @ r))
            if sp.p == 0:
                break
            J = ((R[1:] - r) / h[:, None]).T
            dz = np.linalg.lstsq(J, -r, rcond=None)[0]
            z = np.clip(z + dz, lo, hi)
        r = self.residuals(z[None])[0]
        if r @ r < best[1]:
            best = (z, float(r @ r))
        return {"z": best[0], "values": sp.as_dict(best[0]), "rss": best[1], "rss0": float(r0 @ r0), "n": int(r.size)}

    def fit(self, z0=None, *, max_nfev: int = 30) -> dict:
        """Least-squares fit (trust-region reflective within the space's bounds).  Returns
        dict with ``z``, ``values``, ``rss``, ``rss0`` (at the start), ``n``."""
        sp = self.space
        z0 = sp.z0 if z0 is None else np.asarray(z0, float)
        lo, hi = sp.z_lower, sp.z_upper
        z0 = np.clip(z0, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
        r0 = self.residuals(z0[None])[0]
        if sp.p == 0:
            return {"z": z0, "values": {}, "rss": float(r0 @ r0), "rss0": float(r0 @ r0), "n": r0.size}
        cache = {}

        def fun(z):
            key = z.tobytes()
            if key not in cache:
                cache.clear()
                cache[key] = self.residuals(z[None])[0]
            return cache[key]

        def jac(z):
            h = 1e-6 * np.maximum(1.0, np.abs(z))
            h = np.where(z + h > hi, -h, h)
            Z = np.vstack([z, z + np.diag(h)])
            R = self.residuals(Z)
            return ((R[1:] - R[0]) / h[:, None]).T

        res = least_squares(fun, z0, jac=jac, bounds=(lo, hi), method="trf", max_nfev=max_nfev, x_scale=1.0)
        r = fun(res.x)
        return {"z": res.x, "values": sp.as_dict(res.x), "rss": float(r @ r), "rss0": float(r0 @ r0),
                "n": int(r.size), "nfev": int(res.nfev)}
