"""The pieces of a component build-up (:class:`uvsim.sam.buildup.ComponentBuildup`): a
component's resolved geometry and table (:class:`Component`), the keys a vehicle file's
``components`` entry may have, the checks of their values, the cached body and wing tables
(:mod:`uvsim.hydro`), and the rotations of a component (roll-pitch-yaw) and of the
thrust-vectoring gimbal.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from uvsim.errors import VehicleError


def rotation_rpy(rpy_deg) -> np.ndarray:
    """Rotation component -> body from roll, pitch, yaw (deg, ZYX convention), (3, 3)."""
    r, p, y = np.radians(np.asarray(rpy_deg, float))
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return Rz @ Ry @ Rx


def gimbal_matrix(tv_pitch, tv_yaw) -> np.ndarray:
    """Rotation of the thrust-vectoring unit, ``G = R_y(-tv_pitch) R_z(-tv_yaw)`` ((3, 3) or
    (n, 3, 3)), which turns the body x axis into the thrust direction of
    :class:`uvsim.sam.subsystems.Propulsion`, ``[cos dp cos dy, -sin dy, sin dp cos dy]``."""
    dp, dy = np.asarray(tv_pitch, float), np.asarray(tv_yaw, float)
    c, s, cy, sy = np.cos(dp), np.sin(dp), np.cos(dy), np.sin(dy)
    z = np.zeros_like(c)
    rows = [[c * cy, c * sy, -s], [-sy, cy, z], [s * cy, s * sy, c]]
    return np.stack([np.stack(r, -1) for r in rows], -2)


def matmul33(A, B):
    """Product of two 3x3 matrices given as row-major 9-sequences (plain floats)."""
    a0, a1, a2, a3, a4, a5, a6, a7, a8 = A
    b0, b1, b2, b3, b4, b5, b6, b7, b8 = B
    return (a0 * b0 + a1 * b3 + a2 * b6, a0 * b1 + a1 * b4 + a2 * b7, a0 * b2 + a1 * b5 + a2 * b8,
            a3 * b0 + a4 * b3 + a5 * b6, a3 * b1 + a4 * b4 + a5 * b7, a3 * b2 + a4 * b5 + a5 * b8,
            a6 * b0 + a7 * b3 + a8 * b6, a6 * b1 + a7 * b4 + a8 * b7, a6 * b2 + a7 * b5 + a8 * b8)


@lru_cache(maxsize=32)
def body_table(hull_json: str, dataset: str, nu: float, re_key: tuple | None, cdn_model: str = "subcritical",
                munk_in_table: bool = False):
    from uvsim.hydro.assembly import build_body_table
    from uvsim.hydro.body import BodyModel
    from uvsim.hydro.geometry import hull_from_dict, load_hull

    spec = json.loads(hull_json)
    hull = load_hull(spec) if isinstance(spec, str) else hull_from_dict(spec, name=spec.get("name", "hull"),
                                                                        where="component_buildup hull")
    body = BodyModel(hull, nu=nu, cdn_model=cdn_model, munk_moment=munk_in_table)
    re_grid = None if re_key is None else np.asarray(re_key, float)
    return body, build_body_table(body, re_grid=re_grid, method=dataset)


@lru_cache(maxsize=32)
def wing_table(aspect_ratio: float, oswald: float):
    from uvsim.hydro.assembly import naca0015_table

    return naca0015_table(aspect_ratio=aspect_ratio, oswald=oswald)


@dataclass
class Component:
    """One component of the build-up (resolved geometry and table).

    Attributes
    ----------
    name, kind : str ("body" or "wing")
    r : (3,) origin in the body frame, m (hull: moment reference station; wing: quarter chord)
    C : (3, 3) rotation component -> body
    area : reference area, m^2 (hull: frontal area; wing: planform area)
    length : reference length, m (hull: length; wing: chord)
    table : :class:`uvsim.hydro.HydroTable`
    """

    name: str
    kind: str
    r: np.ndarray
    C: np.ndarray
    area: float
    length: float
    table: object
    gimbal: bool = False


def vec3_field(spec, key, where, default=None):
    val = spec.get(key, default)
    a = np.asarray(val, float) if val is not None else None
    if a is None or a.shape != (3,) or not np.all(np.isfinite(a)):
        raise VehicleError(f"{where}.{key}: expected 3 finite numbers, got {val!r}")
    return a


def positive_field(spec, key, where):
    try:
        v = float(spec[key])
    except (KeyError, TypeError, ValueError):
        raise VehicleError(f"{where}.{key}: expected a positive number, got {spec.get(key)!r}") from None
    if not (np.isfinite(v) and v > 0):
        raise VehicleError(f"{where}.{key}: expected a positive number, got {v}")
    return v


#: Keys of a ``components`` entry, by kind (see :class:`ComponentBuildup`).
COMPONENT_KEYS = {
    "body": ("name", "kind", "hull", "nose", "rpy_deg"),
    "wing": ("name", "kind", "position", "rpy_deg", "area", "chord", "aspect_ratio", "oswald", "gimbal"),
}
