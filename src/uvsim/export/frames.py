"""The one frame conversion between uvsim and Gazebo, and the coefficient matrices it acts on.

uvsim works in NED (world) and FRD (body: x forward, y starboard, z down), SNAME
notation (docs/model.md).  Gazebo (gz-sim, and Gazebo classic under UUV Simulator)
works in ENU (world) and FLU (body/link: x forward, y left/port, z up), REP-103.

* **Body FRD -> FLU**: ``S = diag(1, -1, -1)`` on vectors, ``S6 = diag(1, -1, -1, 1, -1, -1)``
  on 6-DOF velocities and forces (a rotation of pi about x: ``S`` is its own inverse).
  A 6x6 coefficient matrix ``A`` (added mass, linear damping) becomes ``S6 A S6``: the
  diagonal is unchanged and an off-diagonal term changes sign exactly when one of its
  two DOFs is in {y, z, pitch, yaw}'s set and the other in {x, roll}'s, e.g.
  ``X_vdot`` -> ``-X_vdot``, ``Y_wdot`` unchanged, ``K_qdot`` -> ``-K_qdot``, ``M_rdot`` unchanged.
  A quadratic term ``A_ij |nu_j| nu_j`` transforms the same way (``|nu_j|`` is invariant).
  Positions (CG, CB, thrusters) and directions map with ``S``; an inertia tensor with
  ``S J S``.
* **World NED -> ENU**: ``(n, e, d) -> (e, n, -d)`` (used for the ocean current).

UUV Simulator converts Gazebo's FLU velocities to FRD itself before applying Fossen's
model (``HydrodynamicModel::ToNEDConvention`` negates y and z), so its coefficients are
written in uvsim's FRD form; only positions it reads in the link frame (centre of
buoyancy, thruster joints) are converted with ``S``.
"""
from __future__ import annotations

import numpy as np

from uvsim.errors import VehicleError

S3 = np.diag([1.0, -1.0, -1.0])
S6 = np.diag([1.0, -1.0, -1.0, 1.0, -1.0, -1.0])
#: SNAME letters of force/moment rows and velocity columns (gz-sim parameter names)
FORCE = "xyzkmn"
VEL = "UVWPQR"


def frd_to_flu_matrix(A: np.ndarray) -> np.ndarray:
    """``S6 A S6`` for a 6x6 coefficient matrix (its own inverse)."""
    return S6 @ np.asarray(A, float) @ S6


def frd_to_flu_vector(v) -> np.ndarray:
    return S3 @ np.asarray(v, float)


def ned_to_enu(v) -> np.ndarray:
    v = np.asarray(v, float)
    return np.array([v[1], v[0], -v[2]])


def damping_matrices(vehicle) -> tuple[np.ndarray, np.ndarray]:
    """Linear ``D_L`` and quadratic ``D_Q`` (6x6, paper sign, FRD) of a vehicle:
    ``tau_D = D_L nu + D_Q (|nu| * nu)``."""
    from uvsim.forces.damping import LINEAR_NAMES, QUADRATIC_NAMES, CoupledDamping, DiagonalDamping

    d = vehicle.damping
    if isinstance(d, DiagonalDamping):
        p = d.parameters()
        return np.diag([p[k] for k in LINEAR_NAMES]), np.diag([p[k] for k in QUADRATIC_NAMES])
    if isinstance(d, CoupledDamping):
        return d.DL.copy(), d.DQ.copy()
    raise VehicleError(f"{vehicle.source}: damping type {d.kind!r} cannot be exported (diagonal and coupled can)")


def inertia_about_cg(vehicle) -> np.ndarray:
    """Inertia tensor (3x3, FRD) about the centre of gravity from uvsim's tensor about
    the body origin (parallel-axis theorem)."""
    r = np.asarray(vehicle.r_g, float)
    return vehicle.inertia_matrix - vehicle.mass * (np.dot(r, r) * np.eye(3) - np.outer(r, r))
