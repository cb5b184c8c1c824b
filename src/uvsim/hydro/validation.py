"""Comparisons of the analytic models with data (numbers reported in docs/hydro.md)."""
from __future__ import annotations

import numpy as np

from uvsim.hydro.polars import PolarSet
from uvsim.hydro.wings import WingModel, montgomerie_blend


def wing_rms_vs_polars(wing: WingModel, polars: PolarSet, step_deg: float = 1.0) -> list[dict]:
    """RMS difference of the analytic blend from each polar over 0..180 deg.

    The polar is interpolated linearly onto a uniform ``step_deg`` grid from 0 to 180 deg so that
    the RMS weights all angles equally (the Sheldahl tables are 1 deg apart near stall and
    5 deg apart post-stall).  Returns one dict per Reynolds number with ``re``, ``rms_CL``,
    ``rms_CD``, ``max_abs_CL``, ``max_abs_CD``.
    """
    a = np.radians(np.arange(0.0, 180.0 + 1e-9, step_deg))
    out = []
    for p in polars.polars:
        cl = np.interp(a, p.alpha, p.CL)
        cd = np.interp(a, p.alpha, p.CD)
        c = montgomerie_blend(wing, a, p.re)
        out.append({"re": p.re,
                    "rms_CL": float(np.sqrt(np.mean((c.CL - cl) ** 2))),
                    "rms_CD": float(np.sqrt(np.mean((c.CD - cd) ** 2))),
                    "max_abs_CL": float(np.max(np.abs(c.CL - cl))),
                    "max_abs_CD": float(np.max(np.abs(c.CD - cd)))})
    return out
