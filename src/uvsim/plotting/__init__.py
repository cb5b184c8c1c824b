"""Plots.  The only part of uvsim that imports matplotlib (with the non-interactive
Agg backend, so it works on machines without a display).  One module per area."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
