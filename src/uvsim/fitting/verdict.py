"""One verdict: is a model better than another on logged runs, channel by channel and pooled?

Calibration compares the fitted model with the model the user started from; diagnosis
compares the model with an effect (or re-tuned coefficients) with the model without it.
Both call :func:`compare`, on the open-loop predictions of :func:`uvsim.fitting.evaluate.open_loop`
(free simulations of whole runs from their estimated starts), through the one measure of
:mod:`uvsim.metrics` (each logged channel's error, angles wrapped).

**The score.**  Per logged channel ``c`` the mean squared error ``MSE_c`` over the runs.  The
pooled score of a model is ``S = sum_c w_c log MSE_c / sum_c w_c``, with ``w_c`` the seconds
of log in which channel ``c`` has samples (so every channel counts per second of log, a 10 Hz
depth as much as a 100 Hz gyro).  ``-S/2`` per second is the Gaussian log-likelihood of the
errors with each channel's variance estimated from its own errors (the maximum-likelihood
criterion of a multi-output model with unknown diagonal noise covariance, Ljung 1999 sec. 7.3,
``log det`` of the error covariance), so it needs no noise level: the scale of a channel,
metres or radians, a filtered yaw logged to 0.01 deg or a noisy accelerometer, drops out, and
no channel dominates because its noise was estimated too small.  The change from model A to B
is ``S_B - S_A = sum_c w_c log(MSE_B,c / MSE_A,c) / sum_c w_c``; it is reported as the
geometric-mean change of the channels' RMSE, ``exp((S_B - S_A) / 2) - 1`` (-40 %: the errors
are 40 % smaller, in the geometric mean over channels).  The fits end on the same measure
(:mod:`uvsim.calibration.stages`: the joint stage's last stage simulates whole runs with
each channel scaled by its own RMS error, which is the least-squares form of ``S``).

**The noise of the comparison.**  Errors of a free simulation are correlated over seconds,
so the comparison is judged by a paired **block bootstrap** (Kunsch 1989): the runs are cut
into blocks of :data:`BLOCK_S` seconds, the blocks are resampled with replacement
:data:`N_BOOT` times, and each resample gives each channel's MSE ratio and the pooled change.

* the pooled change is *better* when it is below 0 in at least :data:`LEVEL` of the resamples;
* a channel is *worse* when its MSE grows by more than :data:`EQUIVALENCE` in at least
  ``1 - (1 - LEVEL) / k`` of the resamples (``k`` channels: Bonferroni, so that ten channels
  that did not change do not make one look worse by chance), or when its RMSE grows by
  :data:`MATERIAL` or more and the growth holds in at least LEVEL of the resamples (a few
  seconds of validation give a few blocks, and a few blocks cannot reach the Bonferroni level
  however large the loss: one 8 s run, three blocks, depth 2.5 times worse, worse in 97 % of
  the resamples); *better* likewise.  A change under :data:`EQUIVALENCE` (1 % of the RMSE) is
  equal for practical purposes: with paired blocks, a channel at its noise floor in both
  models can otherwise be "significantly" 0.1 % worse.

**Three outcomes** (docs/calibration.md, "The verdict"):

* ``better``: the pooled score is better beyond the noise and no channel is worse;
* ``trade-off``: the pooled score is better, but some channel is worse beyond the noise (the
  channels and numbers are named: a fit that buys better rates with a worse attitude is a
  finding to look into, not a result);
* ``worse``: the pooled score is not better beyond the noise (or is worse), or B's simulation
  diverges where A's does not.

**Models that diverge.**  A free simulation that blows up (:data:`uvsim.simulate.BLOWUP_SPEED`)
is NaN from then on.  Each run is compared over the rows where both models' predictions are
finite, every channel (none is dropped); the verdict lists the runs compared over less than
their length and which model diverged.  A B that diverges where A does not is *worse*: its
error there is unbounded.  No stability test replaces the comparison: an open-loop unstable
model whose simulation stays finite is judged on what it predicts.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from uvsim.metrics import channel_series, fit_from_sums

#: Block length of the bootstrap, s: a few of an ROV's velocity time constants, so that
#: neighbouring blocks of a free simulation's error are only weakly dependent.
BLOCK_S = 3.0
#: One-sided confidence of "better" (pooled) and, divided among the channels, of "worse".
LEVEL = 0.95
#: Relative change of a channel's MSE within which it counts as unchanged (2 % of the MSE, 1 %
#: of the RMSE; module docstring).
EQUIVALENCE = 0.02
#: Relative RMSE change of a channel that is material: beyond it, LEVEL without the Bonferroni
#: division makes the change count (module docstring).
MATERIAL = 0.10
N_BOOT = 2000
#: What to check when a channel's open-loop error dominates (physics each channel
#: responds to; docs/diagnose.md "Not explained"); a trade-off's message names them for its worse channels.
HINTS = {
    "depth": "net buoyancy (B - W), the depth sensor's position and offset, a vertical pull (tether, payload)",
    "z": "net buoyancy (B - W), a vertical pull (tether, payload), the heave damping",
    "x": "a current, a horizontal pull (tether), the surge thrust curve and damping",
    "y": "a current, a horizontal pull (tether), the sway thrust curve and damping",
    "roll": "the roll restoring moment (CG/CB height, an off-centre payload or float)",
    "pitch": "the pitch restoring moment (CG/CB, an off-centre payload or float), the heave-pitch coupling",
    "yaw": "thruster alignment and asymmetry, a yaw moment from a tether or current, the yaw damping",
    "p": "the roll damping and restoring moment, gyro bias", "q": "the pitch damping and restoring moment, gyro bias",
    "r": "the yaw damping, the thrusters' positions and asymmetry, gyro bias",
    "u": "the surge damping and thrust curve, a current", "v": "the sway damping and thrust curve, a current",
    "w": "the heave damping and thrust curve, buoyancy",
    # an accelerometer reads the motion's acceleration plus gravity tilted by the attitude
    "acc_x": "the surge thrust and damping, the pitch attitude (gravity along x), the IMU's position and offset",
    "acc_y": "the sway thrust and damping, the roll attitude (gravity along y), the IMU's position and offset",
    "acc_z": "the heave thrust and damping, net buoyancy, the IMU's position and offset",
}
#: Exit status of each outcome (the commands; docs/calibration.md). *refused* is the commands' own:
#: the fit fails a sanity check (``uvsim.commands.checks``) whatever the verdict says of it.
EXIT_CODES = {"better": 0, "trade-off": 3, "worse": 2, "refused": 2}


def _horizon(meas, pred_a: dict, pred_b: dict) -> tuple[np.ndarray, dict]:
    """Rows (n,) before either prediction stops being finite in a logged channel, and the first
    such row of each model ({"a", "b"}: n when it never does)."""
    n = meas.n

    def first_bad(pred):
        bad = np.zeros(n, bool)
        for g, grp in meas.groups.items():
            v = np.asarray(pred[g]).reshape(n, -1)[:, grp.logged]
            bad |= ~np.isfinite(v).all(axis=1)
        return int(np.argmax(bad)) if bad.any() else n

    ia, ib = first_bad(pred_a), first_bad(pred_b)
    end = min(ia, ib)
    rows = np.arange(n) < end
    return rows, {"a": ia, "b": ib}


def _seconds(meas, valid: np.ndarray) -> float:
    """Seconds of log a channel's samples ``valid`` (n,) cover: samples times their median interval."""
    t = meas.t[valid]
    if t.size < 2:
        return 0.0
    return float(t.size * np.median(np.diff(t)))


def compare(meas: Sequence, pred_a: Sequence[dict], pred_b: Sequence[dict], *, names=("A", "B"),
            block_s: float = BLOCK_S, level: float = LEVEL, equivalence: float = EQUIVALENCE,
            n_boot: int = N_BOOT, seed: int = 0) -> dict:
    """The verdict on model B against model A (module docstring).

    Parameters
    ----------
    meas : the runs' :class:`uvsim.measurements.RunMeasurements`.
    pred_a, pred_b : per run, each model's predicted measurements (``open_loop(...)["pred"]``).
    names : how the messages call A and B (e.g. ``("the starting model", "the fitted model")``).

    Returns
    -------
    JSON-ready dict: ``status`` ("better", "trade-off", "worse"), ``ok`` (status is better),
    ``exit_code``, ``message`` (one paragraph naming the channels and numbers), ``pooled``
    ({"change": S_B - S_A, "rmse_change": exp(change / 2) - 1, "p_better", "better"}),
    ``channels`` ({channel: {"unit", "group", "rmse_a", "rmse_b", "fit_a", "fit_b", "mse_ratio",
    "rmse_change", "mse_ratio_upper" (its LEVEL quantile over the resamples), "p_worse", "p_better",
    "worse", "better", "seconds", "n"}}), ``worse`` and
    ``better`` (channel lists), ``horizon`` ({run: {"compared_s", "of_s", "diverged"}} for
    runs compared over less than their length), ``diverged`` (runs where B diverges and A does
    not), and the settings.
    """
    meas = list(meas)
    if not meas:
        raise ValueError("verdict: no runs to compare")
    blocks: dict[str, dict] = {}   # channel -> run index -> (sse_a (B_r,), sse_b (B_r,))
    n_blocks: list[int] = []       # blocks of each run
    sums: dict[str, dict] = {}
    horizon, diverged = {}, []
    for m, pa, pb in zip(meas, pred_a, pred_b):
        rows, first = _horizon(m, pa, pb)
        t = np.asarray(m.t, float)
        if first["a"] < m.n or first["b"] < m.n:
            who = [nm for nm, i in zip(names, (first["a"], first["b"])) if i < m.n]
            end = min(first["a"], first["b"])
            horizon[m.name] = {"compared_s": float(t[end - 1] - t[0]) if end > 0 else 0.0,
                               "of_s": float(t[-1] - t[0]), "diverged": who,
                               "t_diverged": {nm: float(t[i]) for nm, i in zip(names, (first["a"], first["b"]))
                                              if i < m.n}}
            if first["b"] < m.n and first["a"] == m.n:
                diverged.append(m.name)
        blk = np.floor((t - t[0]) / block_s).astype(int)
        n_blk = int(blk[rows].max()) + 1 if rows.any() else 0
        n_blocks.append(n_blk)
        sa, sb = channel_series(m, pa, rows), channel_series(m, pb, rows)
        for c in sa:
            ok = sa[c]["valid"] & sb[c]["valid"]
            if not ok.any():
                continue
            ea, eb = np.where(ok, sa[c]["e"], 0.0), np.where(ok, sb[c]["e"], 0.0)
            blocks.setdefault(c, {})[len(n_blocks) - 1] = (
                np.bincount(blk[ok], weights=ea[ok] ** 2, minlength=n_blk),
                np.bincount(blk[ok], weights=eb[ok] ** 2, minlength=n_blk))
            y = sa[c]["y"][ok]
            d = sums.setdefault(c, {"unit": sa[c]["unit"], "group": sa[c]["group"], "sse_a": 0.0, "sse_b": 0.0,
                                    "sst": 0.0, "n": 0, "seconds": 0.0})
            d["sse_a"] += float(np.sum(ea[ok] ** 2))
            d["sse_b"] += float(np.sum(eb[ok] ** 2))
            d["sst"] += float(np.sum((y - y.mean()) ** 2))
            d["n"] += int(ok.sum())
            d["seconds"] += _seconds(m, ok)
    # every channel on the blocks of all runs end to end (zeros where a run does not log it), so
    # that one resampling of the blocks serves every channel: the comparison is paired
    A = {c: np.concatenate([blocks[c][r][0] if r in blocks[c] else np.zeros(nb) for r, nb in enumerate(n_blocks)])
         for c in blocks}
    B = {c: np.concatenate([blocks[c][r][1] if r in blocks[c] else np.zeros(nb) for r, nb in enumerate(n_blocks)])
         for c in blocks}
    out = _judge(A, B, sums, level, equivalence, n_boot, seed)
    out.update(horizon=horizon, diverged=diverged, block_s=block_s, level=level, equivalence=equivalence,
               n_boot=n_boot, runs=[m.name for m in meas], models=list(names))
    if diverged:
        out["status"], out["ok"] = "worse", False
        out["exit_code"] = EXIT_CODES["worse"]
    out["message"] = message(out)
    return out


def _judge(A, B, sums, level, equivalence, n_boot, seed) -> dict:
    """Point estimates, bootstrap and status from the per-channel block sums ``A``, ``B``
    (channel -> (blocks,) sums of squared errors of each model, on one common block axis)."""
    chans = [c for c in sums if sums[c]["sse_a"] > 0 or sums[c]["sse_b"] > 0]
    k = max(len(chans), 1)
    ch_level = 1.0 - (1.0 - level) / k
    w = np.array([max(sums[c]["seconds"], 1e-9) for c in chans])
    size = next(iter(A.values())).size if A else 0
    idx = np.random.default_rng(seed).integers(0, max(size, 1), (n_boot, size))
    tiny = 1e-300
    logs = np.zeros((n_boot, len(chans)))
    point = np.zeros(len(chans))
    for j, c in enumerate(chans):
        with np.errstate(divide="ignore", invalid="ignore"):
            logs[:, j] = (np.log(np.maximum(B[c][idx].sum(axis=1), tiny))
                          - np.log(np.maximum(A[c][idx].sum(axis=1), tiny)))
            point[j] = math.log(max(sums[c]["sse_b"], tiny)) - math.log(max(sums[c]["sse_a"], tiny))
    pooled_boot = logs @ w / w.sum() if chans else np.zeros(n_boot)
    change = float(point @ w / w.sum()) if chans else 0.0
    p_better = float(np.mean(pooled_boot < 0.0))
    margin = math.log1p(equivalence)
    material = 2.0 * math.log1p(MATERIAL)  # in log MSE
    channels, worse, better = {}, [], []
    for j, c in enumerate(chans):
        s = sums[c]
        p_w = float(np.mean(logs[:, j] > margin))
        p_b = float(np.mean(logs[:, j] < -margin))
        is_w = p_w >= ch_level or (point[j] >= material and p_w >= level)
        is_b = p_b >= ch_level or (point[j] <= -material and p_b >= level)
        ra, rb = math.sqrt(s["sse_a"] / s["n"]), math.sqrt(s["sse_b"] / s["n"])
        channels[c] = {"unit": s["unit"], "group": s["group"], "rmse_a": ra, "rmse_b": rb,
                       "fit_a": fit_from_sums(s["sse_a"], s["sst"]), "fit_b": fit_from_sums(s["sse_b"], s["sst"]),
                       "mse_ratio": float(math.exp(point[j])), "rmse_change": float(math.exp(point[j] / 2) - 1),
                       "mse_ratio_upper": float(math.exp(np.quantile(logs[:, j], level))),
                       "p_worse": p_w, "p_better": p_b, "worse": bool(is_w), "better": bool(is_b),
                       "seconds": float(s["seconds"]), "n": int(s["n"])}
        (worse if is_w else better if is_b else []).append(c)
    pooled_better = p_better >= level
    status = "worse" if not pooled_better else ("trade-off" if worse else "better")
    return {"status": status, "ok": status == "better", "exit_code": EXIT_CODES[status],
            "pooled": {"change": change, "rmse_change": float(math.exp(change / 2) - 1), "p_better": p_better,
                       "better": bool(pooled_better)},
            "channels": channels, "worse": worse, "better": better, "channel_level": ch_level}


def score(meas: Sequence, preds: Sequence[dict]) -> float:
    """The pooled score ``S`` of one model (module docstring): ``sum_c w_c log MSE_c / sum_c w_c``
    over the runs' logged channels, ``w_c`` the seconds of log of channel ``c``; lower is better,
    inf when a prediction is not finite at a measured sample (a diverged simulation).  Two models
    are ranked by it on the same runs (diagnosis' challengers); whether one is better beyond the
    noise is :func:`compare`'s question."""
    sse: dict[str, float] = {}
    n: dict[str, int] = {}
    sec: dict[str, float] = {}
    for m, p in zip(meas, preds):
        for c, ser in channel_series(m, p).items():
            ok = ser["measured"]
            if not ok.any():
                continue
            e = ser["e"][ok]
            sse[c] = sse.get(c, 0.0) + (float(np.sum(e * e)) if np.isfinite(e).all() else math.inf)
            n[c] = n.get(c, 0) + int(ok.sum())
            sec[c] = sec.get(c, 0.0) + max(_seconds(m, ok), 1e-9)
    if not sse:
        return float("nan")
    w = sum(sec.values())
    with np.errstate(divide="ignore"):
        return float(sum(sec[c] * math.log(max(sse[c] / n[c], 1e-300)) if np.isfinite(sse[c]) else math.inf
                         for c in sse) / w)


def _pct(x: float) -> str:
    return f"{100 * x:+.0f} %" if abs(x) >= 0.01 else f"{100 * x:+.1f} %"


def message(v: dict) -> str:
    """One paragraph saying the verdict ``v`` (:func:`compare`) with its numbers."""
    a, b = v["models"]
    p = v["pooled"]
    pooled = (f"pooled error {_pct(p['rmse_change'])} (geometric mean of the channels' RMSE change, "
              f"{len(v['channels'])} channels; lower in {100 * p['p_better']:.0f} % of resamples)")
    ch = v["channels"]

    def listed(names):
        return ", ".join(f"{c} {_pct(ch[c]['rmse_change'])} (RMSE {ch[c]['rmse_a']:.3g} -> {ch[c]['rmse_b']:.3g} "
                         f"{ch[c]['unit']})" for c in names)

    if v["diverged"]:
        t = "; ".join(f"{r} at t = {v['horizon'][r]['t_diverged'][b]:.2f} s" for r in v["diverged"])
        text = f"worse: {b}'s free simulation diverges where {a}'s does not ({t})"
    elif v["status"] == "better":
        text = f"better: {pooled}; no channel worse beyond the comparison's noise"
        loose = [c for c, d in ch.items() if d["rmse_change"] >= MATERIAL and not d["worse"]]
        if loose:  # said, not hidden: a loss the validation runs are too short to confirm
            text += (f" (higher but within the noise: {listed(loose)}; longer or more validation runs would "
                     "tell)")
    elif v["status"] == "trade-off":
        check = "; ".join(f"{c}: {HINTS[c]}" for c in v["worse"] if c in HINTS)
        text = (f"trade-off: {pooled}, but worse beyond the comparison's noise in {listed(v['worse'])}: "
                f"{b} buys its gain with these channels, a finding to look into rather than a result (what "
                f"the model may lack there: {check or 'the sensor positions, the restoring moments, the thrust model'})")
    elif p["change"] > 0 and p["p_better"] <= 1.0 - v["level"]:
        text = f"worse: {pooled}" + (f"; worse in {listed(v['worse'])}" if v["worse"] else "")
    else:
        text = (f"worse: not better than {a} beyond the comparison's noise: {pooled}"
                + (f"; worse in {listed(v['worse'])}" if v["worse"] else ""))
    cut = [f"{r} over its first {h['compared_s']:.1f} of {h['of_s']:.1f} s ({' and '.join(h['diverged'])} "
           "diverges after)" for r, h in v["horizon"].items()]
    if cut:
        text += "; compared " + ", ".join(cut)
    return text


def table(v: dict) -> list[str]:
    """The verdict's per-channel lines for a terminal: RMSE and Fit % of both models, the change."""
    a, b = v["models"]
    lines = [f"{'channel':>8} {'unit':>6} {'RMSE':>11} {'':2} {'RMSE':<11} {'change':>8} {'Fit %':>7} {'':2} "
             f"{'Fit %':<7}  ({a} -> {b})"]
    for c, d in v["channels"].items():
        tag = "worse" if d["worse"] else ("better" if d["better"] else "same (within noise)")
        lines.append(f"{c:>8} {d['unit']:>6} {d['rmse_a']:11.4g} -> {d['rmse_b']:<11.4g} {_pct(d['rmse_change']):>8} "
                     f"{d['fit_a']:7.1f} -> {d['fit_b']:<7.1f}  {tag}")
    return lines
