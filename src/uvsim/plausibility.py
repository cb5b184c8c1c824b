"""Unit plausibility of logged runs for a vehicle: is this data in the units uvsim reads?

A run can satisfy the log format (:mod:`uvsim.logs`) and still be in the wrong units:
time in milliseconds, positions in millimetres, angles in degrees, accelerations in g,
or sampled so slowly that one RK4 step per sample cannot follow the vehicle.  Such a
run "calibrates" with absurd results instead of failing.  :func:`check_run` looks at a
run together with the vehicle it is simulated with and reports each problem as a
:class:`Finding` naming the file, the column, the row and the value, what was expected,
and the check's name.  ``uvsim simulate``, ``calibrate`` and ``diagnose`` call
:func:`check_runs` before any work; ``--allow NAME[,NAME]`` turns the named checks into
printed warnings (docs/contracts.md).

Checks (name: what is flagged):

``sample-interval``
    The median sample interval exceeds the vehicle's shortest time constant
    (:func:`time_constants`): RK4 takes one step per sample, so it cannot follow the
    fastest mode (and is unstable beyond ~2.8 time constants).  Typical cause: ``t`` in
    milliseconds.
``time-gap``
    One interval longer than both ``GAP_FACTOR`` x the median interval and the shortest
    time constant: inputs are held and one RK4 step spans the gap.
``speed``
    Speed implied by the position / depth columns (differences over ``LAG_S``) or given
    by ``u, v, w``, in more than 1 % of the rows above ``MAX_SPEED``: positions in mm
    or cm, velocities in cm/s.
``angular-rate``
    Angular rate implied by the attitude (the rotation angle between attitudes ``LAG_S``
    apart; angle by angle, unwrapped, for a partial attitude) or given by ``p, q, r``, in
    more than 1 % of the rows above ``MAX_RATE``: angles in degrees.
``angle-range``
    ``roll`` outside [-pi, pi] or ``pitch`` outside [-pi/2, pi/2] (ZYX Euler angles,
    ``ANGLE_TOL`` of slack): angles in degrees.
``position-range``
    ``z`` or ``depth`` deeper than the deepest ocean (``MAX_DEPTH``): millimetres; a position
    beyond half the Earth's circumference (``MAX_POSITION``); a ``depth`` above ``MIN_DEPTH``
    (a negative absolute pressure): a sign flip.
``accel-units``
    The median magnitude of the accelerometer specific force is not near ``g`` (a
    vehicle at rest reads (0, 0, -g)): accelerations logged in g.
``z-as-depth``
    The run logs ``z`` but neither ``x`` nor ``y`` (nor ``depth``) while the vehicle file
    declares a pressure sensor off the body origin: a depth sensor's reading written in the
    body origin's column, whose lever arm every method would then ignore.
``pwm-range`` (cannot be allowed)
    A PWM command outside the range of the vehicle's thrust curve: the curve has no
    value there and nothing is clipped (docs/thrusters.md).
``input-columns`` (cannot be allowed)
    The run's thrust/PWM columns do not match the vehicle's thrusters.

Thresholds are deliberately loose: each is an order of magnitude beyond what an
underwater vehicle does (hydrobatic AUVs reach ~5 m/s and ~1-2 rad/s, seed 003 sec.
V-C; an open-frame ROV such as the BlueROV2 ~1.5 m/s), so a flagged run is almost
certainly in other units, and a real run is never flagged.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

import numpy as np

from uvsim.errors import PlausibilityError, UvsimError
from uvsim.kinematics import attitude_error_angle
from uvsim.schema import did_you_mean

#: Speeds above this (m/s) are not an underwater vehicle's (an order of magnitude above
#: a hydrobatic AUV's ~5 m/s, seed 003 sec. V-C).
MAX_SPEED = 10.0
#: Angular rates above this (rad/s, 573 deg/s) are not an underwater vehicle's.
MAX_RATE = 10.0
#: Slack on the Euler angle ranges, rad.
ANGLE_TOL = 0.05
#: Deeper than the Challenger Deep (~10 935 m, the deepest point of the ocean), m.
MAX_DEPTH = 11000.0
#: Farthest a local NED position (``x``, ``y``, ``z``) may be from its origin, m: half the Earth's
#: circumference (2.0e7 m), so that UTM coordinates (northings up to 1e7 m) still pass.
MAX_POSITION = 2.0e7
#: Shallowest depth a pressure sensor can read, m: absolute pressure cannot be negative, so its depth
#: (p - p_surface) / (rho g) stays above -p_surface / (rho g) = -101325 / (1000 x 9.81) = -10.3 m.
MIN_DEPTH = -10.5
#: Implied speeds and rates are differences over this time span (s), so that sensor
#: noise (mm, mrad) divided by a short interval is not mistaken for motion.
LAG_S = 0.1
#: Share of the rows (a percentile) that must exceed a limit before a run is flagged,
#: so that a single glitch in a log is not a unit problem.
EXCEED_FRACTION = 0.01
#: A gap is an interval above this many median intervals (and above the shortest time constant).
GAP_FACTOR = 5.0
#: Accepted median |specific force| / g of an accelerometer.
ACCEL_RANGE = (0.5, 1.5)
#: Reference speed (m/s or rad/s) at which quadratic damping gives a time constant.
REFERENCE_SPEED = 1.0

#: check name -> one-line description (the names ``--allow`` accepts, plus the two that
#: cannot be allowed).
CHECKS = {
    "sample-interval": "median sample interval above the vehicle's shortest time constant (t in ms?)",
    "time-gap": "a gap in t above 5 median intervals and the shortest time constant",
    "speed": f"speeds above {MAX_SPEED:g} m/s (positions in mm or cm?)",
    "angular-rate": f"angular rates above {MAX_RATE:g} rad/s (angles in degrees?)",
    "angle-range": "roll outside [-pi, pi] or pitch outside [-pi/2, pi/2] (degrees?)",
    "position-range": f"z or depth below {MAX_DEPTH:g} m (millimetres?), a position beyond {MAX_POSITION:g} m or a "
                      f"depth above {MIN_DEPTH:g} m",
    "accel-units": "median accelerometer magnitude far from g (logged in g?)",
    "z-as-depth": "z without x and y beside a declared pressure sensor (its reading belongs in depth)",
    "pwm-range": "PWM outside the vehicle's thrust-curve range (cannot be allowed)",
    "input-columns": "thrust/PWM columns that do not match the vehicle's thrusters (cannot be allowed)",
}
#: Checks that ``--allow`` cannot downgrade: the simulation itself would fail.
NOT_ALLOWABLE = ("pwm-range", "input-columns")


@dataclass
class Finding:
    """One plausibility problem: ``check`` (its ``--allow`` name) and ``message`` (file,
    column, row, value and what was expected)."""

    check: str
    message: str

    @property
    def allowable(self) -> bool:
        return self.check not in NOT_ALLOWABLE


# ----------------------------------------------------------------------------- vehicle
def time_constants(vehicle) -> dict[str, float]:
    """The vehicle's time constants, s, by what they come from.

    * ``<dof> restoring``: roll and pitch pendulum, ``sqrt(M_ii / k)`` with the small-angle
      restoring stiffness ``k = z_g W - z_b B`` (Fossen 2021 eq. 4.7); only when ``k > 0``;
    * ``<dof> linear damping``: ``M_ii / |D_L,ii|`` (diagonal damping models);
    * ``<dof> quadratic damping at 1 m/s (rad/s)``: ``M_ii / (|D_Q,ii| REFERENCE_SPEED)``.

    ``M_ii`` is the diagonal of ``M = M_RB + M_A``.
    """
    from uvsim.vehicle import DOFS, damping_diagonals

    M = np.diag(vehicle.M)
    out = {}
    k = vehicle.weight * vehicle.r_g[2] - vehicle.buoyancy * vehicle.r_b[2]
    if k > 0:
        for i, dof in ((3, "roll"), (4, "pitch")):
            out[f"{dof} restoring"] = float(np.sqrt(M[i] / k))
    DL, DQ = damping_diagonals(vehicle.damping)
    for i, dof in enumerate(DOFS):
        if DL is not None and DL[i] < 0:
            out[f"{dof} linear damping"] = float(M[i] / -DL[i])
        if DQ is not None and DQ[i] < 0:
            unit = "m/s" if i < 3 else "rad/s"
            out[f"{dof} quadratic damping at {REFERENCE_SPEED:g} {unit}"] = float(M[i] / (-DQ[i] * REFERENCE_SPEED))
    return out


def shortest_time_constant(vehicle) -> tuple[float, str]:
    """``(seconds, what)`` of the shortest of :func:`time_constants`; ``(inf, "")`` if none."""
    tc = time_constants(vehicle)
    if not tc:
        return float("inf"), ""
    what = min(tc, key=tc.get)
    return tc[what], what


# ----------------------------------------------------------------------------- helpers
def _src(run) -> str:
    return str(run.path) if run.path is not None else f"run {run.name!r}"


def _row(run, i: int) -> str:
    from uvsim.log_columns import _row as row

    return row(int(i) + getattr(run, "row_offset", 0), _src(run))  # a segment's rows are the file's from row_offset on


def _lag(t: np.ndarray) -> int:
    dt = float(np.median(np.diff(t)))
    return max(1, int(round(LAG_S / dt))) if dt > 0 else 1


def _exceeds(values: np.ndarray, limit: float) -> int | None:
    """First row of ``values`` above ``limit`` when more than EXCEED_FRACTION of the
    finite rows are; None otherwise."""
    finite = np.isfinite(values)
    if finite.sum() == 0:
        return None
    over = finite & (values > limit)
    if over.sum() <= EXCEED_FRACTION * finite.sum():
        return None
    return int(np.flatnonzero(over)[0])


def _implied_rate(t, x, k):
    """|x[i+k] - x[i]| / (t[i+k] - t[i]) per row i (NaN where missing), length n."""
    out = np.full(t.size, np.nan)
    if t.size > k:
        out[:-k] = np.abs(x[k:] - x[:-k]) / (t[k:] - t[:-k])
    return out


# ----------------------------------------------------------------------------- checks
def _check_time(run, vehicle, tau, what) -> list[Finding]:
    t = run.t
    d = np.diff(t)
    med = float(np.median(d))
    out = []
    if med > tau:
        out.append(Finding("sample-interval", (
            f"{_src(run)}: column 't': median sample interval {med:.4g} s is {med / tau:.3g} times the shortest "
            f"time constant of vehicle {vehicle.name} ({tau:.3g} s, {what}); one RK4 step per sample cannot "
            f"follow it (expected intervals up to {tau:.3g} s; if t is in milliseconds, divide it by 1000)")))
        return out
    limit = max(GAP_FACTOR * med, tau)
    gap = np.flatnonzero(d > limit)
    if gap.size:
        i = int(gap[0]) + 1
        out.append(Finding("time-gap", (
            f"{_src(run)}: column 't', {_row(run, i)}: gap of {d[i - 1]:.4g} s after t = {t[i - 1]:.6g} s "
            f"(median interval {med:.4g} s); the inputs are held and one RK4 step spans the gap (expected no "
            f"interval above {limit:.3g} s = max({GAP_FACTOR:g} median intervals, the shortest time constant "
            f"{tau:.3g} s); split the run at the gap (uvsim.gaps.split_run, as datasets and the commands do)")))
    return out


def _over_limit(run, c, values, limit, check, unit, hint, implied=False):
    """A Finding when more than EXCEED_FRACTION of ``values`` (per row of column ``c``)
    exceed ``limit``; None otherwise."""
    i = _exceeds(values, limit)
    if i is None:
        return None
    what = (f"implied {'speed' if check == 'speed' else 'angular rate'} {values[i]:.4g} {unit} (change over "
            f"{LAG_S:g} s) in" if implied else f"{run.data[c].iloc[i]:.6g} {unit}, and")
    label = f"column {c!r}" if c in run.data.columns else f"columns {c}"
    return Finding(check, (f"{_src(run)}: {label}, {_row(run, i)}: {what} more than {100 * EXCEED_FRACTION:g} % "
                           f"of the rows above {limit:g} {unit}; {hint}"))


def _check_translation(run) -> list[Finding]:
    from uvsim.logs import DEPTH_COLUMN, POSITION_COLUMNS, VELOCITY_COLUMNS

    t, data, out = run.t, run.data, []
    k = _lag(t)
    for c in POSITION_COLUMNS + (DEPTH_COLUMN,):
        if c not in data.columns:
            continue
        x = data[c].to_numpy()
        deep = np.flatnonzero(x > MAX_DEPTH) if c in ("z", DEPTH_COLUMN) else ()
        if len(deep):
            i = int(deep[0])
            out.append(Finding("position-range", (
                f"{_src(run)}: column {c!r}, {_row(run, i)}: {x[i]:.6g} m is deeper than the deepest ocean "
                f"({MAX_DEPTH:g} m); expected metres (positions in millimetres?)")))
            continue
        far = np.flatnonzero(np.abs(x) > MAX_POSITION)
        if far.size:
            i = int(far[0])
            out.append(Finding("position-range", (
                f"{_src(run)}: column {c!r}, {_row(run, i)}: {x[i]:.6g} m is farther than half the Earth's "
                f"circumference ({MAX_POSITION:g} m) from the origin; expected a local NED position in metres")))
            continue
        above = np.flatnonzero(x < MIN_DEPTH) if c == DEPTH_COLUMN else ()
        if len(above):
            i = int(above[0])
            out.append(Finding("position-range", (
                f"{_src(run)}: column {c!r}, {_row(run, i)}: depth {x[i]:.6g} m is more than {-MIN_DEPTH:g} m above "
                f"the surface, where a pressure sensor would read a negative absolute pressure; expected depth in "
                f"metres, positive down (a sign flip, or a pressure not converted to depth?)")))
            continue
        out.append(_over_limit(run, c, _implied_rate(t, x, k), MAX_SPEED, "speed", "m/s",
                               "expected metres (positions in millimetres or centimetres?)", implied=True))
    for c in VELOCITY_COLUMNS:
        if c in data.columns:
            out.append(_over_limit(run, c, np.abs(data[c].to_numpy()), MAX_SPEED, "speed", "m/s",
                                   "expected m/s (velocity in cm/s or mm/s?)"))
    return [f for f in out if f is not None]


def _check_rotation(run) -> list[Finding]:
    from uvsim.logs import EULER_COLUMNS, RATE_COLUMNS

    t, data, out = run.t, run.data, []
    k = _lag(t)
    out_of_range = set()
    for c, bound in (("roll", np.pi), ("pitch", np.pi / 2)):
        if c in data.columns:
            a = data[c].to_numpy()
            bad = np.flatnonzero(np.abs(a) > bound + ANGLE_TOL)
            if bad.size:
                i = int(bad[0])
                out_of_range.add(c)
                out.append(Finding("angle-range", (
                    f"{_src(run)}: column {c!r}, {_row(run, i)}: {a[i]:.6g} is outside [-{bound:.4g}, "
                    f"{bound:.4g}] rad (ZYX Euler angles); expected radians (angles in degrees?)")))
    if run.has_full_attitude and not out_of_range:
        # the rotation angle between attitudes k samples apart: no Euler singularity (roll and
        # yaw jump by pi when a loop passes pitch +-90 deg)
        q = run.quaternion
        rate = np.full(t.size, np.nan)
        if t.size > k:
            rate[:-k] = attitude_error_angle(q[:-k], q[k:]) / (t[k:] - t[:-k])
        label = "qw..qz" if run.has_quaternion else "roll, pitch, yaw"
        out.append(_over_limit(run, label, rate, MAX_RATE, "angular-rate", "rad/s",
                               "expected radians (angles in degrees?)", implied=True))
    elif not run.has_full_attitude:
        for c in EULER_COLUMNS:  # partial attitude (e.g. an IMU without magnetometer): angle by angle
            if c in data.columns and c not in out_of_range:
                a = data[c].to_numpy()
                ok = np.isfinite(a)
                u = np.full_like(a, np.nan)
                u[ok] = np.unwrap(a[ok])
                out.append(_over_limit(run, c, _implied_rate(t, u, k), MAX_RATE, "angular-rate", "rad/s",
                                       "expected radians (angles in degrees?)", implied=True))
    for c in RATE_COLUMNS:
        if c in data.columns:
            out.append(_over_limit(run, c, np.abs(data[c].to_numpy()), MAX_RATE, "angular-rate", "rad/s",
                                   "expected rad/s (rates in deg/s?)"))
    return [f for f in out if f is not None]


def _check_accel(run, vehicle) -> list[Finding]:
    if not run.has_acceleration:
        return []
    f = np.linalg.norm(run.acceleration, axis=1)
    f = f[np.isfinite(f)]
    if not f.size:
        return []
    med = float(np.median(f))
    lo, hi = ACCEL_RANGE
    if lo * vehicle.g <= med <= hi * vehicle.g:
        return []
    return [Finding("accel-units", (
        f"{_src(run)}: columns acc_x, acc_y, acc_z: median magnitude {med:.4g}; expected about g = "
        f"{vehicle.g:g} m/s^2 (specific force; a vehicle at rest reads (0, 0, -g)) within "
        f"{lo:g}..{hi:g} g (accelerations logged in g?)"))]


def _check_z_as_depth(run, vehicle) -> list[Finding]:
    """``z`` alone beside a pressure sensor declared off the body origin (module docstring).
    A sensor at the origin reads the origin's depth, so ``z`` is then right either way."""
    cols = run.data.columns
    r_p = np.asarray(vehicle.sensors.get("pressure", np.zeros(3)), float)
    if "z" not in cols or "x" in cols or "y" in cols or "depth" in cols or not np.any(r_p != 0):
        return []
    at = "[" + ", ".join(f"{v:g}" for v in r_p) + "]"
    return [Finding("z-as-depth", (
        f"run {_src(run)} logs z without x and y while the vehicle declares a pressure sensor at {at} m "
        f"({vehicle.source}: sensors.pressure.position): a pressure sensor's reading belongs in the `depth` column "
        "(z is the NED position of the body origin, e.g. motion capture); rename the column, or --allow "
        "z-as-depth if z really is the body origin's"))]


def _check_inputs(run, vehicle) -> list[Finding]:
    kind = run.input_kind
    if kind == "force":
        return []
    act = vehicle.actuators
    n = run.inputs.shape[1]
    cols = run.input_columns
    if getattr(act, "check_inputs", None) is not None:
        try:
            act.check_inputs(kind, n, where=f"{_src(run)}: columns {cols[0]}..{cols[-1]}")
        except UvsimError as exc:
            return [Finding("input-columns", f"{exc} (vehicle {vehicle.name}, {vehicle.source})")]
    if kind != "pwm" or not act.curves:
        return []
    U = run.inputs
    for j, (c, curve) in enumerate(zip(cols, act.curves)):
        bad = np.flatnonzero((U[:, j] < curve.pwm_min) | (U[:, j] > curve.pwm_max))
        if bad.size:
            i = int(bad[0])
            name = act.names[j] if act.names else f"T{j + 1}"
            return [Finding("pwm-range", (
                f"{_src(run)}: column {c!r}, {_row(run, i)}: PWM {U[i, j]:g} us is outside the range "
                f"{curve.pwm_min:g}..{curve.pwm_max:g} us of thrust curve {curve.name!r} (thruster {name} of "
                f"vehicle {vehicle.name}; {bad.size} of {len(U)} rows outside); the curve has no thrust there "
                "and commands are never clipped (docs/thrusters.md)"))]
    return []


def require_inputs_match(run, vehicle) -> None:
    """Raise :class:`PlausibilityError` when the run's input columns do not fit the
    vehicle's thrusters or a PWM lies outside their curves (the checks that cannot be
    allowed); :func:`uvsim.simulate.simulate_run` calls it."""
    for f in _check_inputs(run, vehicle):
        raise PlausibilityError(f"{f.message} [check {f.check}]")


def check_run(run, vehicle) -> list[Finding]:
    """Every plausibility finding of ``run`` (a :class:`uvsim.logs.Run`) simulated with
    ``vehicle`` (a :class:`uvsim.vehicle.Vehicle`), in the order of the module docstring."""
    tau, what = shortest_time_constant(vehicle)
    return (_check_inputs(run, vehicle) + _check_time(run, vehicle, tau, what) + _check_translation(run)
            + _check_rotation(run) + _check_accel(run, vehicle) + _check_z_as_depth(run, vehicle))


def parse_allow(text: str | Iterable[str] | None, option: str = "--allow") -> set[str]:
    """``"speed,time-gap"`` -> ``{"speed", "time-gap"}``; unknown names and the checks that
    cannot be allowed raise :class:`UvsimError` naming ``option``."""
    if not text:
        return set()
    names = [x.strip() for x in (text.split(",") if isinstance(text, str) else text) if x.strip()]
    for n in names:
        if n not in CHECKS:
            raise UvsimError(f"{option}: unknown check {n!r}{did_you_mean(n, CHECKS)}; expected some of "
                             f"{', '.join(c for c in CHECKS if c not in NOT_ALLOWABLE)}")
        if n in NOT_ALLOWABLE:
            raise UvsimError(f"{option}: check {n!r} cannot be allowed ({CHECKS[n]})")
    return set(names)


def check_runs(runs, vehicle, allow: Iterable[str] = ()) -> list[Finding]:
    """Check every run; raise :class:`PlausibilityError` for the first finding whose check
    is not in ``allow`` (the message ends with how to allow it), and return the allowed
    findings (the caller prints them as warnings)."""
    allow = set(allow)
    warnings = []
    for run in runs:
        for f in check_run(run, vehicle):
            if f.check in allow and f.allowable:
                warnings.append(f)
                continue
            how = (f" [check {f.check}; --allow {f.check} proceeds anyway]" if f.allowable
                   else f" [check {f.check}]")
            raise PlausibilityError(f.message + how)
    return warnings
