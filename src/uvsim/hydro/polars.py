"""Experimental and CFD polars: readers and interpolation.

A :class:`PolarSet` is a set of polars ``CL, CD, CM (alpha)`` at discrete Reynolds numbers.
Readers:

- :func:`read_sheldahl` - the Sheldahl & Klimas (1981) NACA 0015 tables in the CACTUS file
  format (``data/external/sheldahl-naca0015``, see its SOURCE.md).  The 5 CACTUS dynamic-stall
  lines of each block are skipped; Cm is all zero in that file (not given by SAND80-2114).
- :func:`read_polar_csv` - user CFD/experiment tables: CSV with header ``Re,alpha,CL,CD,CM``
  (``alpha`` in **degrees**, also accepted as ``alpha_deg``).  Data given only for
  ``alpha >= 0`` are mirrored to negative angles when ``symmetric=True`` (CL, CM odd; CD even).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from uvsim.errors import HydroError

SHELDAHL_FILE = (Path(__file__).resolve().parent.parent / "data" / "external" / "sheldahl-naca0015"
                 / "NACA_0015.dat")


@dataclass
class Polar:
    """One polar: ``alpha`` (rad, strictly increasing) and coefficients, shape (n,)."""

    re: float
    alpha: np.ndarray
    CL: np.ndarray
    CD: np.ndarray
    CM: np.ndarray


@dataclass
class PolarSet:
    """Polars at several Reynolds numbers.

    Parameters
    ----------
    polars : list of Polar
        Sorted by Reynolds number on construction.
    kind : {"experiment", "cfd"}
        Fidelity class used as provenance label by the table builders.
    name : str
        Label (file name).
    """

    polars: list
    kind: str = "experiment"
    name: str = ""
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.kind not in ("experiment", "cfd"):
            raise HydroError(f"polar set {self.name!r}: kind must be 'experiment' or 'cfd', got {self.kind!r}")
        if not self.polars:
            raise HydroError(f"polar set {self.name!r}: no polars")
        self.polars = sorted(self.polars, key=lambda p: p.re)
        self._logre = np.log10([p.re for p in self.polars])

    @property
    def res(self) -> np.ndarray:
        return np.array([p.re for p in self.polars])

    def _bracket(self, re: float):
        lr = np.log10(re)
        if len(self.polars) == 1:
            if abs(lr - self._logre[0]) <= 1e-9:
                return 0, 0, 0.0
            return None
        if lr < self._logre[0] - 1e-9 or lr > self._logre[-1] + 1e-9:
            return None
        j = int(np.clip(np.searchsorted(self._logre, lr) - 1, 0, len(self._logre) - 2))
        t = (lr - self._logre[j]) / (self._logre[j + 1] - self._logre[j])
        return j, j + 1, float(min(max(t, 0.0), 1.0))

    def covers(self, re: float, alpha) -> np.ndarray:
        """Boolean mask (shape of ``alpha``): is ``(re, alpha)`` inside the data?

        ``re`` must lie within the Reynolds range of the polars (between two of them, or equal to
        the only one) and ``alpha`` within the angle range of both bracketing polars.  No
        extrapolation.
        """
        a = np.asarray(alpha, float)
        b = self._bracket(float(re))
        if b is None:
            return np.zeros(a.shape, bool)
        p, q = self.polars[b[0]], self.polars[b[1]]
        lo = max(p.alpha[0], q.alpha[0]) - 1e-12
        hi = min(p.alpha[-1], q.alpha[-1]) + 1e-12
        return (a >= lo) & (a <= hi)

    def evaluate(self, re: float, alpha):
        """``(CL, CD, CM)`` at ``(re, alpha)``: linear in alpha, linear in log10(Re) between polars.
        Raises :class:`HydroError` for points not covered (see :meth:`covers`)."""
        a = np.asarray(alpha, float)
        if not np.all(self.covers(re, a)):
            raise HydroError(f"polar set {self.name!r}: (Re={re:g}, alpha) outside the data")
        j, k, t = self._bracket(float(re))
        out = []
        for key in ("CL", "CD", "CM"):
            vj = np.interp(a, self.polars[j].alpha, getattr(self.polars[j], key))
            vk = np.interp(a, self.polars[k].alpha, getattr(self.polars[k], key))
            out.append((1.0 - t) * vj + t * vk)
        return tuple(out)


def _make_polar(re, alpha_deg, cl, cd, cm, where, symmetric):
    alpha_deg = np.asarray(alpha_deg, float)
    cl, cd, cm = (np.asarray(v, float) for v in (cl, cd, cm))
    if alpha_deg.size < 2:
        raise HydroError(f"{where}: Re={re:g} has fewer than 2 angles")
    if symmetric and alpha_deg.min() >= 0.0:
        neg = alpha_deg > 0
        alpha_deg = np.concatenate([-alpha_deg[neg][::-1], alpha_deg])
        cl = np.concatenate([-cl[neg][::-1], cl])
        cd = np.concatenate([cd[neg][::-1], cd])
        cm = np.concatenate([-cm[neg][::-1], cm])
    order = np.argsort(alpha_deg, kind="stable")
    alpha_deg = alpha_deg[order]
    if np.any(np.diff(alpha_deg) == 0):
        dup = alpha_deg[1:][np.diff(alpha_deg) == 0]
        raise HydroError(f"{where}: duplicate angle(s) {dup[:5].tolist()} deg at Re={re:g}")
    return Polar(float(re), np.radians(alpha_deg), cl[order], cd[order], cm[order])


def read_polar_csv(path, kind: str = "cfd", symmetric: bool = True) -> PolarSet:
    """Read a CFD or experimental table (CSV: ``Re, alpha, CL, CD, CM``; alpha in degrees).

    Raises :class:`HydroError` naming the file and the problem for missing columns, non-numeric
    or non-finite values, Re <= 0, angles outside [-180, 180] deg, duplicate (Re, alpha) rows or
    Reynolds numbers with fewer than two angles.
    """
    path = Path(path)
    where = f"polar table {str(path)!r}"
    if not path.exists():
        raise HydroError(f"{where} does not exist")
    try:
        df = pd.read_csv(path, comment="#", skipinitialspace=True)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise HydroError(f"{where}: cannot parse CSV ({exc})") from None
    df.columns = [str(c).strip() for c in df.columns]
    if "alpha" not in df.columns and "alpha_deg" in df.columns:
        df = df.rename(columns={"alpha_deg": "alpha"})
    required = ["Re", "alpha", "CL", "CD", "CM"]
    missing = [c for c in required if c not in df.columns]
    if missing:
        raise HydroError(f"{where}: missing column(s) {missing}; expected header Re,alpha,CL,CD,CM "
                         f"(alpha in degrees), got {list(df.columns)}")
    if df.empty:
        raise HydroError(f"{where}: no data rows")
    for c in required:
        vals = pd.to_numeric(df[c], errors="coerce")
        bad = vals.isna() | ~np.isfinite(vals.to_numpy(dtype=float, na_value=np.nan))
        if bad.any():
            row = int(np.flatnonzero(bad.to_numpy())[0])
            raise HydroError(f"{where}: column {c!r} row {row + 2} (line) is not a finite number: "
                             f"{df[c].iloc[row]!r}")
        df[c] = vals.astype(float)
    if (df["Re"] <= 0).any():
        raise HydroError(f"{where}: column 'Re' must be > 0")
    if ((df["alpha"] < -180) | (df["alpha"] > 180)).any():
        raise HydroError(f"{where}: column 'alpha' must be in [-180, 180] degrees")
    polars = [_make_polar(re, g["alpha"], g["CL"], g["CD"], g["CM"], where, symmetric)
              for re, g in df.groupby("Re", sort=True)]
    return PolarSet(polars, kind=kind, name=path.name, meta={"path": str(path)})


def read_sheldahl(path=None) -> PolarSet:
    """NACA 0015 section data of Sheldahl & Klimas (1981), 11 Reynolds numbers, -180..180 deg."""
    path = Path(path) if path is not None else SHELDAHL_FILE
    where = f"Sheldahl file {str(path)!r}"
    if not path.exists():
        raise HydroError(f"{where} does not exist")
    lines = path.read_text().splitlines()
    polars = []
    re = None
    rows: list = []

    def flush():
        if re is not None:
            if not rows:
                raise HydroError(f"{where}: block Re={re:g} has no data rows")
            arr = np.array(rows)
            polars.append(_make_polar(re, arr[:, 0], arr[:, 1], arr[:, 2], arr[:, 3], where, False))

    in_data = False
    for n, line in enumerate(lines, 1):
        s = line.strip()
        if s.startswith("Reynolds Number:"):
            flush()
            try:
                re = float(s.split(":", 1)[1])
            except ValueError:
                raise HydroError(f"{where}: line {n}: bad Reynolds number {s!r}") from None
            rows, in_data = [], False
        elif s.startswith("AOA"):
            in_data = True
        elif in_data and s:
            parts = s.split()
            if len(parts) != 4:
                raise HydroError(f"{where}: line {n}: expected 4 columns (AOA CL CD Cm25), got {s!r}")
            try:
                rows.append([float(p) for p in parts])
            except ValueError:
                raise HydroError(f"{where}: line {n}: non-numeric value in {s!r}") from None
    flush()
    return PolarSet(polars, kind="experiment", name="Sheldahl & Klimas (1981) NACA 0015",
                    meta={"path": str(path), "thickness": 0.15})
