"""Scenario specifications: every random choice of a dataset, drawn from a seed.

:func:`sample_scenario` draws a :class:`ScenarioSpec` for a profile; :func:`uvsim.scenarios.generate`
turns it into files.  The spec is plain data (JSON/YAML-serializable) and holds everything
but the noise realizations (drawn from ``noise_seed`` when the files are written), so a
spec read back from ``truth.yaml`` regenerates the same dataset.

Profiles (docs/scenarios.md lists every distribution):

``diagnose``        issue 10: BlueROV2 Heavy, Table 5 coefficients perturbed +-10 %, motion
                    capture, one random input kind, 10-100 Hz, 20-30 training runs of 8-15 s
                    with a random mix of shapes, a spiral and one more validation run,
                    neutral or trimmed, 0-2 effects.
``issue10_timing``  the fixed issue-10 timing configuration: 48 step-then-reverse runs (8 per
                    DOF) and a spiral validation run, 14 s at 50 Hz, force inputs, positively
                    buoyant (Table 2: B - W = 3.34 N) held by a trim force, 3 mm / 0.003 rad
                    motion capture, one effect.
``realsensor``      issue 14: multi-DOF telegraph PWM runs logged by an IMU at 100-200 Hz (gyro
                    with bias, accelerometer, lagged roll/pitch), depth from a pressure sensor
                    0.15 m aft at 10 Hz, no position; the truth may move the CB (z_b) and have a
                    weak thruster.

Structural overrides (issue 21; off by default, so a spec without them is what it always
was): ``thruster_position_error`` moves the truth's thrusters off the vehicle file's positions
(``vehicle.thruster_offsets``, drawn from the seed in a stream of its own), ``time_jitter``
stamps the logged rows with a noisy clock (``sensors.clock``), ``sensor_latency`` delays every
sensor but a DVL (``sensors.<section>.latency``), ``pilot_inputs`` (realsensor) replaces the
telegraph runs by runs flown by a pilot (``pilot`` shapes, drawn in a stream of their own).
Each leaves every other random choice of the seed as it was.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from uvsim.scenarios.effects import CATALOGUED, EFFECTS, ScenarioError, effect_from_dict, sample_effect
from uvsim.scenarios.inputs import (AMPLITUDE_RANGES, DOF_NAMES, THRUST_MARGIN, force_profile, sample_shape,
                                    scale_shape, thrust_utilization)
from uvsim.scenarios.sensors import DEPTH_MODES, MAX_LATENCY, validate_sensors
from uvsim.scenarios.vehicle_data import DEFAULT_VEHICLE_FILE, PERTURBABLE, load_vehicle_data

PROFILES = ("diagnose", "issue10_timing", "realsensor")
#: Sensor suite of each profile; it selects the effects' magnitude ranges (effects.MAGNITUDE_RANGES).
PROFILE_SUITE = {"diagnose": "mocap", "issue10_timing": "mocap", "realsensor": "imu"}
INPUT_KINDS = ("force", "thrust", "pwm")
SPEC_VERSION = 1
#: Log rates, Hz: motion-capture profiles and IMU profiles (multiples of the 10 Hz depth sensor).
MOCAP_RATES = (10.0, 20.0, 25.0, 40.0, 50.0, 100.0)
IMU_RATES = (100.0, 150.0, 200.0)
#: Where runs start: NED centre (m) and half-widths of a box around it.
START_CENTRE = (0.0, 0.0, 1.2)
START_HALF_WIDTH = (0.5, 0.5, 0.2)
#: Training shape mix of the diagnose profile (relative weights).
DIAGNOSE_SHAPES = {"step": 0.25, "step_reverse": 0.25, "sine": 0.15, "decay": 0.15, "telegraph": 0.1,
                   "spiral": 0.1}

#: Keys every run of a spec has.
RUN_KEYS = ("name", "dof", "split", "weight", "duration", "shape", "pos0", "yaw0")
OVERRIDES = {
    "n_runs": "number of training runs",
    "n_validation": "number of validation runs (the first is a spiral, except in realsensor)",
    "duration": "run length, s: a number or [low, high]",
    "rate_hz": "log rate, Hz",
    "input_kind": "force, thrust or pwm",
    "n_effects": "number of effects (0, 1, 2, ...)",
    "effects": "effect types, or dicts {type, variant, magnitude}",
    "include_uncatalogued": "let the random effects include periodic_force",
    "perturbation": "bound of the coefficient factors (0.1: +-10 %)",
    "buoyancy": "neutral or trimmed",
    "net_buoyancy": "B - W of a trimmed vehicle, N",
    "sigma_position": "motion-capture position noise, m",
    "sigma_attitude": "motion-capture attitude noise, rad",
    "yaw": "realsensor: log yaw from the attitude filter",
    "depth_mode": "realsensor: native, held or interpolated",
    "dvl": "realsensor: add a DVL (u, v, w)",
    "perturb_z_b": "realsensor: move the truth's CB height by up to +-30 %",
    "max_step": "RK4 step bound, s",
    "curve_voltage": "diagnose: the truth's T200s run at this supply voltage (10-20 V, measured curves) while the "
                     "model's file says 16 V; PWM inputs",
    "thruster_position_error": "bound, m, of the truth's thruster position errors: each thruster and axis off by "
                               "U(-bound, bound) from the vehicle file (which the model keeps); thrust or PWM "
                               "inputs (default PWM); 0: off",
    "time_jitter": "s, standard deviation of the logged time stamps about the true sample times (kept strictly "
                   "increasing); 0: off",
    "sensor_latency": "s, every sensor but a DVL logs at t the truth at t - latency; inputs are logged at their "
                      "own times; 0: off",
    "pilot_inputs": "realsensor: training and validation runs flown by a pilot on a gamepad (ArduSub manual "
                    "mode) instead of telegraph PWM",
}
#: Bounds of the structural overrides (see :func:`_check_overrides`): a thruster position error
#: beyond 0.1 m is a wrong frame, not a measurement error (the BlueROV2 Heavy's thrusters sit
#: within ~0.2 m of its origin); a logger's time-stamp jitter beyond 20 ms is dropped samples, not
#: jitter (a Linux logger's is a few ms); latency up to MAX_LATENCY (sensors.py).
MAX_THRUSTER_POSITION_ERROR = 0.1
MAX_TIME_JITTER = 0.02
#: Extra random streams of a seed (``default_rng([seed, profile index, stream])``): what a
#: structural override draws does not shift the draws of the profile's own stream.
THRUSTER_OFFSET_STREAM = 1
PILOT_STREAM = 2


@dataclass
class ScenarioSpec:
    """Everything a generated dataset is made of (plain data; see module docstring)."""

    seed: int
    profile: str
    description: str
    vehicle: dict
    input_kind: str
    rate_hz: float
    sensors: dict
    effects: list
    runs: list
    noise_seed: int = 0
    max_step: float = 0.002
    version: int = SPEC_VERSION
    start_region: dict = field(default_factory=lambda: {"centre": list(START_CENTRE),
                                                        "half_width": list(START_HALF_WIDTH)})

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> "ScenarioSpec":
        if not isinstance(d, dict):
            raise ScenarioError(f"scenario spec: expected a mapping, got {type(d).__name__}")
        known = set(cls.__dataclass_fields__)
        bad = sorted(set(d) - known)
        if bad:
            raise ScenarioError(f"scenario spec: unknown field(s) {bad}; expected {sorted(known)}")
        missing = sorted(k for k in ("seed", "profile", "vehicle", "input_kind", "rate_hz", "sensors", "runs")
                         if k not in d)
        if missing:
            raise ScenarioError(f"scenario spec: missing field(s) {missing}")
        spec = cls(**{"description": "", "effects": [], **d})
        spec.validate()
        return spec

    def validate(self) -> None:
        """Raise :class:`ScenarioError` naming the first malformed field."""
        if self.input_kind not in INPUT_KINDS:
            raise ScenarioError(f"scenario spec: input_kind {self.input_kind!r}; expected one of {list(INPUT_KINDS)}")
        if not (isinstance(self.rate_hz, (int, float)) and 0 < self.rate_hz <= 1000):
            raise ScenarioError(f"scenario spec: rate_hz {self.rate_hz!r}; expected a number in (0, 1000] Hz")
        if not (isinstance(self.max_step, (int, float)) and 1e-5 <= self.max_step <= 0.05):
            raise ScenarioError(f"scenario spec: max_step {self.max_step!r}; expected seconds in [1e-5, 0.05]")
        validate_sensors(self.sensors)
        if not isinstance(self.vehicle, dict) or "file" not in self.vehicle:
            raise ScenarioError("scenario spec: vehicle: expected a mapping with at least 'file'")
        if not isinstance(self.runs, list) or not self.runs:
            raise ScenarioError("scenario spec: runs: expected a non-empty list")
        for i, r in enumerate(self.runs):
            missing = [k for k in RUN_KEYS if not isinstance(r, dict) or k not in r]
            if missing:
                raise ScenarioError(f"scenario spec: runs[{i}]: missing {missing}")
            if not (isinstance(r["duration"], (int, float)) and r["duration"] * self.rate_hz >= 1):
                raise ScenarioError(f"scenario spec: runs[{i}].duration {r['duration']!r}; expected seconds "
                                    "covering at least two samples")
        for e in self.effects:
            effect_from_dict(e)


def sensor_suite(spec: "ScenarioSpec") -> str:
    """``mocap`` when the runs log position (motion capture), else ``imu``."""
    return "mocap" if "mocap" in spec.sensors else "imu"


def _r(x, nd=6):
    return round(float(x), nd)


def _u(rng, lo, hi, nd=6):
    return _r(rng.uniform(lo, hi), nd)


def _check_overrides(over: dict) -> None:
    bad = sorted(set(over) - set(OVERRIDES))
    if bad:
        raise ScenarioError(f"sample_scenario: unknown override(s) {bad}; expected one of {sorted(OVERRIDES)}")
    if "input_kind" in over and over["input_kind"] not in INPUT_KINDS:
        raise ScenarioError(f"sample_scenario: input_kind {over['input_kind']!r}; expected one of {list(INPUT_KINDS)}")
    if "buoyancy" in over and over["buoyancy"] not in ("neutral", "trimmed"):
        raise ScenarioError(f"sample_scenario: buoyancy {over['buoyancy']!r}; expected neutral or trimmed")
    if "depth_mode" in over and over["depth_mode"] not in DEPTH_MODES:
        raise ScenarioError(f"sample_scenario: depth_mode {over['depth_mode']!r}; expected one of {list(DEPTH_MODES)}")
    for key, lo, hi in (("n_runs", 1, 500), ("n_validation", 1, 50), ("n_effects", 0, len(EFFECTS))):
        if key in over and not (isinstance(over[key], (int, np.integer)) and lo <= over[key] <= hi):
            raise ScenarioError(f"sample_scenario: {key} = {over[key]!r}; expected an integer in [{lo}, {hi}]")
    for key, lo, hi in (("rate_hz", 1.0, 1000.0), ("perturbation", 0.0, 0.5), ("net_buoyancy", -20.0, 20.0),
                        ("sigma_position", 1e-5, 0.1), ("sigma_attitude", 1e-5, 0.2), ("max_step", 1e-4, 0.02)):
        if key in over and not (isinstance(over[key], (int, float)) and lo <= over[key] <= hi):
            raise ScenarioError(f"sample_scenario: {key} = {over[key]!r}; expected a number in [{lo:g}, {hi:g}]")
    if "curve_voltage" in over and over["curve_voltage"] not in (10, 12, 14, 16, 18, 20):
        raise ScenarioError(f"sample_scenario: curve_voltage = {over['curve_voltage']!r}; expected one of the measured "
                            "T200 voltages 10, 12, 14, 16, 18, 20 V")
    for key, hi in (("thruster_position_error", MAX_THRUSTER_POSITION_ERROR), ("time_jitter", MAX_TIME_JITTER),
                    ("sensor_latency", MAX_LATENCY)):
        v = over.get(key, 0.0)
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) \
                or not (np.isfinite(v) and 0.0 <= v <= hi):
            unit = "m" if key == "thruster_position_error" else "s"
            raise ScenarioError(f"sample_scenario: {key} = {v!r}; expected a number in [0, {hi:g}] {unit} (0: off)")
    if "pilot_inputs" in over and not isinstance(over["pilot_inputs"], (bool, np.bool_)):
        raise ScenarioError(f"sample_scenario: pilot_inputs = {over['pilot_inputs']!r}; expected True or False")
    if over.get("thruster_position_error") and over.get("input_kind") == "force":
        raise ScenarioError("sample_scenario: thruster_position_error with input_kind 'force': force inputs drive "
                            "the truth with the generalized force itself, no thruster geometry; expected input_kind "
                            "'thrust' or 'pwm'")
    if "duration" in over:
        d = np.atleast_1d(np.asarray(over["duration"], dtype=float))
        if d.size not in (1, 2) or not np.all((d >= 1.0) & (d <= 600.0)):
            raise ScenarioError(f"sample_scenario: duration = {over['duration']!r}; expected seconds in [1, 600] "
                                "or [low, high]")


def _duration(rng, over, default):
    d = np.atleast_1d(np.asarray(over.get("duration", default), dtype=float))
    return _r(d[0] if d.size == 1 else rng.uniform(d[0], d[1]), 1)


def _vehicle(rng, over, *, buoyancy, net=None, perturb_z_b=False) -> dict:
    nominal = load_vehicle_data(DEFAULT_VEHICLE_FILE)
    p = float(over.get("perturbation", 0.1))
    factors = {k: _r(1.0 + rng.uniform(-p, p)) for k in PERTURBABLE}
    mode = over.get("buoyancy", buoyancy)
    if mode == "neutral":
        net = 0.0
    else:
        net = float(over.get("net_buoyancy", net if net is not None else _u(rng, 1.5, 6.0, 3)))
    z_b = float(nominal.r_b[2])
    if over.get("perturb_z_b", perturb_z_b):
        z_b = _r(z_b * rng.uniform(0.7, 1.3))
    out = {"file": nominal.name, "perturbation": p, "factors": factors, "buoyancy": mode,
           "net_buoyancy": _r(net), "z_b": z_b, "model_name": "myrov"}
    if "curve_voltage" in over:
        out["truth_curve"] = f"t200_{int(over['curve_voltage'])}v_measured"
    return out


def _effects(rng, over, kind, default_n, pool, context, forced=(), suite="mocap") -> list:
    spec = over.get("effects")
    if spec is None:
        n = int(over.get("n_effects", default_n if default_n is not None else rng.integers(0, 3)))
        pool = list(pool) + (["periodic_force"] if over.get("include_uncatalogued") else [])
        if n > len(pool):
            raise ScenarioError(f"sample_scenario: n_effects = {n}, but only {len(pool)} effect types can be drawn "
                                f"here ({', '.join(pool)})")
        chosen = [f for f in forced if f in pool][:n]
        rest = [p for p in pool if p not in chosen]
        chosen += [str(x) for x in rng.choice(rest, size=min(n - len(chosen), len(rest)), replace=False)]
        spec = chosen
    out = []
    for item in spec:
        d = {"type": item} if isinstance(item, str) else dict(item)
        if d.get("type") not in EFFECTS:
            raise ScenarioError(f"sample_scenario: effect {d.get('type')!r}; expected one of {sorted(EFFECTS)}")
        bad = sorted(set(d) - {"type", "variant", "magnitude"})
        if bad:
            raise ScenarioError(f"sample_scenario: effect {d['type']}: unknown key(s) {bad}; "
                                "expected type, variant, magnitude")
        out.append(sample_effect(rng, d["type"], kind=kind, suite=suite, variant=d.get("variant"),
                                 magnitude=d.get("magnitude"), **context).to_dict())
    types = [e["type"] for e in out]
    if len(set(types)) != len(types):
        raise ScenarioError(f"sample_scenario: an effect type appears twice in {types}")
    return out


def _fit_shape(shape, duration, rate, veh, trim):
    """Scale a shape down until no thruster needs more than THRUST_MARGIN of its limit."""
    t = np.arange(int(round(duration * rate)) + 1) / rate
    A = veh.allocation()
    scale = 1.0
    for _ in range(40):
        use = thrust_utilization(force_profile(scale_shape(shape, scale), t), A, veh.curve, trim)
        if use <= THRUST_MARGIN:
            break
        scale *= 0.9
    return (scale_shape(shape, scale) if scale < 1.0 else shape), _r(scale)


def _runs(rng, shapes_train, shapes_val, durations, rate, veh, trim, imu=False, pilot_rng=None) -> list:
    """The runs of a spec.  With ``pilot_rng`` each run is a ``pilot`` shape drawn from it, and
    the shape ``rng`` would have drawn is drawn and dropped, so the other draws stay as they are."""
    runs = []
    c, hw = np.asarray(START_CENTRE), np.asarray(START_HALF_WIDTH)
    for i, ((shape, split), dur) in enumerate(zip([(s, "train") for s in shapes_train]
                                                 + [(s, "validation") for s in shapes_val], durations)):
        if isinstance(shape, dict):
            sh = shape
        else:
            name, dof = shape
            sh = sample_shape(rng, name, dur, dof=dof)
        if pilot_rng is not None:
            sh = sample_shape(pilot_rng, "pilot", dur)
        sh, scale = _fit_shape(sh, dur, rate, veh, trim)
        run = {"name": f"{'val' if split == 'validation' else 'run'}_{i + 1:02d}_{sh['shape']}_{sh['dof']}",
               "dof": sh["dof"], "split": split, "weight": 1.0, "duration": dur, "shape": sh, "amplitude_scale": scale,
               "pos0": [_r(x) for x in c + rng.uniform(-1, 1, 3) * hw], "yaw0": _u(rng, -np.pi, np.pi)}
        if imu:
            run["gyro_bias"] = [_u(rng, -0.02, 0.02) for _ in range(3)]
            run["acc_bias"] = [_u(rng, -0.05, 0.05) for _ in range(3)]
        runs.append(run)
    return runs


def _diagnose(seed, rng, over) -> ScenarioSpec:
    kind = over.get("input_kind", str(rng.choice(INPUT_KINDS)))
    if "curve_voltage" in over or over.get("thruster_position_error"):
        kind = over.get("input_kind", "pwm")  # a curve mismatch and the thrusters' geometry are thruster matters
    rate = float(over.get("rate_hz", rng.choice(MOCAP_RATES)))
    vehicle = _vehicle(rng, over, buoyancy=str(rng.choice(["neutral", "trimmed"])))
    veh = load_vehicle_data()
    n_train = int(over.get("n_runs", rng.integers(20, 31)))
    n_val = int(over.get("n_validation", 2))
    names, w = list(DIAGNOSE_SHAPES), np.array(list(DIAGNOSE_SHAPES.values()))
    picks = rng.choice(names, size=n_train, p=w / w.sum())
    dofs = [DOF_NAMES[j] for j in rng.permutation(6)]
    train, k = [], 0
    for s in picks:
        if s in ("spiral", "telegraph"):
            train.append((str(s), None))
        else:
            train.append((str(s), dofs[k % 6]))
            k += 1
    val = [("spiral", None)] + [(str(rng.choice(["telegraph", "sine", "step_reverse"])), None)
                                for _ in range(n_val - 1)]
    durs = [_duration(rng, over, (8.0, 15.0)) for _ in range(n_train + n_val)]
    ctx = {"start_region": {"centre": list(START_CENTRE)}, "directions": veh.thruster_directions, "g": veh.g,
           "rho": veh.rho}
    effects = _effects(rng, over, kind, None, CATALOGUED, ctx)
    sensors = {"mocap": {"sigma_position": float(over.get("sigma_position", _u(rng, 0.001, 0.005))),
                         "sigma_attitude": float(over.get("sigma_attitude", _u(rng, 0.002, 0.01)))}}
    runs = _runs(rng, train, val, durs, rate, veh, vehicle["net_buoyancy"])
    return ScenarioSpec(seed, "diagnose", f"diagnose profile, seed {seed}: {kind} inputs at {rate:g} Hz, "
                        f"{len(effects)} effect(s)", vehicle, kind, rate, sensors, effects, runs, noise_seed=seed)


def _issue10(seed, rng, over) -> ScenarioSpec:
    kind = over.get("input_kind", "pwm" if over.get("thruster_position_error") else "force")
    rate = float(over.get("rate_hz", 50.0))
    veh = load_vehicle_data()
    vehicle = _vehicle(rng, over, buoyancy="trimmed", net=_r(veh.buoyancy - veh.weight))
    n_per_dof = 8
    train = []
    for dof in DOF_NAMES:
        lo, hi = AMPLITUDE_RANGES[dof]
        for j, a in enumerate(np.linspace(lo, hi, n_per_dof)):
            train.append({"shape": "step_reverse", "dof": dof, "amplitude": _r(a * (-1) ** j), "t_on": 0.0,
                          "t_reverse": 5.0, "t_off": 10.0})
    val = [("spiral", None)]
    ctx = {"start_region": {"centre": list(START_CENTRE)}, "directions": veh.thruster_directions, "g": veh.g,
           "rho": veh.rho}
    effects = _effects(rng, over, kind, 1, CATALOGUED, ctx)
    sensors = {"mocap": {"sigma_position": float(over.get("sigma_position", 0.003)),
                         "sigma_attitude": float(over.get("sigma_attitude", 0.003))}}
    dur = _duration(rng, over, 14.0)
    runs = _runs(rng, train, val, [dur] * (len(train) + 1), rate, veh, vehicle["net_buoyancy"])
    return ScenarioSpec(seed, "issue10_timing", f"issue-10 timing configuration, seed {seed}: 48 step-reverse runs "
                        f"and a spiral, {dur:g} s at {rate:g} Hz, {len(effects)} effect(s)",
                        vehicle, kind, rate, sensors, effects, runs, noise_seed=seed)


def _realsensor(seed, rng, over) -> ScenarioSpec:
    kind = over.get("input_kind", "pwm")
    rate = float(over.get("rate_hz", rng.choice(IMU_RATES)))
    veh = load_vehicle_data()
    vehicle = _vehicle(rng, over, buoyancy=str(rng.choice(["neutral", "trimmed"])), perturb_z_b=rng.random() < 0.5)
    n_train = int(over.get("n_runs", rng.integers(8, 15)))
    n_val = int(over.get("n_validation", 2))
    durs = [_duration(rng, over, (10.0, 20.0)) for _ in range(n_train + n_val)]
    forced = ("weak_thruster",) if rng.random() < 0.5 else ()
    ctx = {"start_region": {"centre": list(START_CENTRE)}, "directions": veh.thruster_directions, "g": veh.g,
           "rho": veh.rho}
    n_eff = None if "n_effects" in over or "effects" in over else len(forced) + int(rng.integers(0, 2))
    # Without position or DVL a current is nearly invisible (effect_snr ~1 at 0.1 m/s, docs/scenarios.md):
    # it is drawn only when the runs log a DVL.
    pool = [e for e in CATALOGUED if e != "current" or over.get("dvl")]
    effects = _effects(rng, over, kind, n_eff, pool, ctx, forced=forced, suite="imu")
    sensors = {
        "imu": {"position": [_u(rng, -0.05, 0.10), _u(rng, -0.03, 0.03), _u(rng, -0.08, 0.0)],
                "gyro_sigma": _u(rng, 0.001, 0.005), "acc_sigma": _u(rng, 0.01, 0.05)},
        "euler": {"time_constant": _u(rng, 0.05, 0.3), "sigma": _u(rng, 0.002, 0.01),
                  "yaw": bool(over.get("yaw", False))},
        "depth": {"position": [-0.15, 0.0, 0.0], "rate_hz": 10.0,
                  "mode": over.get("depth_mode", str(rng.choice(DEPTH_MODES))), "sigma": _u(rng, 0.005, 0.02)},
    }
    if over.get("dvl"):
        sensors["dvl"] = {"position": [-0.1, 0.0, 0.1], "sigma": 0.01}
    shapes = [("telegraph", None)] * (n_train + n_val)
    pilot_rng = (np.random.default_rng([seed, PROFILES.index("realsensor"), PILOT_STREAM])
                 if over.get("pilot_inputs") else None)
    runs = _runs(rng, shapes[:n_train], shapes[n_train:], durs, rate, veh, vehicle["net_buoyancy"], imu=True,
                 pilot_rng=pilot_rng)
    flown = "pilot" if pilot_rng is not None else "telegraph"
    return ScenarioSpec(seed, "realsensor", f"realsensor profile, seed {seed}: {kind} {flown} runs, IMU at "
                        f"{rate:g} Hz, depth at 10 Hz ({sensors['depth']['mode']}), {len(effects)} effect(s)",
                        vehicle, kind, rate, sensors, effects, runs, noise_seed=seed)


def sample_scenario(seed: int, profile: str = "diagnose", **overrides) -> ScenarioSpec:
    """Draw a scenario for ``profile`` from ``seed`` (deterministic).

    Parameters
    ----------
    seed : non-negative integer.
    profile : "diagnose", "issue10_timing" or "realsensor" (module docstring).
    **overrides : fix some of the random choices (:data:`OVERRIDES` lists them), e.g.
        ``n_effects=1``, ``effects=["tether"]``, ``input_kind="pwm"``, ``duration=10``; and the
        structural ones, off by default (module docstring): ``thruster_position_error=0.02`` (m),
        ``time_jitter=0.002`` (s), ``sensor_latency=0.02`` (s), ``pilot_inputs=True``.

    Returns
    -------
    ScenarioSpec
    """
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ScenarioError(f"sample_scenario: seed must be a non-negative integer, got {seed!r}")
    if profile not in PROFILES:
        raise ScenarioError(f"sample_scenario: profile {profile!r}; expected one of {list(PROFILES)}")
    _check_overrides(overrides)
    if overrides.get("pilot_inputs") and profile != "realsensor":
        raise ScenarioError(f"sample_scenario: pilot_inputs with profile {profile!r}; only the realsensor profile's "
                            "telegraph runs can be flown by a pilot")
    rng = np.random.default_rng([int(seed), PROFILES.index(profile)])
    spec = {"diagnose": _diagnose, "issue10_timing": _issue10, "realsensor": _realsensor}[profile](
        int(seed), rng, overrides)
    if "max_step" in overrides:
        spec.max_step = float(overrides["max_step"])
    _structure(spec, overrides)
    return spec


def _structure(spec: ScenarioSpec, over: dict) -> None:
    """Record the structural overrides in ``spec`` (module docstring); nothing when they are off."""
    notes = []
    bound = float(over.get("thruster_position_error", 0.0))
    if bound > 0:
        prng = np.random.default_rng([spec.seed, PROFILES.index(spec.profile), THRUSTER_OFFSET_STREAM])
        k = load_vehicle_data(DEFAULT_VEHICLE_FILE).n_thrusters
        spec.vehicle["thruster_position_error"] = _r(bound)
        spec.vehicle["thruster_offsets"] = [[_u(prng, -bound, bound) for _ in range(3)] for _ in range(k)]
        notes.append(f"thruster positions off by up to {bound * 1000:g} mm")
    jitter = float(over.get("time_jitter", 0.0))
    if jitter > 0:
        spec.sensors["clock"] = {"jitter": jitter}
        notes.append(f"time stamps jittered by {jitter * 1000:g} ms")
    latency = float(over.get("sensor_latency", 0.0))
    if latency > 0:
        for name, sec in spec.sensors.items():
            if name not in ("dvl", "clock"):   # a DVL's own timing is not modelled; the clock has no readings
                sec["latency"] = latency
        notes.append(f"sensors {latency * 1000:g} ms late")
    if notes:
        spec.description += "; " + ", ".join(notes)
