"""Measured vs simulated for one logged run (``uvsim simulate --compare``): one panel per
compared channel and a 3-D view of the trajectory (NED, depth axis pointing down)."""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np


def compare_run(t, channels: list[dict], sim_pos, meas_pos, path, title: str = "") -> Path:
    """Write the comparison figure.

    Parameters
    ----------
    t : (n,) sample times, s.
    channels : [{"name", "unit", "measured" (n,), "simulated" (n,)}] in display units.
    sim_pos : (n, 3) simulated NED position of the body origin, m.
    meas_pos : (n, 3) measured NED position (NaN where not logged; a depth-only log has
        x, y NaN and is shown on the depth axis only).
    path : PNG file to write.
    """
    path = Path(path)
    k = len(channels)
    ncol = 2 if k > 4 else 1
    nrow = max(int(np.ceil(k / ncol)), 1)
    fig = plt.figure(figsize=(6.5 * ncol + 5.5, max(2.0 * nrow, 5.0) + 0.6))
    gs = fig.add_gridspec(nrow, ncol + 1, width_ratios=[1.0] * ncol + [1.1])
    for i, ch in enumerate(channels):
        ax = fig.add_subplot(gs[i % nrow, i // nrow])
        ok = np.isfinite(ch["measured"])
        ax.plot(t[ok], ch["measured"][ok], ".", ms=2.5, color="0.35", label="measured")
        ax.plot(t, ch["simulated"], "-", lw=1.2, color="tab:blue", label="simulated")
        ax.set_ylabel(f"{ch['name']} ({ch['unit']})")
        ax.grid(alpha=0.3)
        if i % nrow == nrow - 1 or i == k - 1:
            ax.set_xlabel("t (s)")
        if i == 0:
            ax.legend(fontsize=8, loc="best")
    ax3 = fig.add_subplot(gs[:, ncol], projection="3d")
    ax3.plot(sim_pos[:, 0], sim_pos[:, 1], sim_pos[:, 2], "-", color="tab:blue", lw=1.3, label="simulated")
    ax3.scatter(*sim_pos[0], color="tab:green", s=25, label="start")
    full = np.isfinite(meas_pos).all(axis=1)
    if full.any():
        ax3.plot(meas_pos[full, 0], meas_pos[full, 1], meas_pos[full, 2], ".", ms=2.5, color="0.35", label="measured")
    ax3.set_xlabel("x north (m)")
    ax3.set_ylabel("y east (m)")
    ax3.set_zlabel("z down (m)")
    ax3.invert_zaxis()  # NED: depth grows downwards on the plot
    ax3.set_title("trajectory (NED)" + ("; measured axes held between samples" if full.any()
                                        else "; log has no 3-D position"), fontsize=9)
    ax3.legend(fontsize=8, loc="upper left")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
