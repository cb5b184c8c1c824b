"""Component build-up damping from full-envelope lookup tables (seed 003 sec. II-B, V-A-2).

The vehicle is split into components (hull, thrust-vectoring nozzle sections, fins), each
with its own frame (origin ``r_c`` and rotation ``C_c`` component -> body) and its own
coefficient table ``(C_L, C_D, C_M)(alpha, Re)`` from :mod:`uvsim.hydro`.  At every
integrator stage, for each component:

1. local flow: ``v_c = C_c^T (v_r + omega x r_c)`` (relative velocity at the component
   origin, including the rotation term), speed ``U``;
2. angles and Reynolds number:

   * **body of revolution** (hull): total incidence ``alpha_t = atan2(sqrt(v^2 + w^2), u)``
     in [0, pi] (sideslip is the same by axial symmetry), cross-flow direction
     ``e_c = (0, v, w) / sqrt(v^2 + w^2)``, ``Re = U L / nu``;
   * **wing** (lifting surface, span along component y): ``alpha = atan2(w, u)`` in
     (-pi, pi], the spanwise component is ignored (independence principle),
     ``Re = U_p c / nu`` with ``U_p = sqrt(u^2 + w^2)``;

3. coefficients from that component's table (bilinear in (alpha, log10 Re), any angle);
4. force in the component frame, transformed to the body and summed:

   * body: ``f = q A [-C_A, -C_N e_c,y, -C_N e_c,z]`` with ``C_N = C_L cos a + C_D sin a``,
     ``C_A = -C_L sin a + C_D cos a`` (axial positive aft, normal opposite the cross flow);
   * wing: ``f = q S (C_L (e_y x v_hat) - C_D v_hat)`` (lift normal to the in-plane flow);

5. moment: ``r_cp x f`` (seed 003 eq. 24) with the centre of pressure on the component
   axis, ``x_cp = C_M L_ref / C_N`` from the table's moment coefficient.  It is evaluated
   as ``C_M q A L (e_c x e_x)`` (body) or ``C_M q S c e_y`` (wing), which is identical
   wherever ``C_N != 0`` and stays finite where the normal force vanishes, plus the
   moment of the component force about the body origin ``r_c x F``;
6. rotational damping ``[K_pp |p| p, M_qq |q| q, N_rr |r| r]`` (eq. 24; SNAME sign, the
   coefficients are negative), and optionally the force/angular-velocity couplings of
   eq. 26 (``cross_coupled``): ``X += X_qq |q| q + X_rr |r| r``,
   ``Y += Y_pp |p| p + Y_rr |r| r``, ``Z += Z_pp |p| p + Z_qq |q| q`` (SNAME derivatives
   of the force on the vehicle; the signs printed in eq. 26 are absorbed into them).

7. the Munk moment is counted once (``munk_moment``): with ``"added_mass"`` (default) the
   hull tables are built without the potential-flow Munk couple (``BodyModel(munk_moment=
   False)``) and the model's added-mass Coriolis term ``C_A(nu_r) nu_r`` supplies it,
   ``v x (M_A,11 v)`` (Fossen 2021 eq. 6.43; ``(Z_wdot - X_udot) u w`` in pitch for a
   diagonal ``M_A``); with ``"table"`` the tables keep it (seed 003 eqs. 9, 11, 19 as
   printed) and this term adds ``+ v x (M_A,11 v)`` to cancel the copy in ``C_A``, as
   Fossen's remus100.py zeroes the Munk entries of ``C_A``.

Zero speed gives zero force (``q = 0``) without any division by zero; flow from behind
(``alpha`` near 180 deg) and from the side (90 deg) are ordinary table entries.  With a
single hull at the body origin this is exactly eq. 23-25 with table-valued
``X_uu, Y_vv, Z_ww`` and ``r_cp`` (see docs/sam.md for the derivation).

Two evaluation paths give identical results: numpy arrays for batches (``n > 1``) and
plain Python floats for a single trajectory (``n == 1``, the real-time case: numpy's
per-call overhead dominates for 1-element arrays).
"""
from __future__ import annotations

import json
import math

import numpy as np

from uvsim.errors import VehicleError
from uvsim.forces import register
from uvsim.forces.base import ForceTerm, first_violation
from uvsim.sam.components import (COMPONENT_KEYS, Component, body_table, gimbal_matrix, matmul33, positive_field,
                                  rotation_rpy, vec3_field, wing_table)
from uvsim.schema import check_keys

#: Body-table data sets (seed 003 sec. V-C compares Jorgensen-only, CFD and multifidelity).
DATASETS = ("multifidelity", "jorgensen", "datcom")
#: Where the potential-flow Munk moment comes from (exactly one place; module docstring, item 7).
MUNK_SOURCES = ("added_mass", "table")
ROT_NAMES = ("K_pp", "M_qq", "N_rr")
CROSS_NAMES = ("X_qq", "X_rr", "Y_pp", "Y_rr", "Z_pp", "Z_qq")


@register("component_buildup")
class ComponentBuildup(ForceTerm):
    """Component build-up damping (see module docstring).

    Parameters
    ----------
    components : list of dict
        ``{name, kind: body, hull: <built-in hull name or {stations|myring: ...}>,
        nose: [x, y, z], rpy_deg: [0, 0, 0]}`` - a hull whose nose is at ``nose`` (body
        frame, m) and whose axis is the component x axis (pointing forward); its origin is
        the table's moment reference (volume centroid) ``nose - C [x_m, 0, 0]``.
        ``{name, kind: wing, position: [x, y, z], rpy_deg: [r, p, y], area, chord,
        aspect_ratio, oswald: 0.9, gimbal: false}`` - a NACA 0015 lifting surface (seed 003
        Table IV: lifting line < 10 deg, Montgomerie blend, flat plate) with its quarter chord
        at ``position``, span along its y axis and lift in its x-z plane.  With ``gimbal:
        true`` its frame is turned by the thrust-vector angles of the vehicle's
        ``sam_propulsion`` term (``C = G(tv_pitch, tv_yaw) C_0``, :func:`gimbal_matrix`,
        about the component origin): the nozzle of SAM is the thrust-vectoring unit.
    dataset : {"multifidelity", "jorgensen", "datcom"}
        Which body table (seed 003 Algorithm 1, or one method over the full envelope).
    rho : float
        Water density, kg/m^3.
    nu : float
        Kinematic viscosity, m^2/s (Reynolds numbers of lookups and tables).
    rotational : dict
        ``{K_pp, M_qq, N_rr}`` quadratic rotational damping, N m s^2 (SNAME sign, <= 0).
    cross_coupled : dict, optional
        eq. 26 force/angular-rate derivatives ``{X_qq, X_rr, Y_pp, Y_rr, Z_pp, Z_qq}``
        (N s^2 or kg m); omitted = eq. 25 form.
    re_grid : list of float, optional
        Reynolds numbers of the body table (default :func:`uvsim.hydro.default_re_grid`).
    cdn_model : {"subcritical", "reynolds"}
        Cross-flow drag coefficient of the body tables (:mod:`uvsim.hydro.crossflow`);
        default ``"subcritical"`` (Jorgensen's method, seed 003 eqs. 7-11).
    munk_moment : {"added_mass", "table"}
        Where the Munk moment comes from (module docstring, item 7); default ``"added_mass"``.
    """

    def __init__(self, components, dataset: str = "multifidelity", rho: float = 1025.0, nu: float = 1.0e-6,
                 rotational=None, cross_coupled=None, re_grid=None, cdn_model: str = "subcritical",
                 munk_moment: str = "added_mass"):
        from uvsim.hydro.crossflow import CDN_MODELS

        where = "damping (component_buildup)"
        if dataset not in DATASETS:
            raise VehicleError(f"{where}.dataset: {dataset!r} not one of {DATASETS}")
        if cdn_model not in CDN_MODELS:
            raise VehicleError(f"{where}.cdn_model: {cdn_model!r} not one of {CDN_MODELS}")
        if munk_moment not in MUNK_SOURCES:
            raise VehicleError(f"{where}.munk_moment: {munk_moment!r} not one of {MUNK_SOURCES}")
        self.cdn_model = cdn_model
        self.munk_moment = munk_moment
        if not isinstance(components, list) or not components:
            raise VehicleError(f"{where}.components: expected a non-empty list")
        self.dataset = dataset
        self.rho = positive_field({"rho": rho}, "rho", where)
        self.nu = positive_field({"nu": nu}, "nu", where)
        rot = dict(rotational or {})
        check_keys(rot, ROT_NAMES, f"{where}.rotational", error=VehicleError)
        self.rotational = {k: float(rot.get(k, 0.0)) for k in ROT_NAMES}
        for k, v in self.rotational.items():
            if not np.isfinite(v) or v > 0:
                raise VehicleError(f"{where}.rotational.{k}: expected a finite number <= 0 (SNAME sign), got {v}")
        self.cross_coupled = None
        if cross_coupled is not None:
            cc = dict(cross_coupled)
            check_keys(cc, CROSS_NAMES, f"{where}.cross_coupled", error=VehicleError)
            self.cross_coupled = {k: float(cc.get(k, 0.0)) for k in CROSS_NAMES}
        self.re_grid = None if re_grid is None else [float(x) for x in re_grid]
        self.spec_components = [dict(c) for c in components]
        self.components = [self._build(c, i) for i, c in enumerate(components)]

    # ------------------------------------------------------------------ construction
    def _build(self, spec, i) -> Component:
        where = f"damping (component_buildup).components[{i}]"
        if not isinstance(spec, dict):
            raise VehicleError(f"{where}: expected a mapping")
        kind = spec.get("kind")
        if kind in COMPONENT_KEYS:
            check_keys(spec, COMPONENT_KEYS[kind], where, error=VehicleError)
        name = str(spec.get("name", f"component_{i}"))
        C = rotation_rpy(spec.get("rpy_deg", [0.0, 0.0, 0.0]))
        if kind == "body":
            if "hull" not in spec:
                raise VehicleError(f"{where}.hull: missing (a built-in hull name or a stations/myring mapping)")
            nose = vec3_field(spec, "nose", where)
            re_key = None if self.re_grid is None else tuple(self.re_grid)
            body, table = body_table(json.dumps(spec["hull"], sort_keys=True), self.dataset, self.nu, re_key,
                                      self.cdn_model, self.munk_moment == "table")
            r = nose - C @ np.array([body.xm, 0.0, 0.0])
            return Component(name, "body", r, C, body.A, body.L, table)
        if kind == "wing":
            pos = vec3_field(spec, "position", where)
            area, chord = positive_field(spec, "area", where), positive_field(spec, "chord", where)
            ar = positive_field(spec, "aspect_ratio", where)
            oswald = positive_field({"oswald": spec.get("oswald", 0.9)}, "oswald", where)
            gimbal = spec.get("gimbal", False)
            if not isinstance(gimbal, bool):
                raise VehicleError(f"{where}.gimbal: expected true or false, got {gimbal!r}")
            return Component(name, "wing", pos, C, area, chord, wing_table(ar, oswald), gimbal)
        raise VehicleError(f"{where}.kind: expected 'body' or 'wing', got {kind!r}")

    def check_values(self, values):
        for k in ROT_NAMES:
            if k in values:
                bad = first_violation(values[k], np.asarray(values[k], float) <= 0, k)
                if bad:
                    raise VehicleError(f"parameter {bad}: rotational damping is in the SNAME sign (<= 0), as in "
                                       "the vehicle file's damping (component_buildup).rotational")

    def parameters(self):
        p = dict(self.rotational)
        if self.cross_coupled is not None:
            p.update(self.cross_coupled)
        return p

    def to_dict(self):
        d = {"type": self.kind, "dataset": self.dataset, "rho": self.rho, "nu": self.nu,
             "cdn_model": self.cdn_model, "munk_moment": self.munk_moment,
             "rotational": dict(self.rotational), "components": [dict(c) for c in self.spec_components]}
        if self.cross_coupled is not None:
            d["cross_coupled"] = dict(self.cross_coupled)
        if self.re_grid is not None:
            d["re_grid"] = list(self.re_grid)
        return d

    def with_dataset(self, dataset: str) -> "ComponentBuildup":
        """A copy using another body data set (``jorgensen``, ``datcom``, ``multifidelity``)."""
        d = self.to_dict()
        d.pop("type")
        d["dataset"] = dataset
        return ComponentBuildup(**d)

    # ------------------------------------------------------------------ evaluation
    _gimbal_key = None
    _munk_M11 = None   # (3, 3) translational added mass of the vehicle, "table" mode only

    def bind(self, vehicle, index):
        """Copy bound to the vehicle (called by :class:`uvsim.model.Model`): it reads the
        thrust-vector angles of the vehicle's ``sam_propulsion`` term (components with
        ``gimbal: true``) and, with ``munk_moment: table``, the translational added mass
        whose Munk couple it cancels.  With ``munk_moment: added_mass`` the vehicle's
        added mass must produce a Munk couple (else the hull would have none)."""
        import copy

        new = copy.copy(self)
        where = f"{vehicle.source}: damping (component_buildup)"
        if any(c.kind == "body" for c in self.components):
            M11 = np.asarray(vehicle.added_mass_matrix, float)[:3, :3]
            if self.munk_moment == "table":
                new._munk_M11 = M11.copy()
            elif max(M11[1, 1], M11[2, 2]) - M11[0, 0] <= 0.0:
                raise VehicleError(
                    f"{where}.munk_moment: 'added_mass' takes the hull's Munk moment from the added mass, but "
                    f"added_mass gives none (Y_vdot = {M11[1, 1]:g}, Z_wdot = {M11[2, 2]:g} not above "
                    f"X_udot = {M11[0, 0]:g}); give the hull's added mass or set munk_moment: table")
        if any(c.gimbal for c in self.components):
            terms = vehicle.terms
            keys = [j for j, t in enumerate(terms) if getattr(t, "kind", None) == "sam_propulsion"]
            if len(keys) != 1:
                raise VehicleError(f"{where}: components with gimbal: true need exactly one sam_propulsion effect, "
                                   f"found {len(keys)}")
            new._gimbal_key = keys[0]
        return new

    def prepare(self, params, n):
        names = list(ROT_NAMES) + (list(CROSS_NAMES) if self.cross_coupled is not None else [])
        vals = {k: np.broadcast_to(np.asarray(params[k], float), (n,)) for k in names}
        scalar = n == 1
        comps = []
        for c in self.components:
            comps.append((c.kind == "body", tuple(float(x) for x in c.r), tuple(float(x) for x in c.C.ravel()),
                          0.5 * self.rho * c.area, c.length, c.length / self.nu, c.table, c.gimbal))
        munk = None
        if self._munk_M11 is not None:
            # the model's M_A with the named diagonal entries (possibly per row) of params
            M11 = np.broadcast_to(self._munk_M11, (n, 3, 3)).copy()
            for i, k in enumerate(("X_udot", "Y_vdot", "Z_wdot")):
                if k in params:
                    M11[:, i, i] = np.broadcast_to(np.asarray(params[k], float), (n,))
            munk = M11
        return {"vals": vals, "scalar": scalar, "comps": comps, "munk": munk,
                "svals": {k: float(v[0]) for k, v in vals.items()},
                "smunk": None if munk is None else tuple(float(x) for x in munk[0].ravel())}

    @staticmethod
    def munk_couple(v, M11) -> np.ndarray:
        """The Munk couple ``v x (M11 v)`` (N m, (n, 3)) of translational added mass ``M11``
        ((3, 3) or (n, 3, 3), kg) at relative velocity ``v`` (n, 3): the moment part of the
        added-mass Coriolis term ``C_A(nu_r) nu_r`` (Fossen 2021 eq. 6.43) on the left-hand
        side of the equations of motion."""
        a = v @ M11.T if M11.ndim == 2 else np.einsum("nij,nj->ni", M11, v)
        return np.cross(v, a)

    def _gimbal_angles(self, ctx):
        """(n, 2) thrust-vector angles [tv_pitch, tv_yaw] (rad), or None when not bound."""
        if self._gimbal_key is None:
            return None
        return ctx.states[self._gimbal_key][:, 2:4]

    def forces(self, ctx, prep):
        g = self._gimbal_angles(ctx)
        if prep["scalar"] and ctx.nu_r.shape[0] == 1:
            return np.array([self._forces_single(ctx.nu_r[0].tolist(), prep, None if g is None else g[0].tolist())])
        return self._forces_batch(ctx.nu_r, prep, g)

    def component_forces(self, nu_r, tv=None) -> dict:
        """Per-component generalized force (body frame, about the body origin) for velocities
        ``nu_r`` (n, 6) and thrust-vector angles ``tv`` (n, 2) [pitch, yaw] rad (default 0;
        used by ``gimbal`` components); a diagnostic for docs and tests.  Rotational damping
        excluded."""
        nu_r = np.atleast_2d(np.asarray(nu_r, float))
        prep = self.prepare({k: 0.0 for k in self.parameters()}, nu_r.shape[0])
        G = None
        if tv is not None:
            tv = np.broadcast_to(np.asarray(tv, float), (nu_r.shape[0], 2))
            G = gimbal_matrix(tv[:, 0], tv[:, 1])
        out = {}
        for c, pc in zip(self.components, prep["comps"]):
            out[c.name] = self._batch_component(nu_r, pc, G)
        return out

    def _forces_single(self, nu, prep, gimbal=None):
        u, v, w, p, q, r = nu
        X = Y = Z = K = M = N = 0.0
        sqrt, atan2 = math.sqrt, math.atan2
        G = None
        if gimbal is not None:
            dp, dy = gimbal
            c, s_, cy, sy = math.cos(dp), math.sin(dp), math.cos(dy), math.sin(dy)
            G = (c * cy, c * sy, -s_, -sy, cy, 0.0, s_ * cy, s_ * sy, c)  # gimbal_matrix(dp, dy)
        for is_body, (rx, ry, rz), Cf, qa, L, l_nu, table, gim in prep["comps"]:
            if gim and G is not None:
                Cf = matmul33(G, Cf)
            c00, c01, c02, c10, c11, c12, c20, c21, c22 = Cf
            vx = u + q * rz - r * ry
            vy = v + r * rx - p * rz
            vz = w + p * ry - q * rx
            lu = c00 * vx + c10 * vy + c20 * vz
            lv = c01 * vx + c11 * vy + c21 * vz
            lw = c02 * vx + c12 * vy + c22 * vz
            if is_body:
                cr2 = lv * lv + lw * lw
                U2 = lu * lu + cr2
                if U2 <= 0.0:
                    continue  # zero dynamic pressure: zero force (no division)
                U = sqrt(U2)
                ct = sqrt(cr2)
                CL, CD, CM = table.lookup(atan2(ct, lu), U * l_nu)
                ca, sa = lu / U, ct / U
                CN = CL * ca + CD * sa
                CA = -CL * sa + CD * ca
                Q = qa * U2
                if ct > 0.0:
                    ey, ez = lv / ct, lw / ct
                else:
                    ey = ez = 0.0
                fx, fy, fz = -Q * CA, -Q * CN * ey, -Q * CN * ez
                QL = Q * L * CM
                mx, my, mz = 0.0, QL * ez, -QL * ey
            else:
                U2 = lu * lu + lw * lw
                if U2 <= 0.0:
                    continue
                U = sqrt(U2)
                CL, CD, CM = table.lookup(atan2(lw, lu), U * l_nu)
                a, b = lu / U, lw / U
                Q = qa * U2
                fx, fy, fz = Q * (CL * b - CD * a), 0.0, Q * (-CL * a - CD * b)
                mx, my, mz = 0.0, Q * L * CM, 0.0
            Fx = c00 * fx + c01 * fy + c02 * fz
            Fy = c10 * fx + c11 * fy + c12 * fz
            Fz = c20 * fx + c21 * fy + c22 * fz
            X += Fx
            Y += Fy
            Z += Fz
            K += c00 * mx + c01 * my + c02 * mz + ry * Fz - rz * Fy
            M += c10 * mx + c11 * my + c12 * mz + rz * Fx - rx * Fz
            N += c20 * mx + c21 * my + c22 * mz + rx * Fy - ry * Fx
        sm = prep["smunk"]
        if sm is not None:  # munk_moment "table": cancel the copy in C_A(nu_r) nu_r
            a0 = sm[0] * u + sm[1] * v + sm[2] * w
            a1 = sm[3] * u + sm[4] * v + sm[5] * w
            a2 = sm[6] * u + sm[7] * v + sm[8] * w
            K += v * a2 - w * a1
            M += w * a0 - u * a2
            N += u * a1 - v * a0
        s = prep["svals"]
        K += s["K_pp"] * abs(p) * p
        M += s["M_qq"] * abs(q) * q
        N += s["N_rr"] * abs(r) * r
        if self.cross_coupled is not None:
            X += s["X_qq"] * abs(q) * q + s["X_rr"] * abs(r) * r
            Y += s["Y_pp"] * abs(p) * p + s["Y_rr"] * abs(r) * r
            Z += s["Z_pp"] * abs(p) * p + s["Z_qq"] * abs(q) * q
        return [X, Y, Z, K, M, N]

    @staticmethod
    def _batch_component(nu_r, pc, G=None):
        is_body, rc, Cf, qa, L, l_nu, table, gim = pc
        rc = np.asarray(rc)
        C = np.asarray(Cf).reshape(3, 3)
        if gim and G is not None:
            C = G @ C  # (n, 3, 3): component -> body through the gimbal
        vc = nu_r[:, :3] + np.cross(nu_r[:, 3:], rc)
        loc = vc @ C if C.ndim == 2 else np.einsum("ni,nij->nj", vc, C)  # C^T v for each row
        lu, lv, lw = loc[:, 0], loc[:, 1], loc[:, 2]
        n = nu_r.shape[0]
        f = np.zeros((n, 3))
        m = np.zeros((n, 3))
        if is_body:
            cr2 = lv * lv + lw * lw
            U2 = lu * lu + cr2
            U = np.sqrt(U2)
            ct = np.sqrt(cr2)
            CL, CD, CM = table.lookup(np.arctan2(ct, lu), np.maximum(U * l_nu, 1.0))  # Re >= 1: no log10(0)
            Us = np.where(U > 0, U, 1.0)
            ca, sa = np.where(U > 0, lu / Us, 1.0), ct / Us
            CN = CL * ca + CD * sa
            CA = -CL * sa + CD * ca
            Q = qa * U2
            cts = np.where(ct > 0, ct, 1.0)
            ey, ez = np.where(ct > 0, lv / cts, 0.0), np.where(ct > 0, lw / cts, 0.0)
            f[:, 0], f[:, 1], f[:, 2] = -Q * CA, -Q * CN * ey, -Q * CN * ez
            QL = Q * L * CM
            m[:, 1], m[:, 2] = QL * ez, -QL * ey
        else:
            U2 = lu * lu + lw * lw
            U = np.sqrt(U2)
            CL, CD, CM = table.lookup(np.arctan2(lw, lu), np.maximum(U * l_nu, 1.0))
            Us = np.where(U > 0, U, 1.0)
            a, b = lu / Us, lw / Us
            Q = qa * U2
            f[:, 0], f[:, 2] = Q * (CL * b - CD * a), Q * (-CL * a - CD * b)
            m[:, 1] = Q * L * CM
        if C.ndim == 2:
            F = f @ C.T
            Mb = m @ C.T + np.cross(rc, F)
        else:
            F = np.einsum("nij,nj->ni", C, f)
            Mb = np.einsum("nij,nj->ni", C, m) + np.cross(rc, F)
        return np.concatenate([F, Mb], axis=1)

    def _forces_batch(self, nu_r, prep, gimbal=None):
        G = None if gimbal is None else gimbal_matrix(gimbal[:, 0], gimbal[:, 1])
        tau = None
        for pc in prep["comps"]:
            f = self._batch_component(nu_r, pc, G)
            tau = f if tau is None else tau + f
        if prep["munk"] is not None:  # munk_moment "table": cancel the copy in C_A(nu_r) nu_r
            tau[:, 3:] += self.munk_couple(nu_r[:, :3], prep["munk"])
        vals = prep["vals"]
        p, q, r = nu_r[:, 3], nu_r[:, 4], nu_r[:, 5]
        tau[:, 3] += vals["K_pp"] * np.abs(p) * p
        tau[:, 4] += vals["M_qq"] * np.abs(q) * q
        tau[:, 5] += vals["N_rr"] * np.abs(r) * r
        if self.cross_coupled is not None:
            tau[:, 0] += vals["X_qq"] * np.abs(q) * q + vals["X_rr"] * np.abs(r) * r
            tau[:, 1] += vals["Y_pp"] * np.abs(p) * p + vals["Y_rr"] * np.abs(r) * r
            tau[:, 2] += vals["Z_pp"] * np.abs(p) * p + vals["Z_qq"] * np.abs(q) * q
        return tau

    # ------------------------------------------------------------------ eq. 23-25 view
    def equivalent_coefficients(self, alpha, speed: float, component: str | None = None) -> dict:
        """Table-valued eq. 23-25 quantities of a body component in the incidence plane
        (``v = 0``): ``X_uu = X / (u|u|)``, ``Z_ww = Z / (w|w|)`` (kg/m) and ``x_cp`` (m from
        the component origin), at angles ``alpha`` (rad) and ``speed`` (m/s).  Entries where
        ``u`` or ``w`` (or ``C_N``) vanish are NaN: this is why the simulator evaluates
        forces directly rather than through these ratios."""
        comp = next(c for c in self.components if (component is None and c.kind == "body") or c.name == component)
        a = np.atleast_1d(np.asarray(alpha, float))
        U = float(speed)
        CL, CD, CM = comp.table.lookup(a, np.full_like(a, U * comp.length / self.nu))
        CN = CL * np.cos(a) + CD * np.sin(a)
        CA = -CL * np.sin(a) + CD * np.cos(a)
        Q = 0.5 * self.rho * comp.area * U * U
        u, w = U * np.cos(a), U * np.sin(a)
        with np.errstate(divide="ignore", invalid="ignore"):
            Xuu = np.where(np.abs(u) > 1e-9, -Q * CA / (u * np.abs(u)), np.nan)
            Zww = np.where(np.abs(w) > 1e-9, -Q * CN / (w * np.abs(w)), np.nan)
            xcp = np.where(np.abs(CN) > 1e-9, CM * comp.length / CN, np.nan)
        return {"X_uu": Xuu, "Z_ww": Zww, "x_cp": xcp}
