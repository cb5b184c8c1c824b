"""Calibration plots (matplotlib, Agg backend; only imported when plots are asked for).

* ``runs/<run>.png``: measured vs simulated (initial and fitted vehicle) for each
  logged channel of every run;
* ``error_boxplots.png``: error distributions per run, grouped by DOF, as seed 000
  Fig. 6 (position error of linear DOFs, m) and Fig. 7 (orientation error of
  rotational DOFs, rad) - for the validation runs when there are any;
* ``ga_convergence.png``: best and mean fitness per generation and DOF (logbook).
"""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt  # the package __init__ selects the Agg backend
import numpy as np  # noqa: E402

from uvsim.kinematics import quat_to_euler  # noqa: E402

LINEAR = ("surge", "sway", "heave")
ROTATIONAL = ("roll", "pitch", "yaw")
_AXIS = {"surge": 0, "sway": 1, "heave": 2, "roll": 0, "pitch": 1, "yaw": 2}


def _channels(measured, predicted):
    """[(label, t-index-aligned measured, predicted)] for the logged channels."""
    out = []
    if "position" in measured:
        for j, c in enumerate("xyz"):
            if np.isfinite(measured["position"][:, j]).any():
                out.append((f"{c} (m)", measured["position"][:, j], predicted["position"][:, j]))
    if "quaternion" in measured:
        em = quat_to_euler(measured["quaternion"])
        ep = quat_to_euler(predicted["quaternion"])
        ok = np.isfinite(em).all(axis=1)
        em[ok] = np.unwrap(em[ok], axis=0)
        ep = em - ((em - ep + np.pi) % (2 * np.pi) - np.pi)
        for j, c in enumerate(("roll", "pitch", "yaw")):
            out.append((f"{c} (rad)", em[:, j], ep[:, j]))
    for key, names, unit in (("velocity", "uvw", "m/s"), ("rates", "pqr", "rad/s")):
        if key in measured:
            for j, c in enumerate(names):
                if np.isfinite(measured[key][:, j]).any():
                    out.append((f"{c} ({unit})", measured[key][:, j], predicted[key][:, j]))
    return out


def plot_runs(runs, measured, fitted, initial, out_dir) -> list[Path]:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for run, m, pf, pi in zip(runs, measured, fitted, initial):
        chans = _channels(m, pf)
        chans_i = _channels(m, pi)
        fig, axes = plt.subplots(len(chans), 1, figsize=(7, 1.8 * len(chans) + 0.6), sharex=True, squeeze=False)
        for ax, (label, y, yf), (_, _, yi) in zip(axes[:, 0], chans, chans_i):
            ax.plot(run.t, y, ".", ms=2, color="0.4", label="measured")
            ax.plot(run.t, yi, "--", lw=1, color="tab:orange", label="initial model")
            ax.plot(run.t, yf, "-", lw=1.2, color="tab:blue", label="fitted model")
            ax.set_ylabel(label)
        axes[0, 0].set_title(f"{run.name} ({run.dof or 'no dof'}, {run.split})")
        axes[0, 0].legend(fontsize=7, loc="best")
        axes[-1, 0].set_xlabel("t (s)")
        fig.tight_layout()
        p = out_dir / f"{run.name}.png"
        fig.savefig(p, dpi=90)
        plt.close(fig)
        paths.append(p)
    return paths


def plot_error_boxplots(runs, measured, fitted, path) -> Path:
    """Seed 000 Fig. 6-7 style: per run, the error of its DOF's own coordinate."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, group, unit in ((axes[0], LINEAR, "position error E_p (m)"), (axes[1], ROTATIONAL,
                                                                         "orientation error E_o (rad)")):
        data, labels = [], []
        for dof in group:
            for run, m, p in zip(runs, measured, fitted):
                if run.dof != dof:
                    continue
                j = _AXIS[dof]
                if dof in LINEAR and "position" in m and np.isfinite(m["position"][:, j]).any():
                    e = m["position"][:, j] - p["position"][:, j]
                elif dof in ROTATIONAL and "quaternion" in m:
                    em, ep = quat_to_euler(m["quaternion"]), quat_to_euler(p["quaternion"])
                    e = (em[:, j] - ep[:, j] + np.pi) % (2 * np.pi) - np.pi
                else:
                    continue
                data.append(e[np.isfinite(e)])
                labels.append(run.name)
        if data:
            ax.boxplot(data, showfliers=False)
            ax.set_xticks(range(1, len(labels) + 1), labels, rotation=60, fontsize=7)
        ax.axhline(0, color="0.6", lw=0.8)
        ax.set_ylabel(unit)
    axes[0].set_title("linear DOFs (seed 000 Fig. 6 style)")
    axes[1].set_title("rotational DOFs (seed 000 Fig. 7 style)")
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def plot_convergence(logbooks, path) -> Path:
    fig, ax = plt.subplots(figsize=(7, 4))
    for dof, lb in logbooks.items():
        gen = [r["gen"] for r in lb]
        line, = ax.semilogy(gen, [r["min"] for r in lb], "-", label=f"{dof} best")
        ax.semilogy(gen, [r["avg"] for r in lb], ":", color=line.get_color(), lw=0.8)
    ax.set_xlabel("generation")
    ax.set_ylabel("fitness (weighted mean |normalized error|)")
    ax.set_title("GA convergence (solid: best, dotted: population mean)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def plot_calibration(cal, dataset, out_dir, *, run_plots: str = "all") -> list[Path]:
    """All calibration plots of a fitted :class:`uvsim.calibration.Calibrator` into ``out_dir``.

    ``run_plots``: "all" runs, only the "validation" runs, or "none" get a
    measured-vs-simulated figure (one matplotlib figure per run is the slow part)."""
    from uvsim.calibration.batching import prepare_runs, simulate_dataset

    out_dir = Path(out_dir)
    runs = list(dataset.runs)
    groups: dict = {}
    for r in runs:
        groups.setdefault((r.input_kind, r.inputs.shape[1]), []).append(r)
    ordered, meas, fit, ini = [], [], [], []
    for grp in groups.values():
        b = prepare_runs(grp, initial_velocity=cal.initial_velocity)
        ordered += grp
        meas += b.measured
        fit += simulate_dataset(cal.vehicle_, b)
        ini += simulate_dataset(cal.initial_vehicle_, b)
    val = [i for i, r in enumerate(ordered) if r.split == "validation"] or list(range(len(ordered)))
    sel = {"all": list(range(len(ordered))), "validation": val, "none": []}[run_plots]
    paths = plot_runs([ordered[i] for i in sel], [meas[i] for i in sel], [fit[i] for i in sel],
                      [ini[i] for i in sel], out_dir / "runs")
    paths.append(plot_error_boxplots([ordered[i] for i in val], [meas[i] for i in val], [fit[i] for i in val],
                                     out_dir / "error_boxplots.png"))
    paths.append(plot_convergence(cal.logbook_, out_dir / "ga_convergence.png"))
    return paths


__all__ = ["plot_calibration", "plot_runs", "plot_error_boxplots", "plot_convergence"]
