"""The truth model: 6-DOF equations of motion of an open-frame ROV, integrated with RK4.

Written from the equations (seed 000 eq. 1-12, Fossen 2021 ch. 2, 3, 6, 10), in the
Newton-Euler / Kirchhoff vector form, independently of ``uvsim.model``.  Every array is
stored *component first* (``(3, n)``, ``(6, n)``, ``(6, 6, n)``): ``n`` trajectories
(the runs of a dataset, each with its own parameters) advance together.

State per trajectory: NED position ``p`` (3), unit quaternion body->NED ``q = [w, x, y, z]``
(4), body velocity ``nu = [u, v, w, p, q, r]`` (6), then the actuator-lag states (``a``).

Kinematics (Fossen 2021 eq. 2.72, 2.78)::

    p_dot = R(q) v,        q_dot = 1/2 [ -eps . omega ;  eta omega + eps x omega ]

Kinetics with a current ``v_c`` constant in NED (Fossen 2021 eq. 10.1-10.9), relative
velocity ``nu_r = nu - [R^T v_c; 0]``, ``nu_c_dot = [-omega x R^T v_c; 0]``::

    (M_RB + M_A) nu_dot = tau - C_RB(nu) nu - C_A(nu_r) nu_r + D_L nu_r + D_Q |nu_r| nu_r
                          + g_loads + M_A nu_c_dot

* ``M_RB`` (Fossen 2021 eq. 3.44) from mass ``m``, CG ``r_g`` and inertia ``I_o`` about the
  origin; ``M_A`` a symmetric positive 6x6 matrix.
* ``C_RB(nu) nu`` in the Newton-Euler form about the origin (Fossen 2021 eq. 3.57)::

      [ m (omega x v + omega x (omega x r_g)) ;  omega x (I_o omega) + m r_g x (omega x v) ]

* ``C_A(nu_r) nu_r`` in Kirchhoff's form (Fossen 2021 eq. 6.43 times ``nu_r``), with
  ``[a1; a2] = M_A nu_r``::

      [ omega x a1 ;  v_r x a1 + omega x a2 ]

* damping: diagonal, paper sign (seed 000 eq. 7-9), on ``nu_r``; optionally a translational
  quadratic drag along the relative velocity, ``D_i |v_r| v_r,i`` (``along_flow``).
* restoring (``g_loads``): vertical point loads ``F_i`` (N, + down) at ``r_i`` on the body:
  weight ``W`` at ``r_g``, buoyancy ``-B`` at ``r_b``, ballast.  With ``k = R^T e_3``,
  ``g_loads = [(sum F_i) k ; (sum F_i r_i) x k]``.
* actuators: ``tau = A f`` with ``f`` the delivered actuator outputs (thrusts, or the
  components of a generalized force) and ``A`` the allocation (``[d_i; r_i x d_i]``
  columns).  A first-order lag ``T f_dot = f_e - f`` per output when ``T > 0``.
* extra wrenches (tether, coupled damping, periodic disturbance) as callables.

Inputs are held constant over each log interval (zero-order hold).  RK4 with fixed
sub-steps; the quaternion is renormalized after each step.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from uvsim.errors import SimulationError
from uvsim.scenarios import dynamics_compiled

POS, QUAT, NU = slice(0, 3), slice(3, 7), slice(7, 13)
N_BASE = 13


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product of component-first arrays ``(3, n) x (3, n) -> (3, n)``."""
    return np.array((a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]))


def matvec(M: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``(r, c, n) @ (c, n) -> (r, n)`` per trajectory, or ``(r, c) @ (c, n)`` for a matrix
    shared by all trajectories."""
    return M @ x if M.ndim == 2 else np.einsum("ijn,jn->in", M, x)


def _shared(M: np.ndarray) -> np.ndarray:
    """``M[..., 0]`` when every trajectory has the same matrix, else ``M``."""
    return M[..., 0].copy() if np.all(M == M[..., :1]) else M


def rotation(q: np.ndarray) -> np.ndarray:
    """Body->NED rotation matrices ``(3, 3, n)`` of unit quaternions ``q`` (4, n),
    scalar first (Fossen 2021 eq. 2.72)."""
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def to_body(R: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``R^T v`` for ``R`` (3, 3, n), ``v`` (3, n)."""
    return np.einsum("jin,jn->in", R, v)


def skew(a: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrix ``S(a)`` with ``S(a) b = a x b``, for one vector (3,)."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def rigid_body_mass_matrix(mass: float, r_g, inertia) -> np.ndarray:
    """``M_RB = [[m I, -m S(r_g)], [m S(r_g), I_o]]`` (Fossen 2021 eq. 3.44), (6, 6)."""
    S = skew(np.asarray(r_g, dtype=float))
    return np.block([[mass * np.eye(3), -mass * S], [mass * S, np.asarray(inertia, dtype=float)]])


@dataclass
class Context:
    """What a wrench callable sees at one RK4 stage (component-first arrays)."""

    t: float
    pos: np.ndarray      # (3, n) NED position of the body origin, m
    R: np.ndarray        # (3, 3, n) body->NED
    nu: np.ndarray       # (6, n) body velocity
    nu_r: np.ndarray     # (6, n) body velocity relative to the water


Wrench = Callable[[Context], np.ndarray]


@dataclass
class Plant:
    """Physical parameters of ``n`` trajectories (component-first arrays).

    Attributes
    ----------
    mass : (n,) kg, rigid-body mass (vehicle plus any ballast).
    r_g : (3, n) m, centre of gravity in body axes.
    inertia : (3, 3, n) kg m^2, inertia tensor about the body origin.
    added_mass : (6, 6, n) positive added-mass matrix.
    linear, quadratic : (6, n) damping coefficients, paper sign (negative).
    load : (n,) N, sum of the vertical point loads (weight - buoyancy + ballast), + down.
    load_moment : (3, n) N m, ``sum F_i r_i`` of those loads.
    current : (3, n) m/s, NED current.
    allocation : (6, a, n) actuator outputs -> generalized force.
    lag_time : (a, n) s, first-order lag per output (0: none).
    along_flow : (3, n) translational quadratic drag along the relative velocity, paper sign:
        ``tau_i += D_i |v_r| v_r,i`` (the field logs' truth, :mod:`uvsim.scenarios.field`); zeros
        when not given.
    wrenches : extra generalized forces, each ``f(ctx) -> (6, n)``.
    """

    mass: np.ndarray
    r_g: np.ndarray
    inertia: np.ndarray
    added_mass: np.ndarray
    linear: np.ndarray
    quadratic: np.ndarray
    load: np.ndarray
    load_moment: np.ndarray
    current: np.ndarray
    allocation: np.ndarray
    lag_time: np.ndarray
    wrenches: list = field(default_factory=list)
    along_flow: np.ndarray | None = None

    def __post_init__(self):
        n = self.mass.shape[0]
        if self.along_flow is None:
            self.along_flow = np.zeros((3, n))
        self.has_along_flow = bool(np.any(self.along_flow != 0.0))
        M = np.empty((6, 6, n))
        for i in range(n):
            M[:, :, i] = rigid_body_mass_matrix(self.mass[i], self.r_g[:, i], self.inertia[:, :, i])
        M += self.added_mass
        self.M = M
        self.M_inv = _shared(np.linalg.inv(M.transpose(2, 0, 1)).transpose(1, 2, 0))
        # matrices common to all trajectories (the usual case) are applied as one matrix product
        self.inertia_op = _shared(self.inertia)
        self.added_mass_op = _shared(self.added_mass)
        self.allocation_op = _shared(self.allocation)
        self.has_current = bool(np.any(self.current != 0.0))
        self.has_cg_offset = bool(np.any(self.r_g != 0.0))
        self.lagged = self.lag_time > 0.0
        self.rate = np.where(self.lagged, 1.0 / np.where(self.lagged, self.lag_time, 1.0), 0.0)
        # the parameters as the compiled form reads them (fixed after construction; ``current``,
        # ``has_current`` and ``wrenches`` may change between calls)
        self.packed = dynamics_compiled.pack(self)

    @property
    def n(self) -> int:
        return self.mass.shape[0]

    @property
    def n_actuators(self) -> int:
        return self.allocation.shape[1]

    def rhs(self, t: float, y: np.ndarray, f_e: np.ndarray) -> np.ndarray:
        """State derivative ``(n_y, n)`` for held actuator commands ``f_e`` (a, n).

        Compiled (:mod:`uvsim.scenarios.dynamics_compiled`) where numba is installed, the extra
        wrenches summed here; else :meth:`rhs_numpy`, the reference.
        """
        fast = compiled()
        if fast is None:
            return self.rhs_numpy(t, y, f_e)
        # one type signature for numba: C-ordered float arrays, Python bools
        y, f_e = np.ascontiguousarray(y, dtype=float), np.ascontiguousarray(f_e, dtype=float)
        current, has_current = np.ascontiguousarray(self.current, dtype=float), bool(self.has_current)
        n = y.shape[1]
        tau_w = np.zeros((6, n))
        if self.wrenches:
            R, nu_r = np.empty((3, 3, n)), np.empty((6, n))
            fast[2](y, current, has_current, R, nu_r)
            ctx = Context(t, y[POS], R, y[NU], nu_r)
            for wr in self.wrenches:
                tau_w += wr(ctx)
        out = np.empty((y.shape[0], n))
        fast[0](y, f_e, self.packed, current, has_current, self.has_cg_offset, tau_w, out)
        return out

    def rhs_numpy(self, t: float, y: np.ndarray, f_e: np.ndarray) -> np.ndarray:
        """:meth:`rhs` in numpy: the reference of the compiled form, and the path without numba."""
        q, nu = y[QUAT], y[NU]
        v, w = nu[:3], nu[3:]
        R = rotation(q)
        if self.has_current:
            vc_b = to_body(R, self.current)
            v_r = v - vc_b
            nu_r = np.concatenate((v_r, w))
        else:
            v_r, nu_r = v, nu
        # omega x (...) for several vectors at once: v, a1, a2, I_o omega, eps (and R^T v_c)
        a = matvec(self.added_mass_op, nu_r)         # [a1; a2] = M_A nu_r
        eps = q[1:]
        stack = [v, a[:3], a[3:], matvec(self.inertia_op, w), eps] + ([vc_b] if self.has_current else [])
        wx = cross(w[:, None], np.stack(stack, axis=1))
        wxv, wxa1, wxa2, wxIw, wxeps = (wx[:, i] for i in range(5))
        k = R[2]                                     # R^T e_3: third row of R
        c2 = cross(np.stack((v_r, self.load_moment), axis=1), np.stack((a[:3], k), axis=1))
        vxa, mxk = c2[:, 0], c2[:, 1]
        # rigid-body Coriolis/centripetal (Newton-Euler about the origin) and added-mass
        # Coriolis/centripetal (Kirchhoff) forces, damping, restoring
        tau = self.linear * nu_r + self.quadratic * np.abs(nu_r) * nu_r
        if self.has_along_flow:
            tau[:3] += self.along_flow * np.sqrt((v_r * v_r).sum(axis=0)) * v_r
        tau[:3] += self.load * k - self.mass * wxv - wxa1
        tau[3:] += mxk - wxIw - vxa - wxa2
        if self.has_cg_offset:
            tau[:3] -= self.mass * cross(w, cross(w, self.r_g))
            tau[3:] -= self.mass * cross(self.r_g, wxv)
        lag = y[N_BASE:]
        delivered = np.where(self.lagged, lag, f_e)
        tau += matvec(self.allocation_op, delivered)
        if self.wrenches:
            ctx = Context(t, y[POS], R, nu, nu_r)
            for wr in self.wrenches:
                tau += wr(ctx)
        if self.has_current:
            # + M_A nu_c_dot, nu_c_dot = [-omega x R^T v_c; 0]
            tau -= matvec(self.added_mass_op[:, :3], wx[:, 5])
        dy = np.empty_like(y)
        dy[POS] = matvec(R, v)
        dy[3] = -0.5 * (eps * w).sum(axis=0)
        dy[4:7] = 0.5 * (q[0] * w - wxeps)
        dy[NU] = matvec(self.M_inv, tau)
        dy[N_BASE:] = self.rate * (f_e - lag)
        return dy


def compiled():
    """``(rhs, advance, frame)`` of :mod:`uvsim.scenarios.dynamics_compiled` compiled by numba (compiled on
    first use, cached on disk), or None where numba is not installed or ``use_compiled(False)``."""
    return dynamics_compiled.compiled() if _use_compiled else None


_use_compiled = True


def use_compiled(flag: bool) -> bool:
    """Run the truth model compiled where numba is installed (True, the default) or always in
    numpy (False: the reference, for tests). Returns the previous setting."""
    global _use_compiled
    previous, _use_compiled = _use_compiled, bool(flag)
    return previous


def integrate(plant: Plant, t: np.ndarray, commands: np.ndarray, y0: np.ndarray, max_step: float = 0.002,
              *, renormalize: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Integrate ``plant`` over the log grid ``t`` with fixed-step RK4.

    Parameters
    ----------
    t : (n_t,) s, shared uniform sample times.
    commands : (n_t, a, n) actuator commands after the static actuator effects, held
        from each sample to the next.
    y0 : (n_y, n) initial states.
    max_step : s; each log interval is split into ``ceil(dt / max_step)`` equal sub-steps.
    renormalize : renormalize the quaternion after each step (off only to measure drift).

    Returns
    -------
    Y : (n_t, n_y, n) states at the samples.
    nu_dot : (n_t, 6, n) body acceleration at the samples (right limit: the command of
        that sample already acts).
    """
    t = np.ascontiguousarray(t, dtype=float)
    dts = np.diff(t)
    if t.size < 2 or np.any(dts <= 0):
        raise SimulationError("scenario truth model: times must be strictly increasing (>= 2 samples)")
    n_t = t.size
    Y = np.empty((n_t,) + y0.shape)
    A = np.empty((n_t, 6, y0.shape[1]))
    fast = compiled()
    if fast is not None and not plant.wrenches:
        bad = fast[1](t, np.ascontiguousarray(commands, dtype=float), np.array(y0, dtype=float), plant.packed,
                      np.ascontiguousarray(plant.current, dtype=float), bool(plant.has_current), plant.has_cg_offset,
                      float(max_step), bool(renormalize), Y, A)
        if bad >= 0:
            raise SimulationError(f"scenario truth model diverged at t = {t[bad]:.3f} s")
        return Y, A
    y = np.array(y0, dtype=float)
    Y[0] = y
    for k in range(n_t - 1):
        u = commands[k]
        m = max(1, int(np.ceil(dts[k] / max_step - 1e-9)))
        h = dts[k] / m
        for s in range(m):
            ts = t[k] + s * h
            k1 = plant.rhs(ts, y, u)
            if s == 0:
                A[k] = k1[NU]
            k2 = plant.rhs(ts + 0.5 * h, y + 0.5 * h * k1, u)
            k3 = plant.rhs(ts + 0.5 * h, y + 0.5 * h * k2, u)
            k4 = plant.rhs(ts + h, y + h * k3, u)
            y = y + (h / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
            if renormalize:
                y[QUAT] /= np.sqrt((y[QUAT] ** 2).sum(axis=0))
        if not np.all(np.isfinite(y)):
            raise SimulationError(f"scenario truth model diverged at t = {t[k + 1]:.3f} s")
        Y[k + 1] = y
    A[-1] = plant.rhs(t[-1], y, commands[-1])[NU]
    return Y, A
