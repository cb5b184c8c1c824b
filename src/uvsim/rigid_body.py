"""Rigid-body and added-mass matrices and Coriolis-centripetal terms.

Notation follows Fossen (2021), *Handbook of Marine Craft Hydrodynamics and Motion
Control*, 2nd ed.: ``nu = [u, v, w, p, q, r]``, ``M_RB`` eq. (3.44) (seed 002 eq. 2),
and the parameterization-independent Coriolis matrix eq. (3.46)/(6.43):

    C(nu) = [[ 0_3x3,          -S(M11 nu1 + M12 nu2)],
             [-S(M11 nu1 + M12 nu2), -S(M21 nu1 + M22 nu2)]]

which is skew-symmetric for any symmetric 6x6 ``M`` (rigid body with CG offset and
full inertia tensor, or a full added-mass matrix).  Functions broadcast over leading
axes: ``M`` is ``(..., 6, 6)`` and ``nu`` is ``(..., 6)``.
"""
from __future__ import annotations

import numpy as np


def skew(a: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrix ``S(a)`` with ``S(a) b = a x b``; ``(..., 3) -> (..., 3, 3)``."""
    a = np.asarray(a, dtype=float)
    S = np.zeros(a.shape[:-1] + (3, 3))
    S[..., 0, 1], S[..., 0, 2] = -a[..., 2], a[..., 1]
    S[..., 1, 0], S[..., 1, 2] = a[..., 2], -a[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -a[..., 1], a[..., 0]
    return S


def inertia_tensor(Ixx, Iyy, Izz, Ixy=0.0, Ixz=0.0, Iyz=0.0) -> np.ndarray:
    """Inertia tensor about the body origin with Fossen's product-of-inertia signs
    (Fossen 2021 eq. 3.34), broadcasting over array arguments -> (..., 3, 3)."""
    arrs = np.broadcast_arrays(*[np.asarray(a, float) for a in (Ixx, Iyy, Izz, Ixy, Ixz, Iyz)])
    Ixx, Iyy, Izz, Ixy, Ixz, Iyz = arrs
    Ixy, Ixz, Iyz = Ixy + 0.0, Ixz + 0.0, Iyz + 0.0
    row0 = np.stack([Ixx, 0.0 - Ixy, 0.0 - Ixz], -1)
    row1 = np.stack([0.0 - Ixy, Iyy, 0.0 - Iyz], -1)
    row2 = np.stack([0.0 - Ixz, 0.0 - Iyz, Izz], -1)
    return np.stack([row0, row1, row2], -2)


def rigid_body_mass_matrix(mass, inertia, r_g) -> np.ndarray:
    """``M_RB`` about the body origin (Fossen 2021 eq. 3.44; seed 002 eq. 2).

    Parameters
    ----------
    mass : array_like, shape (...)
        Mass m, kg.
    inertia : array_like, shape (..., 3, 3)
        Inertia tensor about the body origin ``I_b`` (kg m^2), symmetric, with the
        products of inertia entering as ``-I_xy`` etc. exactly as written in the tensor.
    r_g : array_like, shape (..., 3)
        Centre of gravity in body coordinates, m.

    Returns
    -------
    ndarray, shape (..., 6, 6)
    """
    mass = np.asarray(mass, dtype=float)
    inertia = np.asarray(inertia, dtype=float)
    r_g = np.asarray(r_g, dtype=float)
    shape = np.broadcast_shapes(mass.shape, inertia.shape[:-2], r_g.shape[:-1])
    M = np.zeros(shape + (6, 6))
    m = np.broadcast_to(mass, shape)
    mS = m[..., None, None] * skew(np.broadcast_to(r_g, shape + (3,)))
    M[..., 0, 0] = M[..., 1, 1] = M[..., 2, 2] = m
    M[..., :3, 3:] = -mS
    M[..., 3:, :3] = mS
    M[..., 3:, 3:] = np.broadcast_to(inertia, shape + (3, 3))
    return M


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the last axis, written out (faster than ``np.cross`` on small batches)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def coriolis_vector(M: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """``C(nu) nu`` for the Coriolis matrix induced by ``M`` (Fossen 2021 eq. 3.46).

    With ``[a; b] = M nu`` (a linear, b angular part) and ``nu = [v; w]`` this is
    ``[w x a; v x a + w x b]``.  Shapes: ``M`` (..., 6, 6), ``nu`` (..., 6) -> (..., 6).
    """
    ab = np.einsum("...ij,...j->...i", M, nu)
    return coriolis_from_momentum(ab, nu)


def coriolis_from_momentum(ab: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """``C(nu) nu`` given the generalized momentum ``ab = M nu`` (see :func:`coriolis_vector`)."""
    a, b = ab[..., :3], ab[..., 3:]
    v, w = nu[..., :3], nu[..., 3:]
    return np.concatenate([cross(w, a), cross(v, a) + cross(w, b)], axis=-1)


def m2c(M: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """Coriolis-centripetal matrix ``C(nu)`` from a 6x6 mass matrix (Fossen's ``m2c``,
    eq. 3.46).  ``M`` is symmetrized first.  Shapes (..., 6, 6), (..., 6) -> (..., 6, 6)."""
    M = 0.5 * (np.asarray(M, dtype=float) + np.swapaxes(M, -1, -2))
    nu = np.asarray(nu, dtype=float)
    ab = np.einsum("...ij,...j->...i", M, nu)
    Sa, Sb = skew(ab[..., :3]), skew(ab[..., 3:])
    C = np.zeros(np.broadcast_shapes(M.shape, nu.shape[:-1] + (6, 6)))
    C[..., :3, 3:] = -Sa
    C[..., 3:, :3] = -Sa
    C[..., 3:, 3:] = -Sb
    return C
