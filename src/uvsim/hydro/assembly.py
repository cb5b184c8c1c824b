"""Multifidelity database assembly (seed 003 Algorithms 1 and 2).

Per cell ``(Re, alpha)`` the highest-fidelity source that covers it is used:
experiment > CFD > semi-empirical rules.

Body (Algorithm 1), rule part:
    ``Re <= re_threshold``: DATCOM for |alpha| < 15 deg, Jorgensen for 15..180 deg;
    ``Re > re_threshold``: DATCOM over the full envelope (DATCOM itself switches to Jorgensen
    with its refined axial drag beyond 12/15 deg, Table I).
    ``re_threshold`` defaults to the largest Re of the CFD/experiment data (seed 003 Table IV
    used the upper end of its CFD range, 3.9e6), or +inf when no data are given.
Wing (Algorithm 2), rule part:
    lifting line for |alpha| < 10 deg, linear (Montgomerie) blend 10..15 deg, flat plate beyond.

Then optional makima smoothing across method boundaries (:meth:`HydroTable.smooth`).
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import HydroError
from uvsim.hydro import wings as W
from uvsim.hydro.body import BodyModel
from uvsim.hydro.datcom import DRAG_LIMIT, LIFT_LIMIT, datcom
from uvsim.hydro.geometry import HullGeometry, load_hull
from uvsim.hydro.jorgensen import jorgensen
from uvsim.hydro.polars import PolarSet, read_sheldahl
from uvsim.hydro.table import HydroTable, alpha_grid

BODY_METHODS = ("multifidelity", "jorgensen", "datcom")


#: Most rows of a Reynolds grid (``--n-re``), refused before anything is allocated: the tables are
#: interpolated in log Re, and 1000 rows over the default two decades are a 0.5 % step in Re, far
#: finer than the 5-10 % scatter of the drag data they come from; 1e8 rows asked for 269 GiB.
MAX_RE_ROWS = 1000


def default_re_grid(re_min: float = 1e5, re_max: float = 1e7, n: int = 21) -> np.ndarray:
    """Log-spaced Reynolds grid (Algorithm 1 runs Re from 1e5 to 1e7)."""
    if not (np.isfinite(re_min) and np.isfinite(re_max) and 0 < re_min < re_max) or n < 2:
        raise HydroError(f"Re grid (--re-min, --re-max, --n-re) needs finite 0 < re_min < re_max and n >= 2, got "
                         f"{re_min}, {re_max}, {n}")
    if n > MAX_RE_ROWS:
        raise HydroError(f"Re grid (--n-re): {n} rows; at most {MAX_RE_ROWS} (a {MAX_RE_ROWS}-row table already "
                         "resolves Re far finer than the drag data; the default is 21)")
    return np.logspace(np.log10(re_min), np.log10(re_max), int(n))


def _fill_from_data(sources, re, alpha, CL, CD, CM, method, j):
    """Fill row ``j`` from the polar sets in priority order where they cover; returns filled mask."""
    filled = np.zeros(alpha.size, bool)
    for ps in sources:
        if ps is None:
            continue
        cov = ps.covers(re, alpha) & ~filled
        if np.any(cov):
            cl, cd, cm = ps.evaluate(re, alpha[cov])
            CL[j, cov], CD[j, cov], CM[j, cov] = cl, cd, cm
            method[j, cov] = ps.kind
            filled |= cov
    return filled


def _check_sources(experiment, cfd):
    if experiment is not None and not isinstance(experiment, PolarSet):
        raise HydroError("experiment must be a PolarSet (see uvsim.hydro.polars.read_polar_csv)")
    if cfd is not None and not isinstance(cfd, PolarSet):
        raise HydroError("cfd must be a PolarSet (see uvsim.hydro.polars.read_polar_csv)")
    if experiment is not None and experiment.kind != "experiment":
        raise HydroError(f"experiment data {experiment.name!r} is labelled {experiment.kind!r}")
    if cfd is not None and cfd.kind != "cfd":
        raise HydroError(f"CFD data {cfd.name!r} is labelled {cfd.kind!r}")


def build_body_table(body: BodyModel | HullGeometry | str, re_grid=None, method: str = "multifidelity",
                     cfd: PolarSet | None = None, experiment: PolarSet | None = None,
                     re_threshold: float | None = None, alpha_step_deg: float = 1.0,
                     smooth: bool = True, name: str | None = None) -> HydroTable:
    """Coefficient table of a hull (Algorithm 1).

    Parameters
    ----------
    body : BodyModel, HullGeometry or str
        A hull name/path is loaded with :func:`load_hull` and wrapped in a default BodyModel.
    re_grid : array_like, optional
        Reynolds numbers on ``body.L`` (default :func:`default_re_grid`).
    method : {"multifidelity", "jorgensen", "datcom"}
        ``"jorgensen"``/``"datcom"`` fill every cell with that method (data are ignored).
    cfd, experiment : PolarSet, optional
        Higher-fidelity data (``multifidelity`` only); alpha in the data is the body's angle of
        attack, coefficients on the same reference area/length/moment point as ``body``.
    re_threshold : float, optional
        See module docstring.
    smooth : bool
        Apply makima smoothing across method boundaries.
    """
    if isinstance(body, (str,)) or hasattr(body, "__fspath__"):
        body = load_hull(body)
    if isinstance(body, HullGeometry):
        body = BodyModel(body)
    if method not in BODY_METHODS:
        raise HydroError(f"body method {method!r} not in {BODY_METHODS}")
    _check_sources(experiment, cfd)
    re_grid = default_re_grid() if re_grid is None else np.asarray(re_grid, float)
    alpha = alpha_grid(alpha_step_deg)
    shape = (re_grid.size, alpha.size)
    CL, CD, CM = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    meth = np.empty(shape, dtype=object)
    if re_threshold is None:
        data_res = [ps.res.max() for ps in (experiment, cfd) if ps is not None]
        re_threshold = max(data_res) if data_res else np.inf
    low = np.abs(alpha) < DRAG_LIMIT
    for j, re in enumerate(re_grid):
        filled = np.zeros(alpha.size, bool)
        if method == "multifidelity":
            filled = _fill_from_data([experiment, cfd], re, alpha, CL, CD, CM, meth, j)
        jor = jorgensen(body, alpha, re)
        dat = datcom(body, alpha, re)
        if method == "jorgensen":
            use_j = np.ones(alpha.size, bool)
        elif method == "datcom":
            use_j = np.zeros(alpha.size, bool)
        else:
            use_j = (~low) if re <= re_threshold else np.zeros(alpha.size, bool)
        for src, sel, label in ((jor, use_j & ~filled, "jorgensen"), (dat, ~use_j & ~filled, "datcom")):
            CL[j, sel], CD[j, sel], CM[j, sel] = src.CL[sel], src.CD[sel], src.CM[sel]
            meth[j, sel] = label
    h = body.hull
    meta = {
        "kind": "body", "hull": h.name, "hull_source": h.source, "assembly": method,
        "ref_area_m2": body.A, "ref_length_m": body.L, "moment_ref_from_nose_m": body.xm,
        "re_reference": "V * ref_length / nu", "cdn_model": body.cdn_model,
        "friction_line": body.friction_line, "munk_k2_minus_k1": body.k, "eta": body.eta_value,
        "munk_moment_in_cm": body.munk_moment,
        "re_threshold": None if not np.isfinite(re_threshold) else float(re_threshold),
        "cfd": cfd.name if cfd is not None else None,
        "experiment": experiment.name if experiment is not None else None,
        "angles": "alpha = angle of attack; for a body of revolution use the total incidence "
                  "angle (beta by symmetry)",
    }
    table = HydroTable(name or f"{h.name}_{method}", re_grid, alpha, CL, CD, CM, meth, meta=meta)
    if not smooth:
        return table
    # DATCOM switches internally (eq. 12/19 -> Jorgensen at 12 deg, eq. 17 -> Jorgensen at 15 deg):
    # treat those as boundaries too.
    seg = meth.copy()
    aa = np.abs(alpha)[None, :].repeat(re_grid.size, 0)
    is_d = meth == "datcom"
    seg[is_d & (aa <= LIFT_LIMIT)] = "datcom_eq12_17_19"
    seg[is_d & (aa > LIFT_LIMIT) & (aa <= DRAG_LIMIT)] = "datcom_eq17_jorgensen"
    return table.smooth(segments=seg)


def build_wing_table(wing: W.WingModel | None = None, re_grid=None, experiment: PolarSet | None = None,
                     cfd: PolarSet | None = None, alpha_step_deg: float = 1.0, smooth: bool = True,
                     name: str = "wing", cm_from_analytic: bool = False) -> HydroTable:
    """Coefficient table of a wing/control surface (Algorithm 2).

    ``re_grid`` is the chord Reynolds number (default 1e4..1e6, as Algorithm 2).  Cells covered by
    ``experiment`` (then ``cfd``) take those data; the rest the analytic Montgomerie blend, labelled
    ``lifting_line`` (|alpha| < 10 deg), ``montgomerie_blend`` (10..15 deg) or ``flat_plate``.
    Note: 2-D section data (e.g. Sheldahl) apply to a wing only with ``aspect_ratio = inf``;
    for a finite wing pass 3-D data or none.  ``cm_from_analytic`` takes ``CM`` from the analytic
    blend in every cell (for data without moments, such as Sheldahl's; recorded in ``meta``).
    """
    wing = wing or W.WingModel()
    _check_sources(experiment, cfd)
    re_grid = default_re_grid(1e4, 1e6, 11) if re_grid is None else np.asarray(re_grid, float)
    alpha = alpha_grid(alpha_step_deg)
    shape = (re_grid.size, alpha.size)
    CL, CD, CM = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    meth = np.empty(shape, dtype=object)
    w = W.blend_weight(alpha)
    labels = np.where(w == 0.0, "lifting_line", np.where(w == 1.0, "flat_plate", "montgomerie_blend"))
    for j, re in enumerate(re_grid):
        filled = _fill_from_data([experiment, cfd], re, alpha, CL, CD, CM, meth, j)
        an = W.montgomerie_blend(wing, alpha, re)
        sel = ~filled
        CL[j, sel], CD[j, sel], CM[j, sel] = an.CL[sel], an.CD[sel], an.CM[sel]
        if cm_from_analytic:
            CM[j] = an.CM
        meth[j, sel] = labels[sel]
    meta = {
        "kind": "wing", "assembly": "algorithm2", "aspect_ratio": float(wing.aspect_ratio),
        "oswald": wing.oswald, "thickness": wing.thickness, "cd90": wing.cd90_value,
        "friction_line": wing.friction_line, "ref": "planform area S, chord c; CM about c/4",
        "re_reference": "V * chord / nu",
        "cm_source": "analytic blend in all cells" if cm_from_analytic else "per-cell method",
        "cfd": cfd.name if cfd is not None else None,
        "experiment": experiment.name if experiment is not None else None,
    }
    table = HydroTable(name, re_grid, alpha, CL, CD, CM, meth, meta=meta)
    if smooth:
        # Only the data/analytic boundaries need makima; the analytic methods are already blended.
        table = _smooth_data_boundaries(table)
    return table


def _smooth_data_boundaries(table: HydroTable) -> HydroTable:
    """Makima-smooth only where data meet analytic cells (LL/blend/FP boundaries are continuous)."""
    coarse = table.method.copy()
    analytic = np.isin(coarse.astype(str), ["lifting_line", "montgomerie_blend", "flat_plate"])
    coarse[analytic] = "analytic"
    tmp = HydroTable(table.name, table.re, table.alpha, table.CL, table.CD, table.CM, coarse,
                     table.smoothed, table.meta).smooth()
    return HydroTable(table.name, table.re, table.alpha, tmp.CL, tmp.CD, tmp.CM, table.method,
                      tmp.smoothed, tmp.meta)


def naca0015_table(re_grid=None, aspect_ratio: float = np.inf, use_experiment: bool = True,
                   oswald: float = 0.9, name: str | None = None) -> HydroTable:
    """NACA 0015 section/wing table: Sheldahl & Klimas data (2-D only) + analytic blend.

    With ``aspect_ratio = inf`` and ``use_experiment`` the Sheldahl polars (Re 1e4..1e7) fill every
    cell they cover.  For a finite aspect ratio (e.g. a nozzle ring of NACA 0015 sections) the
    2-D data do not apply and only the lifting line / flat plate blend is used.
    """
    wing = W.WingModel(aspect_ratio=aspect_ratio, oswald=oswald, thickness=0.15)
    exp = read_sheldahl() if (use_experiment and np.isinf(aspect_ratio)) else None
    label = name or ("naca0015" if np.isinf(aspect_ratio) else f"naca0015_ar{aspect_ratio:g}")
    # SAND80-2114 gives no Cm (the file's Cm25 column is all zero): CM comes from the analytic model.
    return build_wing_table(wing, re_grid, experiment=exp, name=label, cm_from_analytic=True)
