"""Measurement models: what each logged column measures, predicted from the state.

Calibration, diagnosis and ``uvsim simulate --compare`` compare a model with a log
through these models, so a log may carry any subset of the channels below
(docs/log_format.md).  Sensor positions ``r_s`` on the body come from the vehicle
file's ``sensors:`` section (default: the body origin).  ``R`` is the body->NED
rotation of the state, ``k = R^T e_3`` the NED down axis in body coordinates,
``nu = [v, omega]``.

=============  ==================  ==================================================
group          columns             model (predicted measurement)
=============  ==================  ==================================================
position       x, y, z             NED position of the body origin (motion capture)
depth          depth               ``z + (R r_p)_z``: depth of the pressure sensor at r_p
attitude       qw..qz, or any of   ZYX Euler angles, each logged angle compared by its
               roll, pitch, yaw    wrapped difference (a quaternion log is turned into
                                   its three angles; e.g. roll and pitch only of a
                                   magnetometer-free IMU); optionally through an
                                   attitude filter's first-order lag (``attitude_lag``,
                                   below)
velocity       u, v, w             ``v + omega x r_d``: velocity of the DVL at r_d
rates          p, q, r             ``omega + b``: gyro with a constant bias ``b`` per run
                                   (a nuisance parameter the fits estimate)
acceleration   acc_x..acc_z        specific force at the IMU r_i:
                                   ``v_dot + omega x v + omega_dot x r_i +
                                   omega x (omega x r_i) - g k`` (a level vehicle at
                                   rest reads (0, 0, -g))
=============  ==================  ==================================================

**One error per channel.**  :meth:`RunMeasurements.residuals` is the only definition of a
channel's error, ``measured - predicted`` in the channel's unit, with angles as the wrapped
difference of Euler angles in (-pi, pi] whether the log holds a quaternion or angles.  The
fits, the verdict (:mod:`uvsim.fitting.verdict`), Fit %, the CLI tables, report.json and the
plots all read it, so "roll got worse" means the same thing everywhere.  (Near pitch +-90 deg
the split of an attitude into roll and yaw is ill-conditioned; an ROV does not go there, and
for a hydrobatic vehicle that does, the roll and yaw errors there are large but bounded by pi.)

Every logged channel has a noise level (``sigma``: given, declared in the vehicle file or
estimated from the log, with floors) and a weight (:mod:`uvsim.signals`); residuals are divided
by ``sigma`` and multiplied by ``sqrt(weight)``, so metres, radians, rad/s and m/s^2 add up and
a correct model leaves about 1 per entry.  The fits, the diagnosis' costs and shares,
report.json and the plots all divide by this one level; :attr:`RunMeasurements.notes` names the
floors and declarations used.

A slow sensor logged on a faster grid by holding or interpolating its value counts only at its
native samples (:func:`uvsim.estimation.noise.sample_kind`); :attr:`RunMeasurements.notes` says so.

Attitude filter lag: angles reported by an attitude filter (EKF, complementary
filter) trail the motion.  With ``attitude_lag = tau > 0`` the predicted Euler angles
pass through the first-order lag of :func:`uvsim.estimation.lag.first_order_lag`
(in quaternion mode the lagged angles are turned back into a quaternion), started
from the logged attitude at the first row, or at every window start of a windowed
fit (:meth:`RunMeasurements.for_windows`); ``tau`` can be estimated from the gyro
(:func:`uvsim.estimation.lag.estimate_attitude_lag`).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Mapping

import numpy as np

from uvsim.fit_settings import SAMPLE_WEIGHTINGS  # noqa: F401 (its home: uvsim.fit_settings)
from uvsim.errors import CalibrationError
from uvsim.estimation.lag import first_order_lag, lag_time_constant, uniform_steps
from uvsim.estimation.noise import SampleKind, sample_kind
from uvsim.accelerometer import _components, _specific_force, specific_force  # noqa: F401  (specific_force: re-exported)
from uvsim.kinematics import (cross_components, down_axis_components, quat_to_euler,  # noqa: F401
                              rotation_vector_error, unwrap_angles, wrap)  # (rotation_vector_error: re-exported)
from uvsim.logs import POSITION_COLUMNS, RATE_COLUMNS, VELOCITY_COLUMNS
from uvsim.signals import (CHANNEL_GROUP, GROUPS, UNITS, _filter_floor, channel_weight,  # noqa: F401
                           check_sample_weighting, check_signal_settings, noise_level,
                           per_second_factors)  # (CHANNEL_GROUP: re-exported, its home uvsim.signals)

#: Default standard gravity if the vehicle gives none, m/s^2 (Fossen 2021).
G_DEFAULT = 9.81
#: Half-width (s) of the straight-line fit that gives the logged attitude where the
#: attitude lag restarts (a few filter-output samples; the lagged signal is smooth).
LAG_RESTART_HALF_S = 0.1


@dataclass
class Group:
    """One signal group of a run.

    Attributes
    ----------
    name : group name (key of :data:`GROUPS`).
    values : (n, k) measured values (attitude: ZYX Euler angles (n, 3) in either mode, as logged:
        not unwrapped).
    logged : (k,) bool, which channels of the group the run logged.
    valid : (n, k) bool, rows that carry a measurement of each channel (native samples).
    sigma : (k,) noise level per channel (NaN for channels not logged).
    kinds : per channel, how it was logged (:class:`uvsim.estimation.noise.SampleKind`) or None.
    mode : attitude only: "quaternion" (logged as a quaternion: all three angles, a sample is all or
        nothing) or "euler" (logged as angles, any subset).
    noise : per channel, where its ``sigma`` comes from (:class:`uvsim.estimation.noise.NoiseLevel`)
        or None (not logged, or a group built by hand).
    """

    name: str
    values: np.ndarray
    logged: np.ndarray
    valid: np.ndarray
    sigma: np.ndarray
    kinds: list
    mode: str = ""
    noise: list = field(default_factory=list)

    @property
    def channels(self) -> tuple:
        return GROUPS[self.name]


@dataclass
class RunMeasurements:
    """The measurement model of one run: its logged groups, noise levels, sensor
    positions and weights (module docstring).

    Build it with :func:`measurements_for`.  ``predict`` maps simulated states to
    predicted measurements and ``residuals`` / ``normalized`` compare them."""

    name: str
    t: np.ndarray
    groups: dict
    sensors: dict
    g: float
    weights: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    run_weight: float = 1.0
    #: time constant (s) of the attitude filter's first-order lag (0: none)
    attitude_lag: float = 0.0
    #: rows where the lag filter restarts from the logged attitude (window starts of a
    #: windowed fit, :meth:`for_windows`); None: once, at the first row
    restart_rows: np.ndarray | None = None
    #: channel -> factor on its weight that makes it count per second of log rather than per
    #: sample (:func:`uvsim.signals.per_second_factors`; empty: per sample)
    rate_factors: dict = field(default_factory=dict)
    _restart_cache: tuple | None = field(default=None, repr=False, compare=False)
    _uniform: bool | None = field(default=None, repr=False, compare=False)

    # ------------------------------------------------------------------ structure
    @property
    def n(self) -> int:
        return self.t.size

    @property
    def needs_acceleration(self) -> bool:
        return "acceleration" in self.groups

    @property
    def has_gyro(self) -> bool:
        return "rates" in self.groups

    @property
    def has_accelerometer(self) -> bool:
        return "acceleration" in self.groups

    @property
    def has_filter_attitude(self) -> bool:
        """Roll and pitch logged as Euler angles beside a gyro: an attitude filter's output
        (an AHRS / EKF), whose tilt carries a constant bias (``attitude_bias`` of :meth:`predict`)."""
        grp = self.groups.get("attitude")
        return self.has_gyro and grp is not None and grp.mode == "euler" and bool(grp.logged[0] and grp.logged[1])

    def channel_weights(self, group: str) -> np.ndarray:
        """(k,) weights: ``weights[group]`` x ``weights[channel]`` (default 1; :func:`uvsim.signals.channel_weight`)."""
        return np.array([channel_weight(self.weights, group, c) * float(self.rate_factors.get(c, 1.0))
                         for c in GROUPS[group]])

    def used(self, group: str) -> np.ndarray:
        """(n, k) bool: entries that enter a fit (valid and weight > 0)."""
        grp = self.groups[group]
        return grp.valid & (self.channel_weights(group) > 0)[None, :]

    def with_sigma(self, sigma: Mapping[str, float]) -> "RunMeasurements":
        """This model with the noise levels of the channels in ``sigma`` (channel -> scale, the
        channel's unit) replaced, the others as they were: e.g. the judged scales of a fit's
        whole-run stage (:func:`uvsim.fitting.evaluate.judged_scales`)."""
        groups = {}
        for g, grp in self.groups.items():
            new = np.array([float(sigma.get(c, s)) for c, s in zip(grp.channels, grp.sigma)])
            noise = [replace(lv, sigma=float(sigma[c]), source="judged",
                             basis="the model's RMS open-loop error (the verdict's scale)")
                     if lv is not None and c in sigma else lv for c, lv in zip(grp.channels, grp.noise)]
            groups[g] = replace(grp, sigma=np.where(grp.logged, new, grp.sigma), noise=noise)
        return replace(self, groups=groups, _restart_cache=None)

    def n_used(self) -> int:
        return int(sum(self.used(g).sum() for g in self.groups))

    def for_windows(self, starts) -> "RunMeasurements":
        """This model for a windowed fit whose windows start at rows ``starts``: the
        attitude lag restarts at each window start from the logged attitude there (the
        filter's output is what was logged), so a window's prediction depends on its own
        start state only.  Returns self when there is no lag."""
        if not (self.attitude_lag > 0 and "attitude" in self.groups):
            return self
        return replace(self, restart_rows=np.asarray(starts, int))

    def _logged_euler_at(self, rows: np.ndarray) -> np.ndarray:
        """Logged Euler angles (R, 3) at ``rows``, each from a straight-line fit over the
        valid samples within :data:`LAG_RESTART_HALF_S` (NaN where none / not logged)."""
        grp = self.groups["attitude"]
        e = unwrap_angles(np.where(grp.valid, grp.values, np.nan))
        out = np.full((len(rows), 3), np.nan)
        for j in range(3):
            ok = grp.valid[:, j] & np.isfinite(e[:, j])
            if not grp.logged[j] or ok.sum() < 2:
                continue
            tv, xv = self.t[ok], e[ok, j]
            for i, r in enumerate(rows):
                sel = np.abs(tv - self.t[r]) <= LAG_RESTART_HALF_S
                if sel.sum() >= 2:
                    out[i, j] = np.polyfit(tv[sel] - self.t[r], xv[sel], 1)[-1]
        return out

    def _lagged_euler(self, euler: np.ndarray, offset: np.ndarray | None = None) -> np.ndarray:
        """Predicted Euler angles (..., n, 3) through the attitude filter's lag, restarted
        at :attr:`restart_rows` from the logged attitude (module docstring) less the
        filter's ``offset`` (..., 3) when it has one (the logged angles carry it)."""
        rows = np.array([0] if self.restart_rows is None else self.restart_rows, int)
        key = tuple(rows.tolist())
        if self._restart_cache is None or self._restart_cache[0] != key:
            self._restart_cache = (key, self._logged_euler_at(rows))
        start = self._restart_cache[1]
        if offset is not None:
            start = start - np.asarray(offset)[..., None, :]  # (..., R, 3)
        bounds = np.array(list(rows) + [self.n])
        out = np.empty_like(euler)
        # segments of one length on one uniform clock (a windowed fit's windows) in one call:
        # each segment is still filtered on its own, with the first segment's filter coefficient
        # (equal to the others' on a uniform clock to round-off, 1e-13 measured)
        lengths = np.diff(bounds)
        same = np.flatnonzero(lengths == lengths[0])
        i_run = int(same.size if np.array_equal(same, np.arange(same.size)) else 1)
        if i_run > 1 and self._uniform_clock():
            a, L = int(bounds[0]), int(lengths[0])
            seg = euler[..., a:a + i_run * L, :].reshape(euler.shape[:-2] + (i_run, L, euler.shape[-1]))
            out[..., a:a + i_run * L, :] = self._lag_segments(seg, start[..., :i_run, :], self.t[a:a + L]).reshape(
                euler.shape[:-2] + (i_run * L, euler.shape[-1]))
        else:
            i_run = 0
        for i in range(i_run, lengths.size):
            a, b = int(bounds[i]), int(bounds[i + 1])
            out[..., a:b, :] = self._lag_segments(euler[..., a:b, :], start[..., i, :], self.t[a:b])
        return out

    def _lag_segments(self, euler, start, t):
        """The lagged angles of segments ``euler`` (..., L, 3) started at ``start`` (..., 3)."""
        x0 = euler[..., 0, :]  # the unwrapped series starts at the first sample
        y0 = np.where(np.isfinite(start), start, x0)
        y0 = x0 + wrap(y0 - x0)  # on the prediction's branch
        L = euler.shape[-2]
        if L >= 2 and self.attitude_lag > 0 and uniform_steps(np.diff(t)):
            from uvsim.kernels import compiled_unwrapped_lag  # the same values, in one pass

            kernel = compiled_unwrapped_lag()
            if kernel is not None and np.isfinite(euler).all():
                a = float(np.exp(-(t[1] - t[0]) / self.attitude_lag))
                flat = np.ascontiguousarray(euler, dtype=float).reshape(-1, L, euler.shape[-1])
                out = np.empty_like(flat)
                kernel(flat, np.ascontiguousarray(np.broadcast_to(y0, euler[..., 0, :].shape)).reshape(flat.shape[0], -1),
                       1.0 - a, a, out)
                return out.reshape(euler.shape)
        return first_order_lag(t, unwrap_angles(euler, axis=-2), self.attitude_lag, y0)

    def _uniform_clock(self) -> bool:
        """True when the run's time steps are uniform (the lag's one-coefficient filter)."""
        if self._uniform is None:
            self._uniform = uniform_steps(np.diff(self.t))
        return self._uniform

    # ------------------------------------------------------------------ prediction
    def predict(self, y: np.ndarray, nu_dot: np.ndarray | None = None,
                gyro_bias: np.ndarray | None = None, attitude_bias: np.ndarray | None = None,
                acc_bias: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Predicted measurements from states ``y`` (..., n, n_y) and accelerations
        ``nu_dot`` (..., n, 6) (needed only for the accelerometer); ``gyro_bias``
        (..., 3) rad/s; ``attitude_bias`` (..., 2) rad: the attitude filter's constant roll
        and pitch offset (Euler mode only, :attr:`has_filter_attitude`); ``acc_bias`` (..., 3)
        m/s^2: the accelerometer's constant offset in body axes, added to the specific force.  Returns group ->
        (..., n, k) (attitude: ZYX Euler angles (..., n, 3) in both modes)."""
        y = np.asarray(y, float)
        out: dict[str, np.ndarray] = {}
        q = y[..., 3:7]
        nu = y[..., 7:13]
        comps = k = None

        def qnu():
            # q and nu component-major, (10, ..., n): one pass over the strided states, after
            # which every formula below reads contiguous memory
            nonlocal comps
            if comps is None:
                comps = _components(y[..., 3:13])
            return comps

        def down():
            # k = R^T e_3 (3 arrays (..., n)), the only part of R any group needs; computed once
            nonlocal k
            if k is None:
                k = down_axis_components(*qnu()[:4])
            return k

        for g, grp in self.groups.items():
            if g == "position":
                out[g] = y[..., 0:3]
            elif g == "depth":
                r = self.sensors.get("pressure")
                z = y[..., 2]
                if r is not None and np.any(r):
                    z = z + np.einsum("...j,j->...", np.stack(down(), axis=-1), r)  # (R r)_z = (R^T e_3) . r
                out[g] = z[..., None]
            elif g == "attitude":
                off = None
                if attitude_bias is not None and grp.mode == "euler":
                    ab = np.asarray(attitude_bias, float)
                    off = np.concatenate([ab, np.zeros(ab.shape[:-1] + (1,))], -1)  # roll, pitch; yaw 0
                out[g] = self._lagged_euler(quat_to_euler(q), off) if self.attitude_lag > 0 else quat_to_euler(q)
                if off is not None:
                    out[g] = out[g] + off[..., None, :]
            elif g == "velocity":
                v = nu[..., :3]
                r = self.sensors.get("dvl")
                if r is not None and np.any(r):
                    c = qnu()
                    wr = cross_components(c[7:10], np.asarray(r, float))
                    v = np.stack([c[4 + i] + wr[i] for i in range(3)], axis=-1)  # v + omega x r_d
                out[g] = v
            elif g == "rates":
                w = nu[..., 3:]
                out[g] = w if gyro_bias is None else w + np.asarray(gyro_bias)[..., None, :]
            elif g == "acceleration":
                if nu_dot is None:
                    raise CalibrationError(f"run {self.name}: the accelerometer model needs the simulated accelerations")
                f = _specific_force(qnu()[4:10], _components(nu_dot), down(), self.sensors.get("imu"), self.g)
                out[g] = np.stack(f, axis=-1)
                if acc_bias is not None:
                    out[g] = out[g] + np.asarray(acc_bias, float)[..., None, :]
        return out

    # ------------------------------------------------------------------ residuals
    def residuals(self, pred: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Measured minus predicted per group, (..., n, k) in the channel unit (attitude:
        wrapped differences of the Euler angles, module docstring); NaN where the entry is
        not a measurement.  The one definition of a channel's error (module docstring)."""
        out = {}
        for g, grp in self.groups.items():
            p = np.asarray(pred[g])
            e = wrap(grp.values - p) if g == "attitude" else grp.values - p
            out[g] = np.where(grp.valid, e, np.nan)
        return out

    def normalized(self, pred: Mapping[str, np.ndarray], *, fill: float | None = None) -> np.ndarray:
        """One residual vector (..., m): every used entry divided by its channel's noise
        level and multiplied by ``sqrt(weight x run weight)``; entries in a fixed order
        (group, then channel, then time), so the length does not depend on the
        parameters.  Non-finite predictions become ``fill`` (default: raise)."""
        parts = []
        for g, grp in self.groups.items():
            used = self.used(g)
            scale = np.sqrt(self.channel_weights(g) * self.run_weight) / np.where(grp.logged, grp.sigma, 1.0)
            p = np.asarray(pred[g])
            if p.shape[-2:] != grp.values.shape:  # a prediction that broadcasts: the whole (n, k) way
                e = np.where(grp.valid, wrap(grp.values - p) if g == "attitude" else grp.values - p, np.nan)
                parts.append(np.moveaxis(e * scale, -1, -2)[..., used.T])
                continue
            # the used entries only (used implies valid), channel-major, time inside: the same
            # element-wise operations as residuals() on the whole (n, k), so the same values
            ch, row = np.nonzero(used.T)
            flat = row * grp.values.shape[1] + ch
            d = grp.values.reshape(-1)[flat] - p.reshape(p.shape[:-2] + (-1,))[..., flat]
            parts.append((wrap(d) if g == "attitude" else d) * scale[ch])
        if not parts:
            return np.zeros(np.shape(next(iter(pred.values())))[:-2] + (0,))
        v = np.concatenate(parts, axis=-1)
        bad = ~np.isfinite(v)
        if bad.any():
            if fill is None:
                raise CalibrationError(f"run {self.name}: non-finite prediction (diverged simulation)")
            v = np.where(bad, fill, v)
        return v

    def row_index(self) -> np.ndarray:
        """(m,) sample row of every entry of :meth:`normalized`'s vector (same order)."""
        rows = []
        for g in self.groups:
            used = self.used(g)
            rr = np.broadcast_to(np.arange(self.n)[:, None], used.shape)
            rows.append(rr.T[used.T])
        return np.concatenate(rows) if rows else np.zeros(0, int)

    def describe(self) -> dict:
        """JSON-ready summary: per logged channel its noise level, where the level comes from
        (:meth:`uvsim.estimation.noise.NoiseLevel.describe`: ``source``, ``basis``, ``estimate``,
        ``quantum``), unit and sampling."""
        out = {}
        for g, grp in self.groups.items():
            for j, c in enumerate(grp.channels):
                if not grp.logged[j]:
                    continue
                k = grp.kinds[j]
                lv = grp.noise[j] if j < len(grp.noise) else None
                out[c] = {**(lv.describe() if lv is not None else {}), "sigma": float(grp.sigma[j]), "unit": UNITS[g],
                          "sampling": k.kind if k is not None else "native",
                          "native_rate_hz": (float(1.0 / k.native_interval_s)
                                             if k is not None and np.isfinite(k.native_interval_s) else None),
                          "samples_used": int(grp.valid[:, j].sum())}
        return out


def measurements_for(run, vehicle=None, *, noise: Mapping[str, float] | None = None,
                     weights: Mapping[str, float] | None = None, run_weight: float | None = None,
                     sensors: Mapping[str, np.ndarray] | None = None, attitude_lag: float = 0.0,
                     sample_weighting: str = "per_sample") -> RunMeasurements:
    """The measurement model of ``run`` (a :class:`uvsim.logs.Run`).

    Parameters
    ----------
    vehicle : gives the sensor positions (``vehicle.sensors``) and ``g``; None: sensors
        at the body origin, g = 9.81.
    noise : 1-sigma noise levels by group or channel name (e.g. ``{"depth": 0.01,
        "attitude": 0.005, "yaw": 0.02}``), in the channel units; where not given, the
        vehicle's declared ``sensors.noise``, else estimated from the log with its floors
        (:mod:`uvsim.signals`).
    weights : weights by group or channel (default 1; 0 leaves a channel out of fits).
    run_weight : the run's weight (default: ``run.weight`` from the manifest).
    sensors : sensor positions overriding the vehicle's.
    attitude_lag : time constant (s) of the attitude filter's first-order lag
        (module docstring; 0: none).
    sample_weighting : "per_sample" (every sample of every channel alike) or "per_second"
        (channels logged at a lower rate weighted up by :func:`uvsim.signals.per_second_factors`).
    """
    attitude_lag = lag_time_constant(attitude_lag)
    check_sample_weighting(sample_weighting)
    noise = dict(noise or {})
    check_signal_settings(noise, weights)
    declared = dict(getattr(vehicle, "sensor_noise", {}) or {})
    sens = dict(getattr(vehicle, "sensors", {}) or {})
    sens.update(sensors or {})
    g = float(getattr(vehicle, "g", G_DEFAULT))
    t = run.t
    n = t.size
    groups: dict[str, Group] = {}
    notes: list[str] = []

    def build(name, values, logged, mode=""):
        k = len(GROUPS[name])
        valid = np.zeros((n, k), bool)
        sigma = np.full(k, np.nan)
        kinds: list = [None] * k
        levels: list = [None] * k
        for j in range(k):
            if not logged[j]:
                continue
            col = values[:, j]
            sk: SampleKind = sample_kind(t, col)
            kinds[j] = sk
            valid[:, j] = sk.native
            if sk.kind in ("held", "interpolated"):
                notes.append(f"run {run.name}: " + sk.describe(GROUPS[name][j]))
            ch = GROUPS[name][j]
            levels[j] = noise_level(name, ch, col, sk.native, given=noise, declared=declared)
            sigma[j] = levels[j].sigma
            if not np.isfinite(sigma[j]):
                raise CalibrationError(
                    f"run {run.name}: cannot estimate the noise level of {ch!r} (fewer than 8 native samples); "
                    f"give it (noise={{'{ch}': ...}}, --noise {ch}=... or sensors.noise.{ch} in the vehicle file)")
        if name == "attitude" and mode == "quaternion":
            valid[:] = valid.all(axis=1, keepdims=True)  # a quaternion sample is all or nothing
        groups[name] = Group(name, values, np.asarray(logged, bool), valid, sigma, kinds, mode, levels)

    cols = run.data.columns
    if run.has_position:
        build("position", run.position, [c in cols for c in POSITION_COLUMNS])
    if run.has_depth:
        build("depth", run.depth[:, None], [True])
    if run.has_attitude:
        if run.has_full_attitude:
            build("attitude", run.euler, [True, True, True], "quaternion")
        else:
            build("attitude", run.euler, list(run.euler_mask), "euler")
    if run.has_velocity:
        build("velocity", run.velocity[:, :3], [c in cols for c in VELOCITY_COLUMNS])
    if run.has_rates:
        build("rates", run.velocity[:, 3:], [c in cols for c in RATE_COLUMNS])
    if run.has_acceleration:
        build("acceleration", run.acceleration, [True, True, True])
    _filter_floor(groups)
    notes += [f"run {run.name}: {lv.note}" for grp in groups.values() for lv in grp.noise if lv is not None and lv.note]
    factors = per_second_factors(groups) if sample_weighting == "per_second" else {}
    return RunMeasurements(run.name, t, groups, sens, g, dict(weights or {}), notes,
                           float(run.weight if run_weight is None else run_weight), attitude_lag,
                           rate_factors=factors)
