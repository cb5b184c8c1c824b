"""Which parameters a calibration frees, their bounds, and which ones the data excite.

* :func:`expand_names` - names or families (``thruster_gain_*``, ``z_b``) -> parameter
  names; an unknown name is an error with the closest known names;
* :func:`check_bounds` - user bounds ``{name: (low, high)}`` validated (known names,
  finite, low < high, paper signs: damping <= 0, inertia / added mass > 0); that they
  contain the start value is checked when the space is built
  (:func:`uvsim.fitting.make_space`), with an error naming both;
* :func:`joint_candidates` - the default free set of the joint stage: seed 000 Table 3
  (:data:`uvsim.calibration.params.DOF_PARAMETERS`) without the rigid-body inertias;
* :func:`excitation` - how well the data determine each candidate on its own: the
  conditional 1-sigma ``scale_k / sqrt(S_kk)`` from the information matrix ``S`` of
  the joint problem at the start (node states and gyro biases profiled out,
  :mod:`uvsim.fitting.solver`), relative to the parameter's value.  A parameter the
  training runs do not excite (e.g. the surge damping of runs that never move in surge
  and log no position or accelerometer) has a large one and is left at its value
  (:data:`EXCITATION_REL_SIGMA`).
"""
from __future__ import annotations

import difflib
import fnmatch
from typing import Iterable, Mapping, Sequence

import numpy as np

from uvsim.blas import single_thread
from uvsim.calibration.params import DOF_PARAMETERS, EFFECTIVE_INERTIA, check_sign, split_names  # noqa: F401
from uvsim.errors import CalibrationError

#: Rigid-body moments of inertia: fixed in the joint stage unless freed (decoupled data
#: determine only the sum with the added inertia, :data:`EFFECTIVE_INERTIA`).
RIGID_INERTIA = ("I_xx", "I_yy", "I_zz")
#: A candidate whose conditional 1-sigma exceeds this fraction of its value is "not
#: excited" by the data and stays fixed: even with every other parameter known, the
#: data would not determine it to better than +-50 %.
EXCITATION_REL_SIGMA = 0.5


def _did_you_mean(name: str, known: Iterable[str]) -> str:
    close = difflib.get_close_matches(name, list(known), n=3, cutoff=0.6)
    return f"; did you mean {', '.join(close)}?" if close else ""


def expand_names(spec, known: Sequence[str], option: str = "free") -> list[str]:
    """Parameter names from names and shell-style families (``thruster_gain_*``,
    ``thruster_?_3``), in the order of ``known``.  A name or family that matches no
    parameter is a :class:`CalibrationError` naming the closest known names."""
    known = list(known)
    out: list[str] = []
    for item in split_names(spec, option):
        hits = [k for k in known if fnmatch.fnmatchcase(k, item)]
        if not hits and item == "supply_voltage":
            raise CalibrationError(f"{option}: supply_voltage is a parameter only of thrusters whose curve depends "
                                   "on the battery voltage; give the vehicle file's thrusters the T200 family with "
                                   "one nominal voltage, curve: {voltage_table: t200, nominal_voltage: 16} "
                                   "(docs/thrusters.md)")
        if not hits:
            raise CalibrationError(f"{option}: unknown parameter {item!r}{_did_you_mean(item, known)} "
                                   f"(`uvsim vehicle show --json` lists a vehicle's parameters)")
        out += [k for k in hits if k not in out]
    return [k for k in known if k in out]


def check_bounds(bounds: Mapping | None, known: Mapping[str, float]) -> dict:
    """Validated ``{name: (low, high)}`` (module docstring)."""
    from uvsim.schema import require_mapping

    out = {}
    for k, b in require_mapping(bounds, "bounds", error=CalibrationError, example="{'X_u': (-1.0, -0.01)}").items():
        if k not in known:
            raise CalibrationError(f"bounds: unknown parameter {k!r}{_did_you_mean(k, known)}")
        try:
            lo, hi = float(b[0]), float(b[1])
        except (TypeError, ValueError, IndexError):
            raise CalibrationError(f"bounds for {k}: expected (low, high), got {b!r}") from None
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise CalibrationError(f"bounds for {k}: need finite low < high, got ({lo:g}, {hi:g})")
        check_sign(k, lo, hi)
        out[k] = (lo, hi)
    return out


def joint_candidates(dofs: Sequence[str] = tuple(DOF_PARAMETERS)) -> list[str]:
    """Table 3 parameters of ``dofs`` without the rigid-body inertias."""
    return [k for d in dofs for k in DOF_PARAMETERS[d] if k not in RIGID_INERTIA]


def information(problems, z: np.ndarray, workers: int = 1) -> np.ndarray:
    """Information matrix (p, p) on the scaled parameters ``z`` of windowed problems
    (:class:`uvsim.fitting.objective.WindowedProblem`) at ``z`` with the nuisance at its
    reference, the nuisance profiled out: ``sum_r A_r - B_r^T D_r^-1 B_r``."""
    from uvsim.fitting.evaluators import PoolEvaluator, SerialEvaluator

    nus = [n for p in problems for n in p.zero_nuisance()]
    ev = PoolEvaluator(problems, int(workers)) if workers > 1 and len(problems) > 1 else SerialEvaluator(problems)
    try:
        with single_thread():
            blocks = ev.linearize(np.asarray(z, float), nus)
    finally:
        ev.close()
    S = np.zeros((z.size, z.size))
    for b in blocks:
        S += b.A - (b.B.T @ np.linalg.solve(b.D, b.B) if b.D.shape[0] else 0.0)
    return S


def excitation(space, S: np.ndarray) -> dict[str, float]:
    """Conditional relative 1-sigma of every free parameter of ``space`` (module
    docstring); ``inf`` for a parameter no residual depends on."""
    out = {}
    for i, p in enumerate(space.free):
        info = float(S[i, i])
        sig = p.scale / np.sqrt(info) if info > 0 else np.inf
        out[p.name] = float(sig / max(abs(p.start), 1e-12))
    return out


def effective_inertia_start(ga_values: Mapping, base: Mapping, extra, fixed, bounds_of, explicit: Mapping):
    """Start values and bounds of the joint stage for the rotational DOFs.

    Unless freed, a rigid-body moment of inertia (``I_xx``) stays at the vehicle's value
    in the joint stage; the data determine only its sum with the added inertia
    (``I_xx + K_pdot``).  The GA split that sum arbitrarily, so the joint stage starts the
    added inertia at ``GA sum - I_xx (vehicle)`` and, unless bounds were given for it,
    bounds it by the GA's range of the sum minus the fixed ``I_xx`` (not below 0): the
    search range of the effective inertia is kept.  Returns (start values {name: value},
    bounds function name -> (low, high))."""
    start, joint = {}, {}
    for a, b in (EFFECTIVE_INERTIA[d] for d in ("roll", "pitch", "yaw")):
        if a in extra or a in fixed or b in fixed:
            continue
        if a in ga_values and b in ga_values:
            s = ga_values[a] + ga_values[b] - base[a]
            if s < 0:
                raise CalibrationError(
                    f"the GA's effective inertia {a} + {b} = {ga_values[a] + ga_values[b]:.4g} is below the vehicle's "
                    f"{a} = {base[a]:.4g}: the rigid-body inertia cannot be right; free it (--free {a})")
            start[a], start[b] = float(base[a]), float(s)
        joint[b] = None
    def joint_bounds(k):
        if k in joint and k not in explicit:
            pair = next(p for p in EFFECTIVE_INERTIA.values() if p[1] == k)
            (la, ha), (lb, hb) = bounds_of(pair[0]), bounds_of(k)
            return max(la + lb - base[pair[0]], 0.0), ha + hb - base[pair[0]]
        return bounds_of(k)

    return start, joint_bounds
