"""SAM hydrobatic maneuver 'helix' (seed 003 sec. V-C): CSV + plots.

Run:  python examples/sam_helix.py [OUT_DIR]     (default: out/sam)
Same as:  uvsim maneuver helix --out OUT_DIR/helix.csv --plots OUT_DIR
"""
import json
import sys
from pathlib import Path

from uvsim.logs import write_run
from uvsim.maneuvers import run_maneuver
from uvsim.plotting.sam import plot_maneuver

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/sam")
res = run_maneuver("helix")
write_run(out / "helix.csv", res.frame)
plot_maneuver(res.frame, out, "helix")
t_end = float(res.frame["t"].iloc[-1])
print(json.dumps(dict(res.metrics, realtime_factor=t_end / res.wall_time), indent=2))
