"""Actuators: thrusters with position and direction -> allocation (configuration) matrix.

For thruster ``i`` at body position ``r_i`` with unit thrust direction ``d_i`` the
column of the allocation matrix is ``[d_i; r_i x d_i]`` (Fossen 2021 eq. 11.6), so
``tau = B f`` for thrusts ``f`` (N).  A vehicle may instead give the matrix itself
(seed 002 eq. 9).  Inputs can be generalized forces (used as ``tau``), per-thruster
thrust (N) or per-thruster ESC PWM (us, mapped by each thruster's curve).

Calibratable actuator parameters (issue 14; each a named model parameter, default 1 or
the vehicle file's value):

* ``thruster_gain_i`` (-): thruster i delivers ``gain_i`` times its curve (a fouled,
  damaged or weaker unit; seed 000 sec. 6 and the logs' authors report such units);
* ``thruster_reverse_i`` (-): extra factor on its reverse (negative) thrust, beyond the
  curve's own reverse branch (propeller asymmetry, seed 002 sec. 5);
* ``thruster_x_i``, ``thruster_y_i``, ``thruster_z_i`` (m): its position (lever arm),
  when the vehicle gives thruster positions (``units``);
* ``force_gain_X`` ... ``force_gain_N`` and ``force_reverse_X`` ... (-): the same per
  degree of freedom for generalized-force inputs;
* ``supply_voltage`` (V), only when the thrusters' curves depend on the supply voltage
  (``curve: {voltage_table: t200, nominal_voltage: 16}``, :mod:`uvsim.voltage_curves`):
  the battery voltage the curves are read at where a run logged none, i.e. the curves'
  ``nominal_voltage`` (one battery feeds every thruster: curves with different nominal
  voltages have no such parameter). A run that logs its voltage
  uses the logged one. Fitting it fits the thrust curve's *shape* within the measured
  family (at low voltage the T200 loses more thrust at full command than near its dead
  band), which no gain can.

With generalized-force inputs the thruster gains and reverse ratios act through the
allocation: the commanded ``tau`` is distributed over the thrusters by the pseudo-inverse
``f = B^+ tau`` (the unconstrained allocation of Fossen 2021 sec. 11.2.3, what a controller
commanding ``tau`` does), scaled per thruster and summed back, ``tau = B f_eff``; with every
factor at 1 this is exactly ``tau``.

So the delivered thrust is ``f_i = gain_i * curve_i(u_i) * (reverse_i if curve_i(u_i) < 0
else 1)`` and ``tau = B(r) f``.  With every parameter at its default the mapping is
exactly the allocation above.

The vehicle file's ``thrusters`` section is read and checked, and fitted parameters written
back into it, by :mod:`uvsim.forces.thrusters_section`; :func:`build_actuators` builds the
term from it.
"""
from __future__ import annotations

import numpy as np

from uvsim.bilinear import matvec
from uvsim.errors import SimulationError, VehicleError
from uvsim.forces import register
from uvsim.forces.base import ForceTerm
from uvsim.forces.thrusters_section import (  # noqa: F401 (allocation_matrix re-exported: it lived here)
    DOF_LETTERS, allocation_matrix, force_factors, section_with_values, thruster_arguments)


@register("actuators")
class Actuators(ForceTerm):
    """Maps the run's inputs to ``tau``.

    Parameters
    ----------
    matrix : (6, n) allocation matrix.
    curves : list of n thrust curves (objects with ``thrust(pwm)``) or None.
    names : thruster names.
    """
    position_axes = ()  # reads no position (ForceTerm.position_axes)

    def __init__(self, matrix=None, curves=None, names=None, specs=None, *, positions=None, directions=None,
                 gains=None, reverse=None, force_gain=None, force_reverse=None):
        self.matrix = None if matrix is None else np.asarray(matrix, float)
        self.curves = curves
        self.names = names
        self.specs = specs  # vehicle-file form, kept for to_dict
        k = self.n_thrusters
        self.positions = None if positions is None else np.asarray(positions, float)
        self.directions = None if directions is None else np.asarray(directions, float)
        self.gains = np.ones(k) if gains is None else np.asarray(gains, float)
        self.reverse = np.ones(k) if reverse is None else np.asarray(reverse, float)
        self.force_gain = np.ones(6) if force_gain is None else np.asarray(force_gain, float)
        self.force_reverse = np.ones(6) if force_reverse is None else np.asarray(force_reverse, float)

    @property
    def n_thrusters(self) -> int:
        return 0 if self.matrix is None else self.matrix.shape[1]

    def _supply_voltage(self) -> float | None:
        """The voltage-dependent curves' common nominal voltage (V); None without such curves,
        or when their nominal voltages differ (thrusters on separate batteries: no one
        ``supply_voltage`` describes them)."""
        volts = {float(c.nominal_voltage) for c in (self.curves or []) if getattr(c, "voltage_dependent", False)}
        return volts.pop() if len(volts) == 1 else None

    def parameters(self) -> dict[str, float]:
        """Named actuator parameters (module docstring) with their current values."""
        out = {}
        for i in range(self.n_thrusters):
            out[f"thruster_gain_{i + 1}"] = float(self.gains[i])
            out[f"thruster_reverse_{i + 1}"] = float(self.reverse[i])
            if self.positions is not None:
                for a, c in enumerate("xyz"):
                    out[f"thruster_{c}_{i + 1}"] = float(self.positions[i, a])
        for j, c in enumerate(DOF_LETTERS):
            out[f"force_gain_{c}"] = float(self.force_gain[j])
            out[f"force_reverse_{c}"] = float(self.force_reverse[j])
        v = self._supply_voltage()
        if v is not None:
            out["supply_voltage"] = v
        return out

    def with_parameters(self, values) -> "Actuators":
        """A copy with some actuator parameters replaced (vehicle-file spec updated too)."""
        own = {k: float(v) for k, v in values.items() if k in self.parameters()}
        if not own:
            return self
        spec = section_with_values(self.specs, own, self.n_thrusters, self.gains, self.reverse)
        return build_actuators(spec, "thrusters")

    def prepare(self, params, n):
        groups = []
        if self.curves:
            # group thrusters sharing a curve object so PWM mapping is one call per curve
            seen = {}
            for i, c in enumerate(self.curves):
                seen.setdefault(id(c), (c, []))[1].append(i)
            groups = [(c, np.array(idx)) for c, idx in seen.values()]
        # inputs are held over a sample interval, so the four RK4 stages see the same
        # array object: map PWM -> thrust once per interval (cache keyed on identity)
        prep = {"groups": groups, "u": None, "v": None, "f": None, "gain": None, "rev": None, "B": self.matrix,
                "fgain": None, "frev": None, "supply": None, "B_pinv": None}
        if "supply_voltage" in params and self._supply_voltage() is not None:
            sv = np.asarray(params["supply_voltage"], float)
            prep["supply"] = np.broadcast_to(sv, (n,)) if sv.ndim else sv
        k = self.n_thrusters

        def family(names, defaults):
            """(k,) when every value is one number for all rows, else (n, k)."""
            vals = [params.get(nm, d) for nm, d in zip(names, defaults)]
            if all(np.ndim(v) == 0 for v in vals):
                return np.array(vals, float)
            a = np.stack([np.broadcast_to(np.asarray(v, float), (n,)) for v in vals], -1)
            return a[0] if np.all(a == a[:1]) else a

        if k:
            g = family([f"thruster_gain_{i + 1}" for i in range(k)], self.gains)
            r = family([f"thruster_reverse_{i + 1}" for i in range(k)], self.reverse)
            prep["gain"] = g if np.any(g != 1.0) else None
            prep["rev"] = r if np.any(r != 1.0) else None
            if self.positions is not None:
                rows = [family([f"thruster_{c}_{i + 1}" for c in "xyz"], self.positions[i]) for i in range(k)]
                if any(r.ndim == 2 for r in rows):
                    rows = [np.broadcast_to(r, (n, 3)) for r in rows]
                P = np.stack(rows, -2)  # (k, 3) or (n, k, 3)
                if np.any(P != self.positions):
                    d = self.matrix[:3].T  # unit directions (k, 3)
                    if P.ndim == 2:
                        Bn = self.matrix.copy()
                        Bn[3:, :] = np.cross(P, d).T
                    else:
                        Bn = np.broadcast_to(self.matrix, (n, 6, k)).copy()
                        Bn[:, 3:, :] = np.swapaxes(np.cross(P, d[None]), 1, 2)
                    prep["B"] = Bn
        fg = family([f"force_gain_{c}" for c in DOF_LETTERS], self.force_gain)
        fr = family([f"force_reverse_{c}" for c in DOF_LETTERS], self.force_reverse)
        prep["fgain"] = fg if np.any(fg != 1.0) else None
        prep["frev"] = fr if np.any(fr != 1.0) else None
        return prep

    @property
    def voltage_dependent(self) -> bool:
        """True when some thruster curve depends on the supply voltage."""
        return bool(self.curves) and any(getattr(c, "voltage_dependent", False) for c in self.curves)

    def thrusts(self, u, kind, groups, voltage=None):
        """Thrusts (n, k) for inputs ``u`` (n, k); ``voltage`` (n,) V or None feeds
        voltage-dependent curves (fixed-voltage curves do not use it)."""
        if kind == "thrust":
            return u
        if kind == "pwm":
            if not groups:
                raise SimulationError("inputs are PWM but the vehicle's thrusters have no thrust curves")
            f = np.empty_like(u)
            for curve, idx in groups:
                # one curve for every thruster, in order (the usual vehicle): no column copies
                every = len(groups) == 1 and idx.size == u.shape[1] and bool(np.all(idx == np.arange(idx.size)))
                try:
                    if voltage is not None and getattr(curve, "voltage_dependent", False):
                        t = curve.thrust(u if every else u[:, idx], voltage=np.asarray(voltage, float)[:, None])
                    else:
                        t = curve.thrust(u if every else u[:, idx])
                    if every:
                        return t
                    f[:, idx] = t
                except SimulationError as exc:
                    raise SimulationError(self._pwm_error(u, curve, idx, exc)) from None
            return f
        raise SimulationError(f"unknown input kind {kind!r}")

    def _pwm_error(self, u, curve, idx, exc) -> str:
        """Name the input column and thruster of a PWM outside ``curve``'s range."""
        sub = u[:, idx]
        bad = ~((sub >= curve.pwm_min) & (sub <= curve.pwm_max))
        if not bad.any():
            return str(exc)
        row, j = np.unravel_index(int(np.argmax(bad)), sub.shape)
        col = int(idx[j])
        name = self.names[col] if self.names else f"T{col + 1}"
        return (f"input column pwm_{col + 1} (thruster {name}): PWM {sub[row, j]:g} us is outside the range "
                f"{curve.pwm_min:g}..{curve.pwm_max:g} us of thrust curve {curve.name!r} (trajectory {row} of the "
                "batch); commands are never clipped. For a logged run, uvsim.plausibility.check_run names its file "
                "and row")

    def delivered(self, u, kind, prep, voltage=None, repeat: int = 1):
        """What the units deliver for inputs ``u`` (m, k): per-thruster inputs give the thrusts
        (m, k) of the curves (at ``voltage``, or the fitted ``supply_voltage`` where the run
        logged none) times each unit's gain and reverse ratio; generalized-force inputs give the
        generalized force (m, 6) after the same per-unit factors through the pseudo-inverse
        allocation (Fossen 2021 sec. 11.2.3) and the per-DOF factors.  The thruster effects
        (:mod:`uvsim.effects.thrusters`: lag, asymmetry, scale) act on this, so that a weak
        unit's lag lags its weak thrust.  ``prep``: :meth:`prepare`'s for n rows; each row stands
        for ``repeat`` consecutive rows of ``u`` (m = n * repeat)."""
        gain, rev = repeat_rows(prep["gain"], repeat, 1), repeat_rows(prep["rev"], repeat, 1)
        fg, fr = repeat_rows(prep["fgain"], repeat, 1), repeat_rows(prep["frev"], repeat, 1)
        if kind == "force":
            tau = u
            if self.matrix is not None and (gain is not None or rev is not None):
                # thrusters that deliver less than commanded: the commanded generalized force is
                # allocated by the pseudo-inverse (unconstrained allocation), scaled per thruster
                # and summed back
                if prep["B_pinv"] is None:  # B is fixed for the prepared rows: once
                    prep["B_pinv"] = np.linalg.pinv(prep["B"])
                f = _scaled(matvec(repeat_rows(prep["B_pinv"], repeat, 2), tau), gain, rev)
                tau = matvec(repeat_rows(prep["B"], repeat, 2), f)
            return tau if fg is None and fr is None else _scaled(tau, fg, fr)
        if self.matrix is None:
            raise SimulationError(f"inputs are per-thruster {kind} but the vehicle defines no thrusters")
        return _scaled(self._curve_thrusts(u, kind, prep, voltage, repeat), gain, rev)

    def _curve_thrusts(self, u, kind, prep, voltage, repeat: int = 1):
        """The curves' thrusts (m, k) for per-thruster inputs ``u`` (m, k), at ``voltage`` (m,)
        or, where the run logged none, the fitted ``supply_voltage``."""
        volt = voltage
        sv = repeat_rows(prep["supply"], repeat, 0)  # one fitted voltage (0-d) or one per row (n,)
        if sv is not None:  # the fitted supply where the run logged no voltage
            volt = (np.broadcast_to(sv, (u.shape[0],)) if volt is None
                    else np.where(np.isnan(np.asarray(volt, float)), sv, volt))
        return self.thrusts(u, kind, prep["groups"], volt)

    def generalized(self, u, kind, prep, voltage=None, repeat: int = 1):
        """The generalized force (m, 6) the units deliver for inputs ``u`` (m, k)
        (:meth:`delivered`, then the allocation matrix for per-thruster inputs); ``prep`` and
        ``repeat`` as there.  It depends on the input, the voltage and the parameters only, so
        it is held over a sample interval with the input (the compiled RK4 takes it per
        interval: :meth:`kernel_part`)."""
        d = self.delivered(u, kind, prep, voltage, repeat)
        return d if kind == "force" else matvec(repeat_rows(prep["B"], repeat, 2), d)

    def held_along(self, U, kind, prep, V=None, rows=None):
        """:meth:`generalized` for ``n`` trajectories of ``m`` samples: ``U`` (n, m, k),
        ``V`` (n, m) or None; returns (n, m, 6).  With ``rows`` (:func:`distinct_histories`
        of the whole run) the thrust curves are evaluated once per distinct input history: a
        fit's parameter sets share their runs' inputs.  The same numbers as
        :meth:`generalized` on the rows."""
        n, m, k = U.shape
        flat_v = None if V is None else V.reshape(n * m)
        if kind == "force" or self.matrix is None or np.ndim(prep["supply"]) != 0:
            rows = None
        if rows is None:
            return self.generalized(U.reshape(n * m, k), kind, prep, flat_v, repeat=m).reshape(n, m, 6)
        first, inv = rows
        try:
            f = self._curve_thrusts(U[first].reshape(-1, k), kind, prep, None if V is None else V[first].reshape(-1))
        except SimulationError:  # name the trajectory of the whole batch
            return self.generalized(U.reshape(n * m, k), kind, prep, flat_v, repeat=m).reshape(n, m, 6)
        f = f.reshape(first.size, m, k)[inv].reshape(n * m, k)
        f = _scaled(f, repeat_rows(prep["gain"], m, 1), repeat_rows(prep["rev"], m, 1))
        return matvec(repeat_rows(prep["B"], m, 2), f).reshape(n, m, 6)

    def kernel_part(self, prep):
        # a subclass (SAM's command inputs) may read the state: the numpy path
        return ("held",) if type(self) is Actuators else None

    def forces(self, ctx, prep):
        u = ctx.u
        # inputs are held over a sample interval: the four RK4 stages share the array object
        if prep["u"] is u and prep["v"] is ctx.voltage:
            return prep["f"]
        tau = self.generalized(u, ctx.input_kind, prep, ctx.voltage)
        prep["u"], prep["v"], prep["f"] = u, ctx.voltage, tau
        return tau

    def check_inputs(self, kind: str, k: int, where: str = "inputs") -> None:
        if kind == "force":
            if k != 6:
                raise SimulationError(f"{where}: generalized-force inputs need 6 columns (X, Y, Z, K, M, N), got {k}")
            return
        if self.matrix is None:
            raise SimulationError(f"{where}: per-thruster {kind} inputs but the vehicle defines no thrusters")
        if k != self.n_thrusters:
            raise SimulationError(
                f"{where}: {k} {kind} columns but the vehicle has {self.n_thrusters} thrusters"
            )

    def to_dict(self):
        return {"type": "actuators"}


def distinct_histories(U, V):
    """``(first, inverse)`` with ``U[first][inverse] == U`` (and ``V`` likewise, NaN equal to
    NaN) for input histories ``U`` (n, m, k), or None when every row differs."""
    n = U.shape[0]
    flat = U.reshape(n, -1)
    if V is not None:
        flat = np.concatenate([flat, np.nan_to_num(V.reshape(n, -1), nan=-1.0)], axis=1)
    w = np.random.default_rng(0).standard_normal(flat.shape[1])  # a fingerprint, checked below
    _, first, inv = np.unique(flat @ w, return_index=True, return_inverse=True)
    inv = np.asarray(inv).ravel()
    if first.size == n or not np.array_equal(flat, flat[first[inv]]):
        return None
    return first, inv


def repeat_rows(a, repeat: int, shared_ndim: int):
    """``a`` with each per-row entry (leading axis n) repeated ``repeat`` times; None, or an
    array of ``shared_ndim`` dimensions (one value for every row), as it is."""
    if a is None or repeat == 1 or np.ndim(a) == shared_ndim:
        return a
    return np.repeat(a, repeat, axis=0)


def _scaled(f, gain, rev):
    """``f * gain * (rev where f < 0)``; ``gain``/``rev`` None (1), (k,) or (n, k)."""
    if rev is not None:
        f = np.where(f < 0, f * rev, f)
    if gain is not None:
        f = f * gain
    return f


def build_actuators(spec, where: str) -> Actuators:
    """Build :class:`Actuators` from a vehicle file's ``thrusters`` section.

    Accepted forms::

        thrusters:
          curve: t200_16v              # default curve for every unit (optional)
          units:
            - {name: T1, position: [x, y, z], direction: [dx, dy, dz], curve: t200_16v}
        # or
        thrusters:
          configuration_matrix: [[...n...], ... 6 rows]
          names: [T1, ...]
          curve: t200_16v
    """
    if spec is None:
        return Actuators()
    if isinstance(spec, dict) and not ({"units", "configuration_matrix", "type"} & set(spec)):
        # only generalized-force factors (a vehicle driven by X..N inputs)
        force_gain, force_reverse = force_factors(spec, where)
        return Actuators(force_gain=force_gain, force_reverse=force_reverse, specs=spec)
    if isinstance(spec, dict) and "type" in spec:
        # a registered Actuators subclass (e.g. SAM's command inputs, uvsim.sam.subsystems)
        from uvsim.forces import make_term

        term = make_term(spec, context=f"{where}: thrusters")
        if not isinstance(term, Actuators):
            raise VehicleError(f"{where}: thrusters.type {spec['type']!r} is not an actuator term")
        return term
    return Actuators(specs=spec, **thruster_arguments(spec, where))
