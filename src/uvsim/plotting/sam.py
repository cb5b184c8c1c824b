"""Plots of SAM maneuvers (the only SAM module importing matplotlib).

``plot_maneuver(frame, out_dir, name)`` writes ``NAME_trajectory.png`` (3-D path plus the
x-z and x-y projections, NED with depth down), ``NAME_states.png`` (roll/pitch/yaw,
body rates, speed) and ``NAME_actuators.png`` (commands dashed, actuator states solid),
like seed 003 Figs. 18-29.
"""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt  # the package __init__ selects the Agg backend
import numpy as np  # noqa: E402

from uvsim.sam.vehicle import SAM_INPUTS  # noqa: E402


def plot_maneuver(df, out_dir, name: str) -> list[Path]:
    """Write the three figures of a maneuver frame (see module docstring); returns their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t = df["t"].to_numpy()
    x, y, z = (df[k].to_numpy() for k in ("x", "y", "z"))
    paths = []

    fig = plt.figure(figsize=(12, 4.5))
    ax = fig.add_subplot(1, 3, 1, projection="3d")
    ax.plot(x, y, -z, lw=1)
    ax.set_xlabel("x north [m]")
    ax.set_ylabel("y east [m]")
    ax.set_zlabel("-z (up) [m]")
    ax.set_title(f"{name}: trajectory")
    for k, (a, b, la, lb) in enumerate(((x, -z, "x north [m]", "-z (up) [m]"), (x, y, "x north [m]", "y east [m]"))):
        ax2 = fig.add_subplot(1, 3, k + 2)
        ax2.plot(a, b, lw=1)
        ax2.plot(a[:1], b[:1], "go", ms=5, label="start")
        ax2.plot(a[-1:], b[-1:], "rs", ms=5, label="end")
        ax2.set_xlabel(la)
        ax2.set_ylabel(lb)
        ax2.set_aspect("equal", adjustable="datalim")
        ax2.grid(alpha=0.3)
        ax2.legend(fontsize=7)
    fig.tight_layout()
    p = out / f"{name}_trajectory.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)

    fig, axs = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    for k, lab in zip(("roll", "pitch", "yaw"), ("roll", "pitch", "yaw")):
        axs[0].plot(t, np.degrees(df[k].to_numpy()), lw=1, label=lab)
    axs[0].set_ylabel("Euler angles [deg]")
    for k in ("p", "q", "r"):
        axs[1].plot(t, df[k].to_numpy(), lw=1, label=k)
    axs[1].set_ylabel("rates [rad/s]")
    for k in ("u", "v", "w"):
        axs[2].plot(t, df[k].to_numpy(), lw=1, label=k)
    axs[2].set_ylabel("velocity [m/s]")
    axs[2].set_xlabel("t [s]")
    for a in axs:
        a.grid(alpha=0.3)
        a.legend(fontsize=8, loc="upper right")
    axs[0].set_title(f"{name}: angles and rates")
    fig.tight_layout()
    p = out / f"{name}_states.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)

    fig, axs = plt.subplots(4, 1, figsize=(9, 8), sharex=True)
    groups = [(("rpm_1", "rpm_2"), "rpm", 1.0), (("tv_pitch", "tv_yaw"), "thrust vector [deg]", 180 / np.pi),
              (("vbs", "lcg"), "VBS, LCG [%]", 1.0), (("tcg",), "TCG [deg]", 180 / np.pi)]
    for ax, (names, lab, scale) in zip(axs, groups):
        for nm in names:
            i = SAM_INPUTS.index(nm)
            col = f"thrust_{i + 1}"
            if col in df:
                ax.plot(t, df[col].to_numpy() * scale, "--", lw=0.8, label=f"{nm} cmd")
            if f"{nm}_act" in df:
                ax.plot(t, df[f"{nm}_act"].to_numpy() * scale, lw=1.2, label=f"{nm}")
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axs[-1].set_xlabel("t [s]")
    axs[0].set_title(f"{name}: actuator commands (dashed) and states")
    fig.tight_layout()
    p = out / f"{name}_actuators.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)
    return paths


def plot_datasets(frames: dict, out_path, name: str) -> Path:
    """Trajectories of one maneuver with several hull data sets (top and side view)."""
    fig, axs = plt.subplots(1, 2, figsize=(10, 4.5))
    for label, df in frames.items():
        axs[0].plot(df["x"], df["y"], lw=1, label=label)
        axs[1].plot(df["t"], np.linalg.norm(df[["u", "v", "w"]].to_numpy(), axis=1), lw=1, label=label)
    axs[0].set_xlabel("x north [m]")
    axs[0].set_ylabel("y east [m]")
    axs[0].set_aspect("equal", adjustable="datalim")
    axs[1].set_xlabel("t [s]")
    axs[1].set_ylabel("speed [m/s]")
    for a in axs:
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    axs[0].set_title(f"{name}: hull data sets")
    fig.tight_layout()
    out_path = Path(out_path)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out_path, dpi=110)
    plt.close(fig)
    return out_path
