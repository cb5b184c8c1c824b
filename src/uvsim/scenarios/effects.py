"""Effects of the truth model, written from their physics (independent of ``uvsim.effects``).

Each effect is a dataclass with a ``variant``, parameters in physical units and a scalar
``magnitude`` drawn log-uniformly over a 10x range (:data:`MAGNITUDE_RANGES`; the weak
thruster's gain range is the one of the brief, 0.3-0.8).  Notation: ``R`` body->NED,
``k = R^T e_3``, ``nu_r = [v_r; omega]`` the velocity relative to the water, ``A`` the
thruster allocation (columns ``[d_i; r_i x d_i]``).

An effect acts on the truth model through up to three hooks:

* ``modify(parts, rows)``: changes the rigid body, loads or current of the rows it is on;
* ``map_commands(f, kind, A, rows)``: changes the actuator commands (static, per sample);
* ``wrench(parts, rows)``: a callable adding a generalized force at every RK4 stage.

``rows`` is a boolean mask over the simulated trajectories: the generator simulates each
run with and without each effect in one batch to measure how visible the effect is.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import ClassVar

import numpy as np

from uvsim.errors import UvsimError
from uvsim.scenarios.dynamics import cross, matvec, to_body


class ScenarioError(UvsimError, ValueError):
    """A scenario specification or override is malformed or out of range."""


#: Meaning and unit of each effect's magnitude.
MAGNITUDE_MEANING = {
    "current": "current speed |v_c|, m/s",
    "tether": "tension T_0 (N) and/or stiffness k (N/m), by law",
    "ballast": "net weight |w| of the point load, N",
    "thruster_lag": "time constant T, s",
    "thrust_asymmetry": "reverse-thrust loss 1 - ratio",
    "weak_thruster": "thrust loss 1 - gain of the weak thruster",
    "coupled_damping": "offset of the translational drag centre from the origin, m",
    "periodic_force": "force amplitude, N",
    "payload_pod": "weight of the pod (= lift of its float), N",
}
#: (low, high) of each effect's magnitude per sensor suite: ``mocap`` (position and attitude;
#: profiles diagnose, issue10_timing) and ``imu`` (gyro, accelerometer, lagged roll/pitch,
#: depth; profile realsensor).  Each low end is a round value at which at least 90 % of drawn
#: scenarios give ``effect_snr >= 2`` on their validation runs (docs/scenarios.md,
#: "Detectability", measured with ``uvsim scenario snr``), except ``imu`` ``current``: without a
#: position sensor or a DVL a current is barely visible (83 % at 0.1 m/s), so the realsensor profile
#: draws it only when its runs log a DVL.  The weak thruster's range holds the gains 0.3-0.93.
MAGNITUDE_RANGES = {
    "mocap": {"current": (0.01, 0.1), "tether": (0.1, 1.0), "ballast": (0.1, 1.0), "thruster_lag": (0.03, 0.3),
              "thrust_asymmetry": (0.05, 0.5), "weak_thruster": (0.07, 0.7), "coupled_damping": (0.012, 0.12),
              "periodic_force": (0.3, 3.0), "payload_pod": (2.0, 10.0)},
    "imu": {"current": (0.1, 1.0), "tether": (0.1, 1.0), "ballast": (0.3, 3.0), "thruster_lag": (0.03, 0.3),
            "thrust_asymmetry": (0.05, 0.5), "weak_thruster": (0.07, 0.7), "coupled_damping": (0.012, 0.12),
            "periodic_force": (0.3, 3.0), "payload_pod": (2.0, 10.0)},
}
#: Effects a diagnosis catalogue is expected to know; ``periodic_force`` is not one of them.
CATALOGUED = ("current", "tether", "ballast", "thruster_lag", "thrust_asymmetry", "weak_thruster",
              "coupled_damping")

# Physical constants, with sources.
LEAD_DENSITY = 11340.0       # kg/m^3, lead (CRC Handbook of Chemistry and Physics)
FOAM_DENSITY = 320.0         # kg/m^3, R-3318 subsea buoyancy foam, 20 lb/ft^3 (Blue Robotics product data)
CABLE_CD = 1.2               # circular cylinder in cross-flow, subcritical Re (Hoerner 1965, ch. 3)
CABLE_DIAMETER = 0.0076      # m, Blue Robotics Fathom ROV tether (docs.bluerobotics.com/fathom-r2)
#: BlueROV2 Heavy frame, m (body box the generator places points in; ~0.46 x 0.58 x 0.25 m overall).
FRAME_BOX = ((-0.22, 0.22), (-0.25, 0.25), (-0.12, 0.12))


def log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def frame_point(rng: np.random.Generator) -> list[float]:
    return [float(rng.uniform(lo, hi)) for lo, hi in FRAME_BOX]


@dataclass
class Effect:
    """Base: ``type`` name, ``variant``, ``magnitude`` (see :data:`MAGNITUDE_MEANING`)."""

    type: ClassVar[str] = ""
    variants: ClassVar[tuple] = ()
    variant: str = ""
    magnitude: float = 0.0

    def __post_init__(self):
        if self.variant not in self.variants:
            raise ScenarioError(f"effect {self.type}: variant {self.variant!r}; expected one of {list(self.variants)}")
        if not (np.isfinite(self.magnitude) and self.magnitude > 0):
            raise ScenarioError(f"effect {self.type}: magnitude must be a positive number, got {self.magnitude!r}")

    def to_dict(self) -> dict:
        d = {"type": self.type}
        d.update({k: (np.asarray(v).tolist() if isinstance(v, (np.ndarray, tuple)) else v)
                  for k, v in asdict(self).items()})
        return d

    def modify(self, parts, rows) -> None:
        pass

    def map_commands(self, f, kind, A, rows):
        return f

    def wrench(self, parts, rows):
        return None


@dataclass
class Current(Effect):
    """Constant irrotational current ``v_c`` (m/s, NED) acting through ``nu_r``
    (Fossen 2021 eq. 10.1-10.9; seed 000 eq. 2 and assumption 5).

    Variants: ``horizontal`` (``v_c[2] = 0``) or ``with_vertical`` (an elevation of
    20-60 deg, an up- or down-welling such as near a wall or an outflow)."""

    type: ClassVar[str] = "current"
    variants: ClassVar[tuple] = ("horizontal", "with_vertical")
    velocity_ned: list = field(default_factory=lambda: [0.0, 0.0, 0.0])

    @classmethod
    def sample(cls, rng, variant, magnitude, **_):
        az = rng.uniform(-np.pi, np.pi)
        el = 0.0 if variant == "horizontal" else rng.choice([-1, 1]) * rng.uniform(np.radians(20), np.radians(60))
        v = magnitude * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
        return cls(variant=variant, magnitude=magnitude, velocity_ned=v.tolist())

    def modify(self, parts, rows):
        parts["current"][:, rows] = np.asarray(self.velocity_ned)[:, None]


@dataclass
class Tether(Effect):
    """Umbilical from an anchor ``p_0`` (m, NED) to an attachment point ``r_a`` (m, body).

    With ``p_a = p + R r_a`` and ``d = p_0 - p_a`` (``d_z`` set to 0 for the
    ``horizontal`` variants: the cable lies on the bottom or floats at the surface),
    ``L = |d|``, ``e = d / L``, the pull is::

        F_pull = (T_0 + k max(0, L - L_s)) e                        (N, NED)

    (``law``: ``tension`` has ``k = 0``, ``elastic`` has ``T_0 = 0``, ``both`` has
    ``T_0`` (N) and ``k`` (N/m) equal to the magnitude).  The ``*_drag``
    variants add the drag of a straight cable of length ``l = max(L, L_s)`` pinned at the
    anchor: at the fraction ``s`` of its length it moves with ``s v_n`` (``v_n`` the
    attachment-point velocity through the water normal to the cable), its load per length
    is ``-1/2 rho C_d D s^2 |v_n| v_n`` and the vehicle end carries ``s`` of the load at
    ``s`` (the end reaction of a taut string), so::

        F_drag = -1/2 rho C_d D l |v_n| v_n  * integral_0^1 s^3 ds = -1/8 rho C_d D l |v_n| v_n

    Body wrench: ``f = R^T (F_pull + F_drag)``, ``tau = [f; r_a x f]``.
    """

    type: ClassVar[str] = "tether"
    variants: ClassVar[tuple] = ("3d", "3d_drag", "horizontal", "horizontal_drag")
    law: str = "tension"
    anchor_ned: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    attach_body: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    tension: float = 0.0          # N
    stiffness: float = 0.0        # N/m
    slack_length: float = 0.0     # m
    cd: float = CABLE_CD
    diameter: float = CABLE_DIAMETER  # m
    rho: float = 1000.0           # kg/m^3

    @classmethod
    def sample(cls, rng, variant, magnitude, start_region=None, rho=1000.0, **_):
        """Anchor 2-4 m (horizontally) from the middle of the runs' start region, at the
        surface (3-D variants: the spool or float); slack length 0-0.5 m shorter than the
        distance to that middle, so an elastic cable is taut from the start."""
        centre = np.asarray((start_region or {}).get("centre", [0.0, 0.0, 1.0]))
        az = rng.uniform(-np.pi, np.pi)
        dist = rng.uniform(2.0, 4.0)
        anchor = centre + np.array([dist * np.cos(az), dist * np.sin(az), 0.0])
        anchor[2] = 0.0 if variant.startswith("3d") else centre[2]
        attach = frame_point(rng)
        law = str(rng.choice(["tension", "elastic", "both"]))
        d0 = anchor - centre
        if variant.startswith("horizontal"):
            d0[2] = 0.0
        slack = float(np.linalg.norm(d0) - rng.uniform(0.0, 0.5))
        return cls(variant=variant, magnitude=magnitude, law=law, anchor_ned=anchor.tolist(), attach_body=attach,
                   tension=magnitude if law != "elastic" else 0.0,
                   stiffness=magnitude if law != "tension" else 0.0, slack_length=slack, rho=rho)

    def wrench(self, parts, rows):
        p0 = np.asarray(self.anchor_ned, dtype=float)[:, None]
        ra = np.asarray(self.attach_body, dtype=float)
        horizontal = self.variant.startswith("horizontal")
        drag = self.variant.endswith("drag")
        c_drag = 0.125 * self.rho * self.cd * self.diameter
        on = rows.astype(float)

        def tether(ctx):
            d = p0 - (ctx.pos + np.einsum("ijn,j->in", ctx.R, ra))
            if horizontal:
                d[2] = 0.0
            L = np.sqrt((d * d).sum(axis=0))
            e = d / np.maximum(L, 1e-9)
            F = (self.tension + self.stiffness * np.maximum(L - self.slack_length, 0.0)) * e
            if drag:
                va = matvec(ctx.R, ctx.nu_r[:3] + cross(ctx.nu_r[3:], ra[:, None]))
                vn = va - (va * e).sum(axis=0) * e
                F = F - c_drag * np.maximum(L, self.slack_length) * np.sqrt((vn * vn).sum(axis=0)) * vn
            f = to_body(ctx.R, F) * on
            return np.concatenate((f, cross(np.broadcast_to(ra[:, None], f.shape), f)))

        return tether


@dataclass
class Ballast(Effect):
    """A point load of net weight ``w`` (N, + down) at ``r_p`` (m, body): a lead weight
    (``lead``, ``w > 0``) or a block of buoyancy foam (``foam``, ``w < 0``).

    A real weight adds mass: the piece's mass ``m_p = |w| rho_p / (g |rho_p - rho|)``
    (lead 11340 kg/m^3, foam 320 kg/m^3) joins the rigid body (mass, CG, inertia about
    the origin ``+ m_p (|r_p|^2 I - r_p r_p^T)``), and the load ``w`` at ``r_p`` joins
    the restoring forces: ``[w k; w r_p x k]``.  Its added mass is neglected (a lead
    piece is small; foam blocks are usually inside the frame's own volume)."""

    type: ClassVar[str] = "ballast"
    variants: ClassVar[tuple] = ("lead", "foam")
    weight: float = 0.0        # N, + heavier
    position: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    density: float = LEAD_DENSITY
    mass: float = 0.0          # kg, of the piece

    @classmethod
    def sample(cls, rng, variant, magnitude, g=9.81, rho=1000.0, **_):
        dens = LEAD_DENSITY if variant == "lead" else FOAM_DENSITY
        w = magnitude if variant == "lead" else -magnitude
        return cls(variant=variant, magnitude=magnitude, weight=w, position=frame_point(rng), density=dens,
                   mass=float(abs(w) * dens / (g * abs(dens - rho))))

    def modify(self, parts, rows):
        r = np.asarray(self.position, dtype=float)
        m0 = parts["mass"][rows]
        parts["r_g"][:, rows] = (m0 * parts["r_g"][:, rows] + self.mass * r[:, None]) / (m0 + self.mass)
        parts["mass"][rows] = m0 + self.mass
        parts["inertia"][:, :, rows] += (self.mass * ((r @ r) * np.eye(3) - np.outer(r, r)))[:, :, None]
        parts["load"][rows] += self.weight
        parts["load_moment"][:, rows] += self.weight * r[:, None]


@dataclass
class ThrusterLag(Effect):
    """First-order actuator lag ``T f_dot = f_e - f`` per thruster (thrust / PWM inputs) or
    per generalized-force component (force inputs), on the thrust after the static
    effects (Fossen 2021 sec. 6.7; motor + inflow dynamics).  Variants: ``rest``
    (``f(0) = 0``, thrusters off before the log) or ``command`` (``f(0) = f_e(0)``)."""

    type: ClassVar[str] = "thruster_lag"
    variants: ClassVar[tuple] = ("rest", "command")
    time_constant: float = 0.1   # s

    @classmethod
    def sample(cls, rng, variant, magnitude, **_):
        return cls(variant=variant, magnitude=magnitude, time_constant=magnitude)

    def modify(self, parts, rows):
        parts["lag_time"][:, rows] = self.time_constant


def _per_thruster(f, A, rows, fn):
    """Apply ``fn`` to thruster thrusts; for force inputs (6 components) through the
    controller's allocation ``A^+`` and back (``A A^+ = I``)."""
    out = f.copy()
    if f.shape[1] == A.shape[1]:
        out[:, :, rows] = fn(f[:, :, rows])
    else:
        Ap = np.linalg.pinv(A)
        thr = np.einsum("ij,tjn->tin", Ap, f[:, :, rows])
        out[:, :, rows] = np.einsum("ij,tjn->tin", A, fn(thr))
    return out


@dataclass
class ThrustAsymmetry(Effect):
    """Reverse thrust scaled by ``ratio`` (< 1: weaker than the curve or the force inputs
    claim, e.g. a reversed wake hitting the frame)::

        f_eff = f_c            (f_c >= 0)
        f_eff = ratio * f_c    (f_c < 0)

    Variants: ``per_thruster`` (each thruster's thrust; force inputs are allocated by
    ``A^+`` first) or ``per_dof`` (each generalized-force component; force inputs only)."""

    type: ClassVar[str] = "thrust_asymmetry"
    variants: ClassVar[tuple] = ("per_thruster", "per_dof")
    ratio: float = 1.0

    @classmethod
    def sample(cls, rng, variant, magnitude, **_):
        return cls(variant=variant, magnitude=magnitude, ratio=1.0 - magnitude)

    def map_commands(self, f, kind, A, rows):
        if self.variant == "per_dof" and kind != "force":
            raise ScenarioError("effect thrust_asymmetry: variant per_dof needs force inputs")

        def fn(x):
            return np.where(x < 0, self.ratio * x, x)

        if self.variant == "per_dof":
            out = f.copy()
            out[:, :, rows] = fn(f[:, :, rows])
            return out
        return _per_thruster(f, A, rows, fn)


@dataclass
class WeakThruster(Effect):
    """One thruster delivers ``gain = 1 - magnitude`` times its thrust (fouled or damaged propeller).
    With force inputs the controller's allocation ``A^+`` splits the command among the
    thrusters and ``A diag(gains) A^+ tau`` is delivered.  Variants: which group the
    thruster belongs to (``horizontal`` or ``vertical``, by its direction)."""

    type: ClassVar[str] = "weak_thruster"
    variants: ClassVar[tuple] = ("horizontal", "vertical")
    thruster: int = 1            # 1-based, order of the vehicle file
    gain: float = 1.0

    @classmethod
    def sample(cls, rng, variant, magnitude, directions=None, **_):
        vertical = np.abs(np.asarray(directions)[:, 2]) > 0.7
        group = np.flatnonzero(vertical if variant == "vertical" else ~vertical)
        return cls(variant=variant, magnitude=magnitude, thruster=int(rng.choice(group)) + 1, gain=1.0 - magnitude)

    def map_commands(self, f, kind, A, rows):
        gains = np.ones(A.shape[1])
        gains[self.thruster - 1] = self.gain
        return _per_thruster(f, A, rows, lambda x: x * gains[None, :, None])


@dataclass
class CoupledDamping(Effect):
    """Translational drag acting at a drag centre ``r_cp`` (m, body) instead of the origin:
    the base drag force ``F = D_L v_r + D_Q |v_r| v_r`` (translational part, the truth's own
    coefficients) adds the moment ``r_cp x F``.  Variants: ``vertical_offset``
    (``r_cp = (0, 0, z_cp)``: ``K_v = -z_cp Y_v``, ``K_vv = -z_cp Y_vv``, ``M_u = z_cp X_u``,
    ``M_uu = z_cp X_uu``) and ``longitudinal_offset`` (``r_cp = (x_cp, 0, 0)``:
    ``N_v = x_cp Y_v``, ``N_vv = x_cp Y_vv``, ``M_w = -x_cp Z_w``, ``M_ww = -x_cp Z_ww``);
    ``derivatives`` lists them in SNAME names (paper sign) for the truth record."""

    type: ClassVar[str] = "coupled_damping"
    variants: ClassVar[tuple] = ("vertical_offset", "longitudinal_offset")
    offset: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    derivatives: dict = field(default_factory=dict)

    @classmethod
    def sample(cls, rng, variant, magnitude, **_):
        s = float(rng.choice([-1.0, 1.0]))
        off = [0.0, 0.0, s * magnitude] if variant == "vertical_offset" else [s * magnitude, 0.0, 0.0]
        return cls(variant=variant, magnitude=magnitude, offset=off)

    def with_derivatives(self, linear: dict, quadratic: dict) -> "CoupledDamping":
        x, _, z = self.offset
        if self.variant == "vertical_offset":
            d = {"K_v": -z * linear["Y_v"], "K_vv": -z * quadratic["Y_vv"],
                 "M_u": z * linear["X_u"], "M_uu": z * quadratic["X_uu"]}
        else:
            d = {"N_v": x * linear["Y_v"], "N_vv": x * quadratic["Y_vv"],
                 "M_w": -x * linear["Z_w"], "M_ww": -x * quadratic["Z_ww"]}
        self.derivatives = {k: float(v) for k, v in d.items()}
        return self

    def wrench(self, parts, rows):
        r = np.asarray(self.offset, dtype=float)[:, None]
        lin, quad = parts["linear"][:3].copy(), parts["quadratic"][:3].copy()
        on = rows.astype(float)

        def coupled(ctx):
            vr = ctx.nu_r[:3]
            F = (lin * vr + quad * np.abs(vr) * vr) * on
            return np.concatenate((np.zeros_like(F), cross(np.broadcast_to(r, F.shape), F)))

        return coupled


@dataclass
class PeriodicForce(Effect):
    """Uncatalogued disturbance (for robustness studies): a periodic body-frame force, e.g.
    a wake or a strumming cable, ``F(t) = a sin(2 pi f t + phi) e`` (N) at ``r`` (m, body),
    ``tau = [F; r x F]``, f = 0.1-0.5 Hz.  ``t`` is the run's own clock."""

    type: ClassVar[str] = "periodic_force"
    variants: ClassVar[tuple] = ("body_force",)
    amplitude: float = 0.0     # N
    frequency: float = 0.5     # Hz
    phase: float = 0.0         # rad
    direction: list = field(default_factory=lambda: [1.0, 0.0, 0.0])
    point: list = field(default_factory=lambda: [0.0, 0.0, 0.0])

    @classmethod
    def sample(cls, rng, variant, magnitude, **_):
        e = rng.normal(size=3)
        return cls(variant=variant, magnitude=magnitude, amplitude=magnitude, frequency=float(rng.uniform(0.1, 0.5)),
                   phase=float(rng.uniform(0, 2 * np.pi)), direction=(e / np.linalg.norm(e)).tolist(),
                   point=frame_point(rng))

    def wrench(self, parts, rows):
        e = np.asarray(self.direction, dtype=float)
        tau0 = np.concatenate((e, np.cross(np.asarray(self.point, dtype=float), e)))[:, None] * rows.astype(float)

        def periodic(ctx):
            return self.amplitude * np.sin(2 * np.pi * self.frequency * ctx.t + self.phase) * tau0

        return periodic


@dataclass
class PayloadPod(Effect):
    """Uncatalogued: a neutrally buoyant payload (a camera pod, a sample box) whose weight
    ``w`` acts at ``r_w`` and whose float (``-w``) at ``r_f`` (m, body): no net force, a
    restoring moment ``w (r_w - r_f) x k`` that no single catalogue ballast (one point, a
    net weight) describes.  The pod's mass and added mass are neglected (a few hundred
    grams against the vehicle's 13.2 kg, seed 000 Table 2)."""

    type: ClassVar[str] = "payload_pod"
    variants: ClassVar[tuple] = ("weight_below", "weight_aft")
    weight: float = 0.0                                          # N, the pod's weight (= its float's lift)
    weight_at: list = field(default_factory=lambda: [0.0, 0.0, 0.0])
    float_at: list = field(default_factory=lambda: [0.0, 0.0, 0.0])

    @classmethod
    def sample(cls, rng, variant, magnitude, **_):
        rw = np.asarray(frame_point(rng))
        rf = rw.copy()
        if variant == "weight_below":  # the weight hangs below its float (a pod under the frame)
            rf[2] = rw[2] - float(rng.uniform(0.1, 0.2))
        else:                          # the weight aft of its float (a sampler on a boom)
            rf[0] = rw[0] + float(rng.uniform(0.1, 0.3))
            rf[2] = rw[2] - float(rng.uniform(0.0, 0.1))
        return cls(variant=variant, magnitude=magnitude, weight=magnitude, weight_at=rw.tolist(),
                   float_at=rf.tolist())

    def modify(self, parts, rows):
        d = np.asarray(self.weight_at, dtype=float) - np.asarray(self.float_at, dtype=float)
        parts["load_moment"][:, rows] += self.weight * d[:, None]


EFFECTS = {cls.type: cls for cls in (Current, Tether, Ballast, ThrusterLag, ThrustAsymmetry, WeakThruster,
                                     CoupledDamping, PeriodicForce, PayloadPod)}
#: Effects outside any diagnosis catalogue (for the "not explained" benchmark).
UNCATALOGUED = ("periodic_force", "payload_pod")
#: Order in which command maps are applied (asymmetry of the curve, then the thruster's gain).
COMMAND_ORDER = ("thrust_asymmetry", "weak_thruster")


def effect_from_dict(d: dict) -> Effect:
    """Rebuild an effect from :meth:`Effect.to_dict` output."""
    if not isinstance(d, dict) or d.get("type") not in EFFECTS:
        raise ScenarioError(f"effect {d!r}: expected a mapping with type one of {sorted(EFFECTS)}")
    cls = EFFECTS[d["type"]]
    kw = {k: v for k, v in d.items() if k != "type"}
    known = set(cls.__dataclass_fields__)
    bad = sorted(set(kw) - known)
    if bad:
        raise ScenarioError(f"effect {d['type']}: unknown field(s) {bad}; expected {sorted(known)}")
    return cls(**kw)


def sample_effect(rng: np.random.Generator, type_: str, *, kind: str, suite: str = "mocap",
                  variant: str | None = None, magnitude: float | None = None, **context) -> Effect:
    """Draw one effect: a variant allowed for the input kind, a magnitude log-uniform over
    the suite's range (:data:`MAGNITUDE_RANGES`) unless given."""
    if type_ not in EFFECTS:
        raise ScenarioError(f"effect {type_!r}: expected one of {sorted(EFFECTS)}")
    cls = EFFECTS[type_]
    allowed = list(cls.variants)
    if type_ == "thrust_asymmetry" and kind != "force":
        allowed = ["per_thruster"]
    if variant is None:
        variant = str(rng.choice(allowed))
    elif variant not in allowed:
        raise ScenarioError(f"effect {type_}: variant {variant!r} with {kind} inputs; expected one of {allowed}")
    lo, hi = MAGNITUDE_RANGES[suite][type_]
    if magnitude is None:
        magnitude = log_uniform(rng, lo, hi)
    return cls.sample(rng, variant, float(magnitude), **context)
