"""Candidate effects and their nested variants: what a diagnosis may add to a model.

Each :class:`Candidate` is one physical variant of a catalogue effect
(:mod:`uvsim.effects`) or of the actuator parameters (:mod:`uvsim.forces.actuators`):
the force term to add (``spec``, a vehicle-file ``effects:`` entry, or None when only
existing actuator parameters move), the parameters it frees with their bounds and
start values, and a complexity (its number of free parameters).  Variants of one
effect are compared by the same criterion, and the simplest sufficient one wins
(:mod:`uvsim.diagnosis.core`).

====================  ======================================================  ==========
effect                variants (free parameters)                              needs
====================  ======================================================  ==========
current               horizontal (n, e); 3d (n, e, d)                          -
tether                horizontal pull (stiffness, anchor n, e); horizontal_     position
                      slack (+ slack length); 3d (+ anchor d); tension
                      (constant pull); 3d_slack; 3d_drag (+ wetted cable
                      length: cross-flow drag); the same attached anywhere on
                      the frame (3d_attach, tension_attach, slack_attach,
                      drag_attach); full (tension + stiffness beyond slack +
                      drag + attachment); horizontal_full (the same with a
                      horizontal pull)
ballast               xy (weight, x, y); xyz (weight, x, y, z); xyz_mass (+       -
                      the piece's own mass: inertia only, fitted when xy or
                      xyz wins and kept on a lower open-loop validation cost)
thruster_lag          steady (time constant; starts at the command);            -
                      from_rest (starts at zero thrust); both are fitted when
                      a lag wins, the lower open-loop validation cost is kept
thrust_asymmetry      common (one reverse ratio); per_thruster (one per          -
                      thruster); per_dof (one per DOF, generalized-force
                      inputs)
thruster_gain         unit_i (thruster i's gain, 0-1.5: 0 is a dead unit,      thrusters
                      named as such); reversed_i (thruster i pushes the
                      wrong way, mounted or wired reversed: gain -1.5-0);
                      all (every thruster's gain); fouled_i (thruster i's
                      gain and reverse ratio, named as unit_i; module
                      uvsim.diagnosis.units); with generalized-force
                      inputs through the pseudo-inverse allocation
coupled_damping       drag_centre_z / _xz / _xyz (the translational damping     -
                      acts at a centre of pressure off the origin, seed 003
                      eq. 25); or the named off-diagonal derivatives that a
                      forward stepwise regression of the equation error picks
bottom_effect         drag coefficient and floor depth                          depth
base_model            thrust_scale (every curve scaled); damping (the 6         -
                      diagonal quadratic damping terms re-tuned); damping_thrust
                      (both); hydrodynamics (the 18 added-mass and damping
                      terms), hydrodynamics_thrust: "the base model is off",
                      not an effect
====================  ======================================================  ==========
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping, Sequence

import numpy as np

from uvsim.errors import CalibrationError
from uvsim.diagnosis.units import FOULED_REVERSE_RANGE
from uvsim.fitting.parameters import GAIN_RANGE, REVERSED_GAIN_RANGE

EFFECTS = ("current", "tether", "ballast", "thruster_lag", "thrust_asymmetry", "thruster_gain",
           "coupled_damping", "bottom_effect", "base_model")
#: The "effect" whose acceptance means that the base model, not a missing effect, is off
#: (its variants re-tune base coefficients or the thrust curve; never reported as an effect).
BASE_MODEL = "base_model"
#: The base coefficients a ``base_model:damping`` variant re-tunes: the diagonal quadratic
#: damping (seed 000 Table 5), which dominates the drag at tank speeds; the linear terms are
#: an order smaller there and ill-determined next to them, and the added masses move little.
BASE_DAMPING = ("X_uu", "Y_vv", "Z_ww", "K_pp", "M_qq", "N_rr")
#: ... and a ``base_model:hydrodynamics`` variant every added mass and diagonal damping term
#: (the 18 coefficients of seed 000 Table 5 that ``uvsim bench diagnose`` re-tunes).
BASE_HYDRO = ("X_udot", "Y_vdot", "Z_wdot", "K_pdot", "M_qdot", "N_rdot", "X_u", "Y_v", "Z_w", "K_p", "M_q", "N_r",
              *BASE_DAMPING)
#: Search range of the base model's re-tune, relative (as uvsim diagnose --retune).
BASE_MARGIN = 0.5
#: Search range of the thrust curve's scale: 0.5-1.5 (the T200 between 12 and 20 V at one
#: PWM spans about 0.6-1.5 of its 16 V thrust, thrust ~ V^2; Blue Robotics T200 data).
THRUST_SCALE_RANGE = (0.5, 1.5)
#: Search ranges (stated assumptions of this library, wide against what an ROV meets in a
#: tank or near a dock): currents up to 0.5 m/s horizontally and 0.3 m/s vertically;
#: tether stiffness up to 50 N/m and tension up to 50 N (the BlueROV2's thrusters give
#: ~50 N); anchors within 50 m; a ballast of up to 20 N within 0.5 m of the origin;
#: attachment points within 0.4 m (the frame); lags up to 2 s.
CURRENT_H, CURRENT_V = 0.5, 0.3
TETHER_K, TETHER_T, ANCHOR_RANGE = 50.0, 50.0, 50.0
BALLAST_W, BALLAST_R, ATTACH_R = 20.0, 0.5, 0.4
#: largest lumped cable drag, N s^2/m^2: the whole cross-flow drag 1/2 rho C_d D l of a
#: 7.6 mm Fathom tether (C_d 1.2, effects.tether) of ANCHOR_RANGE metres moving uniformly
LUMPED_DRAG_MAX = 0.5 * 1000.0 * 1.2 * 0.0076 * ANCHOR_RANGE
#: a ballast piece's own mass: up to 2 kg (20 N of lead is 2.3 kg)
BALLAST_M = 2.0
#: a tether's catalogue start has its anchor this far south (m) of the reference position
#: (uvsim.diagnosis.starts recovers the reference position from it)
ANCHOR_START_SOUTH = 5.0
LAG_MAX = 2.0


@dataclass
class Candidate:
    """One variant of one effect (module docstring)."""

    effect: str
    variant: str
    spec: dict | None
    free: list
    bounds: dict
    start: dict
    notes: str = ""
    tags: dict = field(default_factory=dict)

    @property
    def label(self) -> str:
        return f"{self.effect}:{self.variant}"

    @property
    def complexity(self) -> int:
        return len(self.free)

    @property
    def null(self) -> dict:
        """The parameters (and their values) that switch the effect off: what the
        in-sample Wald test of :mod:`uvsim.diagnosis.core` tests against."""
        off = {}
        for n in self.free:
            if n == "thruster_lag_time_constant":
                off[n] = self.bounds[n][0]  # the identifiability floor of a lag (_lag)
            elif n.startswith(("current_", "drag_centre_")) or n in ("tether_stiffness", "tether_tension",
                                                                     "ballast_weight", "bottom_effect_damping"):
                off[n] = 0.0
            elif n.startswith(("thruster_gain_", "thruster_reverse_", "force_reverse_", "force_gain_")) \
                    or n == "thrust_asymmetry_ratio":
                off[n] = 1.0
            elif self.effect == "coupled_damping":
                off[n] = 0.0
            elif self.effect == BASE_MODEL:
                off[n] = 1.0 if n == "thrust_scale_scale" else self.start[n]  # the vehicle file's values
        return off


def _current():
    b = {"current_n": (-CURRENT_H, CURRENT_H), "current_e": (-CURRENT_H, CURRENT_H),
         "current_d": (-CURRENT_V, CURRENT_V)}
    s = {"current_n": 0.0, "current_e": 0.0, "current_d": 0.0}
    spec = {"type": "current"}
    return [Candidate("current", "horizontal", spec, ["current_n", "current_e"], b, s,
                      "constant NED current through the relative velocity; no vertical part"),
            Candidate("current", "3d", spec, ["current_n", "current_e", "current_d"], b, s,
                      "constant NED current with a vertical part")]


def _tether(p_ref):
    """Tether variants, from the elastic line at the origin to the full law.  The pull
    along the line to the anchor is ``T_0 + k max(0, L - L_s)`` (:mod:`uvsim.effects.tether`):
    ``tension`` is ``T_0`` alone, the elastic variants ``k`` (with ``L_s = 0`` or free),
    ``full`` all three (when the line is always taut only ``T_0 - k L_s`` and ``k`` are
    determined; the identifiability report says so)."""
    pn, pe, pd = (float(x) for x in p_ref)
    b = {"tether_stiffness": (0.0, TETHER_K), "tether_tension": (0.0, TETHER_T),
         "tether_anchor_n": (pn - ANCHOR_RANGE, pn + ANCHOR_RANGE),
         "tether_anchor_e": (pe - ANCHOR_RANGE, pe + ANCHOR_RANGE),
         "tether_anchor_d": (pd - ANCHOR_RANGE, pd + ANCHOR_RANGE),
         "tether_attach_x": (-ATTACH_R, ATTACH_R), "tether_attach_y": (-ATTACH_R, ATTACH_R),
         "tether_attach_z": (-ATTACH_R, ATTACH_R), "tether_length": (0.0, 2 * ANCHOR_RANGE),
         "tether_slack_length": (0.0, ANCHOR_RANGE), "tether_lumped_drag": (0.0, LUMPED_DRAG_MAX)}
    s = {"tether_stiffness": 0.5, "tether_tension": 1.0, "tether_anchor_n": pn - ANCHOR_START_SOUTH,
         "tether_anchor_e": pe,
         "tether_anchor_d": pd, "tether_attach_x": 0.0, "tether_attach_y": 0.0, "tether_attach_z": 0.0,
         "tether_length": 10.0, "tether_slack_length": 0.0, "tether_lumped_drag": 1.0}
    base = {"type": "tether", "tension": 0.0, "stiffness": 0.5, "slack_length": 0.0, "length": 0.0,
            "anchor_n": pn - ANCHOR_START_SOUTH, "anchor_e": pe, "anchor_d": pd}
    tens = {**base, "stiffness": 0.0, "tension": 1.0}
    a3 = ["tether_anchor_n", "tether_anchor_e", "tether_anchor_d"]
    at = ["tether_attach_x", "tether_attach_y", "tether_attach_z"]
    k, ls, t0, ln = "tether_stiffness", "tether_slack_length", "tether_tension", "tether_length"
    drag = "quadratic cross-flow drag of the wetted cable (C_d 1.2, 7.6 mm Fathom tether)"

    def cand(variant, spec, free, notes):
        return Candidate("tether", variant, spec, free, b, s, notes)

    return [
        cand("horizontal", {**base, "horizontal": True}, [k, "tether_anchor_n", "tether_anchor_e"],
             "elastic line pulling horizontally towards an anchor (cable on the floor or at the surface)"),
        cand("horizontal_slack", {**base, "horizontal": True}, [k, ls, "tether_anchor_n", "tether_anchor_e"],
             "elastic line pulling horizontally once stretched beyond its slack length"),
        cand("3d", dict(base), [k] + a3, "elastic line pulling in 3-D towards an anchor, attached at the body origin"),
        cand("tension", tens, [t0] + a3, "constant pull towards an anchor (a spool or float), attached at the origin"),
        cand("3d_slack", dict(base), [k, ls] + a3, "elastic line pulling in 3-D once stretched beyond its slack"),
        cand("3d_drag", dict(base, length=10.0), [k] + a3 + [ln], f"elastic line in 3-D plus {drag}"),
        cand("3d_attach", dict(base), [k] + a3 + at, "elastic line in 3-D, attached anywhere on the frame"),
        cand("tension_attach", tens, [t0] + a3 + at, "constant pull, attached anywhere on the frame"),
        cand("slack_attach", dict(base), [k, ls] + a3 + at,
             "elastic line beyond its slack length, attached anywhere on the frame"),
        cand("drag_attach", {**tens, "length": 10.0}, [t0] + a3 + at + [ln],
             f"constant pull plus {drag}, attached anywhere on the frame"),
        cand("horizontal_full", {**base, "horizontal": True, "tension": 1.0, "length": 10.0},
             [t0, k, ls, "tether_anchor_n", "tether_anchor_e"] + at + [ln],
             f"horizontal pull (tension plus elastic beyond a slack length), plus {drag}, attached anywhere "
             "on the frame (a cable trailing on the floor or at the surface)"),
        cand("horizontal_lumped", {**base, "horizontal": True, "lumped_drag": 1.0},
             [k, "tether_anchor_n", "tether_anchor_e"] + at + ["tether_lumped_drag"],
             "elastic line pulling horizontally, attached anywhere on the frame, with the cable's drag lumped at "
             "the attachment against its velocity in every direction (a slack cable's bight)"),
        cand("lumped_attach", {**base, "lumped_drag": 1.0}, [k] + a3 + at + ["tether_lumped_drag"],
             "elastic line in 3-D, attached anywhere on the frame, with the cable's drag lumped at the attachment"),
        cand("full", {**base, "tension": 1.0, "length": 10.0}, [t0, k, ls] + a3 + at + [ln],
             f"tension plus elastic pull beyond a slack length, plus {drag}, attached anywhere on the frame"),
    ]


def _ballast():
    b = {"ballast_weight": (-BALLAST_W, BALLAST_W), "ballast_x": (-BALLAST_R, BALLAST_R),
         "ballast_y": (-BALLAST_R, BALLAST_R), "ballast_z": (-BALLAST_R, BALLAST_R), "ballast_mass": (0.0, BALLAST_M)}
    s = {"ballast_weight": 0.5, "ballast_x": 0.0, "ballast_y": 0.0, "ballast_z": 0.0, "ballast_mass": 0.0}
    spec = {"type": "ballast", "weight": 0.5}
    return [Candidate("ballast", "xy", spec, ["ballast_weight", "ballast_x", "ballast_y"], b, s,
                      "point weight (or buoyancy) at body height 0"),
            Candidate("ballast", "xyz", spec, ["ballast_weight", "ballast_x", "ballast_y", "ballast_z"], b, s,
                      "point weight (or buoyancy) anywhere on the frame"),
            Candidate("ballast", "xyz_mass", spec, ["ballast_weight", "ballast_x", "ballast_y", "ballast_z",
                                                    "ballast_mass"], b, s,
                      "a piece with its own mass (inertia) anywhere on the frame", {"open_loop": "inertia"})]


#: Parameters whose lower bound is a physical limit, not a search limit: a fit may end
#: there (no stiffness, no pre-tension, no slack, no wetted cable, a massless piece) and
#: the effect still be named; every other bound is the edge of the catalogue's search range.
PHYSICAL_FLOORS = ("tether_stiffness", "tether_tension", "tether_slack_length", "tether_length",
                   "tether_lumped_drag", "ballast_mass")


def _physical_floor(c: Candidate, n: str) -> bool:
    """Whether the lower bound of ``n`` in ``c`` is a physical limit (:data:`PHYSICAL_FLOORS`;
    a thruster's gain 0: a dead unit), not the edge of a search range."""
    return n in PHYSICAL_FLOORS or (c.effect == "thruster_gain" and not c.tags.get("reversed")
                                    and n.startswith("thruster_gain_"))


def _dead_end(c: Candidate, n: str) -> bool:
    """Whether ``n`` is a reversed unit's gain, whose upper bound 0 is a physical limit too: a dead
    unit, reported as the unit's own variant (:func:`uvsim.diagnosis.units.reported_variant`)."""
    return c.effect == "thruster_gain" and bool(c.tags.get("reversed")) and n.startswith("thruster_gain_")


def _on_floor(c: Candidate, n: str, values: Mapping[str, float]) -> bool | None:
    """Whether ``n``, ended on a bound of its range, is on the lower one (nearer it than the upper);
    None when ``values`` lacks it."""
    if n not in values:
        return None
    lo, hi = c.bounds[n]
    return abs(values[n] - lo) <= abs(values[n] - hi)


def search_bound_hits(c: Candidate, values: Mapping[str, float], at_bounds: Sequence[str]) -> list[str]:
    """The parameters of ``c`` that ended on the edge of their search range (not on a
    physical floor, :func:`_physical_floor`): such an effect is not named, since the data
    push it beyond what the catalogue considers physical for this vehicle."""
    out = []
    if c.effect == BASE_MODEL:
        # a re-tune is not an effect: a coefficient at +-50 % says "far off", not "unphysical"; but a
        # thrust scale on its floor is below what a supply voltage can do (THRUST_SCALE_RANGE) and
        # stands in for something else: under an autopilot, thrust held against a force the model
        # lacks, which a model without that force reads as thrust that moves nothing (below_supply)
        n = "thrust_scale_scale"
        return [n] if n in at_bounds and n in c.free and _on_floor(c, n, values) else out
    for n in at_bounds:
        if n not in c.free:
            continue
        floor = _on_floor(c, n, values)
        if (_physical_floor(c, n) and floor) or (_dead_end(c, n) and floor is False):
            continue
        out.append(n)
    return out


def below_supply(c: Candidate, values: Mapping[str, float]) -> str | None:
    """Why every unit's gain (``thruster_gain:all``) is no answer when all of them lie below the
    thrust scale's floor (:data:`THRUST_SCALE_RANGE`: what a supply voltage can do), or None.  The
    units fail one at a time; eight at once below what a flat battery gives is the scale of
    ``base_model:thrust_scale`` on its floor in another form: under an autopilot the thrusters
    hold against a force or moment the model lacks (a tether, a current), and a model without it
    sees thrust that moves nothing (field logs, tether seed 7: every gain 0.08-0.18)."""
    if c.effect != "thruster_gain" or c.variant != "all":
        return None
    gains = [float(values[n]) for n in c.free if n in values]
    lo = THRUST_SCALE_RANGE[0]
    if not gains or max(gains) >= lo:
        return None
    return (f"every unit at {min(gains):.2f}-{max(gains):.2f} of its curve, all below the {lo:g} a supply voltage "
            "can explain (base_model:thrust_scale's range): no unit's fault but thrust that moves nothing in the "
            "model, as when an autopilot holds against a force the model lacks (a tether, a current), so it is "
            "not named")


def mirror_start(c: Candidate, values: Mapping[str, float]) -> dict:
    """The start with the same moments and the opposite force: a ballast's weight and
    position negated (``w r`` unchanged); {} for other effects.  Where the log has no linear
    velocities the rotational equation error fixes only the moments (Selector.step)."""
    if c.effect != "ballast":
        return {}
    return {n: -float(values.get(n, c.start[n])) for n in c.free
            if n in ("ballast_weight", "ballast_x", "ballast_y", "ballast_z")}


def inertia_start(c: Candidate, values: Mapping[str, float], g: float) -> dict:
    """Start of the inertial parameters of an ``open_loop`` variant from the winner's
    ``values``: a ballast piece of mass ``|w| / g`` (a density of rho / 2 for buoyancy
    foam, 2 rho for a weight: between syntactic foam and lead, neither assumed)."""
    if c.effect == "ballast":
        return {"ballast_mass": float(min(abs(values.get("ballast_weight", 0.0)) / g, BALLAST_M))}
    return {}


def _lag(dt):
    # The floor is half the log's sample interval: a command held between samples (zero-order
    # hold) acts like the underlying signal delayed by dt / 2 (Franklin, Powell & Workman,
    # Digital Control of Dynamic Systems, 3rd ed., sec. 4.3.1: ZOH ~ e^{-s dt/2}), and a
    # first-order lag T acts like a delay T at low frequency, so a lag of at most dt / 2 is
    # the logged inputs' unknown timing convention (held before or after the sample, sampled
    # from a continuous command), not an actuator.  It is also above the RK4 stability limit
    # at the log's step (T > dt / 2.8, module thrusters).
    lo = max(dt / 2.0, 0.01)
    b = {"thruster_lag_time_constant": (lo, LAG_MAX)}
    s = {"thruster_lag_time_constant": max(0.2, 2 * lo)}
    return [Candidate("thruster_lag", "steady", {"type": "thruster_lag", "time_constant": s[
        "thruster_lag_time_constant"], "start": "steady"}, ["thruster_lag_time_constant"], b, s,
                      "first-order thrust lag, thrust at the command when the log starts", {"alternatives": "lag_start"}),
            Candidate("thruster_lag", "from_rest", {"type": "thruster_lag", "time_constant": s[
                "thruster_lag_time_constant"], "start": "zero"}, ["thruster_lag_time_constant"], b, s,
                      "first-order thrust lag, thrusters at rest when the log starts", {"alternatives": "lag_start"})]


def _asymmetry(kind, k):
    cands = [Candidate("thrust_asymmetry", "common", {"type": "thrust_asymmetry", "ratio": 1.0},
                       ["thrust_asymmetry_ratio"], {"thrust_asymmetry_ratio": (0.1, 1.5)},
                       {"thrust_asymmetry_ratio": 1.0},
                       "one reverse/forward ratio for every thruster" if kind != "force"
                       else "one reverse/forward ratio for every generalized-force component")]
    if k:
        names = [f"thruster_reverse_{i + 1}" for i in range(k)]
        cands.append(Candidate("thrust_asymmetry", "per_thruster", None, names, {n: (0.1, 1.5) for n in names},
                               {n: 1.0 for n in names}, "a reverse ratio per thruster" + (
                                   " (force inputs: through the pseudo-inverse allocation)" if kind == "force" else "")))
    if kind == "force":
        names = [f"force_reverse_{c}" for c in "XYZKMN"]
        cands.append(Candidate("thrust_asymmetry", "per_dof", None, names, {n: (0.1, 1.5) for n in names},
                               {n: 1.0 for n in names}, "a reverse ratio per generalized-force component"))
    return cands


def _gain(k):
    """The ``thruster_gain`` variants of ``k`` thrusters (the table above; :mod:`uvsim.diagnosis.units`
    describes them): per unit ``unit_i`` and ``reversed_i``, then ``all``, then per unit ``fouled_i``."""
    out = []
    for i in range(k):
        n = f"thruster_gain_{i + 1}"
        out.append(Candidate("thruster_gain", f"unit_{i + 1}", None, [n], {n: GAIN_RANGE}, {n: 1.0},
                             f"thruster {i + 1} delivers a fraction of its curve (fouled, damaged; 0: dead)",
                             {"unit": i + 1}))
        out.append(Candidate("thruster_gain", f"reversed_{i + 1}", None, [n], {n: REVERSED_GAIN_RANGE}, {n: -1.0},
                             f"thruster {i + 1} pushes the wrong way (mounted or wired reversed)",
                             {"unit": i + 1, "reversed": True}))
    names = [f"thruster_gain_{i + 1}" for i in range(k)]
    out.append(Candidate("thruster_gain", "all", None, names, {n: GAIN_RANGE for n in names}, {n: 1.0 for n in names},
                         "every thruster's gain"))
    for i in range(k):
        n, r = f"thruster_gain_{i + 1}", f"thruster_reverse_{i + 1}"
        out.append(Candidate("thruster_gain", f"fouled_{i + 1}", None, [n, r], {n: GAIN_RANGE, r: FOULED_REVERSE_RANGE},
                             {n: 1.0, r: 1.0},
                             f"thruster {i + 1} delivers a fraction of its curve, a smaller one in reverse (fouled: "
                             "a line or weed round the propeller, a damaged blade)",
                             {"unit": i + 1, "fouled": True}))
    return out


def _bottom(z_max):
    lo, hi = z_max - 2.0, z_max + 3.0
    b = {"bottom_effect_damping": (-5000.0, -1e-3), "bottom_effect_floor_d": (lo, hi)}
    s = {"bottom_effect_damping": -50.0, "bottom_effect_floor_d": z_max + 0.1}
    return [Candidate("bottom_effect", "floor", {"type": "bottom_effect", "floor_d": z_max + 0.1, "damping": -50.0,
                                                 "decay_length": 0.25},
                      ["bottom_effect_damping", "bottom_effect_floor_d"], b, s,
                      f"extra vertical drag near a floor searched within {lo:.2f}..{hi:.2f} m; decay length 0.25 m "
                      "(the BlueROV2's height)")]


def _base_model(base: Mapping[str, float], n_thrusters: int, input_kind: str):
    """"The base model is off": the diagonal damping re-tuned, the thrust curve scaled
    (thrusters: every curve; force inputs: the logged forces), or both.  Compared with the
    effects like an effect, and fitted before any actuator fault is judged (parsimony:
    one scale beats per-thruster gains that say the same)."""
    from uvsim.fitting.parameters import default_bounds

    out = []
    scale_spec = {"type": "thrust_scale", "scale": 1.0}
    sb = {"thrust_scale_scale": THRUST_SCALE_RANGE}
    ss = {"thrust_scale_scale": 1.0}
    what = "every thruster's curve" if input_kind != "force" else "the logged generalized forces"
    out.append(Candidate(BASE_MODEL, "thrust_scale", scale_spec, ["thrust_scale_scale"], sb, ss,
                         f"{what} scaled (another supply voltage, propeller or ESC than the vehicle file's)"))
    if "supply_voltage" in base and input_kind == "pwm":  # thrusters on a voltage family (docs/thrusters.md)
        v0 = float(base["supply_voltage"])
        out.append(Candidate(BASE_MODEL, "supply_voltage", None, ["supply_voltage"],
                             {"supply_voltage": default_bounds("supply_voltage", v0, BASE_MARGIN)},
                             {"supply_voltage": v0},
                             "the thrust curves read at another battery voltage than the file's (their shape "
                             "near the dead band as well as their scale)"))
    damp = [n for n in BASE_DAMPING if n in base and base[n] != 0.0]
    if damp:
        b = {n: default_bounds(n, base[n], BASE_MARGIN) for n in damp}
        st = {n: float(base[n]) for n in damp}
        out.append(Candidate(BASE_MODEL, "damping", None, damp, b, st,
                             f"the diagonal quadratic damping re-tuned within +-{100 * BASE_MARGIN:.0f} % of the vehicle "
                             "file"))
        out.append(Candidate(BASE_MODEL, "damping_thrust", scale_spec, damp + ["thrust_scale_scale"], {**b, **sb},
                             {**st, **ss}, f"the diagonal damping re-tuned and {what} scaled"))
    hydro = [n for n in BASE_HYDRO if n in base and base[n] != 0.0]
    if len(hydro) > len(damp):
        b = {n: default_bounds(n, base[n], BASE_MARGIN) for n in hydro}
        st = {n: float(base[n]) for n in hydro}
        out.append(Candidate(BASE_MODEL, "hydrodynamics", None, hydro, b, st,
                             f"every added mass and diagonal damping term re-tuned within +-{100 * BASE_MARGIN:.0f} % "
                             "of the vehicle file"))
        out.append(Candidate(BASE_MODEL, "hydrodynamics_thrust", scale_spec, hydro + ["thrust_scale_scale"],
                             {**b, **sb}, {**st, **ss}, f"every added mass and damping term re-tuned and {what} scaled"))
    return out


def _drag_centre():
    b = {"drag_centre_x": (-0.5, 0.5), "drag_centre_y": (-0.5, 0.5), "drag_centre_z": (-0.5, 0.5)}
    s = {"drag_centre_x": 0.0, "drag_centre_y": 0.0, "drag_centre_z": 0.0}
    spec = {"type": "drag_centre"}
    return [Candidate("coupled_damping", "drag_centre_z", spec, ["drag_centre_z"], b, s,
                      "translational drag acting below/above the origin (K_v, K_vv, M_u, M_uu; seed 003 eq. 25)"),
            Candidate("coupled_damping", "drag_centre_xz", spec, ["drag_centre_x", "drag_centre_z"], b, s,
                      "translational drag acting at (x, 0, z) off the origin (seed 003 eq. 25)"),
            Candidate("coupled_damping", "drag_centre_xyz", spec, ["drag_centre_x", "drag_centre_y", "drag_centre_z"],
                      b, s, "translational drag acting at a point (x, y, z) off the origin (seed 003 eq. 25)")]


def coupled_candidate(pairs: Sequence[str]) -> Candidate:
    """The coupled-damping candidate for named derivatives (chosen by the equation error)."""
    names = list(pairs)
    spec = {"type": "coupled_damping", **{n: 0.0 for n in names}}  # its parameters are the SNAME names
    return Candidate("coupled_damping", "+".join(names), spec, names, {p: (-200.0, 200.0) for p in names},
                     {p: 0.0 for p in names}, "off-diagonal damping derivatives (seed 003 eq. 26)")


def coupling_terms() -> list[str]:
    """Every off-diagonal linear and quadratic damping derivative name (K_v, K_vv, ...)."""
    out = []
    for i, f in enumerate("XYZKMN"):
        for j, v in enumerate("uvwpqr"):
            if i != j:
                out += [f"{f}_{v}", f"{f}_{v}{v}"]
    return out


def catalogue(*, input_kind: str, n_thrusters: int, dt: float, p_ref, has_position: bool, z_max: float | None,
              only: Sequence[str] | None = None, exclude: Sequence[str] = (), has_depth: bool = False,
              base: Mapping[str, float] | None = None) -> list[Candidate]:
    """The candidate variants that apply to the data (module docstring), except the
    coupled-damping one, which needs the equation error to pick its derivatives.

    Without x/y (IMU + depth, as most ROVs log) the tether variants that pull in 3-D are
    kept when depth is logged: their pull acts on depth, attitude and rates through the
    attachment point, and the horizontal position they need is the model's own (simulated)
    one; the horizontal-pull variants are left out (:func:`observability` says so)."""
    if only is not None:
        unknown = sorted(set(only) - set(EFFECTS))
        if unknown:
            raise CalibrationError(f"unknown candidate effect(s) {unknown}; known: {', '.join(EFFECTS)}")
    want = set(only or EFFECTS) - set(exclude)
    out: list[Candidate] = []
    if "current" in want:
        out += _current()
    if "tether" in want and has_position:
        out += _tether(p_ref)
    elif "tether" in want and has_depth:
        out += [c for c in _tether(p_ref) if not c.spec.get("horizontal")]
    if "ballast" in want:
        out += _ballast()
    if "thruster_lag" in want:
        out += _lag(dt)
    if "thrust_asymmetry" in want:
        out += _asymmetry(input_kind, n_thrusters)
    if "thruster_gain" in want and n_thrusters:
        out += _gain(n_thrusters)
    if "coupled_damping" in want:
        out += _drag_centre()
    if "bottom_effect" in want and z_max is not None and np.isfinite(z_max):
        out += _bottom(z_max)
    if BASE_MODEL in want and base is not None:
        out += _base_model(base, n_thrusters, input_kind)
    return out


def observability(*, has_position: bool, has_depth: bool, has_velocity: bool, z_max: float | None,
                  n_thrusters: int) -> list[dict]:
    """What the logged signals cannot show, per effect: ``[{"effect", "variants", "why"}]``
    (the report's ``not_observable``; an empty list when everything is screened)."""
    out = []
    if not has_position:
        if has_depth:
            out.append({"effect": "tether", "variants": "horizontal pulls",
                        "why": "a horizontal pull depends on x/y, which were not logged; the 3-D variants (a spool "
                               "or float above or beside the vehicle) are screened from depth, attitude and rates"})
        else:
            out.append({"effect": "tether", "variants": "all",
                        "why": "a tether pulls with the distance to its anchor: neither x/y nor depth were logged"})
        if not has_velocity:
            out.append({"effect": "current", "variants": "horizontal",
                        "why": "without x/y or a DVL a horizontal current acts only through the relative-velocity "
                               "terms (damping, Munk moment) on the rates and attitude; it is screened, but a small "
                               "current can stay undetected"})
    if z_max is None or not np.isfinite(z_max):
        out.append({"effect": "bottom_effect", "variants": "all", "why": "needs depth or z, which were not logged"})
    if not n_thrusters:
        out.append({"effect": "thruster_gain", "variants": "all", "why": "the vehicle defines no thrusters"})
    return out
