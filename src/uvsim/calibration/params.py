"""Which parameters each degree of freedom fits, and their search bounds.

Seed 000 Table 3: linear DOFs fit added mass, linear and quadratic damping;
rotational DOFs also the moment of inertia.  Bounds are "chosen from the
initial values ... with some reasonable margin up and down" (sec. 4.4); here the
default margin is +-50 % of each initial value (Table 5 moved values by up to
25 %), overridable per parameter.
"""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from uvsim.errors import CalibrationError
from uvsim.voltage_curves import measured_voltage_range

#: seed 000 Table 3, in the order inertia, added mass, linear, quadratic damping.
DOF_PARAMETERS = {
    "surge": ("X_udot", "X_u", "X_uu"),
    "sway": ("Y_vdot", "Y_v", "Y_vv"),
    "heave": ("Z_wdot", "Z_w", "Z_ww"),
    "roll": ("I_xx", "K_pdot", "K_p", "K_pp"),
    "pitch": ("I_yy", "M_qdot", "M_q", "M_qq"),
    "yaw": ("I_zz", "N_rdot", "N_r", "N_rr"),
}
CALIBRATION_DOFS = tuple(DOF_PARAMETERS)
#: Rigid-body inertia and added-mass parameter of each DOF: in decoupled runs they
#: only enter as their sum (the effective mass / inertia).
EFFECTIVE_INERTIA = {
    "surge": ("m", "X_udot"), "sway": ("m", "Y_vdot"), "heave": ("m", "Z_wdot"),
    "roll": ("I_xx", "K_pdot"), "pitch": ("I_yy", "M_qdot"), "yaw": ("I_zz", "N_rdot"),
}
LINEAR_DAMPING = {"surge": "X_u", "sway": "Y_v", "heave": "Z_w", "roll": "K_p", "pitch": "M_q", "yaw": "N_r"}
QUADRATIC_DAMPING = {"surge": "X_uu", "sway": "Y_vv", "heave": "Z_ww", "roll": "K_pp", "pitch": "M_qq",
                     "yaw": "N_rr"}
DEFAULT_MARGIN = 0.5
#: Channels each DOF's GA fitness looks at by default (seed 000 sec. 4.4: each DOF is
#: optimized on its own motion; positions for the linear DOFs, angles for the
#: rotational ones; plus the matching depth, velocity / rate and accelerometer axis
#: where logged).  Other channels of the same runs depend on parameters of other DOFs
#: (e.g. the depth drift of a positively buoyant vehicle during a surge run), which
#: would bias the per-DOF fit; the joint stage uses every channel.
DOF_CHANNELS = {
    "surge": ("x", "u", "acc_x"), "sway": ("y", "v", "acc_y"), "heave": ("z", "depth", "w", "acc_z"),
    "roll": ("roll", "p"), "pitch": ("pitch", "q"), "yaw": ("yaw", "r"),
}
#: Parameters whose sign is fixed (paper sign): damping <= 0; inertia and added mass > 0.
SIGNED_NEGATIVE = tuple(LINEAR_DAMPING.values()) + tuple(QUADRATIC_DAMPING.values())


def default_channel_weights(dof: str) -> dict:
    """Weights selecting :data:`DOF_CHANNELS` [dof] (1) and nothing else (0), by channel
    (:data:`uvsim.signals.CHANNEL_GROUP`)."""
    from uvsim.signals import CHANNEL_GROUP

    return {c: (1.0 if c in DOF_CHANNELS[dof] else 0.0) for c in CHANNEL_GROUP}


def check_sign(name: str, lo: float, hi: float) -> None:
    """Raise :class:`CalibrationError` for bounds that allow a wrong-signed damping
    coefficient (paper sign: <= 0), a non-positive inertia / added mass, or a supply voltage
    outside the measured thrust curves."""
    if name in SIGNED_NEGATIVE and hi > 0:
        raise CalibrationError(f"bounds for {name}: ({lo:g}, {hi:g}) allow a positive damping coefficient "
                               "(paper sign: damping is <= 0)")
    if lo <= 0 and (name in EFFECTIVE_INERTIA["roll"] + EFFECTIVE_INERTIA["pitch"] + EFFECTIVE_INERTIA["yaw"]
                    or name in ("m", "X_udot", "Y_vdot", "Z_wdot")):
        raise CalibrationError(f"bounds for {name}: ({lo:g}, {hi:g}) allow a non-positive inertia/added mass")
    if name == "supply_voltage":
        vlo, vhi = measured_voltage_range()
        if lo < vlo or hi > vhi:
            raise CalibrationError(f"bounds for supply_voltage: ({lo:g}, {hi:g}) V reach beyond the voltages the "
                                   f"thrust curves were measured at, {vlo:g}..{vhi:g} V (nothing is extrapolated)")


def split_names(spec, option: str = "names") -> list[str]:
    """``"a, b"`` or a sequence of strings -> list of non-empty names; anything else (a number,
    a mapping) is a :class:`CalibrationError` naming ``option``."""
    if spec is None:
        return []
    if isinstance(spec, str):
        spec = spec.split(",")
    if not (isinstance(spec, (list, tuple)) and all(isinstance(s, str) for s in spec)):
        raise CalibrationError(f"{option} {spec!r}: expected names, as 'a,b' or a list of strings")
    return [s.strip() for s in spec if s.strip()]


def parse_dofs(dofs) -> list[str]:
    """A list of DOF names from "surge,yaw" or a sequence; validated."""
    if dofs is None:
        return list(CALIBRATION_DOFS)
    dofs = split_names(dofs, "dofs")
    bad = [d for d in dofs if d not in DOF_PARAMETERS]
    if bad or not dofs:
        raise CalibrationError(f"dof(s) {bad or dofs!r}: expected a non-empty subset of {', '.join(CALIBRATION_DOFS)}")
    if len(set(dofs)) != len(dofs):
        raise CalibrationError(f"dofs {dofs}: a DOF is listed twice")
    return dofs


def parameter_bounds(names: Sequence[str], initial: Mapping[str, float], *, margin: float = DEFAULT_MARGIN,
                     bounds: Mapping[str, Sequence[float]] | None = None) -> np.ndarray:
    """(p, 2) lower/upper bounds: ``initial * (1 -+ margin)`` (ordered) unless given.

    Raises :class:`CalibrationError` for an initial value of 0 without explicit
    bounds (a relative margin has no width), for bounds not containing the initial
    value, or for a bound crossing zero on a damping (sign-constrained) parameter."""
    bounds = dict(bounds or {})
    if not 0 < margin < 1:
        raise CalibrationError(f"margin {margin!r}: expected a fraction between 0 and 1 (0.5 = +-50 %)")
    out = []
    for k in names:
        v = float(initial[k])
        if k in bounds:
            b = bounds[k]
            try:
                lo, hi = (float(b[0]), float(b[1]))
            except (TypeError, ValueError, IndexError):
                raise CalibrationError(f"bounds for {k}: expected (low, high), got {b!r}") from None
        else:
            if v == 0:
                raise CalibrationError(f"parameter {k} starts at 0, so a relative margin gives no search range; "
                                       "give its bounds explicitly (bounds={'%s': (low, high)})" % k)
            lo, hi = sorted((v * (1 - margin), v * (1 + margin)))
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise CalibrationError(f"bounds for {k}: need finite low < high, got ({lo}, {hi})")
        if not lo <= v <= hi:
            raise CalibrationError(f"bounds for {k}: ({lo}, {hi}) do not contain the initial value {v}")
        check_sign(k, lo, hi)
        out.append((lo, hi))
    return np.array(out, float).reshape(-1, 2)
