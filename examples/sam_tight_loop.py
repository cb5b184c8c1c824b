"""SAM hydrobatic maneuver 'tight_loop' (seed 003 sec. V-C): CSV + plots.

Run:  python examples/sam_tight_loop.py [OUT_DIR]     (default: out/sam)
Same as:  uvsim maneuver tight_loop --out OUT_DIR/tight_loop.csv --plots OUT_DIR
"""
import json
import sys
from pathlib import Path

from uvsim.logs import write_run
from uvsim.maneuvers import run_maneuver
from uvsim.plotting.sam import plot_maneuver

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/sam")
res = run_maneuver("tight_loop")
write_run(out / "tight_loop.csv", res.frame)
plot_maneuver(res.frame, out, "tight_loop")
t_end = float(res.frame["t"].iloc[-1])
print(json.dumps(dict(res.metrics, realtime_factor=t_end / res.wall_time), indent=2))
