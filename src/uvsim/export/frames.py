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


#: Mass (kg) and principal inertia (kg m^2) of each exported thruster link: nominal, small
#: values that both physics engines accept for a spinning child link; they are taken out of
#: the base link (:func:`base_link_inertial`) so that the whole model keeps uvsim's mass.
THRUSTER_LINK_MASS = 1e-3
THRUSTER_LINK_INERTIA = 1e-6


def _point_inertia(m: float, p: np.ndarray) -> np.ndarray:
    """Inertia about the origin of a point mass ``m`` at ``p`` (parallel-axis term)."""
    return m * (np.dot(p, p) * np.eye(3) - np.outer(p, p))


def base_link_inertial(vehicle, thruster_positions) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass (kg), centre of mass (3,) and inertia about it (3x3) of the base link, FRD, such
    that the base link and the thruster links (:data:`THRUSTER_LINK_MASS` each, at
    ``thruster_positions`` (k, 3) FRD, inertia :data:`THRUSTER_LINK_INERTIA` I) together have
    uvsim's mass, centre of gravity and inertia about the origin.

    Without this the thruster links would add k grams of weight that no buoyancy carries
    (8 g and 0.078 N on the BlueROV2 Heavy, 2 % of its 3.3 N net buoyancy)."""
    P = np.asarray(thruster_positions, float).reshape(-1, 3)
    mt, k = THRUSTER_LINK_MASS, P.shape[0]
    mb = vehicle.mass - k * mt
    if not mb > 0.5 * vehicle.mass:
        raise VehicleError(f"{vehicle.source}: mass {vehicle.mass:g} kg is too small for {k} thruster links of "
                           f"{mt:g} kg each")
    cb = (vehicle.mass * np.asarray(vehicle.r_g, float) - mt * P.sum(axis=0)) / mb
    J = vehicle.inertia_matrix - sum((_point_inertia(mt, p) + THRUSTER_LINK_INERTIA * np.eye(3) for p in P),
                                     np.zeros((3, 3)))
    Jb = J - _point_inertia(mb, cb)
    if np.any(np.linalg.eigvalsh(0.5 * (Jb + Jb.T)) <= 0):
        raise VehicleError(f"{vehicle.source}: the inertia left for the base link after the thruster links is not "
                           "positive definite")
    return float(mb), cb, Jb
