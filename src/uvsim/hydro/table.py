"""Multifidelity coefficient table over (Re, alpha) with per-cell provenance.

:class:`HydroTable` holds ``CL, CD, CM`` on a grid of Reynolds numbers (rows, increasing) and
angles of attack (columns, rad, increasing, covering [-pi, pi]), the method that filled each
cell (``method``, e.g. ``"experiment"``, ``"cfd"``, ``"datcom"``, ``"jorgensen"``,
``"lifting_line"``, ``"montgomerie_blend"``, ``"flat_plate"``) and whether the cell was re-filled
by makima smoothing (``smoothed``).

Lookup is bilinear in (log10 Re, alpha); see :meth:`HydroTable.lookup`.

Files are CSV (long format, one row per cell): a first comment line
``# uvsim-hydro-table v1 {json metadata}`` then columns
``re, alpha_deg, CL, CD, CM, method, smoothed``.  CSV was chosen over NetCDF/HDF5 because the
tables are small (tens of Re x 361 angles), must be readable and diffable by people checking
provenance, and CSV needs no dependency beyond pandas; values are written with 17 significant
digits so a save/load round trip is exact.
"""
from __future__ import annotations

import bisect
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.interpolate import Akima1DInterpolator

from uvsim.errors import HydroError

COEFFS = ("CL", "CD", "CM")
_MAGIC = "# uvsim-hydro-table v1 "


@dataclass
class HydroTable:
    """Coefficient table of one component.

    Parameters
    ----------
    name : str
    re : ndarray, shape (n_re,)
        Reynolds numbers, strictly increasing, > 0.
    alpha : ndarray, shape (n_alpha,)
        Angles of attack, rad, strictly increasing, from -pi to pi inclusive.
    CL, CD, CM : ndarray, shape (n_re, n_alpha)
    method : ndarray of str, shape (n_re, n_alpha)
        Provenance label per cell.
    smoothed : ndarray of bool, shape (n_re, n_alpha)
        True where makima smoothing replaced the value.
    meta : dict
        JSON-serialisable metadata (reference area/length, moment reference, component kind,
        Reynolds reference length, notes).
    """

    name: str
    re: np.ndarray
    alpha: np.ndarray
    CL: np.ndarray
    CD: np.ndarray
    CM: np.ndarray
    method: np.ndarray
    smoothed: np.ndarray | None = None
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        where = f"hydro table {self.name!r}"
        self.re = np.asarray(self.re, float)
        self.alpha = np.asarray(self.alpha, float)
        n_re, n_a = self.re.size, self.alpha.size
        if self.re.ndim != 1 or n_re < 1 or np.any(self.re <= 0) or np.any(np.diff(self.re) <= 0):
            raise HydroError(f"{where}: re must be a strictly increasing 1-D array of positive numbers")
        if self.alpha.ndim != 1 or n_a < 3 or np.any(np.diff(self.alpha) <= 0):
            raise HydroError(f"{where}: alpha must be a strictly increasing 1-D array (rad)")
        if abs(self.alpha[0] + np.pi) > 1e-9 or abs(self.alpha[-1] - np.pi) > 1e-9:
            raise HydroError(f"{where}: alpha must span [-pi, pi] (got {self.alpha[0]:.6g}..{self.alpha[-1]:.6g} rad)")
        for key in COEFFS:
            arr = np.asarray(getattr(self, key), float)
            if arr.shape != (n_re, n_a):
                raise HydroError(f"{where}: {key} must have shape {(n_re, n_a)}, got {arr.shape}")
            if not np.all(np.isfinite(arr)):
                raise HydroError(f"{where}: {key} has non-finite values")
            setattr(self, key, arr)
        self.method = np.asarray(self.method, dtype=object)
        if self.method.shape != (n_re, n_a):
            raise HydroError(f"{where}: method must have shape {(n_re, n_a)}, got {self.method.shape}")
        if self.smoothed is None:
            self.smoothed = np.zeros((n_re, n_a), bool)
        self.smoothed = np.asarray(self.smoothed, bool)
        self._prepare()

    # ------------------------------------------------------------------ lookup
    def _prepare(self):
        self._logre = np.log10(self.re)
        self._stack = np.stack([self.CL, self.CD, self.CM])  # (3, n_re, n_a)
        da = np.diff(self.alpha)
        self._uniform = bool(np.allclose(da, da[0], rtol=1e-9, atol=1e-12))
        self._a0, self._da = float(self.alpha[0]), float(da[0])
        self._logre_list = self._logre.tolist()
        self._alpha_list = self.alpha.tolist()
        self._rows = [[row.tolist() for row in c] for c in (self.CL, self.CD, self.CM)]

    def _re_index(self, re, extrapolate):
        lr = np.log10(np.asarray(re, float))
        lo, hi = self._logre[0], self._logre[-1]
        if extrapolate == "raise":
            if np.any(lr < lo - 1e-12) or np.any(lr > hi + 1e-12) or np.any(~np.isfinite(lr)):
                raise HydroError(f"hydro table {self.name!r}: Re outside the table range "
                                 f"[{self.re[0]:g}, {self.re[-1]:g}]")
        elif extrapolate != "clamp":
            raise HydroError(f"lookup: extrapolate must be 'clamp' or 'raise', got {extrapolate!r}")
        if self.re.size == 1:
            z = np.zeros(np.shape(lr), int)
            return z, z, np.zeros(np.shape(lr))
        lr = np.clip(np.nan_to_num(lr, nan=lo, neginf=lo), lo, hi)  # explicit 'clamp' policy
        j = np.clip(np.searchsorted(self._logre, lr, side="right") - 1, 0, self.re.size - 2)
        t = (lr - self._logre[j]) / (self._logre[j + 1] - self._logre[j])
        return j, j + 1, t

    def lookup(self, alpha, re=None, extrapolate: str = "clamp"):
        """Coefficients at angles ``alpha`` (rad) and Reynolds numbers ``re``.

        Parameters
        ----------
        alpha : float or ndarray, any shape
            Angle of attack (or, for bodies of revolution, the total incidence angle), rad.
            Wrapped periodically to [-pi, pi).
        re : float or ndarray broadcastable with ``alpha``, optional
            Reynolds number on the table's reference length.  Default: the table's only/first Re.
        extrapolate : {"clamp", "raise"}
            Policy for Re outside the table range: ``"clamp"`` (default) uses the nearest
            tabulated Re - intended for a simulator passing through rest, where Re -> 0 and the
            dynamic pressure vanishes anyway; ``"raise"`` raises :class:`HydroError`.

        Returns
        -------
        (CL, CD, CM) : tuple of float or ndarray of the broadcast shape
            Bilinear interpolation in (log10 Re, alpha).
        """
        if re is None:
            re = self.re[0]
        if np.ndim(alpha) == 0 and np.ndim(re) == 0:
            return self._lookup_scalar(float(alpha), float(re), extrapolate)
        a = np.asarray(alpha, float)
        a = (a + np.pi) % (2.0 * np.pi) - np.pi
        j0, j1, t = self._re_index(re, extrapolate)
        a, j0, j1, t = np.broadcast_arrays(a, j0, j1, t)
        if self._uniform:
            u = (a - self._a0) / self._da
            i = np.minimum(u.astype(np.intp), self.alpha.size - 2)
            s = u - i
        else:
            i = np.clip(np.searchsorted(self.alpha, a, side="right") - 1, 0, self.alpha.size - 2)
            s = (a - self.alpha[i]) / (self.alpha[i + 1] - self.alpha[i])
        st = self._stack
        v00, v01 = st[:, j0, i], st[:, j0, i + 1]
        v10, v11 = st[:, j1, i], st[:, j1, i + 1]
        lo = v00 + s * (v01 - v00)
        hi = v10 + s * (v11 - v10)
        out = lo + t * (hi - lo)
        return out[0], out[1], out[2]

    def _lookup_scalar(self, a: float, re: float, extrapolate: str):
        a = (a + math.pi) % (2.0 * math.pi) - math.pi
        lgs = self._logre_list
        if re > 0 and math.isfinite(re):
            lr = math.log10(re)
        else:
            lr = -math.inf
        if lr < lgs[0] - 1e-12 or lr > lgs[-1] + 1e-12:
            if extrapolate == "raise":
                raise HydroError(f"hydro table {self.name!r}: Re={re:g} outside the table range "
                                 f"[{self.re[0]:g}, {self.re[-1]:g}]")
            if extrapolate != "clamp":
                raise HydroError(f"lookup: extrapolate must be 'clamp' or 'raise', got {extrapolate!r}")
            lr = min(max(lr, lgs[0]), lgs[-1])
        n = len(lgs)
        if n == 1:
            j, t = 0, 0.0
        else:
            j = min(max(bisect.bisect_right(lgs, lr) - 1, 0), n - 2)
            t = (lr - lgs[j]) / (lgs[j + 1] - lgs[j])
        if self._uniform:
            u = (a - self._a0) / self._da
            i = min(int(u), len(self._alpha_list) - 2)
            s = u - i
        else:
            al = self._alpha_list
            i = min(max(bisect.bisect_right(al, a) - 1, 0), len(al) - 2)
            s = (a - al[i]) / (al[i + 1] - al[i])
        out = []
        j1 = j + 1 if n > 1 else j
        for rows in self._rows:
            r0, r1 = rows[j], rows[j1]
            lo = r0[i] + s * (r0[i + 1] - r0[i])
            hi = r1[i] + s * (r1[i + 1] - r1[i])
            out.append(lo + t * (hi - lo))
        return out[0], out[1], out[2]

    # --------------------------------------------------------------- analysis
    def provenance(self, alpha, re) -> str:
        """Method label of the cell nearest to ``(alpha rad, re)``."""
        i = int(np.argmin(np.abs(self.alpha - float(alpha))))
        j = int(np.argmin(np.abs(np.log10(self.re) - np.log10(float(re)))))
        return str(self.method[j, i])

    def boundary_mask(self) -> np.ndarray:
        """(n_re, n_alpha-1) bool: True where neighbouring cells along alpha have different methods."""
        return self.method[:, 1:] != self.method[:, :-1]

    def max_jump(self, coeff: str, at_boundaries: bool = True, detrend: bool = True) -> float:
        """Largest jump of ``coeff`` between alpha-neighbouring cells.

        The step between cells ``k`` and ``k+1`` is ``d_k = v[k+1] - v[k]``.  With ``detrend``
        (default) the jump is ``|d_k - (d_(k-1) + d_(k+1))/2|``, the departure of the step from
        the neighbouring steps: about the size of a discontinuity, and ~0 on a smooth curve
        however steep.  Without ``detrend`` it is ``|d_k|``.  With ``at_boundaries`` only pairs
        that straddle a change of ``method`` count.
        """
        v = getattr(self, coeff)
        d = np.diff(v, axis=1)
        if detrend:
            ex = np.zeros_like(d)
            ex[:, 1:-1] = np.abs(d[:, 1:-1] - 0.5 * (d[:, :-2] + d[:, 2:]))
            ex[:, 0], ex[:, -1] = np.abs(d[:, 0] - d[:, 1]), np.abs(d[:, -1] - d[:, -2])
            d = ex
        else:
            d = np.abs(d)
        if at_boundaries:
            m = self.boundary_mask()
            return float(d[m].max()) if np.any(m) else 0.0
        return float(d.max())

    def smooth(self, width: int = 3, re_width: int = 1, segments=None) -> "HydroTable":
        """Makima smoothing across method boundaries (seed 003 sec. IV-B, Fig. 32).

        Along alpha, in each Re row, the ``width`` cells on each side of every method boundary are
        removed and re-filled by a modified-Akima interpolant
        (``scipy.interpolate.Akima1DInterpolator(method="makima")``) through the remaining
        cells.  Along Re (in log10 Re), the same with ``re_width`` rows at boundaries between
        rows, if at least 4 rows remain.  Returns a new table; ``method`` is kept, ``smoothed``
        marks the re-filled cells.

        ``segments`` (same shape as ``method``, optional) gives finer labels used only to find
        the boundaries, e.g. DATCOM's own switch from eq. 12 to Jorgensen at 12 deg.
        """
        seg = self.method if segments is None else np.asarray(segments, dtype=object)
        if seg.shape != self.method.shape:
            raise HydroError(f"smooth: segments must have shape {self.method.shape}")
        vals = {k: getattr(self, k).copy() for k in COEFFS}
        sm = self.smoothed.copy()
        n_re, n_a = self.method.shape
        if width > 0:
            for j in range(n_re):
                b = np.flatnonzero(seg[j, 1:] != seg[j, :-1])
                if b.size == 0:
                    continue
                mask = np.zeros(n_a, bool)
                for k in b:
                    mask[max(k - width + 1, 1):min(k + width + 1, n_a - 1)] = True
                keep = ~mask
                if keep.sum() < 4:
                    continue
                for key in COEFFS:
                    f = Akima1DInterpolator(self.alpha[keep], vals[key][j, keep], method="makima")
                    vals[key][j, mask] = f(self.alpha[mask])
                sm[j, mask] = True
        if re_width > 0 and n_re >= 4:
            lr = np.log10(self.re)
            for i in range(n_a):
                col = seg[:, i]
                b = np.flatnonzero(col[1:] != col[:-1])
                if b.size == 0:
                    continue
                mask = np.zeros(n_re, bool)
                for k in b:
                    mask[max(k - re_width + 1, 1):min(k + re_width + 1, n_re - 1)] = True
                keep = ~mask
                if keep.sum() < 4 or not mask.any():
                    continue
                for key in COEFFS:
                    f = Akima1DInterpolator(lr[keep], vals[key][keep, i], method="makima")
                    vals[key][mask, i] = f(lr[mask])
                sm[mask, i] = True
        meta = dict(self.meta, smoothing={"method": "makima", "alpha_width_cells": width,
                                          "re_width_rows": re_width})
        return HydroTable(self.name, self.re, self.alpha, vals["CL"], vals["CD"], vals["CM"],
                          self.method.copy(), sm, meta)

    # ------------------------------------------------------------------ files
    def to_frame(self) -> pd.DataFrame:
        """Long-format DataFrame (one row per cell), ``alpha_deg`` in degrees."""
        R, A = np.meshgrid(self.re, self.alpha, indexing="ij")
        return pd.DataFrame({
            "re": R.ravel(), "alpha_deg": np.degrees(A).ravel(),
            "CL": self.CL.ravel(), "CD": self.CD.ravel(), "CM": self.CM.ravel(),
            "method": self.method.ravel().astype(str), "smoothed": self.smoothed.ravel().astype(int),
        })

    def save(self, path) -> Path:
        """Write the table as CSV (see module docstring); returns the path."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        meta = dict(self.meta, name=self.name, alpha_unit_in_file="deg", n_re=int(self.re.size),
                    n_alpha=int(self.alpha.size))
        with open(path, "w", newline="") as fh:
            fh.write(_MAGIC + json.dumps(meta, sort_keys=True, default=float) + "\n")
            self.to_frame().to_csv(fh, index=False, float_format="%.17g")
        return path

    @classmethod
    def load(cls, path) -> "HydroTable":
        """Read a table written by :meth:`save`; raises :class:`HydroError` if malformed."""
        path = Path(path)
        where = f"hydro table file {str(path)!r}"
        if not path.exists():
            raise HydroError(f"{where} does not exist")
        with open(path) as fh:
            first = fh.readline()
        if not first.startswith(_MAGIC):
            raise HydroError(f"{where}: first line must start with {_MAGIC.strip()!r}")
        try:
            meta = json.loads(first[len(_MAGIC):])
        except json.JSONDecodeError as exc:
            raise HydroError(f"{where}: bad metadata JSON ({exc})") from None
        df = pd.read_csv(path, skiprows=1)
        cols = ["re", "alpha_deg", "CL", "CD", "CM", "method", "smoothed"]
        missing = [c for c in cols if c not in df.columns]
        if missing:
            raise HydroError(f"{where}: missing column(s) {missing}")
        re = np.unique(df["re"].to_numpy(float))
        al = np.unique(df["alpha_deg"].to_numpy(float))
        if len(df) != re.size * al.size:
            raise HydroError(f"{where}: {len(df)} rows do not form a full {re.size} x {al.size} grid")
        df = df.sort_values(["re", "alpha_deg"])
        shape = (re.size, al.size)
        name = meta.pop("name", path.stem)
        for k in ("alpha_unit_in_file", "n_re", "n_alpha"):
            meta.pop(k, None)
        alpha = np.radians(al)
        alpha[0], alpha[-1] = -np.pi, np.pi  # exact ends after the deg round trip
        return cls(name, re, alpha,
                   *(df[c].to_numpy(float).reshape(shape) for c in COEFFS),
                   method=df["method"].to_numpy(str).astype(object).reshape(shape),
                   smoothed=df["smoothed"].to_numpy(int).astype(bool).reshape(shape), meta=meta)


def alpha_grid(step_deg: float = 1.0) -> np.ndarray:
    """Uniform angle grid from -pi to pi inclusive, rad (``360/step_deg`` must be an integer)."""
    n = 360.0 / step_deg
    if abs(n - round(n)) > 1e-9 or step_deg <= 0:
        raise HydroError(f"alpha step {step_deg} deg must divide 360")
    return np.linspace(-np.pi, np.pi, int(round(n)) + 1)
