"""The target simulators' hydrodynamic plugins, re-implemented from their sources in numpy.

Used by the replay check (:mod:`uvsim.export.replay`) and the tests to show what the
exported model does inside each target, term by term.  Each function cites the file and
the lines of the commit it was written from; where a target's docstring and its code
disagree, the code is followed.

gz-sim ``Hydrodynamics`` system (gazebosim/gz-sim, commit 93bbf3ed1bd2, 2026-07-02):

* ``HydrodynamicsUtils.hh:45-72`` ``buildCoriolisMatrix(Ma, v)``: with the plugin's
  Fossen-negative ``Ma`` (``xDotU < 0``) the matrix it builds equals ``C_A(v)`` of Fossen
  2011 eq. 6.43 entry by entry, not ``-C_A`` as its docstring (lines 35-44) says
  (:func:`gz_coriolis_matrix`; checked against eq. 6.43 in the tests);
* ``Hydrodynamics.cc:552-555`` the acceleration is the one-step finite difference
  ``(v_k - v_{k-1}) / dt`` of the body velocity at the physics step;
* ``Hydrodynamics.cc:557-591`` ``kTotalWrench = -Ma v_dot - Cmat v + Dmat v``, with
  ``Dmat = -(linear + quadAbs |v| + quad v)`` (``HydrodynamicsUtils.hh:89-114``);
* ``Hydrodynamics.cc:593-621`` with ``<fluid_added_mass>`` a correction
  ``Ca_rel v_r - Ca_abs v`` (``buildFullCoriolisMatrix``, lines 150-172, positive M_A) so
  that the engine's implicit ``-C_A(v) v`` becomes ``-C_A(v_r) v_r``;
* ``Hydrodynamics.cc:623-630`` the wrench applied to the link is ``-kTotalWrench``.

So the plugin applies ``+Ma v_dot`` (= ``-M_A v_dot``, right), the damping (right) and
``+C_A(v) v`` where Fossen's equation of motion has ``-C_A(v) v``: with plugin added mass
the Munk moment has the wrong sign in gz-sim.  With ``<fluid_added_mass>`` the plugin's
``Ma`` is zero, the physics engine carries ``M_A`` in the link's spatial inertia (gz-math
``Inertial.hh:76-77``: expressed in the link origin frame; ``SpatialMatrix`` = body +
added, lines 207-211) and, per the plugin's own comment (``Hydrodynamics.cc:595-599``),
applies ``-C_A(v) v`` implicitly.

UUV Simulator ``HMFossen`` (uuvsimulator/uuv_simulator, commit bfb40cb15368, 2020-06-15,
``uuv_gazebo_plugins/src/HydrodynamicModel.cc``):

* lines 102-125 ``ComputeAcc``: ``a_k = (v_k - v_{k-1}) / dt``, low-pass filtered
  ``af_k = (1 - alpha) af_{k-1} + alpha a_k`` with ``alpha = 0.3`` (line 400); the last velocity
  starts at zero (line 29);
* lines 360-446: ``tau = -D(v) v - M_A af - C_A(v) v`` (line 415) in FRD (``ToNED`` negates y and z,
  lines 128-140), ``C_A`` by Fossen eq. 6.43 (lines 449-460, positive ``M_A``),
  ``D = -(D_lin + D_quad |v|)`` (lines 463-487).

All vectors here are 6-DOF ``[force; moment]`` or ``[linear; angular]`` velocity in the
target's own body frame (gz-sim: FLU link frame; UUV Simulator: FRD after its flip).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from uvsim.rigid_body import skew

GZ_SIM_COMMIT = "93bbf3ed1bd25df32709fee40d6935bf36d2bac8"
UUV_SIMULATOR_COMMIT = "bfb40cb153684a0703173117b6bbf4258e8e71c5"
#: Where gz-sim applies the added-mass Coriolis term with the sign opposite to Fossen's.
GZ_CORIOLIS_SOURCE = ("gz-sim src/systems/hydrodynamics/HydrodynamicsUtils.hh:45-72 (buildCoriolisMatrix builds "
                      "+C_A, its docstring says -C_A) and Hydrodynamics.cc:575-580, 623-630 (adds -Cmat*v to "
                      f"kTotalWrench, applies -kTotalWrench), commit {GZ_SIM_COMMIT[:12]}")
#: UUV Simulator's acceleration filter constant (HydrodynamicModel.cc:400).
UUV_ALPHA = 0.3


def gz_coriolis_matrix(Ma: np.ndarray, s: np.ndarray) -> np.ndarray:
    """``buildCoriolisMatrix`` (HydrodynamicsUtils.hh:45-72): diagonal of ``Ma`` only,
    entries copied line by line.  ``Ma`` (6, 6) Fossen-negative; ``s`` (6,)."""
    C = np.zeros((6, 6))
    C[0, 4] = -Ma[2, 2] * s[2]
    C[0, 5] = Ma[1, 1] * s[1]
    C[1, 3] = Ma[2, 2] * s[2]
    C[1, 5] = -Ma[0, 0] * s[0]
    C[2, 3] = -Ma[1, 1] * s[1]
    C[2, 4] = Ma[0, 0] * s[0]
    C[3, 1] = -Ma[2, 2] * s[2]
    C[3, 2] = Ma[1, 1] * s[1]
    C[3, 4] = -Ma[5, 5] * s[5]
    C[3, 5] = Ma[4, 4] * s[4]
    C[4, 0] = Ma[2, 2] * s[2]
    C[4, 2] = -Ma[0, 0] * s[0]
    C[4, 3] = Ma[5, 5] * s[5]
    C[4, 5] = -Ma[3, 3] * s[3]
    C[5, 0] = -Ma[1, 1] * s[1]
    C[5, 1] = Ma[0, 0] * s[0]
    C[5, 3] = -Ma[4, 4] * s[4]
    C[5, 4] = Ma[3, 3] * s[3]
    return C


def fossen_added_coriolis(MA: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``C_A(v)`` of Fossen 2011 eq. 6.43 for a positive (symmetric) ``M_A``: also gz-sim's
    ``buildFullCoriolisMatrix`` (HydrodynamicsUtils.hh:150-172) and UUV Simulator's
    ``ComputeAddedCoriolisMatrix`` (HydrodynamicModel.cc:449-460)."""
    a = MA[:3, :3] @ v[:3] + MA[:3, 3:] @ v[3:]
    b = MA[3:, :3] @ v[:3] + MA[3:, 3:] @ v[3:]
    C = np.zeros((6, 6))
    C[:3, 3:] = -skew(a)
    C[3:, :3] = -skew(a)
    C[3:, 3:] = -skew(b)
    return C


def gz_damping_wrench(linear: np.ndarray, quad_abs: np.ndarray, s: np.ndarray) -> np.ndarray:
    """The damping part of the applied wrench, ``-Dmat s`` with ``Dmat`` of
    ``buildDampingMatrix`` (HydrodynamicsUtils.hh:89-114) for ``quad = 0`` (uvsim writes no
    ``xUU`` terms): ``sum_j (L_ij + sum_k Q_ijk |s_k|) s_j``.  ``linear`` (6, 6) the ``<xU>``
    values, ``quad_abs`` (6, 6, 6) the ``<xUabsV>`` values."""
    D = -linear - np.einsum("ijk,k->ij", quad_abs, np.abs(s))
    return -D @ s


@dataclass
class GzHydrodynamics:
    """The gz-sim Hydrodynamics system of one link, as configured by an SDF that
    :func:`uvsim.export.gz_sim.gz_sdf` wrote (numbers from :func:`parse_gz_sdf`, FLU).

    ``wrench(state, dt)`` returns the terms it applies at one physics step (FLU body
    frame): ``added_mass`` (``+Ma v_dot``), ``coriolis`` (``+Cmat v``), ``damping`` and
    ``total``, updating the stored previous velocity as the plugin does."""

    Ma: np.ndarray                 # plugin xDotU.. terms (Fossen-negative); zeros with fluid added mass
    linear: np.ndarray
    quad_abs: np.ndarray
    fluid_added_mass: np.ndarray | None = None
    #: +1: the plugin as written (``kCmatVec = -Cmat * state``, line 578); -1: that sign patched
    coriolis_sign: float = 1.0
    prev: np.ndarray | None = field(default=None, repr=False)

    @classmethod
    def from_sdf(cls, parsed: dict, coriolis_sign: float = 1.0) -> "GzHydrodynamics":
        q = np.zeros((6, 6, 6))
        for i in range(6):
            for j in range(6):
                q[i, j, j] = parsed["quadratic"][i, j]
        if parsed["fluid_added_mass"]:
            return cls(np.zeros((6, 6)), parsed["linear"], q, parsed["added_mass"], coriolis_sign)
        return cls(-parsed["added_mass"], parsed["linear"], q, None, coriolis_sign)

    def wrench(self, state: np.ndarray, dt: float, abs_state: np.ndarray | None = None) -> dict:
        s = np.asarray(state, float)
        if self.prev is None:  # Hydrodynamics.cc:544-549: first iteration starts from the velocity
            self.prev = s.copy()
        s_dot = (s - self.prev) / dt          # Hydrodynamics.cc:552-553
        self.prev = s.copy()
        out = {"added_mass": self.Ma @ s_dot,                       # -(-Ma s_dot)
               "coriolis": self.coriolis_sign * gz_coriolis_matrix(self.Ma, s) @ s,  # -(-Cmat s)
               "damping": gz_damping_wrench(self.linear, self.quad_abs, s)}
        corr = np.zeros(6)
        if self.fluid_added_mass is not None:  # Hydrodynamics.cc:600-621 (zero without a current)
            a = s if abs_state is None else np.asarray(abs_state, float)
            corr = -(fossen_added_coriolis(self.fluid_added_mass, s) @ s
                     - fossen_added_coriolis(self.fluid_added_mass, a) @ a)
        out["current_correction"] = corr
        out["total"] = out["added_mass"] + out["coriolis"] + out["damping"] + corr
        return out


@dataclass
class UuvFossen:
    """UUV Simulator's ``HMFossen`` of one link (FRD numbers, as its xacro holds them):
    ``wrench(state, dt)`` returns ``damping``, ``added_mass`` (``-M_A af``), ``coriolis``
    (``-C_A(v) v``) and ``total`` at one physics step, filtering the acceleration as the
    plugin does."""

    MA: np.ndarray
    linear: np.ndarray
    quadratic_diag: np.ndarray
    alpha: float = UUV_ALPHA
    prev: np.ndarray | None = field(default=None, repr=False)
    filtered: np.ndarray = field(default_factory=lambda: np.zeros(6), repr=False)

    def wrench(self, state: np.ndarray, dt: float) -> dict:
        v = np.asarray(state, float)
        if self.prev is None:  # lastVelRel starts at zero (HydrodynamicModel.cc:29)
            self.prev = np.zeros(6)
        acc = (v - self.prev) / dt
        self.filtered = (1.0 - self.alpha) * self.filtered + self.alpha * acc
        self.prev = v.copy()
        D = -self.linear - np.diag(self.quadratic_diag * np.abs(v))
        out = {"damping": -D @ v, "added_mass": -self.MA @ self.filtered,
               "coriolis": -fossen_added_coriolis(self.MA, v) @ v}
        out["total"] = out["damping"] + out["added_mass"] + out["coriolis"]
        return out
