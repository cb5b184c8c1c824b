"""Hull (body of revolution) geometry from a radius profile.

A hull is described by its radius ``r(x)`` at stations ``x`` measured aft from the
nose (m).  From the profile we derive every quantity the Jorgensen and DATCOM
methods need (seed 003 eqs. 7-19):

- volume ``V = int pi r^2 dx``
- maximum (frontal) area ``A_max = pi d^2 / 4`` and base area ``A_b = pi r(L)^2``
- planform area ``A_p = int 2 r dx`` and its centroid ``x_c`` (from the nose)
- wetted area ``S_wet = int 2 pi r sqrt(1 + r'^2) dx``
- station ``x_0`` where ``dS/dx`` is most negative and ``S_0 = S(x_0)``
  (DATCOM / Hopkins: the flow is assumed to cease being potential there)
- volume centroid ``x_B`` (centre of buoyancy, from the nose).

Profiles come from Myring parameters (:func:`myring_profile`), from explicit
stations (:func:`hull_from_stations`), from a YAML file (:func:`load_hull`) or,
optionally, from an STL mesh (:func:`hull_from_stl`, needs ``numpy-stl``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import yaml

from uvsim.errors import HydroError
from uvsim.files import safe_load

#: Folder of the built-in hull definitions (package data, ``data/hulls/*.yaml``).
HULLS_DIR = Path(__file__).resolve().parent.parent / "data" / "hulls"


def _trapz(y: np.ndarray, x: np.ndarray) -> float:
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


@dataclass(frozen=True)
class HullGeometry:
    """Axisymmetric hull described by stations.

    Parameters
    ----------
    x : ndarray, shape (n,)
        Stations from the nose, m, strictly increasing, ``x[0] == 0``.
    r : ndarray, shape (n,)
        Radius at each station, m, ``>= 0``.
    name : str
        Label used in messages and tables.
    source : str
        Citation of where the geometry comes from.
    """

    x: np.ndarray
    r: np.ndarray
    name: str = "hull"
    source: str = ""
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        x = np.asarray(self.x, dtype=float)
        r = np.asarray(self.r, dtype=float)
        where = f"hull {self.name!r}"
        if x.ndim != 1 or r.ndim != 1 or x.shape != r.shape:
            raise HydroError(f"{where}: stations x and radii r must be 1-D arrays of equal length, "
                             f"got shapes {x.shape} and {r.shape}")
        if x.size < 3:
            raise HydroError(f"{where}: need at least 3 stations, got {x.size}")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(r))):
            raise HydroError(f"{where}: stations and radii must be finite")
        if np.any(np.diff(x) <= 0):
            raise HydroError(f"{where}: stations x must be strictly increasing (m from the nose)")
        if np.any(r < 0):
            raise HydroError(f"{where}: radii must be >= 0 m, got min {r.min():g}")
        x = x - x[0]
        if x[-1] <= 0:
            raise HydroError(f"{where}: length must be > 0 m")
        if r.max() <= 0:
            raise HydroError(f"{where}: maximum diameter must be > 0 m")
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "r", r)

    # ---- basic dimensions -------------------------------------------------
    @property
    def length(self) -> float:
        """Overall length ``L`` (m)."""
        return float(self.x[-1])

    @property
    def diameter(self) -> float:
        """Maximum diameter ``d`` (m)."""
        return float(2.0 * self.r.max())

    @property
    def fineness_ratio(self) -> float:
        """``L / d`` (-)."""
        return self.length / self.diameter

    @property
    def frontal_area(self) -> float:
        """Maximum cross-section ``pi d^2 / 4`` (m^2), the default reference area."""
        return float(np.pi * self.r.max() ** 2)

    @property
    def base_area(self) -> float:
        """Cross-section at the aft end ``A_b`` (m^2)."""
        return float(np.pi * self.r[-1] ** 2)

    @property
    def base_diameter(self) -> float:
        """Diameter at the aft end ``d_b`` (m)."""
        return float(2.0 * self.r[-1])

    # ---- integrals --------------------------------------------------------
    @property
    def volume(self) -> float:
        """``V = int pi r^2 dx`` (m^3)."""
        return _trapz(np.pi * self.r ** 2, self.x)

    @property
    def volume_centroid(self) -> float:
        """Centre of buoyancy ``x_B`` from the nose (m)."""
        return _trapz(self.x * np.pi * self.r ** 2, self.x) / self.volume

    @property
    def planform_area(self) -> float:
        """``A_p = int 2 r dx`` (m^2)."""
        return _trapz(2.0 * self.r, self.x)

    @property
    def planform_centroid(self) -> float:
        """Centroid of the planform area ``x_c`` from the nose (m)."""
        return _trapz(self.x * 2.0 * self.r, self.x) / self.planform_area

    @property
    def wetted_area(self) -> float:
        """``S_wet = int 2 pi r ds`` along the meridian (m^2), base disc excluded."""
        ds = np.hypot(np.diff(self.x), np.diff(self.r))
        return float(np.sum(np.pi * (self.r[1:] + self.r[:-1]) * ds))

    def section_area_slope(self) -> np.ndarray:
        """``dS/dx`` at the stations (m), ``S = pi r^2``, shape (n,)."""
        return np.gradient(np.pi * self.r ** 2, self.x)

    @property
    def x0(self) -> float:
        """Station where ``dS/dx`` is most negative (m from the nose), DATCOM 4.2.1.2."""
        return float(self.x[int(np.argmin(self.section_area_slope()))])

    @property
    def s0(self) -> float:
        """Cross-section area at :attr:`x0` (m^2)."""
        return float(np.pi * np.interp(self.x0, self.x, self.r) ** 2)

    def radius_at(self, x) -> np.ndarray:
        """Radius at arbitrary stations (linear between stations), m."""
        return np.interp(x, self.x, self.r)

    def summary(self) -> dict:
        """All derived quantities as a plain dict (SI units)."""
        return {
            "name": self.name,
            "length_m": self.length,
            "diameter_m": self.diameter,
            "fineness_ratio": self.fineness_ratio,
            "volume_m3": self.volume,
            "volume_centroid_m": self.volume_centroid,
            "frontal_area_m2": self.frontal_area,
            "base_area_m2": self.base_area,
            "planform_area_m2": self.planform_area,
            "planform_centroid_m": self.planform_centroid,
            "wetted_area_m2": self.wetted_area,
            "x0_m": self.x0,
            "s0_m2": self.s0,
        }


def myring_profile(a: float, b: float, c: float, d: float, n: float = 2.0, theta: float = 0.0,
                   a_offset: float = 0.0, c_offset: float = 0.0, n_points: int = 401,
                   name: str = "myring", source: str = "") -> HullGeometry:
    """Hull from Myring's profile (Myring 1976; notation of Prestero 2001 eqs. 2.1-2.2).

    Parameters
    ----------
    a, b, c : float
        Nose, parallel mid-body and tail lengths of the full (untruncated) profile, m.
    d : float
        Maximum diameter, m.
    n : float
        Nose shape exponent (-), ``n = 2`` is elliptic.
    theta : float
        Included tail half-angle at the tail tip, rad.
    a_offset, c_offset : float
        Lengths cut off the nose tip and the tail tip, m (REMUS has both).
    n_points : int
        Number of stations (spread over nose, mid-body and tail).

    Returns
    -------
    HullGeometry
        Stations from the (truncated) nose; length ``a + b + c - a_offset - c_offset``.
    """
    params = dict(a=a, b=b, c=c, d=d, n=n, a_offset=a_offset, c_offset=c_offset)
    for key, val in params.items():
        if not np.isfinite(val):
            raise HydroError(f"Myring hull {name!r}: parameter {key} must be finite, got {val!r}")
    for key in ("a", "c", "d", "n"):
        if params[key] <= 0:
            raise HydroError(f"Myring hull {name!r}: parameter {key} must be > 0, got {params[key]!r}")
    for key in ("b", "a_offset", "c_offset"):
        if params[key] < 0:
            raise HydroError(f"Myring hull {name!r}: parameter {key} must be >= 0 m, got {params[key]!r}")
    if a_offset >= a or c_offset >= c:
        raise HydroError(f"Myring hull {name!r}: offsets must be shorter than nose/tail "
                         f"(a_offset {a_offset} < a {a}, c_offset {c_offset} < c {c})")
    n_nose = max(n_points // 3, 20)
    n_tail = max(n_points // 3, 20)
    n_mid = max(n_points - n_nose - n_tail, 3)
    # Nose: cosine spacing to resolve the blunt tip.
    t = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, n_nose)))
    x_nose = t * (a - a_offset)
    r_nose = 0.5 * d * np.clip(1.0 - ((x_nose + a_offset - a) / a) ** 2, 0.0, None) ** (1.0 / n)
    lf = a - a_offset + b
    x_mid = np.linspace(a - a_offset, lf, n_mid)
    r_mid = np.full_like(x_mid, 0.5 * d)
    xi = np.linspace(0.0, c - c_offset, n_tail)
    tt = np.tan(theta)
    r_tail = 0.5 * d - (3.0 * d / (2.0 * c ** 2) - tt / c) * xi ** 2 + (d / c ** 3 - tt / c ** 2) * xi ** 3
    x = np.concatenate([x_nose, x_mid[1:], lf + xi[1:]])
    r = np.concatenate([r_nose, r_mid[1:], r_tail[1:]])
    if np.any(r < -1e-12):
        raise HydroError(f"Myring hull {name!r}: tail radius becomes negative; check theta={theta} and c={c}")
    meta = dict(params, theta=theta, kind="myring")
    return HullGeometry(x=x, r=np.maximum(r, 0.0), name=name, source=source, meta=meta)


def hull_from_stations(x, r, name: str = "stations", source: str = "") -> HullGeometry:
    """Hull from explicit ``(x, r)`` stations (m); see :class:`HullGeometry`."""
    return HullGeometry(x=np.asarray(x, float), r=np.asarray(r, float), name=name, source=source,
                        meta={"kind": "stations"})


def hull_from_dict(spec: dict, name: str = "hull", where: str = "hull definition") -> HullGeometry:
    """Hull from a mapping as found in a hull YAML file.

    Either ``myring: {a, b, c, d, n, theta, a_offset, c_offset}`` (m, rad) or
    ``stations: {x: [...], r: [...]}`` (m).
    """
    if not isinstance(spec, dict):
        raise HydroError(f"{where}: expected a mapping with 'myring' or 'stations', got {type(spec).__name__}")
    name = str(spec.get("name", name))
    source = str(spec.get("source", ""))
    if "myring" in spec:
        p = spec["myring"]
        if not isinstance(p, dict):
            raise HydroError(f"{where}: 'myring' must be a mapping of parameters")
        allowed = {"a", "b", "c", "d", "n", "theta", "a_offset", "c_offset"}
        unknown = set(p) - allowed
        if unknown:
            raise HydroError(f"{where}: unknown myring parameter(s) {sorted(unknown)}; allowed {sorted(allowed)}")
        missing = {"a", "b", "c", "d"} - set(p)
        if missing:
            raise HydroError(f"{where}: myring parameter(s) {sorted(missing)} missing")
        try:
            vals = {k: float(v) for k, v in p.items()}
        except (TypeError, ValueError) as exc:
            raise HydroError(f"{where}: myring parameters must be numbers ({exc})") from None
        return myring_profile(name=name, source=source, **vals)
    if "stations" in spec:
        st = spec["stations"]
        if not isinstance(st, dict) or "x" not in st or "r" not in st:
            raise HydroError(f"{where}: 'stations' must have lists 'x' and 'r' (m)")
        try:
            return hull_from_stations(np.asarray(st["x"], float), np.asarray(st["r"], float),
                                      name=name, source=source)
        except (TypeError, ValueError) as exc:
            raise HydroError(f"{where}: stations must be numbers ({exc})") from None
    raise HydroError(f"{where}: expected key 'myring' or 'stations'")


def builtin_hulls() -> list[str]:
    """Names of the built-in hulls (files ``data/hulls/*.yaml``)."""
    return sorted(p.stem for p in HULLS_DIR.glob("*.yaml"))


def load_hull(name_or_path: str | Path) -> HullGeometry:
    """Load a built-in hull by name (e.g. ``"remus100"``) or a hull YAML file by path."""
    path = Path(name_or_path)
    if not path.suffix:
        cand = HULLS_DIR / f"{name_or_path}.yaml"
        if not cand.exists():
            raise HydroError(f"unknown hull {str(name_or_path)!r}: not a file and not one of the built-in "
                             f"hulls {builtin_hulls()}")
        path = cand
    if not path.exists():
        raise HydroError(f"hull file {str(path)!r} does not exist")
    try:
        spec = safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise HydroError(f"hull file {str(path)!r}: invalid YAML ({exc})") from None
    return hull_from_dict(spec, name=path.stem, where=f"hull file {str(path)!r}")


def hull_from_stl(path: str | Path, axis: int = 0, n_stations: int = 200, name: str | None = None) -> HullGeometry:
    """Hull stations from an STL mesh (CAD workflow of seed 003 sec. IV-A).

    Needs the optional package ``numpy-stl`` (``pip install 'uvsim[cad]'``); the slicing itself is
    :func:`hull_from_triangles`.
    """
    try:
        from stl import mesh as stl_mesh  # type: ignore
    except ImportError:
        raise HydroError("reading STL needs the optional package numpy-stl (pip install 'uvsim[cad]')") from None
    path = Path(path)
    if not path.exists():
        raise HydroError(f"STL file {str(path)!r} does not exist")
    m = stl_mesh.Mesh.from_file(str(path))
    return hull_from_triangles(np.asarray(m.vectors, float), axis=axis, n_stations=n_stations,
                               name=name or path.stem, source=f"STL {path.name}")


def hull_from_triangles(tri, axis: int = 0, n_stations: int = 200, name: str = "mesh",
                        source: str = "") -> HullGeometry:
    """Hull stations from a triangle mesh, array of shape (n_tri, 3 vertices, 3 coordinates), m.

    Slices the mesh with planes normal to ``axis`` and takes, at each station, the largest
    distance from the axis of the slice's edge crossings as the radius.  Only meaningful for
    (nearly) axisymmetric bodies whose axis is the mesh ``axis`` through the origin of the other
    two coordinates.
    """
    tri = np.asarray(tri, float)
    if tri.ndim != 3 or tri.shape[1:] != (3, 3) or tri.shape[0] == 0:
        raise HydroError(f"mesh {name!r}: expected triangles of shape (n, 3, 3), got {tri.shape}")
    if axis not in (0, 1, 2):
        raise HydroError(f"mesh {name!r}: axis must be 0, 1 or 2, got {axis!r}")
    others = [i for i in range(3) if i != axis]
    p0 = tri.reshape(-1, 3)
    xmin, xmax = p0[:, axis].min(), p0[:, axis].max()
    if xmax <= xmin:
        raise HydroError(f"mesh {name!r}: zero extent along axis {axis}")
    xs = np.linspace(xmin, xmax, n_stations)
    a = np.concatenate([tri[:, 0], tri[:, 1], tri[:, 2]])  # edges of all triangles
    b = np.concatenate([tri[:, 1], tri[:, 2], tri[:, 0]])
    radii = np.zeros(n_stations)
    for i, xi in enumerate(xs):
        da, db = a[:, axis] - xi, b[:, axis] - xi
        cross = (da * db) <= 0
        if not np.any(cross):
            continue
        aa, bb = a[cross], b[cross]
        den = bb[:, axis] - aa[:, axis]
        safe = np.where(den == 0, 1.0, den)
        t = np.where(den != 0, (xi - aa[:, axis]) / safe, 0.0)
        pts = aa + t[:, None] * (bb - aa)
        radii[i] = np.max(np.hypot(pts[:, others[0]], pts[:, others[1]]))
    return HullGeometry(x=xs - xmin, r=radii, name=name, source=source, meta={"kind": "mesh"})
