"""The battery-sag figure of docs/thrusters.md (examples/battery_sag.py)."""
from __future__ import annotations

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np


def battery_sag_figure(volt_trace, curve, fits: dict, truth: dict, path) -> Path:
    """Left: the logged battery voltage over the session and the thrust it allows at
    1700 us relative to the nominal voltage.  Right: fitted parameters relative to the
    truth for each calibration in ``fits`` ({label: {name: value}})."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 3.8))
    for tt, v in volt_trace:
        ax.plot(tt, v, "-", color="tab:red", lw=0.8)
    ax.set_xlabel("session time (s)")
    ax.set_ylabel("battery voltage (V)", color="tab:red")
    ax.grid(alpha=0.3)
    ax2 = ax.twinx()
    for tt, v in volt_trace:
        ratio = curve.thrust(np.full(v.shape, 1700.0), voltage=v) / curve.thrust(np.array([1700.0]))
        ax2.plot(tt, 100 * ratio, "-", color="tab:blue", lw=0.8)
    ax2.set_ylabel("thrust at 1700 us vs nominal (%)", color="tab:blue")
    ax.set_title("logged voltage and the thrust it gives")
    names = sorted(next(iter(fits.values())))
    x = np.arange(len(names))
    w = 0.8 / len(fits)
    for i, (label, vals) in enumerate(fits.items()):
        err = [100 * (vals[p] / truth[p] - 1) for p in names]
        bx.bar(x + (i - (len(fits) - 1) / 2) * w, err, w, label=label)
    bx.axhline(0, color="k", lw=0.8)
    bx.set_xticks(x, names)
    bx.set_ylabel("fitted / truth - 1 (%)")
    bx.set_title("surge calibration with and without the voltage column")
    bx.legend(fontsize=8)
    bx.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
