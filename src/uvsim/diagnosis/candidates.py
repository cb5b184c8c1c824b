"""Candidate effects: what the diagnosis fits for each catalogue entry.

A :class:`Candidate` is one catalogue effect (:mod:`uvsim.effects`) with the
subset of its parameters that the data can identify, a start value (seeded by
the signature evidence where possible), a scale and bounds.  The fit works in
*fit variables* ``x``; :meth:`Candidate.to_params` maps them to the effect's
named parameters (vectorized over parameter sets).  Two candidates use a
reparameterization that is linear in the force, which conditions the fit:

* ``tether``: the elastic-line special case (tension 0, slack 0, no cable drag,
  attachment at the body origin): ``F = k (p_0 - p)``.  Fit variables are the
  stiffness ``k`` and the pull ``F_ref = k (p_0 - p_ref)`` at the mean start
  position ``p_ref`` of the runs; the anchor is ``p_0 = p_ref + F_ref / k``.
* ``ballast``: weight ``w`` and the moments ``w x``, ``w y`` (the load's height
  ``z`` only matters when the vehicle is tilted and stays at 0); ``x = (w x) / w``.
  (A pure moment with ``w`` near 0 maps to an unphysical position and is rejected.)

``current`` fits the horizontal components ``current_n``, ``current_e`` (a
steady vertical force is ``ballast``'s); ``thruster_lag`` its time constant;
``thrust_asymmetry`` its ratio; ``coupled_damping`` the two cross-coupling
derivatives with the strongest coupling evidence; ``bottom_effect`` its extra
drag at the floor and the floor's depth (decay length held at 0.25 m), only when
the runs log depth.  Base coefficients named in
``retune`` are added to every candidate (and to the baseline ``none``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import numpy as np

from uvsim.errors import CalibrationError


@dataclass
class Candidate:
    """One effect to try.

    Attributes
    ----------
    name : catalogue name (or "none" for the baseline).
    fit_names : names of the fit variables.
    x0, scale, lower, upper : (p,) start, typical magnitude and bounds of the fit variables.
    effect : the effect's vehicle-file dict with fixed fields (None for the baseline).
    mapping : ``f(X (P, p)) -> {parameter name: (P,)}`` (identity when None).
    notes : what is held fixed, how the start was chosen.
    """

    name: str
    fit_names: list
    x0: np.ndarray
    scale: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    effect: dict | None = None
    mapping: Callable | None = None
    notes: str = ""
    reported: list = field(default_factory=list)  # effect parameter names to report

    @property
    def n_params(self) -> int:
        return len(self.fit_names)

    def to_params(self, X: np.ndarray) -> dict[str, np.ndarray]:
        X = np.atleast_2d(np.asarray(X, float))
        if self.mapping is None:
            return {n: X[:, i] for i, n in enumerate(self.fit_names)}
        return self.mapping(X)


def _evidence(ev: Sequence[dict], name: str) -> dict | None:
    for e in ev:
        if e["signature"] == name:
            return e
    return None


def _clip(x, lo, hi):
    span = hi - lo
    return float(np.clip(x, lo + 1e-3 * span, hi - 1e-3 * span))


def _append_retune(c: Candidate, retune: Mapping[str, tuple[float, float, float]]) -> Candidate:
    """Add base coefficients to re-tune: name -> (start, low, high)."""
    if not retune:
        return c
    names = list(retune)
    x0 = [retune[n][0] for n in names]
    lo = [retune[n][1] for n in names]
    hi = [retune[n][2] for n in names]
    sc = [max(abs(retune[n][0]) * 0.2, 1e-3) for n in names]
    inner = c.mapping
    k = c.n_params

    def mapping(X, inner=inner, k=k, names=names):
        out = {n: X[:, i] for i, n in enumerate(c.fit_names[:k])} if inner is None else inner(X[:, :k])
        out.update({n: X[:, k + i] for i, n in enumerate(names)})
        return out

    return Candidate(c.name, c.fit_names + names, np.r_[c.x0, x0], np.r_[c.scale, sc], np.r_[c.lower, lo],
                     np.r_[c.upper, hi], c.effect, mapping, c.notes + f" Re-tuned base coefficients: {', '.join(names)}.",
                     c.reported + names)


def build_candidates(evidence: Sequence[dict], *, dt: float, p_ref: np.ndarray,
                     retune: Mapping[str, tuple[float, float, float]] | None = None,
                     only: Sequence[str] | None = None, z_max: float | None = None) -> list[Candidate]:
    """The baseline ``none`` and one candidate per catalogue effect (module docstring).

    Parameters
    ----------
    evidence : output of :func:`uvsim.diagnosis.signatures.evidence`.
    dt : sample interval of the runs, s (lower bound of a thruster time constant).
    p_ref : (3,) mean start position of the training runs, NED m.
    retune : base coefficients to re-tune with every candidate: name -> (start, low, high).
    only : restrict to these catalogue names.
    z_max : deepest logged depth of the training runs, m (None: no ``bottom_effect`` candidate).
    """
    retune = dict(retune or {})
    out = [_append_retune(Candidate("none", [], np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0),
                                    notes="The model as given."), retune)]
    cands = []

    # current --------------------------------------------------------------------
    cands.append(Candidate("current", ["current_n", "current_e"], np.zeros(2), np.full(2, 0.05),
                           np.full(2, -1.0), np.full(2, 1.0), {"type": "current"},
                           notes="Horizontal NED current; current_d held at 0 (a steady vertical force is ballast).",
                           reported=["current_n", "current_e"]))

    # tether ---------------------------------------------------------------------
    ev = _evidence(evidence, "growing with distance from the start")
    k0, F0 = 0.1, np.zeros(3)
    if ev is not None:
        det = ev["detail"]
        if det["stiffness_N_per_m"] and det["stiffness_N_per_m"] > 0:
            k0 = det["stiffness_N_per_m"]
        F0 = np.asarray(det["offset_N"], float)
    k0 = _clip(k0, 0.01, 20.0)
    F0 = np.array([_clip(f, -50.0, 50.0) for f in F0])
    pr = np.asarray(p_ref, float)

    def tether_map(X, pr=pr):
        k = X[:, 0]
        return {"tether_stiffness": k, "tether_anchor_n": pr[0] + X[:, 1] / k,
                "tether_anchor_e": pr[1] + X[:, 2] / k, "tether_anchor_d": pr[2] + X[:, 3] / k}

    cands.append(Candidate("tether", ["tether_stiffness", "pull_n_at_start", "pull_e_at_start", "pull_d_at_start"],
                           np.r_[k0, F0], np.array([0.2, 1.0, 1.0, 1.0]), np.array([0.01, -50, -50, -50.0]),
                           np.array([20.0, 50, 50, 50.0]),
                           {"type": "tether", "tension": 0.0, "slack_length": 0.0, "length": 0.0},
                           tether_map,
                           notes="Elastic line to an anchor: tension 0, slack 0, no cable drag, attached at the body "
                                 "origin; fitted as stiffness and pull at the mean start position.",
                           reported=["tether_stiffness", "tether_anchor_n", "tether_anchor_e", "tether_anchor_d"]))

    # thruster lag ---------------------------------------------------------------
    lo_T = max(0.5 * dt, 0.01)
    ev = _evidence(evidence, "lagging the input")
    T0 = 0.15
    if ev is not None and ev["detail"].get("time_constant_s_estimate"):
        T0 = ev["detail"]["time_constant_s_estimate"]
    cands.append(Candidate("thruster_lag", ["thruster_lag_time_constant"], np.array([_clip(T0, lo_T, 1.0)]),
                           np.array([0.1]), np.array([lo_T]), np.array([3.0]),
                           {"type": "thruster_lag", "time_constant": 0.2, "start": "steady"},
                           notes=f"First-order lag of every thruster; lower bound dt/2 = {lo_T:.3g} s.",
                           reported=["thruster_lag_time_constant"]))

    # thrust asymmetry -----------------------------------------------------------
    ev = _evidence(evidence, "sign-dependent on the input")
    r0 = 1.0
    cands.append(Candidate("thrust_asymmetry", ["thrust_asymmetry_ratio"], np.array([r0]), np.array([0.1]),
                           np.array([0.1]), np.array([2.0]), {"type": "thrust_asymmetry", "ratio": 1.0},
                           notes="One ratio for every thruster's reverse thrust.",
                           reported=["thrust_asymmetry_ratio"]))

    # ballast --------------------------------------------------------------------
    ev = _evidence(evidence, "constant in NED")
    w0 = 0.2
    if ev is not None:
        fz = ev["detail"]["mean_force_ned_N"][2]
        w0 = fz if abs(fz) > 0.2 else (0.2 if fz >= 0 else -0.2)
    w0 = _clip(w0, -50.0, 50.0)

    def ballast_map(X):
        w = X[:, 0]
        w_safe = np.where(np.abs(w) < 1e-9, 1e-9, w)  # w x and w y stay finite; x, y are their ratio to w
        return {"ballast_weight": w, "ballast_x": X[:, 1] / w_safe, "ballast_y": X[:, 2] / w_safe}

    cands.append(Candidate("ballast", ["ballast_weight", "weight_times_x", "weight_times_y"],
                           np.array([w0, 0.0, 0.0]), np.array([0.5, 0.02, 0.02]), np.array([-50.0, -10.0, -10.0]),
                           np.array([50.0, 10.0, 10.0]), {"type": "ballast", "weight": float(w0)}, ballast_map,
                           notes="Point load at height z = 0, fitted as weight and its moments (w x, w y); "
                                 "start from the vertical NED force residual.",
                           reported=["ballast_weight", "ballast_x", "ballast_y"]))

    # coupled damping ------------------------------------------------------------
    ev = _evidence(evidence, "coupling one DOF's velocity to another DOF's force")
    pairs = ev["detail"]["pairs"] if ev is not None else []
    chosen, used = [], set()
    for p in pairs:
        if p["force"] in used:
            continue
        chosen.append(p)
        used.add(p["force"])
        if len(chosen) == 2:
            break
    if chosen:
        names = [p["name"] for p in chosen]
        c0 = np.array([p["coefficient"] for p in chosen])
        desc = ", ".join("%s R2=%.2f" % (p["name"], p["r2"]) for p in chosen)
        bnd = np.maximum(50.0, 10 * np.abs(c0))
        c0 = np.array([_clip(c, -b, b) for c, b in zip(c0, bnd)])
        cands.append(Candidate("coupled_damping", names, c0, np.maximum(np.abs(c0), 0.1), -bnd, bnd,
                               {"type": "coupled_damping", **{n: float(v) for n, v in zip(names, c0)}},
                               notes=f"The cross-couplings with the strongest evidence ({desc}).",
                               reported=names))

    # bottom effect ----------------------------------------------------------------
    if z_max is not None and np.isfinite(z_max):
        lo_f, hi_f = z_max - 2.0, z_max + 3.0
        cands.append(Candidate("bottom_effect", ["bottom_effect_damping", "bottom_effect_floor_d"],
                               np.array([-50.0, z_max + 0.1]), np.array([50.0, 0.2]), np.array([-5000.0, lo_f]),
                               np.array([-1e-3, hi_f]),
                               {"type": "bottom_effect", "floor_d": float(z_max + 0.1), "damping": -50.0,
                                "decay_length": 0.25},
                               notes=f"Floor depth searched within {lo_f:.2f}..{hi_f:.2f} m (deepest logged depth "
                                     f"{z_max:.2f} m -2/+3 m); decay length held at 0.25 m (the BlueROV2's height).",
                               reported=["bottom_effect_damping", "bottom_effect_floor_d"]))

    if only is not None:
        unknown = set(only) - {c.name for c in cands}
        if unknown:
            raise CalibrationError(f"unknown candidate effect(s) {sorted(unknown)}; "
                                   f"known: {', '.join(c.name for c in cands)}")
        cands = [c for c in cands if c.name in only]
    return out + [_append_retune(c, retune) for c in cands]
