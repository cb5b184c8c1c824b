"""The windowed prediction-error objective shared by calibration and diagnosis.

Every run is cut into windows of about ``horizon`` seconds (the whole run when
``horizon`` is None).  Each window is simulated from its own node state (reference
from the log, free components as nuisance variables, :mod:`uvsim.fitting.nodes`), all
windows of all runs and all parameter sets as rows of one batched RK4 call
(:func:`uvsim.simulate_batch`).  The residual of a parameter set is, run by run:

1. the normalized measurement residual of every logged sample
   (:meth:`uvsim.measurements.RunMeasurements.normalized`); sample ``i`` is predicted
   by the window that starts at or before it (the sample that ends a window is
   predicted by the next one, whose node it is);
2. continuity defects: the free node components of window ``k`` minus the end state of
   window ``k - 1``, divided by :data:`DEFECT_SIGMA` times the problem's ``continuity``
   factor (the lifted, soft-constrained form of multiple shooting: Bock & Plitt 1984;
   continuity is approached at convergence rather than imposed during the iterations,
   which keeps long runs well-posed).  When the model lacks something the data contain,
   a soft defect is where its error goes: each window restarts from a node that absorbs a
   little of the drift, so a fit can buy a lower windowed cost with a free simulation that
   drifts further (issue 21: open-loop depth worse than the start model's on the very runs
   it was fitted to).  A smaller ``continuity`` factor brings the cost closer to the free
   simulation's (the penalty method's limit is hard continuity: one simulation per run
   from its first node); the calibration tightens it (:mod:`uvsim.fitting.fitter`,
   ``continuity``), diagnosis keeps 1;
3. priors on the free node components (their reference is a measurement-derived
   estimate; :data:`uvsim.fitting.nodes.PRIOR_SIGMA`) and on the sensor biases (gyro;
   the roll and pitch of an attitude filter, :data:`ATTITUDE_BIAS_SIGMA`; the
   accelerometer, :data:`ACC_BIAS_SIGMA`).

Long horizons make the output-error cost rugged (the trajectory of an ROV that yaws away
under the Munk moment depends very nonlinearly on the parameters); short windows keep it
close to quadratic.  :func:`uvsim.fitting.solver.fit` lengthens the horizon by
continuation (Ljung 1999, *System Identification*, sec. 7.2 on k-step-ahead prediction
errors; the multiple-shooting idea of Bock & Plitt 1984).

Term states (e.g. a thruster lag) at the node times are carried along a reference
trajectory for each parameter set (:meth:`WindowedProblem._term_states`), so windows
stay independent rows.
"""
from __future__ import annotations

import numpy as np

from uvsim.blas import single_thread
from uvsim.errors import CalibrationError
from uvsim.fit_settings import LOSSES  # noqa: F401 (its home: uvsim.fit_settings)
from uvsim.fitting.nodes import NodeModel
from uvsim.fitting.windows import apply_tangent, layout, padded_runs, tangent_difference, whole_runs
from uvsim.forces.base import position_axes_read
from uvsim.latency import runs_for
from uvsim.model import Model
from uvsim.simulate import _rk4_loop

#: Standard deviation of a continuity defect (m, rad, m/s, rad/s): the mismatch allowed
#: between a window's end state and the next node, of the order of the state error a
#: window accumulates from noise in its node; small against the motion.
DEFECT_SIGMA = np.array([0.005, 0.005, 0.005, 0.005, 0.005, 0.005, 0.005, 0.005, 0.005, 0.01, 0.01, 0.01])
#: Prior standard deviation of a run's gyro bias, rad/s, when the vehicle file states none
#: (``sensors.imu.gyro_bias_sd``): the in-run bias left after the autopilot's gyro calibration at
#: boot; the ArduSub EKF of a real BlueROV2 estimated 0.001-0.017 rad/s (issue 21's logs).
GYRO_BIAS_SIGMA = 0.02


#: Prior standard deviation of the constant roll / pitch offset of a run's attitude filter
#: (AHRS / EKF), rad: the filter levels on gravity as the accelerometer measures it, so a
#: residual accelerometer bias b tilts it by about b / g; 0.01 rad for b = 0.1 m/s^2 (about
#: 0.01 g, the order of a calibrated consumer MEMS accelerometer's offset), plus the IMU's
#: mounting misalignment on the frame.
ATTITUDE_BIAS_SIGMA = 0.01


#: Prior standard deviation of a run's accelerometer bias, m/s^2 per body axis, when the vehicle
#: file states none (``sensors.imu.acc_bias_sd``): 0.1 m/s^2, about 0.01 g, the offset left in a
#: consumer MEMS accelerometer after the autopilot's calibration (the same figure as
#: :data:`ATTITUDE_BIAS_SIGMA`'s; uncalibrated, such parts are specified at +-25-80 mg, e.g.
#: InvenSense MPU-6000 / ICM-20602 data sheets, zero-g offset).  A per-run offset the model does
#: not carry is a force the fit must explain otherwise: on the structural benchmark's seed 22 it
#: bent the thruster gains by 1-4 % (docs/calibration_sensors.md, "Accelerometer bias").
ACC_BIAS_SIGMA = 0.1


def gyro_bias_sd(vehicle) -> float:
    """Prior sd (rad/s) of a run's gyro bias: the vehicle's ``sensors.imu.gyro_bias_sd``, else
    :data:`GYRO_BIAS_SIGMA`."""
    return float(getattr(vehicle, "gyro_bias_sd", None) or GYRO_BIAS_SIGMA)


def acc_bias_sd(vehicle) -> float:
    """Prior sd (m/s^2) of a run's accelerometer bias: the vehicle's ``sensors.imu.acc_bias_sd``,
    else :data:`ACC_BIAS_SIGMA`."""
    return float(getattr(vehicle, "acc_bias_sd", None) or ACC_BIAS_SIGMA)


#: Residual given to a diverged simulation (in noise sigmas).
FILL = 30.0
#: Largest number of simulated rows per batched call (memory; throughput is flat above ~500).
MAX_ROWS = 6000
#: Huber threshold, in noise sigmas of the normalized residual: beyond it a residual costs
#: linearly (Huber 1964; 1.345 sigma gives 95 % efficiency on Gaussian noise, a larger value
#: leaves honest noise alone and bounds only spikes, dropouts and model-error bursts).
HUBER_SCALE = 3.0


def check_loss(loss: str) -> None:
    """An unknown ``loss`` is a :class:`CalibrationError` naming the known ones."""
    if loss not in LOSSES:
        raise CalibrationError(f"loss {loss!r}: expected one of {', '.join(LOSSES)}")


def continuity_factors(value) -> list[float]:
    """``value`` (a factor or a sequence of them) as a non-empty list of positive finite
    continuity factors (multiples of :data:`DEFECT_SIGMA`), else a :class:`CalibrationError`
    naming ``continuity`` and the value given.  Shared by the windowed problem, :func:`fit`
    and the calibration's settings."""
    values = [value] if isinstance(value, (int, float)) else list(value or ())
    if not values:
        raise CalibrationError("continuity: give at least one factor")
    for c in values:
        if not (isinstance(c, (int, float)) and np.isfinite(c) and c > 0):
            raise CalibrationError(f"continuity: expected positive factors of the continuity defects' standard "
                                   f"deviation (1 = DEFECT_SIGMA), got {c!r}")
    return [float(c) for c in values]


def robust_residuals(r: np.ndarray, loss: str = "linear", scale: float = HUBER_SCALE) -> np.ndarray:
    """Residuals whose half sum of squares is the loss: for "huber", ``rho(r) = r^2/2`` up to
    ``|r| = scale`` and ``scale |r| - scale^2/2`` beyond, written as
    ``sign(r) sqrt(2 rho(r))`` (continuous with a continuous derivative, so Gauss-Newton
    and finite differences apply unchanged)."""
    check_loss(loss)
    if loss == "linear":
        return r
    a = np.abs(r)
    with np.errstate(invalid="ignore"):
        return np.where(a <= scale, r, np.sign(r) * np.sqrt(np.maximum(2.0 * scale * a - scale * scale, 0.0)))


class WindowedProblem:
    """Residuals of a set of runs for batches of (parameters, node perturbations, gyro
    biases) under windowed prediction (module docstring).

    Parameters
    ----------
    vehicle : the model (with any effects already added).
    runs : :class:`uvsim.logs.Run` list (one input kind).
    meas : their :class:`uvsim.measurements.RunMeasurements`.
    space : :class:`uvsim.fitting.parameters.ParameterSpace`.
    horizon : window length, s (None: whole runs).
    z_ref : parameters of the reference simulation (default ``space.z0``).
    gyro_bias : fit a constant gyro bias per run that logs rates.
    attitude_bias : fit a constant roll and pitch offset per run whose attitude comes from a
        filter (:attr:`uvsim.measurements.RunMeasurements.has_filter_attitude`), prior sd
        :data:`ATTITUDE_BIAS_SIGMA`.
    acc_bias : fit a constant accelerometer offset (3, body axes) per run that logs one,
        prior sd :func:`acc_bias_sd`.
    loss : "linear" (least squares) or "huber" (:func:`robust_residuals`) on the
        measurement residuals; defects and priors stay quadratic.
    """

    def __init__(self, vehicle, runs, meas, space, horizon=None, *, z_ref=None, gyro_bias=True,
                 attitude_bias: bool = False, acc_bias: bool = False, initial_velocity: str = "zero",
                 yref: np.ndarray | None = None, loss: str = "linear", continuity: float = 1.0):
        check_loss(loss)  # an unknown loss is an error here, not in a worker
        self.loss = loss
        if not isinstance(continuity, (int, float)):
            raise CalibrationError(f"continuity: a windowed problem takes one factor, got {continuity!r}")
        #: standard deviation of each continuity defect component (DEFECT_SIGMA x continuity)
        self.defect_sigma = DEFECT_SIGMA * continuity_factors(continuity)[0]
        kinds = {(r.input_kind, len(r.input_columns)) for r in runs}
        if len(kinds) != 1:
            raise CalibrationError(f"runs mix input kinds/counts: {sorted(kinds)}; fit them in separate groups")
        # inputs as late as the vehicle's sensors read (sensor_latency, uvsim.latency)
        self.vehicle, self.runs, self.space = vehicle, runs_for(vehicle, runs), space
        self.input_kind = runs[0].input_kind
        self.horizon = horizon
        self.lay = layout(self.runs, horizon)
        # window starts restart a lagged attitude model from the logged attitude
        self.meas = [m.for_windows([s for s, _ in b]) for m, b in zip(meas, self.lay.bounds)]
        self.nodes = [NodeModel(r, m) for r, m in zip(self.runs, self.meas)]
        self.free = np.array([nm.free for nm in self.nodes])             # (R, 12)
        self.bias_runs = np.array([gyro_bias and m.has_gyro for m in self.meas])
        #: prior sd of a run's gyro bias, rad/s (the vehicle's IMU spec, else GYRO_BIAS_SIGMA)
        self.gyro_bias_sd = gyro_bias_sd(vehicle)
        self.att_bias_runs = np.array([attitude_bias and m.has_filter_attitude for m in self.meas])
        self.acc_bias_runs = np.array([acc_bias and m.has_accelerometer for m in self.meas])
        #: prior sd of a run's accelerometer bias, m/s^2 (the vehicle's IMU spec, else ACC_BIAS_SIGMA)
        self.acc_bias_sd = acc_bias_sd(vehicle)
        self.accel = any(m.needs_acceleration for m in self.meas)
        #: NED position axes no term reads (ForceTerm.position_axes): a node moved along one
        #: moves its window's trajectory by as much and changes nothing else
        read = position_axes_read(vehicle.terms)
        self.shift_axes = tuple(a for a in range(3) if a not in read)
        self.initial_velocity = initial_velocity
        z_ref = space.z0 if z_ref is None else np.asarray(z_ref, float)
        if yref is not None:  # reference trajectories simulated for these runs beforehand (whole_runs)
            yref = np.asarray(yref, float)[:, : max(r.t.size for r in self.runs)]
        self._prepare_nodes(z_ref, yref)

    # ------------------------------------------------------------------ set-up
    def model(self, Z: np.ndarray, rows_per_set: int) -> Model:
        Z = np.atleast_2d(Z)
        return Model(self.vehicle, self.space.overrides(Z, rows_per_set), n=Z.shape[0] * rows_per_set,
                     input_kind=self.input_kind)

    def full_runs(self, z: np.ndarray, nu0: np.ndarray | None = None):
        """States (R, n_max, n_y) of whole-run simulations from the runs' estimated initial
        states with parameters z (the reference trajectory; also the open-loop prediction),
        accelerations or None, and the model (:func:`whole_runs`)."""
        return whole_runs(self.vehicle, self.runs, [m.sensors for m in self.meas], self.space, z,
                          initial_velocity=self.initial_velocity, nu0=nu0, accel=self.accel)

    def _prepare_nodes(self, z_ref, yref=None):
        Yref = self.full_runs(z_ref)[0] if yref is None else yref
        self.n_term = Yref.shape[-1] - 13
        W = self.lay.W
        self.x_ref = np.empty((W, 13))
        self.prior_sigma = np.empty((W, 12))
        for r, nm in enumerate(self.nodes):
            starts = np.array([s for s, _ in self.lay.bounds[r]])
            ref, sig = nm.references(starts, Yref[r, : self.runs[r].t.size],
                                     xy_track=not {0, 1} <= set(self.shift_axes))
            w0 = self.lay.first[r]
            self.x_ref[w0:w0 + starts.size] = ref
            self.prior_sigma[w0:w0 + starts.size] = sig
        self._yref = Yref

    # ------------------------------------------------------------------ nuisance layout
    def _bias_blocks(self, r: int) -> list:
        """Run r's sensor-bias blocks in nuisance order, (size, prior sd) each, size 0 when not
        fitted: gyro (3, rad/s), attitude filter's roll and pitch (2, rad), accelerometer (3, m/s^2)."""
        return [(3 if self.bias_runs[r] else 0, self.gyro_bias_sd),
                (2 if self.att_bias_runs[r] else 0, ATTITUDE_BIAS_SIGMA),
                (3 if self.acc_bias_runs[r] else 0, self.acc_bias_sd)]

    def bias_sd(self, r: int) -> np.ndarray:
        """Prior sds of run r's sensor-bias vector (:meth:`_bias_blocks`' blocks end to end;
        (0,) for none)."""
        return np.array([sd for n, sd in self._bias_blocks(r) for _ in range(n)], float)

    def split_bias(self, r: int, b):
        """(gyro bias (..., 3), attitude bias (..., 2), accelerometer bias (..., 3)) of run r's
        bias vector, each None when not fitted."""
        out, i = [], 0
        for n, _ in self._bias_blocks(r):
            out.append(b[..., i:i + n] if n and b is not None else None)
            i += n
        return tuple(out)

    def nuisance_size(self, r: int) -> int:
        nw = len(self.lay.bounds[r])
        return nw * int(self.free[r].sum()) + self.bias_sd(r).size

    def split_nuisance(self, r: int, nu: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """(node perturbations (W_r, 12), sensor-bias vector (:meth:`bias_sd`) or None) of
        run r's nuisance vector."""
        nw = len(self.lay.bounds[r])
        c = self.free[r]
        d = np.zeros((nw, 12))
        k = int(c.sum())
        d[:, c] = nu[: nw * k].reshape(nw, k)
        nb = self.bias_sd(r).size
        return d, (nu[nw * k: nw * k + nb] if nb else None)

    def zero_nuisance(self) -> list:
        return [np.zeros(self.nuisance_size(r)) for r in range(len(self.runs))]

    # ------------------------------------------------------------------ simulation
    def _term_states(self, model: Model, Z: np.ndarray) -> np.ndarray | None:
        """Term states (P * W, n_term) at the node times: the terms' own states carried
        along the reference trajectory (vehicle states from ``self._yref``), for each
        parameter set (rows of ``model``: set-major, one row per run)."""
        if self.n_term == 0:
            return None
        P = Z.shape[0]
        R = len(self.runs)
        n = self._yref.shape[1]
        T, U, V = padded_runs(self.runs)
        Vt = None if V is None else np.tile(V, (P, 1))
        m_run = self.model(Z, R)
        closed = m_run.term_states_along(np.tile(T, (P, 1)), np.tile(U, (P, 1, 1)), Vt)
        if closed is not None:  # input-only states (a lag): exact, no reference trajectory needed
            xs = closed
        else:
            xs = self._term_states_rk4(m_run, P, T, U, Vt)
        out = np.empty((P, self.lay.W, self.n_term))
        xs = xs.reshape(P, R, n, self.n_term)
        for r in range(R):
            for j, (s, _) in enumerate(self.lay.bounds[r]):
                out[:, self.lay.first[r] + j] = xs[:, r, s]
        return out.reshape(P * self.lay.W, self.n_term)

    def _term_states_rk4(self, m_run, P, T, U, Vt):
        """Term states (P * R, n, n_term) by RK4 along the reference trajectory."""
        R = len(self.runs)
        n = self._yref.shape[1]
        y = np.repeat(self._yref[None, :, 0], P, 0).reshape(P * R, -1).copy()
        y[:, 13:] = m_run.initial_state(u0=np.tile(U[:, 0], (P, 1)))[:, 13:]
        Tt, Ut = np.tile(T, (P, 1)), np.tile(U, (P, 1, 1))
        xs = np.empty((P * R, n, self.n_term))
        xs[:, 0] = y[:, 13:]
        with np.errstate(all="ignore"):
            for i in range(n - 1):  # RK4 on the term states only, vehicle states teacher-forced
                h = (Tt[:, i + 1] - Tt[:, i])[:, None]
                ya = np.tile(self._yref[:, i, :13], (P, 1))
                yb = np.tile(self._yref[:, i + 1, :13], (P, 1))
                ym = 0.5 * (ya + yb)
                x = y[:, 13:]
                u = Ut[:, i]
                v = None if Vt is None else Vt[:, i]

                def f(yy, xx, tt):
                    return m_run.rhs(tt, np.concatenate([yy, xx], 1), u, v, states_only=True)

                k1 = f(ya, x, Tt[:, i])
                k2 = f(ym, x + 0.5 * h * k1, Tt[:, i] + 0.5 * h[:, 0])
                k3 = f(ym, x + 0.5 * h * k2, Tt[:, i] + 0.5 * h[:, 0])
                k4 = f(yb, x + h * k3, Tt[:, i + 1])
                y[:, 13:] = x + h / 6.0 * (k1 + 2 * (k2 + k3) + k4)
                xs[:, i + 1] = y[:, 13:]
        return xs

    def simulate(self, Z: np.ndarray, D: np.ndarray):
        """Simulate every window for parameter sets Z (P, p) and node perturbations
        D (P, W, 12).  Returns (states (P, W, L, n_y), accelerations or None)."""
        P = Z.shape[0]
        W, L = self.lay.W, self.lay.T.shape[1]
        Ys, As = [], []
        per_call = max(1, MAX_ROWS // W)
        for a in range(0, P, per_call):
            Zc, Dc = Z[a:a + per_call], D[a:a + per_call]
            pc = Zc.shape[0]
            model = self.model(Zc, W)
            y0 = np.empty((pc * W, model.n_y))
            y0[:, :13] = apply_tangent(np.tile(self.x_ref, (pc, 1)), Dc.reshape(pc * W, 12))
            if model.n_y > 13:
                y0[:, 13:] = self._term_states(model, Zc)
            acc = np.empty((pc * W, L, 6)) if self.accel else None
            # one BLAS thread: the per-stage matrix products are small, and threaded BLAS on
            # them is several times slower on a 2-core machine (docs/performance.md)
            with single_thread():
                Y = _rk4_loop(model, np.tile(self.lay.T, (pc, 1)), np.tile(self.lay.U, (pc, 1, 1)), y0, 1, "nan",
                              accel=acc, V=None if self.lay.V is None else np.tile(self.lay.V, (pc, 1)))
            Ys.append(Y.reshape(pc, W, L, -1))
            if acc is not None:
                As.append(acc.reshape(pc, W, L, 6))
        if len(Ys) == 1:  # one call: its arrays as they are (a copy of them is tens of MB)
            return Ys[0], (As[0] if As else None)
        return np.concatenate(Ys), (np.concatenate(As) if As else None)

    # ------------------------------------------------------------------ residuals
    def run_prediction(self, Y, A, r: int):
        """States (P, n_r, n_y) and accelerations (P, n_r, 6) or None of run r's samples, from
        their windows: ``Y[:, own_win, own_pos]`` for ``Y`` (P, W, L, n_y) and ``A``
        (P, W, L, 6), gathered as one index into the flattened (window, position) axis
        (the same values, several times faster than two fancy indices)."""
        L = Y.shape[2]
        flat = self.lay.own_win[r] * L + self.lay.own_pos[r]

        def gather(X):
            return np.take(X.reshape(X.shape[0], -1, X.shape[-1]), flat, axis=1)

        return gather(Y), (None if A is None else gather(A))

    def predict_run(self, r: int, y, a, bias):
        """Run r's predicted measurements from states ``y``, accelerations ``a`` and its
        sensor-bias vector ``bias`` (P, q_b) or None."""
        gb, ab, cb = self.split_bias(r, bias)
        return self.meas[r].predict(y, a, gb, ab, cb)

    def measurement_residuals(self, Y, A, r: int, bias: np.ndarray | None) -> np.ndarray:
        """Normalized measurement residuals (P, m_r) of run r."""
        y, a = self.run_prediction(Y, A, r)
        pred = self.predict_run(r, y, a, bias)
        with np.errstate(all="ignore"):
            return robust_residuals(self.meas[r].normalized(pred, fill=FILL), self.loss)

    def end_states(self, Y, r: int) -> np.ndarray:
        """End states (P, W_r, n_y) of run r's windows."""
        w0 = self.lay.first[r]
        nw = len(self.lay.bounds[r])
        idx = np.arange(w0, w0 + nw)
        return Y[:, idx, self.lay.length[idx] - 1]

    def defects(self, Y, D, r: int) -> np.ndarray:
        """Continuity defects (P, W_r - 1, k) of run r's free node components."""
        w0 = self.lay.first[r]
        nw = len(self.lay.bounds[r])
        if nw < 2:
            return np.zeros((Y.shape[0], 0, int(self.free[r].sum())))
        ends = self.end_states(Y, r)[:, :-1, :13]
        nodes = apply_tangent(self.x_ref[w0 + 1:w0 + nw][None], D[:, w0 + 1:w0 + nw])
        d = tangent_difference(nodes, ends)
        with np.errstate(all="ignore"):
            out = (d / self.defect_sigma)[..., self.free[r]]
        return np.where(np.isfinite(out), out, FILL)

    def priors(self, D, bias, r: int) -> np.ndarray:
        """Prior residuals (P, q_r) of run r's nuisance (node perturbations, sensor biases)."""
        w0 = self.lay.first[r]
        nw = len(self.lay.bounds[r])
        c = self.free[r]
        pr = (D[:, w0:w0 + nw] / self.prior_sigma[w0:w0 + nw][None])[..., c].reshape(D.shape[0], -1)
        sd = self.bias_sd(r)
        if sd.size:
            pr = np.concatenate([pr, np.atleast_2d(bias) / sd], 1)
        return pr

    def assemble(self, nus: list, P: int = 1):
        """Global node perturbations D (P, W, 12) and sensor-bias vectors (per run: (P, q_b)
        or None, :meth:`bias_sd`) from per-run nuisance vectors (each (q_r,) or (P, q_r))."""
        D = np.zeros((P, self.lay.W, 12))
        biases = []
        for r, nu in enumerate(nus):
            nu = np.broadcast_to(np.atleast_2d(nu), (P, np.size(nu) if np.ndim(nu) == 1 else np.shape(nu)[-1]))
            nw = len(self.lay.bounds[r])
            k = int(self.free[r].sum())
            w0 = self.lay.first[r]
            D[:, w0:w0 + nw][..., self.free[r]] = nu[:, : nw * k].reshape(P, nw, k)
            nb = self.bias_sd(r).size
            biases.append(nu[:, nw * k: nw * k + nb] if nb else None)
        return D, biases

    def residuals(self, z: np.ndarray, nus: list) -> list:
        """Per run, the residual vector [measurements, defects, priors] at one point."""
        D, biases = self.assemble(nus)
        Y, A = self.simulate(np.asarray(z, float)[None], D)
        out = []
        for r in range(len(self.runs)):
            b = biases[r]
            parts = [self.measurement_residuals(Y, A, r, b)[0], self.defects(Y, D, r)[0].ravel(),
                     self.priors(D, b if b is not None else None, r)[0]]
            out.append(np.concatenate(parts))
        return out
