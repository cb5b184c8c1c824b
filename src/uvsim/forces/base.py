"""The force-term plug-in interface.

Every generalized force acting on the vehicle, apart from the inertial and Coriolis
terms, is a :class:`ForceTerm`: restoring forces, damping, actuators and additional
effects (tether, thruster dynamics, ...).  A term is a small strategy object
(filterpy-style) with two phases:

* ``prepare(params, n)`` is called once per simulation with the model's named
  parameters (each a float or an array of shape ``(n,)`` for a batch of ``n``
  parameter sets) and returns whatever the term wants precomputed;
* ``forces(ctx, prep)`` is called at every integrator stage and returns the
  generalized force ``tau`` (shape ``(n, 6)``, body frame, N and N m) that the term
  applies *to* the vehicle (so damping returns ``-D(nu_r) nu_r`` and restoring
  returns ``-g(eta)``).

A term may own internal states (``n_states > 0``, e.g. first-order thruster
dynamics); the model appends them to the state vector and integrates
``state_derivative``.  A term may change the mass properties (``changes_mass``),
e.g. a variable-buoyancy tank; the model then rebuilds ``M_RB`` each stage.  A term
that adds a constant mass (a ballast piece) says so in ``fixed_mass_properties``; the
model folds it into ``M_RB`` once.
Terms declare the named scalar parameters they read in ``parameters()`` so that a
calibration can vary them, and the NED position axes they read from ``ctx.pos`` in
``position_axes`` (a tether's line, the floor's height; most terms read none): the fits
take a node moved along an unread axis as the same trajectory shifted, with no
simulation (:func:`uvsim.fitting.linearization.linearize`).  A term that does not say is taken
to read all three, which is always correct, only slower.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from uvsim.forces.registry import build_term


@dataclass
class Context:
    """Quantities shared by all terms at one integrator stage (batched, ``n`` rows).

    Attributes
    ----------
    t : float or (n,) array
        Time, s: one float when every row shares the time grid, else each row's own time.
    pos : (n, 3) NED position, m.
    q : (n, 4) unit quaternion body -> NED, scalar first.
    R : (n, 3, 3) rotation matrix body -> NED.
    nu : (n, 6) body velocity [u, v, w, p, q, r].
    nu_r : (n, 6) velocity relative to the water, ``nu - nu_c``.
    u : (n, k) inputs held over the current sample interval (forces, thrusts or PWM).
    input_kind : "force" | "thrust" | "pwm".
    weight, mass : (n,) current weight W (N) and mass (kg).
    r_g : (n, 3) current centre of gravity, m.
    states : dict term index -> (n, k_i) internal states of that term.
    params : the model's named parameters (floats or (n,) arrays).
    mass_changed : True when a mass-changing term altered weight / CG at this stage.
    voltage : (n,) battery voltage (V) held over the current sample interval, or None
        when the run logged none (voltage-dependent thrust curves then use their
        nominal voltage; NaN entries mean the same for that row).
    """

    t: Any
    pos: np.ndarray
    q: np.ndarray
    R: np.ndarray
    nu: np.ndarray
    nu_r: np.ndarray
    u: np.ndarray
    input_kind: str
    weight: np.ndarray
    mass: np.ndarray
    r_g: np.ndarray
    states: dict
    params: Mapping[str, Any]
    mass_changed: bool = False
    voltage: Any = None


class ForceTerm:
    """Base class of all force plug-ins (see module docstring)."""

    #: registry name used in vehicle files
    kind: str = "term"
    #: number of internal states
    n_states: int = 0
    #: whether ``mass_properties`` returns non-zero changes
    changes_mass: bool = False
    #: NED position axes (0 north, 1 east, 2 down) that the term's forces or state
    #: derivatives read from ``ctx.pos``.  Along the others a shifted start shifts the whole
    #: trajectory and nothing else, which the fits use for their node Jacobians
    #: (:func:`uvsim.fitting.linearization.linearize`).  A plug-in that does not say is taken to
    #: read all three.
    position_axes: tuple = (0, 1, 2)

    def parameters(self) -> dict[str, float]:
        """Named scalar parameters with their current values."""
        return {}

    def check_values(self, values: Mapping[str, np.ndarray]) -> None:
        """Raise :class:`uvsim.errors.VehicleError` when a value given for one of this
        term's named parameters (each an array, one entry per parameter set) breaks the
        rule the vehicle-file loader applies to that field (e.g. a positive damping
        coefficient).  Called for overrides, so the API and the YAML agree."""

    def bind(self, vehicle, index: int) -> "ForceTerm":
        """Called when a :class:`uvsim.model.Model` is built: a term that needs the
        vehicle (e.g. its thruster allocation) or its own position ``index`` in the term
        list (the key of its states in ``ctx.states``) returns a bound copy."""
        return self

    def prepare(self, params: Mapping[str, Any], n: int) -> Any:
        return None

    def forces(self, ctx: Context, prep: Any) -> np.ndarray:
        raise NotImplementedError

    def kernel_part(self, prep: Any):
        """This term's form in the compiled RK4 (:mod:`uvsim.kernels`), or None (the default):
        a plug-in the compiled kernel does not know runs on the numpy path, which stays the
        reference.  Known forms: ``("restoring", G)`` (a force ``k G`` linear in the body's
        down axis ``k``, G (3, 6) or (n, 3, 6)), ``("diagonal", D_L, D_Q)``,
        ``("coupled", D_L, D_Q)``, ``("tether", values (n, 12))`` (the layout of
        ``uvsim.kernels.rk4_equations.O_TE``), ``("none",)`` (no force of its own) and ``("held",)``:
        a force fixed over each sample interval by the input, which the term computes in
        numpy by ``held_along(U (n, m, k), kind, prep, V (n, m) or None, rows) -> (n, m, 6)``
        (``rows``: :func:`uvsim.forces.actuators.distinct_histories`, or None)."""
        return None

    def state_derivative(self, ctx: Context, prep: Any, x: np.ndarray) -> np.ndarray:
        return np.zeros((ctx.nu.shape[0], 0))

    def initial_state(self, prep: Any, n: int, u0: np.ndarray, input_kind: str) -> np.ndarray:
        return np.zeros((n, self.n_states))

    def states_along(self, prep: Any, T: np.ndarray, U: np.ndarray, input_kind: str, V=None, x0=None):
        """The term's states (n, L, n_states) along whole input histories ``T`` (n, L),
        ``U`` (n, L, k) (voltage ``V`` (n, L) or None), from ``x0`` (n, n_states), when
        they depend on the inputs only and have a closed form (e.g. a first-order lag
        of zero-order-held commands); None otherwise (the caller integrates
        :meth:`state_derivative` along a vehicle trajectory instead)."""
        return None

    def state_names(self) -> list[str]:
        return [f"{self.kind}_{i}" for i in range(self.n_states)]

    def mass_properties(self, ctx: Context, prep: Any, x: np.ndarray):
        """Changes ``(dm (n,), d_first_moment (n, 3), dI (n, 3, 3))`` about the body origin."""
        raise NotImplementedError

    def fixed_mass_properties(self, params: Mapping[str, Any], n: int):
        """Constant mass the term adds to the rigid body (e.g. a ballast piece's own mass):
        ``(dm (n,), d_first_moment (n, 3), dI (n, 3, 3))`` about the body origin, or None.
        :class:`uvsim.model.Model` folds it into ``M_RB`` (and so into ``C_RB``) once, at
        construction; the term's weight stays in its own :meth:`forces`."""
        return None

    def to_dict(self) -> dict:
        """Vehicle-file representation (inverse of the registry constructor)."""
        return {"type": self.kind}

    def with_parameters(self, values: Mapping[str, float]) -> "ForceTerm":
        """A copy with some named parameters replaced (used to write fitted vehicles)."""
        d = self.to_dict()
        _replace_in(d, values)
        return build_term(d, context=self.kind)


def position_axes_read(terms) -> set[int]:
    """The NED position axes (0 north, 1 east, 2 down) some of ``terms`` read from ``ctx.pos``
    (``ForceTerm.position_axes``; a term that does not say is taken to read all three)."""
    return {a for t in terms for a in getattr(t, "position_axes", (0, 1, 2))}


def _replace_in(d: dict, values: Mapping[str, float]) -> None:
    for key, val in list(d.items()):
        if isinstance(val, dict):
            _replace_in(val, values)
        elif key in values:
            d[key] = float(values[key])


def first_violation(values, ok, name: str) -> str:
    """``"X_u = 50"`` (or ``"X_u = 50 in parameter set 3"`` for arrays) for the first entry
    of ``values`` where ``ok`` is False; ``""`` when every entry is ok."""
    a = np.atleast_1d(np.asarray(values, float))
    bad = np.flatnonzero(~np.broadcast_to(ok, a.shape))
    if not bad.size:
        return ""
    i = int(bad[0])
    return f"{name} = {a[i]:g}" + (f" in parameter set {i}" if a.size > 1 else "")


def param(params: Mapping[str, Any], name: str, n: int) -> np.ndarray:
    """Parameter ``name`` as an array of shape ``(n,)`` (broadcast from a float)."""
    return np.broadcast_to(np.asarray(params[name], dtype=float), (n,))
