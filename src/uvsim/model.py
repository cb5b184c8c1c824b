"""The equations of motion (Fossen 2021 eq. 10.x; seed 000 eq. 1-2; seed 003 eq. 1-5).

State vector (per trajectory, shape ``(13 + k,)``)::

    y = [x, y, z,  qw, qx, qy, qz,  u, v, w, p, q, r,  term states...]

NED position of the body origin, unit quaternion body -> NED (scalar first) and body
velocities ``nu``.  Kinematics (seed 003 eq. 1-4)::

    p_dot = R(q) nu_1,     q_dot = 1/2 q (x) [0, nu_2]

Kinetics with an irrotational current ``v_c`` (NED), ``nu_r = nu - nu_c``,
``nu_c = [R^T v_c; 0]`` (seed 000 eq. 1-2)::

    M_RB nu_dot + C_RB(nu) nu + M_A nu_r_dot + C_A(nu_r) nu_r = sum of terms
    nu_r_dot = nu_dot - nu_c_dot,   nu_c_dot = [R^T v_c_dot - omega x R^T v_c; 0]

The ``- omega x R^T v_c`` part is how a current that is constant in NED looks from the
rotating body.  Every other force (restoring, damping, actuators, effects) is a
:class:`uvsim.forces.ForceTerm`.

:class:`Model` is batched: it holds ``n`` parameter sets at once (arrays with a leading
axis of length ``n``); ``rhs(t, y, u)`` takes ``y`` of shape ``(n, n_y)``.
"""
from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from uvsim.errors import SimulationError, VehicleError
from uvsim.forces.base import Context
from uvsim.bilinear import CORIOLIS, CROSS, ROT_QRATE, WRITTEN_OUT_ROWS, bilinear, matvec, rot_qrate
from uvsim.rigid_body import rigid_body_mass_matrix
from uvsim.vehicle import ADDED_MASS_NAMES, INERTIA_NAMES, check_parameter_values, inertia_tensor, load_vehicle

POS, QUAT, NU = slice(0, 3), slice(3, 7), slice(7, 13)
STATE_NAMES = ["x", "y", "z", "qw", "qx", "qy", "qz", "u", "v", "w", "p", "q", "r"]


class _MatVec:
    """``M x`` specialised once for the structure of ``M`` (shared / per-row, diagonal or full)."""

    def __init__(self, M: np.ndarray):
        M = np.asarray(M, float)
        full = M if M.ndim == 3 else M[None]
        off = full - np.einsum("nii->ni", full)[:, :, None] * np.eye(full.shape[-1])
        self.diag = not np.any(off)
        shared = M.ndim == 2 or bool(np.all(full == full[:1]))
        if self.diag:
            d = np.einsum("nii->ni", full)
            self.d = d[0] if shared else d
        else:
            self.M = full[0] if shared else full
            self.MT = self.M.T if shared else None
        self.shared = shared

    def __call__(self, x: np.ndarray) -> np.ndarray:
        if self.diag:
            return x * self.d
        if self.shared:
            return x @ self.MT
        return np.einsum("nij,nj->ni", self.M, x)


# index arrays for C(nu) nu = [w x a; v x a + w x b] (Fossen 2021 eq. 3.46) as 9 products
_CI1 = np.array([4, 5, 3, 1, 2, 0, 4, 5, 3])
_CJ1 = np.array([2, 0, 1, 2, 0, 1, 5, 3, 4])
_CI2 = np.array([5, 3, 4, 2, 0, 1, 5, 3, 4])
_CJ2 = np.array([1, 2, 0, 1, 2, 0, 4, 5, 3])


def coriolis_term(nu: np.ndarray, ab: np.ndarray) -> np.ndarray:
    """``C(nu) nu`` from ``nu`` (n, 6) and the momentum ``ab = M nu`` (n, 6)."""
    if nu.shape[0] < 16:
        return bilinear(nu, ab, CORIOLIS)
    c = nu[:, _CI1] * ab[:, _CJ1] - nu[:, _CI2] * ab[:, _CJ2]
    out = c[:, :6]
    out[:, 3:] += c[:, 6:]
    return out


class Model:
    """Batched equations of motion for a vehicle and ``n`` parameter sets.

    Parameters
    ----------
    vehicle : Vehicle or str
        The vehicle (or a built-in name / file path).
    overrides : mapping name -> float or array (n,), optional
        Named parameters replacing the vehicle's (see :meth:`Vehicle.parameters`);
        arrays give one value per trajectory of the batch.
    n : int, optional
        Batch size; inferred from the override arrays when omitted.
    input_kind : {"force", "thrust", "pwm"}
        What the inputs ``u`` are.
    current : callable, optional
        ``current(t) -> (v_c (3,) NED m/s, v_c_dot (3,) m/s^2)`` for a time-varying
        current; when omitted, the constant ``current_n/e/d`` parameters are used.
    """

    def __init__(self, vehicle, overrides: Mapping[str, Any] | None = None, *, n: int | None = None,
                 input_kind: str = "force", current=None, extra_terms=()):
        self.vehicle = vehicle = load_vehicle(vehicle)
        params: dict[str, Any] = dict(vehicle.parameters())
        overrides = dict(overrides or {})
        self.terms = list(vehicle.terms) + list(extra_terms)
        # terms that need the vehicle (e.g. its thruster allocation) or their own index in
        # ctx.states get a bound copy: ``term.bind(vehicle, index) -> ForceTerm`` (uvsim.effects)
        self.terms = [t.bind(vehicle, i) for i, t in enumerate(self.terms)]
        for t in extra_terms:
            params.update(t.parameters())
        unknown = set(overrides) - set(params)
        if unknown:
            raise VehicleError(f"unknown parameter(s) {sorted(unknown)} for vehicle {vehicle.name}; known: {sorted(params)}")
        sizes = {np.size(v) for v in overrides.values() if np.ndim(v) > 0}
        if n is None:
            n = max(sizes) if sizes else 1
        for k, v in overrides.items():
            try:
                a = np.asarray(v, dtype=float)
            except (TypeError, ValueError):
                raise VehicleError(f"parameter {k}: expected a number or an array of length {n}, got {v!r}"[:300]) from None
            if a.ndim > 1 or (a.ndim == 1 and a.size not in (1, n)):
                raise VehicleError(f"parameter {k}: expected a number or an array of length {n}, got shape {a.shape}")
            if not np.all(np.isfinite(a)):
                raise VehicleError(f"parameter {k}: non-finite value(s) {a}")
            params[k] = a if a.ndim == 1 and a.size == n else float(a.reshape(-1)[0]) if a.size == 1 else a
        check_parameter_values({k: params[k] for k in overrides}, self.terms)
        self.params = params
        params['g'] = vehicle.g  # environment constant, read by the restoring term
        self.n = n
        if input_kind not in ("force", "thrust", "pwm"):
            raise SimulationError(f"input_kind must be 'force', 'thrust' or 'pwm', got {input_kind!r}")
        self.input_kind = input_kind
        self.current_fn = current
        self.g = vehicle.g

        # --- mass properties -------------------------------------------------
        def arr(name):
            return np.broadcast_to(np.asarray(params[name], float), (n,))

        m_meas = arr("m")
        if np.any(m_meas <= 0):
            raise VehicleError("parameter m: mass must be positive")
        r_g_meas = np.stack([arr("x_g"), arr("y_g"), arr("z_g")], -1)
        # constant masses that terms add (a ballast piece): into M_RB, not into the weight W
        # = m g of the restoring term (the piece's weight is in its own force)
        fixed = [(t, fm) for t in self.terms if (fm := t.fixed_mass_properties(params, n)) is not None]
        self.fixed_mass, self.fixed_first, self.fixed_dI = np.zeros(n), np.zeros((n, 3)), np.zeros((n, 3, 3))
        for _, (dm, dfirst, dI_t) in fixed:
            self.fixed_mass, self.fixed_first, self.fixed_dI = (self.fixed_mass + dm, self.fixed_first + dfirst,
                                                                self.fixed_dI + dI_t)
        self.mass = m_meas + self.fixed_mass
        if np.any(self.mass <= 0):
            raise VehicleError("the rigid body's mass with the terms' fixed masses must be positive")
        self.r_g = (m_meas[:, None] * r_g_meas + self.fixed_first) / self.mass[:, None] if fixed else r_g_meas
        # an override that is the same for every row is shared (e.g. values held fixed in a fit)
        varying = {k for k, v in overrides.items()
                   if np.ndim(params[k]) > 0 and np.size(params[k]) > 1 and np.any(params[k] != params[k][0])}
        rb_names = ["m", "x_g", "y_g", "z_g", *INERTIA_NAMES, *(k for t, _ in fixed for k in t.parameters())]
        shared_rb = not (varying & set(rb_names))
        shared_am = not (varying & set(ADDED_MASS_NAMES))
        # mass matrices, eigenvalues and inverses for the distinct parameter sets only (a
        # batch of P sets x W windows has P distinct ones), then indexed back per row
        cols = [arr(k) for k in rb_names + list(ADDED_MASS_NAMES) if k in varying]
        if cols:
            uniq, inv_idx = np.unique(np.stack(cols, -1), axis=0, return_inverse=True)
            first = np.array([np.flatnonzero(inv_idx.ravel() == j)[0] for j in range(len(uniq))])
        else:
            inv_idx, first = np.zeros(n, int), np.zeros(1, int)
        inv_idx = np.asarray(inv_idx).ravel()
        I = inertia_tensor(*(arr(k)[first] for k in INERTIA_NAMES)) + self.fixed_dI[first]
        MA = np.broadcast_to(vehicle.added_mass_matrix, (first.size, 6, 6)).copy()
        for i, k in enumerate(ADDED_MASS_NAMES):
            MA[:, i, i] = arr(k)[first]
        M_RB = rigid_body_mass_matrix(self.mass[first], I, self.r_g[first])
        M = M_RB + MA
        ev = np.linalg.eigvalsh(M)
        bad = np.nonzero(ev[:, 0] <= 0)[0]
        if bad.size:
            rows = [int(np.flatnonzero(inv_idx == b)[0]) for b in bad[:5]]
            raise VehicleError(
                f"M = M_RB + M_A is not positive definite for parameter set(s) {rows} "
                f"(smallest eigenvalue {ev[bad[0], 0]:.3g}); check inertia and added-mass values"
            )
        Minv = np.linalg.inv(M)
        self.M_RB = M_RB[0] if shared_rb else M_RB[inv_idx]
        self.M_A = MA[0] if shared_am else MA[inv_idx]
        self.M = M[0] if (shared_rb and shared_am) else M[inv_idx]
        self.Minv = Minv[0] if (shared_rb and shared_am) else Minv[inv_idx]
        self._M_mv, self._Minv_mv = _MatVec(self.M), _MatVec(self.Minv)
        self._MRB_mv, self._MA_mv = _MatVec(self.M_RB), _MatVec(self.M_A)
        self.weight = m_meas * self.g
        # what the restoring term weighs: the vehicle's measured mass at its measured CG
        self.weight_mass, self.weight_r_g = m_meas, r_g_meas
        self.current_ned = np.stack([arr(k) for k in ("current_n", "current_e", "current_d")], -1)
        self.has_current = current is not None or bool(np.any(self.current_ned != 0))
        self.changes_mass = any(t.changes_mass for t in self.terms)

        # --- terms and their states -------------------------------------------
        self.preps = [t.prepare(params, n) for t in self.terms]
        self.state_slices = {}
        start = 13
        names = list(STATE_NAMES)
        for i, t in enumerate(self.terms):
            if t.n_states:
                self.state_slices[i] = slice(start, start + t.n_states)
                names += t.state_names()
                start += t.n_states
        self.n_y = start
        self.state_names = names

    # ------------------------------------------------------------------ helpers
    def check_inputs(self, k: int, where: str = "inputs") -> None:
        self.vehicle.actuators.check_inputs(self.input_kind, k, where)

    def initial_state(self, pos=None, q=None, nu=None, u0=None) -> np.ndarray:
        """Initial state ``(n, n_y)``; ``pos`` (3,) or (n, 3), ``q`` (4,) or (n, 4), ``nu`` (6,) or (n, 6)."""
        n = self.n
        y = np.zeros((n, self.n_y))
        y[:, POS] = np.zeros(3) if pos is None else _initial(pos, 3, n, "pos0", "NED position, m")
        y[:, QUAT] = np.array([1.0, 0, 0, 0]) if q is None else _initial(q, 4, n, "q0", "unit quaternion qw..qz")
        qn = np.linalg.norm(y[:, QUAT], axis=1)
        if np.any(np.abs(qn - 1) > 1e-3):
            raise SimulationError(f"initial quaternion is not unit norm (|q| = {qn.min():.4f}..{qn.max():.4f})")
        y[:, QUAT] /= qn[:, None]
        y[:, NU] = np.zeros(6) if nu is None else _initial(nu, 6, n, "nu0", "body velocity u, v, w, p, q, r")
        u0 = np.zeros((n, 0)) if u0 is None else np.broadcast_to(u0, (n, np.shape(u0)[-1]))
        for i, t in enumerate(self.terms):
            if t.n_states:
                y[:, self.state_slices[i]] = t.initial_state(self.preps[i], n, u0, self.input_kind)
        return y

    # ------------------------------------------------------------------ dynamics
    def rhs(self, t: float, y: np.ndarray, u: np.ndarray, voltage: np.ndarray | None = None, *,
            states_only: bool = False) -> np.ndarray:
        """State derivative ``(n, n_y)`` for states ``y`` (n, n_y), inputs ``u`` (n, k) and
        the battery voltage ``voltage`` (n,) V or None (see :class:`uvsim.forces.Context`).
        With ``states_only`` only the derivatives of the terms' own states (n, n_y - 13)
        are computed (no forces, no accelerations): used to carry term states along a
        given vehicle trajectory (:mod:`uvsim.fitting`)."""
        n = y.shape[0]
        pos = y[:, 0:3]
        q = y[:, 3:7]
        nu = y[:, 7:13]
        v, w = nu[:, :3], nu[:, 3:]
        # rotation matrix body -> NED (seed 003 eq. 3) and quaternion rate (eq. 2, 4), both
        # bilinear in q and [q, w]: one outer product and one matrix product on small batches,
        # the formulas written out per column on large ones (uvsim.bilinear.rot_qrate)
        rq = rot_qrate(y) if n >= WRITTEN_OUT_ROWS else bilinear(q, y[:, 3:13], ROT_QRATE)
        R = rq[:, :9].reshape(n, 3, 3)

        # current (seed 000 eq. 2)
        if self.has_current:
            if self.current_fn is not None:
                vc, vc_dot = self._current_at(t, n)
            else:
                vc, vc_dot = self.current_ned, None
            vc_b = (vc[:, None, :] @ R)[:, 0]  # R^T v_c
            nu_r = nu.copy()
            nu_r[:, :3] -= vc_b
            nuc_dot = np.zeros_like(nu)
            nuc_dot[:, :3] = -bilinear(w, vc_b, CROSS)  # constant NED current seen from the rotating body
            if vc_dot is not None:
                nuc_dot[:, :3] += (vc_dot[:, None, :] @ R)[:, 0]
        else:
            nu_r = nu

        # mass properties (possibly changed by actuators)
        # (the context carries the weighed mass and its CG: a term's fixed mass is not weighed)
        mass, weight, r_g = self.weight_mass, self.weight, self.weight_r_g
        MRB_mv, Minv_mv = self._MRB_mv, self._Minv_mv
        if self.changes_mass:
            mass, r_g, M_RB, Minv = self._mass_update(t, y, pos, R, nu, nu_r, u)
            weight = mass * self.g
            MRB_mv, Minv_mv = (lambda x: matvec(M_RB, x)), (lambda x: matvec(Minv, x))
        states = {i: y[:, s] for i, s in self.state_slices.items()} if self.state_slices else {}
        ctx = Context(t, pos, q, R, nu, nu_r, u, self.input_kind, weight, mass, r_g, states, self.params,
                      self.changes_mass, voltage)
        if states_only:
            return np.concatenate([self.terms[i].state_derivative(ctx, self.preps[i], y[:, s])
                                   for i, s in self.state_slices.items()] or [np.zeros((n, 0))], axis=1)

        tau = None
        for term, prep in zip(self.terms, self.preps):
            f = term.forces(ctx, prep)
            tau = f if tau is None else tau + f
        # Coriolis-centripetal terms (parameterization-independent form, Fossen 2021 eq. 3.46)
        if self.has_current:
            tau = (tau - coriolis_term(nu, MRB_mv(nu))
                   - coriolis_term(nu_r, self._MA_mv(nu_r))
                   + self._MA_mv(nuc_dot))
        elif self.changes_mass:
            tau = tau - coriolis_term(nu, MRB_mv(nu) + self._MA_mv(nu))
        else:
            tau = tau - coriolis_term(nu, self._M_mv(nu))
        nu_dot = Minv_mv(tau)

        # p_dot = R nu_1;  q_dot = 1/2 q (x) [0, nu_2]  (seed 003 eq. 1-4)
        pdot = (R @ v[:, :, None])[:, :, 0] if n < 16 else np.einsum("nij,nj->ni", R, v)
        parts = [pdot, rq[:, 9:], nu_dot]
        for i, s in self.state_slices.items():
            parts.append(self.terms[i].state_derivative(ctx, self.preps[i], y[:, s]))
        return np.concatenate(parts, axis=1)

    def term_states_along(self, T: np.ndarray, U: np.ndarray, V=None) -> np.ndarray | None:
        """States (n, L, n_y - 13) of the stateful terms along input histories ``T`` (n, L),
        ``U`` (n, L, k) from :meth:`initial_state`, when every stateful term has a closed
        form (:meth:`uvsim.forces.ForceTerm.states_along`); None otherwise."""
        x0 = self.initial_state(u0=U[:, 0])[:, 13:]
        parts = []
        for i, s in self.state_slices.items():
            xi = self.terms[i].states_along(self.preps[i], T, U, self.input_kind, V, x0[:, s.start - 13:s.stop - 13])
            if xi is None:
                return None
            parts.append(xi)
        return np.concatenate(parts, axis=2) if parts else np.zeros(T.shape + (0,))

    def _current_at(self, t, n: int):
        """``(v_c (n, 3), v_c_dot (n, 3))`` of the time-varying current at ``t``: a float
        (one time for every row) or an array (n,) of per-row times (batched runs on
        different time grids), evaluated row by row (``current(t)`` takes one time)."""
        if np.ndim(t) == 0:
            vc, vc_dot = self.current_fn(float(t))
            return (np.broadcast_to(np.asarray(vc, float), (n, 3)),
                    np.broadcast_to(np.asarray(vc_dot, float), (n, 3)))
        pairs = [self.current_fn(float(ti)) for ti in np.asarray(t, float)]
        return (np.array([np.asarray(a, float).reshape(3) for a, _ in pairs]),
                np.array([np.asarray(b, float).reshape(3) for _, b in pairs]))

    def _mass_update(self, t, y, pos, R, nu, nu_r, u):
        """Rebuild M_RB with the mass changes of mass-changing terms (VBS, moving masses).
        Returns the weighed mass and its CG (the vehicle's with those changes), then ``M_RB``
        (which adds the terms' fixed masses) and ``(M_RB + M_A)^-1``."""
        n = y.shape[0]
        mass = self.weight_mass.copy()
        first = mass[:, None] * self.weight_r_g
        I = inertia_tensor(*(np.broadcast_to(np.asarray(self.params[k], float), (n,)) for k in INERTIA_NAMES)) + self.fixed_dI
        ctx = Context(t, pos, y[:, 3:7], R, nu, nu_r, u, self.input_kind, self.weight, self.weight_mass, self.weight_r_g,
                      {i: y[:, s] for i, s in self.state_slices.items()}, self.params, False)
        for i, term in enumerate(self.terms):
            if term.changes_mass:
                s = self.state_slices.get(i)
                dm, dfirst, dI = term.mass_properties(ctx, self.preps[i], None if s is None else y[:, s])
                mass = mass + dm
                first = first + dfirst
                I = I + dI
        r_g = first / mass[:, None]
        if np.any(self.fixed_mass):
            m_all = mass + self.fixed_mass
            M_RB = rigid_body_mass_matrix(m_all, I, (first + self.fixed_first) / m_all[:, None])
        else:
            M_RB = rigid_body_mass_matrix(mass, I, r_g)
        Minv = np.linalg.inv(M_RB + self.M_A)
        return mass, r_g, M_RB, Minv

    # ----------------------------------------------------------------- energy
    def energy(self, y: np.ndarray) -> np.ndarray:
        """Kinetic + potential energy (J) of states ``y`` (..., n_y) for parameter set 0
        (used by tests): ``1/2 nu^T M nu - W z_g_ned + B z_b_ned``."""
        from uvsim.kinematics import quat_to_rotation

        y = np.asarray(y)
        nu = y[..., NU]
        M = self.M if self.M.ndim == 2 else self.M[0]
        T = 0.5 * np.einsum("...i,ij,...j->...", nu, M, nu)
        R = quat_to_rotation(y[..., QUAT])
        zg = y[..., 2] + np.einsum("...j,j->...", R[..., 2, :], self.weight_r_g[0])
        r_b = np.array([self.params[k] if np.ndim(self.params[k]) == 0 else self.params[k][0] for k in ("x_b", "y_b", "z_b")])
        zb = y[..., 2] + np.einsum("...j,j->...", R[..., 2, :], r_b)
        B = self.params["B"] if np.ndim(self.params["B"]) == 0 else self.params["B"][0]
        return T - self.weight[0] * zg + B * zb


def _initial(value, k: int, n: int, where: str, what: str) -> np.ndarray:
    """An initial-state part ``(k,)`` or ``(n, k)`` of finite numbers, else a SimulationError naming
    ``where`` (a NaN velocity would otherwise surface as an integration blow-up)."""
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is None or a.shape not in ((k,), (n, k)) or not np.all(np.isfinite(a)):
        got = "not numbers" if a is None else f"shape {a.shape}" if a.shape not in ((k,), (n, k)) else "non-finite values"
        raise SimulationError(f"{where}: expected {k} finite numbers ({what}) or an array of shape ({n}, {k}), "
                              f"got {got}: {str(value)[:80]}")
    return a
