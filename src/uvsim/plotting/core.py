"""Plots of simulated vs measured tank runs (``uvsim demo``)."""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from uvsim.kinematics import quat_to_euler

#: measured signal shown for each DOF
DOF_SIGNAL = {"surge": ("x", "m"), "sway": ("y", "m"), "heave": ("z", "m"),
              "roll": ("roll", "deg"), "pitch": ("pitch", "deg"), "yaw": ("yaw", "deg")}


def _series(run, y, name):
    if name in ("x", "y", "z"):
        j = "xyz".index(name)
        return run.data[name].to_numpy(), y[:, j]
    j = ("roll", "pitch", "yaw").index(name)
    meas = np.degrees(np.unwrap(run.euler[:, j]))
    sim = np.degrees(np.unwrap(quat_to_euler(y[:, 3:7])[:, j]))
    return meas, sim


def tank_runs(runs_by_dof: dict, sims: dict[str, dict], path: str | Path, title: str = "") -> Path:
    """One panel per DOF: the DOF's main measured signal for every run, and each model's
    simulation of it.  ``sims[label][run.name]`` is the simulated state array (n, n_y)."""
    path = Path(path)
    dofs = [d for d in DOF_SIGNAL if d in runs_by_dof]
    ncol = 3
    nrow = int(np.ceil(len(dofs) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(5 * ncol, 3.4 * nrow), squeeze=False)
    styles = ["-", "--", ":", "-."]
    for ax, dof in zip(axes.flat, dofs):
        name, unit = DOF_SIGNAL[dof]
        for k, run in enumerate(runs_by_dof[dof]):
            color = plt.cm.viridis(k / max(1, len(runs_by_dof[dof]) - 1))
            for s, (label, sim) in enumerate(sims.items()):
                meas, pred = _series(run, sim[run.name], name)
                if s == 0:
                    ax.plot(run.t, meas, ".", ms=1.5, color=color, label="measured" if k == 0 else None)
                ax.plot(run.t, pred, styles[s % 4], lw=1, color=color, label=label if k == 0 else None)
        ax.set_title(f"{dof}: {name}")
        ax.set_xlabel("t (s)")
        ax.set_ylabel(f"{name} ({unit})")
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(dofs):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=8, loc="best")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path

