"""Calibration plots (matplotlib, Agg backend; only imported when plots are asked for).

* ``runs/<run>.png``: every logged channel of a run (its native samples) with the
  open-loop predictions of the initial and the fitted vehicle (through the measurement
  models: depth at the pressure sensor, lagged attitude, specific force, gyro with its
  bias);
* ``channel_errors.png``: per channel, the distribution of the fitted model's error in
  noise sigmas over the validation runs (all runs when none is marked validation);
* ``error_boxplots.png``: for runs marked with a DOF, the error of the DOF's own
  coordinate per run, as seed 000 Fig. 6 (linear DOFs, m) and Fig. 7 (rotational
  DOFs, rad);
* ``ga_convergence.png``: per DOF the best fitness so far (never rising), each generation's best
  and its mean (when a GA ran).
"""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt  # the package __init__ selects the Agg backend
import numpy as np  # noqa: E402

from uvsim.fitting.evaluate import judged_label  # noqa: E402
from uvsim.metrics import channel_series  # noqa: E402

LINEAR = ("surge", "sway", "heave")
ROTATIONAL = ("roll", "pitch", "yaw")
#: The coordinate of each DOF in seed 000's error plots, in order of preference.
OWN_CHANNEL = {"surge": ("x",), "sway": ("y",), "heave": ("z", "depth"), "roll": ("roll",), "pitch": ("pitch",),
               "yaw": ("yaw",)}


def _series(meas, pred) -> list:
    """[(channel, unit, valid (n,), measured (n,), predicted (n,), error (n,), sigma)] of every
    logged channel, from the one measure (:func:`uvsim.metrics.channel_series`): the predicted
    curve is the model's free simulation through the measurement model (angles on the measured
    value's branch), never the measurement minus a residual of another kind."""
    return [(c, s["unit"], s["valid"], s["y"], s["y_hat"], s["e"], s["sigma"])
            for c, s in channel_series(meas, pred).items()]


def plot_runs(runs, meas, fitted, initial, out_dir, what: str = "free simulation") -> list[Path]:
    """One figure per run: measured vs initial vs fitted model, every logged channel; ``what``: the
    predictions' kind in the legend (the free simulation, or windows on closed-loop logs: the
    report's ``judged``)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for run, m in zip(runs, meas):
        fit = _series(m, fitted[run.name]["pred"])
        ini = _series(m, initial[run.name]["pred"])
        fig, axes = plt.subplots(len(fit), 1, figsize=(7, 1.7 * len(fit) + 0.6), sharex=True, squeeze=False)
        for ax, (c, unit, ok, y, yf, _, _), (_, _, _, _, yi, _, _) in zip(axes[:, 0], fit, ini):
            ax.plot(run.t[ok], y[ok], ".", ms=2, color="0.4", label="measured")
            ax.plot(run.t[ok], yi[ok], "--", lw=1, color="tab:orange", label=f"initial model ({what})")
            ax.plot(run.t[ok], yf[ok], "-", lw=1.2, color="tab:blue", label=f"fitted model ({what})")
            ax.set_ylabel(f"{c} ({unit})")
        axes[0, 0].set_title(f"{run.name} ({run.dof or 'no dof'}, {run.split})")
        axes[0, 0].legend(fontsize=7, loc="best")
        axes[-1, 0].set_xlabel("t (s)")
        fig.tight_layout()
        p = out_dir / f"{run.name}.png"
        fig.savefig(p, dpi=90)
        plt.close(fig)
        paths.append(p)
    return paths


def _save(fig, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def plot_channel_errors(runs, meas, fitted, path) -> Path:
    """Per channel, the fitted model's error / noise level pooled over ``runs``."""
    pooled: dict = {}
    for run, m in zip(runs, meas):
        for c, _, ok, _, _, e, sig in _series(m, fitted[run.name]["pred"]):
            pooled.setdefault(c, []).append(e[ok & np.isfinite(e)] / sig)
    fig, ax = plt.subplots(figsize=(max(5, 0.8 * len(pooled) + 2), 4))
    if pooled:
        ax.boxplot([np.concatenate(v) for v in pooled.values()], showfliers=False)
        ax.set_xticks(range(1, len(pooled) + 1), list(pooled))
    ax.axhline(0, color="0.6", lw=0.8)
    ax.set_ylabel("open-loop error / noise sigma")
    ax.set_title("fitted model, open-loop error per channel")
    return _save(fig, path)


def plot_error_boxplots(runs, meas, fitted, path) -> Path:
    """Seed 000 Fig. 6-7 style: per run marked with a DOF, the error of its own coordinate."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, group, unit in ((axes[0], LINEAR, "position error E_p (m)"),
                            (axes[1], ROTATIONAL, "orientation error E_o (rad)")):
        data, labels = [], []
        for dof in group:
            for run, m in zip(runs, meas):
                if run.dof != dof:
                    continue
                chans = {c: (ok, e) for c, _, ok, _, _, e, _ in _series(m, fitted[run.name]["pred"])}
                own = next((c for c in OWN_CHANNEL[dof] if c in chans), None)
                if own is None:
                    continue
                ok, e = chans[own]
                data.append(e[ok & np.isfinite(e)])
                labels.append(run.name)
        if data:
            ax.boxplot(data, showfliers=False)
            ax.set_xticks(range(1, len(labels) + 1), labels, rotation=60, fontsize=7)
        ax.axhline(0, color="0.6", lw=0.8)
        ax.set_ylabel(unit)
    axes[0].set_title("linear DOFs (seed 000 Fig. 6 style)")
    axes[1].set_title("rotational DOFs (seed 000 Fig. 7 style)")
    return _save(fig, path)


def plot_convergence(logbooks, path) -> Path:
    fig, ax = plt.subplots(figsize=(7, 4))
    for dof, lb in logbooks.items():
        gen = [r["gen"] for r in lb]
        best = [r["min"] for r in lb]
        line, = ax.semilogy(gen, np.minimum.accumulate(best), "-", label=f"{dof} best so far")
        ax.semilogy(gen, best, "--", color=line.get_color(), lw=0.7)
        ax.semilogy(gen, [r["avg"] for r in lb], ":", color=line.get_color(), lw=0.8)
    ax.set_xlabel("generation")
    ax.set_ylabel("fitness (weighted mean |error| / noise)")
    ax.set_title("GA convergence (solid: best so far, dashed: each generation's best, dotted: its mean)",
                 fontsize=9)
    ax.legend(fontsize=7)
    return _save(fig, path)


def plot_calibration(cal, dataset, out_dir, *, run_plots: str = "all") -> list[Path]:
    """All calibration plots of a fitted :class:`uvsim.calibration.Calibrator` into ``out_dir``.

    ``run_plots``: "all" runs, only the "validation" runs, or "none" get a
    measured-vs-simulated figure (one matplotlib figure per run is the slow part)."""
    out_dir = Path(out_dir)
    ev = cal.evaluation_
    runs = [r for r in dataset.runs if r.name in ev["meas"]]
    meas = [ev["meas"][r.name] for r in runs]
    val = [i for i, r in enumerate(runs) if r.split == "validation"] or list(range(len(runs)))
    sel = {"all": list(range(len(runs))), "validation": val, "none": []}[run_plots]
    paths = plot_runs([runs[i] for i in sel], [meas[i] for i in sel], ev["fitted"], ev["initial"], out_dir / "runs",
                      judged_label(ev.get("judged"), "free simulation"))
    vr, vm = [runs[i] for i in val], [meas[i] for i in val]
    paths.append(plot_channel_errors(vr, vm, ev["fitted"], out_dir / "channel_errors.png"))
    if any(r.dof in LINEAR + ROTATIONAL for r in vr):
        paths.append(plot_error_boxplots(vr, vm, ev["fitted"], out_dir / "error_boxplots.png"))
    if cal.logbook_:
        paths.append(plot_convergence(cal.logbook_, out_dir / "ga_convergence.png"))
    return paths


__all__ = ["plot_calibration", "plot_runs", "plot_channel_errors", "plot_error_boxplots", "plot_convergence"]
