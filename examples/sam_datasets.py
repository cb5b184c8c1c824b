"""The accelerating turn with the three hull data sets (seed 003 Table V remark):
Jorgensen-only, DATCOM-only and multifidelity.  Writes a comparison plot and prints the
largest position / speed differences.

Run:  python examples/sam_datasets.py [OUT_DIR]     (default: out/sam)
"""
import sys
from pathlib import Path

import numpy as np

from uvsim.maneuvers import run_maneuver
from uvsim.plotting.sam import plot_datasets

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/sam")
runs = {ds: run_maneuver("accelerating_turn", dataset=ds) for ds in ("jorgensen", "datcom", "multifidelity")}
ref = runs["multifidelity"].frame
for ds, r in runs.items():
    d = np.abs(r.frame[["x", "y", "z"]].to_numpy() - ref[["x", "y", "z"]].to_numpy()).max()
    print(f"{ds:14s} max speed {r.metrics['max_speed_m_s']:.3f} m/s, max position difference "
          f"from multifidelity {d:.3f} m, realtime factor {30.0 / r.wall_time:.0f}")
print(plot_datasets({k: r.frame for k, r in runs.items()}, out / "accelerating_turn_datasets.png",
                    "accelerating_turn"))
