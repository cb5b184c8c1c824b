"""``uvsim bench calibrate-structural``: calibration when the data differ from the model in structure.

Issue 21: a least-squares fit on data whose truth has the fitted model's structure says
nothing about real logs. Here every dataset comes from the independent truth generator
(:mod:`uvsim.scenarios`, profile ``realsensor``: its dynamics, thrusters and sensors are
written apart from uvsim's simulator and from :mod:`uvsim.fitting`, which it does not
import: ``tests/test_calibration_structural.py`` checks) and differs from the model the
calibration starts from in structure, not only in values:

* start model 20-40 % off: every base coefficient of the truth is the vehicle file's times
  a factor drawn in ``1 +- p``, ``p`` uniform in [0.2, 0.4];
* half the seeds: the truth's T200s run on the curve measured at another supply voltage
  (12, 14, 18 or 20 V; the model's file says 16 V): another thrust-curve shape;
* 0-1 effects the model lacks (tether, ballast, thruster lag, ...; the generator's
  catalogue for IMU logs) and, half the seeds, a weak thruster; the centre of buoyancy
  moved up to +-30 % half the seeds;
* sensors as a real ROV logs them: IMU at 100 Hz (gyro and accelerometer with a bias per
  run), roll and pitch from an attitude filter with a lag and noise, depth from a pressure
  sensor 0.15 m aft at 10 Hz, no position; telegraph PWM on all thrusters;
* each independently on a third of the seeds: the truth's thrusters off the vehicle file's
  positions by up to 1-3 cm per axis (``thruster_position_error``); time stamps jittered by
  1-5 ms (``time_jitter``, a Linux logger's); IMU, attitude and depth 10-50 ms late
  (``sensor_latency``); training and validation runs flown by a pilot on a gamepad instead of
  telegraph PWM (``pilot_inputs``).  These are drawn after the draws above, so every seed's
  perturbation, effects and curve are what they were before they were added.

Each dataset is calibrated with the command docs/calibration.md gives for real logs
(``uvsim calibrate --data DIR --free "z_b,thruster_gain_*,thruster_reverse_*" --latency auto
--supply-voltage auto``: :class:`uvsim.calibration.Calibrator` with ``free=`` :data:`REAL_LOG_FREE`,
``latency=`` :data:`REAL_LOG_LATENCY`, ``supply_voltage=`` :data:`REAL_LOG_SUPPLY`; ``--free z_b``
gives the command of the releases before, which fitted no actuator parameter), once with the
priors (default) and, with ``--compare-no-prior``, once without; ``--loss huber`` calibrates with
the Huber loss instead of least squares.  Judged by the calibration's own verdict
(:mod:`uvsim.fitting.verdict`: the validation runs' free simulations, every logged channel, the
pooled error and each channel against the start model, by a block bootstrap): *better*,
*trade-off* or *worse*, with the verdict's per-channel figures.  Beside it, a fixed threshold the
verdict does not use: a channel whose pooled validation Fit % drops by more than
:data:`WORSE_POINTS` points (``worse_points``), so that a *better* verdict on a fit that loses a
point somewhere within the comparison's noise is counted, not hidden.

A second verdict needs no data at all: the generator's noise-free truth of each validation
run (:func:`uvsim.scenarios.generate.simulate_spec`), against which the start and the fitted
model are simulated from the *true* initial state with the logged inputs; per state channel
(depth, roll, pitch, p, q, r) the fit is *farther from the truth* when its RMS error exceeds
the start's by more than :data:`TRUTH_TOLERANCE`. (uvsim with the generator's true
coefficients follows its truth to 0.1 mm on a 16 V scenario without effects, so what remains is
the structural mismatch and the fit.)

Two references are judged exactly as a fit is (the verdict), against the same start model on the
same validation runs (:func:`reference_checks`): the truth itself as a uvsim vehicle file states it
(coefficients, centre of buoyancy, thrust curve, thruster positions, a weak thruster, latency;
seeds with another effect have no such reference; never the time-stamp jitter), counted only where
it follows the generator's noise-free truth to :data:`REFERENCE_TOLERANCE`, and the start model
with the truth's coefficients (what a fit of the coefficients alone could at best reach). Where the truth itself validates worse than the start,
"no worse than the start" is out of reach of any fit: the open-loop metric then rewards a start
model whose errors happen to cancel, or compares a free simulation the vehicle's own instability
makes diverge.

Metrics: share of seeds whose verdict is *better* (goal >= 95 %), *better* verdicts on fits that
lose more than WORSE_POINTS in some channel, the median pooled error change and the median Fit %
gain per channel, and the fits farther from the noise-free truth. Records go to a JSON-lines
file as they finish, so an interrupted run resumes.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from uvsim.benchmarks.records import append_record, load_records
from uvsim.errors import UvsimError
from uvsim.progress import as_progress

#: A channel whose validation Fit % drops by more than this many points: the fit is worse.
WORSE_POINTS = 1.0
#: Relative growth of a state channel's RMS error against the truth that counts as farther.
TRUTH_TOLERANCE = 0.02
#: What the real-log command of docs/calibration.md frees beside the default set: the CB height,
#: every thruster's gain and reverse ratio (prior sd :data:`uvsim.fitting.priors.THRUSTER_GAIN_SD`,
#: :data:`~uvsim.fitting.priors.THRUSTER_REVERSE_SD`), so that a thrust curve, unit, propeller or
#: battery that differs from the file's is carried by the thrust model rather than by the
#: hydrodynamic coefficients (issue 22's "thrust model first").
REAL_LOG_FREE = "z_b,thruster_gain_*,thruster_reverse_*"
#: The real-log command's ``--latency`` (docs/calibration_sensors.md, "Sensor latency"): estimated after the
#: joint fit, fitted again with it when it lowers the windowed cost by 2 % or more.
REAL_LOG_LATENCY = "auto"
#: The real-log command's ``--supply-voltage`` (docs/calibration_method.md, "Supply voltage"): a second
#: joint fit with the thrusters on the T200 voltage family, kept when the verdict on the training
#: runs calls it better than the first fit in every channel.  ``supply`` of :func:`run_one`: False none, True freed from the start, "auto".
REAL_LOG_SUPPLY = "auto"
#: The real-log command's ``--trade-off`` (docs/calibration_method.md, "After a trade-off"): after a
#: trade-off, fit again with the structure the worse channels point to and keep a *better* refit.
REAL_LOG_TRADE_OFF = "explore"
#: Scenario size: a few runs of 15-25 s at 100 Hz (a real session's order) and two validation runs.
SIZE = dict(n_runs=3, n_validation=2, duration=[15, 25], rate_hz=100.0)


#: The structural classes drawn on a third of the seeds each (module docstring).
STRUCTURE_CLASSES = ("thruster_position_error", "time_jitter", "sensor_latency", "pilot_inputs")


def scenario(seed: int, *, structure: bool = True) -> dict:
    """``sample_scenario`` overrides of benchmark seed ``seed`` (module docstring); with
    ``structure=False`` without the :data:`STRUCTURE_CLASSES` (the seed as the benchmark drew it
    before they were added: the examples of docs/calibration.md)."""
    rng = np.random.default_rng([seed, 21])
    over = {**SIZE, "perturbation": round(float(rng.uniform(0.2, 0.4)), 3), "n_effects": int(rng.random() < 0.5)}
    if rng.random() < 0.5:
        over["curve_voltage"] = int(rng.choice([12, 14, 18, 20]))
    # issue 21's structural classes, after the draws above (which they leave as they were): each on
    # with p = 1/3, its coin and its size always drawn so that no class shifts another's draws
    on = rng.random(4) < 1 / 3
    position = round(float(rng.uniform(0.01, 0.03)), 4)   # m: thrusters placed by hand on the frame
    jitter = round(float(rng.uniform(0.001, 0.005)), 4)   # s: a Linux logger's stamps, a few ms
    latency = round(float(rng.uniform(0.01, 0.05)), 3)    # s: ArduSub's sensor/telemetry path, tens of ms
    for key, value, flag in (("thruster_position_error", position, on[0]), ("time_jitter", jitter, on[1]),
                             ("sensor_latency", latency, on[2]), ("pilot_inputs", True, on[3])):
        if flag and structure:
            over[key] = value
    return over


def judge(rep: dict) -> dict:
    """The benchmark's record of a calibration report (module docstring): the verdict's status,
    pooled change and worse channels, each channel's Fit % gain, and the fixed-threshold judge."""
    v = rep.get("verdict") or {}
    ch = v.get("channels") or {}
    gain = {c: d["fit_b"] - d["fit_a"] for c, d in ch.items()
            if d["fit_a"] is not None and d["fit_b"] is not None and np.isfinite(d["fit_a"]) and np.isfinite(d["fit_b"])}
    stages = (rep.get("refinement") or {}).get("stages") or []
    unfinished = bool(stages) and str(stages[-1].get("message", "")).startswith("maximum number of iterations")
    status = v.get("status", "worse")   # an unfinished fit is judged like any other (commands.checks)
    return {"status": status, "pooled_rmse_change": (v.get("pooled") or {}).get("rmse_change"),
            "gain": gain, "worse": list(v.get("worse") or []),
            "worse_points": sorted(c for c, g in gain.items() if g < -WORSE_POINTS),
            "check_ok": status == "better", "unfinished": unfinished, "horizon": v.get("horizon") or {},
            "at_bounds": list(rep.get("at_bounds", [])), "data_weight": (rep.get("prior") or {}).get("data_weight")}


def truth_errors(spec, vehicles: dict) -> dict:
    """Per model name, per state channel: RMS error over the validation runs of a simulation
    from the true initial state against the generator's noise-free truth (module docstring)."""
    import uvsim
    from uvsim.kinematics import quat_to_euler
    from uvsim.scenarios.generate import simulate_spec

    res = simulate_spec(spec, with_snr=False)
    sim = res["sim"]
    sq = {name: {} for name in vehicles}
    for i, r in enumerate(spec.runs):
        if r["split"] != "validation":
            continue
        n = res["n_samples"][i]
        t, U = res["t"][:n], np.asarray(res["logged"][i], float)[:n]
        true = {"depth": sim["pos"][i, :n, 2], "roll": quat_to_euler(sim["quat"][i, :n])[:, 0],
                "pitch": quat_to_euler(sim["quat"][i, :n])[:, 1], "p": sim["nu"][i, :n, 3],
                "q": sim["nu"][i, :n, 4], "r": sim["nu"][i, :n, 5]}
        for name, veh in vehicles.items():
            out = uvsim.simulate(veh, t, U, input_kind=spec.input_kind, pos0=sim["pos"][i, 0], q0=sim["quat"][i, 0],
                                 nu0=sim["nu"][i, 0])
            e = quat_to_euler(out.quaternion)
            got = {"depth": out.position[:, 2], "roll": e[:, 0], "pitch": e[:, 1], "p": out.nu[:, 3],
                   "q": out.nu[:, 4], "r": out.nu[:, 5]}
            for c in true:
                d = got[c] - true[c]
                if c in ("roll", "pitch"):
                    d = (d + np.pi) % (2 * np.pi) - np.pi
                a, m = sq[name].get(c, (0.0, 0))
                sq[name][c] = (a + float(np.nansum(d * d)), m + int(np.isfinite(d).sum()))
    return {name: {c: float(np.sqrt(a / m)) if m else float("nan") for c, (a, m) in ch.items()}
            for name, ch in sq.items()}


#: The references judged beside each fit (:func:`reference_checks`).
REFERENCES = ("truth", "truth_coefficients")
#: Largest RMS state error (m, rad, rad/s) of the ``truth`` reference against the generator's
#: noise-free truth (from the true initial state) for it to count as the truth: uvsim follows the
#: generator to ~1e-8 where it states the truth fully (module docstring).
REFERENCE_TOLERANCE = 1e-5


def reference_models(dataset_dir, start, over: dict) -> dict:
    """The references of :func:`reference_checks` as uvsim vehicles, for the dataset of scenario
    overrides ``over`` (:func:`scenario`): ``truth_coefficients``, the start model ``start`` with the
    truth's hydrodynamic coefficients and centre of buoyancy (its thrusters, curve and effects as
    the start model has them: the best a fit of the coefficients alone could reach), and ``truth``,
    the generator's truth as a vehicle file states it: ``truth.yaml``'s vehicle (coefficients, centre
    of buoyancy, thruster positions) on the T200 voltage family at the truth's supply voltage
    (:func:`on_voltage_family`), a weak thruster as its ``thruster_gain_<k>``; absent when the truth
    has another effect, which no parameter states.  Both with the truth's sensor latency; neither
    with its time-stamp jitter.  :func:`run_one` checks that ``truth`` follows the generator's
    noise-free truth (``reference_truth_rmse``) before it counts."""
    from uvsim.scenarios import load_truth
    from uvsim.vehicle import vehicle_from_dict

    truth = load_truth(dataset_dir)
    p0 = start.parameters()
    coef = {k: float(v) for k, v in truth["coefficients"]["truth"].items() if k in p0}
    coef["z_b"] = float(truth["buoyancy"]["z_b_truth"])
    lat = float(over.get("sensor_latency") or 0.0)
    out = {"truth_coefficients": start.with_parameters(coef).with_latency(lat)}
    if all(e["type"] == "weak_thruster" for e in truth["effects"]):
        veh = vehicle_from_dict(truth["vehicle"], source=f"{dataset_dir}/truth.yaml")
        if over.get("curve_voltage"):
            veh = on_voltage_family(veh).with_parameters({"supply_voltage": float(over["curve_voltage"])})
        veh = veh.with_parameters({f"thruster_gain_{int(e['thruster'])}": float(e["gain"]) for e in truth["effects"]})
        out["truth"] = veh.with_latency(lat)
    return out


def reference_checks(cal, dataset_dir, models: dict) -> dict:
    """Per reference model (:func:`reference_models`): the verdict on it against the start model, on
    the validation runs, exactly as a fit is judged (:func:`judge`): whether *better* is within reach
    of the truth itself on this dataset.  ``cal``: the fitted Calibrator (its start model,
    measurement models and open-loop evaluations of the start are reused); ``models``: name ->
    vehicle (:func:`reference_models`)."""
    from uvsim.calibration.report import calibration_verdict, evaluate_runs
    from uvsim.logs import read_dataset

    runs = [r for r in read_dataset(dataset_dir).runs if r.split == "validation"]
    md, base = cal.evaluation_["meas"], cal.evaluation_["initial"]
    out = {}
    for name, veh in models.items():
        ev = evaluate_runs(veh, runs, [md[r.name] for r in runs], None, initial_velocity=cal.initial_velocity,
                           judged_as=cal.evaluation_.get("judged"))
        j = judge({"verdict": calibration_verdict(runs, ev, base, md)})
        out[name] = {"ok": j["check_ok"], "status": j["status"], "gain": j["gain"], "worse": j["worse"],
                     "pooled_rmse_change": j["pooled_rmse_change"]}
    return out


def on_voltage_family(vehicle):
    """``vehicle`` with its thrusters on the T200 voltage family at the nominal voltage its
    fixed curve was measured at (16 V), so that ``supply_voltage`` can be fitted
    (:func:`uvsim.calibration.supply_voltage.on_voltage_family`)."""
    from uvsim.calibration import supply_voltage

    if supply_voltage.not_applicable(vehicle):
        raise UvsimError(f"--supply-voltage: the benchmark's start vehicle {vehicle.name!r} does not run on the "
                         "t200_16v curve")
    return supply_voltage.on_voltage_family(vehicle)


def dataset_vehicle_on_family(dataset_dir):
    """:func:`on_voltage_family` of the vehicle a generated dataset names (the benchmarks'
    ``--supply-voltage`` start model)."""
    from uvsim.calibration.inputs import resolve_vehicle
    from uvsim.logs import read_dataset

    return on_voltage_family(resolve_vehicle(None, read_dataset(dataset_dir)))


def run_one(seed: int, *, prior: bool = True, loss: str = "linear", supply=REAL_LOG_SUPPLY, workers: int = 1,
            free: str = REAL_LOG_FREE, latency=REAL_LOG_LATENCY, trade_off=REAL_LOG_TRADE_OFF,
            tmp: Path | None = None) -> dict:
    """Generate and calibrate one scenario; returns its record.  ``free``: the calibration's
    ``--free``; ``latency``: its ``--latency`` (None: the vehicle file's, i.e. none);
    ``supply``: "auto" the calibration's ``supply_voltage="auto"``; True the start model's
    thrusters on the T200 voltage family and ``supply_voltage`` freed beside ``free``
    (:func:`on_voltage_family`); False neither; ``trade_off``: the calibration's (None: none)."""
    from uvsim.calibration import Calibrator
    from uvsim.errors import CalibrationError
    from uvsim.scenarios import generate, load_truth, sample_scenario

    over = scenario(seed)
    with tempfile.TemporaryDirectory(dir=tmp) as d:
        spec = sample_scenario(seed, profile="realsensor", **over)
        out = generate(spec, Path(d) / "ds")
        truth = load_truth(out)
        t0 = time.perf_counter()
        try:
            freed = supply is True  # True: freed from the start; "auto": the calibration's supply_voltage="auto"
            start = dataset_vehicle_on_family(out) if freed else None
            names = f"{free},supply_voltage" if freed else free
            cal = Calibrator(free=names, workers=workers, prior=prior, loss=loss, latency=latency,
                             supply_voltage="auto" if supply == "auto" else None, trade_off=trade_off).fit(out, start)
            seconds = time.perf_counter() - t0  # the calibration's, not the verdicts' and references' below
            rec = judge(cal.report_)
            rec["latency_fitted"] = cal.latency_["value"]  # s, what the fitted vehicle states
            rec["supply_voltage"] = cal.params_.get("supply_voltage")  # fitted (V), None when not freed
            rec["supply_voltage_auto"] = cal.supply_voltage_  # the "auto" refit and its choice, None otherwise
            rec["trade_off_explored"] = cal.trade_off_  # what was tried after a trade-off, None otherwise
            refs = reference_models(out, cal.initial_vehicle_, over)
            err = truth_errors(spec, {"start": cal.initial_vehicle_, "fitted": cal.vehicle_, **refs})
            rec["truth_rmse_start"], rec["truth_rmse_fitted"] = err["start"], err["fitted"]
            # the truth as uvsim states it must follow the generator's noise-free truth to count
            rec["reference_truth_rmse"] = err.get("truth")
            if "truth" in refs and not max(err["truth"].values()) <= REFERENCE_TOLERANCE:
                del refs["truth"]
            rec["reference"] = reference_checks(cal, out, refs)
            rec["farther_from_truth"] = sorted(c for c, e0 in err["start"].items()
                                               if err["fitted"][c] > (1 + TRUTH_TOLERANCE) * e0)
            error = None
        except CalibrationError as exc:  # refused before a result: counted as "not ok", not as worse
            rec, error = {"status": "refused", "pooled_rmse_change": None, "gain": {}, "worse": [],
                          "worse_points": [], "check_ok": False, "unfinished": False, "horizon": {}, "at_bounds": [],
                          "data_weight": None, "farther_from_truth": []}, str(exc)
        if error is not None:
            seconds = time.perf_counter() - t0
    return {"seed": seed, "prior": prior, "loss": loss, "supply": supply, "free": free, "latency": latency,
            "trade_off": trade_off, **over,
            "effects": [e["type"] for e in truth["effects"]],
            "curve": spec.vehicle.get("truth_curve"), **rec, "error": error, "seconds": seconds}


def summarize(records: list[dict]) -> dict:
    out = {}
    modes = sorted({_mode(r) for r in records}, key=lambda m: (not m[0], m[1], str(m[2]), m[3], str(m[4]), str(m[5])))
    for mode in modes:
        mine = [r for r in records if _mode(r) == mode]
        rs = [r for r in mine if r["error"] is None and "status" in r]  # records of the verdict's releases
        if not rs:
            continue
        status = {k: sum(r["status"] == k for r in rs) for k in ("better", "trade-off", "worse")}
        better = [r for r in rs if r["status"] == "better"]
        farther = [r for r in rs if r.get("farther_from_truth")]
        chans = sorted({c for r in rs for c in r["gain"]})
        changes = [r["pooled_rmse_change"] for r in rs if r.get("pooled_rmse_change") is not None]
        out[_label(mode)] = {
            "n": len(rs), "errors": sum(1 for r in mine if r["error"] is not None), **status,
            "better_rate": status["better"] / len(rs),
            "better_but_a_channel_loses_points": sum(bool(r["worse_points"]) for r in better),
            "worse_channels_named": sum(len(r["worse"]) for r in rs),
            "seeds_compared_over_a_shorter_horizon": sum(bool(r.get("horizon")) for r in rs),
            "closer_to_truth_everywhere": len(rs) - len(farther),
            "farther_from_truth": len(farther), "farther_not_better": sum(not r["check_ok"] for r in farther),
            "not_better_though_closer_to_truth": sum(not r["check_ok"] for r in rs if not r.get("farther_from_truth")),
            **_reference_summary(rs),
            "median_pooled_rmse_change": float(np.median(changes)) if changes else None,
            "median_gain_points": {c: float(np.median([r["gain"][c] for r in rs if c in r["gain"]])) for c in chans},
            "fits_with_a_bound_hit": sum(bool(r["at_bounds"]) for r in rs),
            "seconds_median": float(np.median([r["seconds"] for r in rs])),
            "seconds_max": float(max(r["seconds"] for r in rs))}
    return out


def _reference_summary(rs: list[dict]) -> dict:
    """Per reference (:func:`reference_checks`): on how many seeds its verdict against the start is
    *better*, and of the fits not better, on how many the reference is not better either, over the
    records that have it (``truth`` only where uvsim states the truth)."""
    out = {}
    for name in REFERENCES:
        have = [r for r in rs if name in (r.get("reference") or {}) and "status" in r["reference"][name]]
        out[f"{name}_n"] = len(have)
        out[f"{name}_better"] = sum(r["reference"][name]["ok"] for r in have)
        out[f"fits_not_better_whose_{name}_is_not_better_either"] = sum(
            not r["check_ok"] and not r["reference"][name]["ok"] for r in have)
    return out


def _mode(rec: dict) -> tuple:
    """How a record was calibrated: (prior, loss, supply voltage freed, ``--free``, ``--latency``,
    ``--trade-off``; records of the releases before :data:`REAL_LOG_FREE` freed ``z_b``, before
    :data:`REAL_LOG_LATENCY` had no latency setting, before :data:`REAL_LOG_TRADE_OFF` no
    trade-off setting: None)."""
    return (rec["prior"], rec.get("loss", "linear"), rec.get("supply", False), rec.get("free", "z_b"),
            rec.get("latency"), rec.get("trade_off"))


def _label(mode: tuple) -> str:
    """The summary's key and the progress line's name of a mode (:func:`_mode`)."""
    prior, loss, supply, free, latency, trade_off = mode
    return (("prior" if prior else "no_prior") + ("" if loss == "linear" else f"+{loss}")
            + {True: "+supply_voltage", "auto": "+supply_voltage_auto"}.get(supply, "") + f" (--free {free}"
            + ("" if latency is None else f" --latency {latency}")
            + ("" if trade_off is None else f" --trade-off {trade_off}") + ")")


def run_benchmark(n: int, seed: int, *, compare_no_prior: bool = False, loss: str = "linear", supply=REAL_LOG_SUPPLY,
                  free: str = REAL_LOG_FREE, latency=REAL_LOG_LATENCY, trade_off=REAL_LOG_TRADE_OFF, workers: int = 1,
                  results: str | Path | None = None, progress=None, stages=None) -> dict:
    """``n`` seeds from ``seed`` (resumed from ``results``, JSON lines), calibrated with
    ``--free free --latency latency`` and ``supply`` (:func:`run_one`; latency None: no ``--latency``);
    ``progress``: callable(line) of each finished calibration; ``stages``: each as a stage
    (:func:`uvsim.progress.as_progress`)."""
    if n < 1:
        raise UvsimError(f"--scenarios {n}: need at least one scenario")
    from uvsim.calibration.inputs import latency_setting
    from uvsim.calibration.selection import expand_names
    from uvsim.scenarios.vehicle_data import DEFAULT_VEHICLE_FILE
    from uvsim.vehicle import load_vehicle

    # a name no parameter of the generator's start model has is an error now, not one per seed
    # (run_one records a calibration that raises as "refused before a result")
    expand_names(free, list(load_vehicle(DEFAULT_VEHICLE_FILE).parameters()), "--free")
    latency_setting(latency)  # likewise a bad --latency
    say = progress or (lambda m: None)
    path = Path(results) if results else None
    done = load_records(path, lambda rec: (rec["seed"], *_mode(rec)), say, "calibration")
    todo = [(s, p) for s in range(seed, seed + n) for p in ((True, False) if compare_no_prior else (True,))]
    records = []
    for i, (s, p) in enumerate(todo, 1):
        key = (s, p, loss, supply, free, latency, trade_off)
        if key in done:
            records.append(done[key])
            continue
        with as_progress(stages).stage(f"[{i}/{len(todo)}] seed {s} {_label(key[1:])}"):
            rec = run_one(s, prior=p, loss=loss, supply=supply, free=free, latency=latency, trade_off=trade_off,
                          workers=workers)
        records.append(rec)
        append_record(path, rec)
        say(f"[{i}/{len(todo)}] seed {s} {_label(key[1:])}: effects {rec['effects'] or 'none'}, "
            f"curve {rec['curve'] or '16 V'}, off {rec['perturbation']:.0%}: "
            + (f"ERROR {rec['error']}" if rec["error"] else
               f"verdict {rec['status']} (pooled {100 * (rec['pooled_rmse_change'] or 0):+.0f} %)"
               + (f", worse in {', '.join(rec['worse'])}" if rec["worse"] else ""))
            + (f"; farther from the truth in {rec['farther_from_truth'] or 'no channel'}" if not rec["error"] else "")
            + f", {rec['seconds']:.1f} s")
    return {"summary": summarize(records), "records": records}
