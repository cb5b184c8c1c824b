"""Common machinery of the effects catalogue (:mod:`uvsim.effects`).

An *effect* is a :class:`uvsim.forces.ForceTerm` with a fixed list of physical
fields.  Each field has a vehicle-file key (``tension``), a named model
parameter (``tether_tension``: the name calibration and diagnosis vary), a unit
and a range of physically sensible values.  Construction validates every field
and raises :class:`uvsim.errors.VehicleError` naming the effect, the field, the
value and the accepted range, so an absurd value in a vehicle file is caught at
load time.  :meth:`Effect.to_dict` writes the same keys back, so
``make_term(effect.to_dict())`` round-trips.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from uvsim.errors import VehicleError
from uvsim.forces.base import ForceTerm, first_violation
from uvsim.schema import check_keys, finite_number


@dataclass(frozen=True)
class Field:
    """One physical field of an effect.

    key : vehicle-file key; unit : SI unit; lo, hi : accepted closed range
    (``lo_open`` makes the lower bound exclusive); default : value when the key is
    absent (None = required); doc : one-line meaning.
    """

    key: str
    unit: str
    lo: float
    hi: float
    default: float | None
    doc: str
    lo_open: bool = False


class Effect(ForceTerm):
    """Base class: validated physical fields <-> named parameters <-> YAML keys.

    Subclasses set ``kind`` (via :func:`uvsim.forces.register`), ``FIELDS`` and
    implement :meth:`forces` (and, if they have internal states, the state
    methods of :class:`ForceTerm`).
    """

    FIELDS: tuple[Field, ...] = ()
    #: extra (non-numeric) vehicle-file keys and their defaults
    OPTIONS: Mapping[str, Any] = {}

    def __init__(self, **kwargs):
        where = f"effects ({self.kind})"
        check_keys(kwargs, [f.key for f in self.FIELDS] + list(self.OPTIONS), where, error=VehicleError)
        self.values: dict[str, float] = {}
        for f in self.FIELDS:
            raw = kwargs.get(f.key, f.default)
            if raw is None:
                raise VehicleError(f"{where}.{f.key}: missing ({f.doc}, {f.unit})")
            self.values[f.key] = check_number(raw, f, where)
        self.options = {k: kwargs.get(k, v) for k, v in self.OPTIONS.items()}

    # -- naming ------------------------------------------------------------------
    def param_name(self, key: str) -> str:
        """Model-parameter name of field ``key`` (``<kind>_<key>``)."""
        return f"{self.kind}_{key}"

    def parameters(self) -> dict[str, float]:
        return {self.param_name(f.key): self.values[f.key] for f in self.FIELDS}

    def units(self) -> dict[str, str]:
        """Unit of each named parameter."""
        return {self.param_name(f.key): f.unit for f in self.FIELDS}

    def field_for(self, name: str) -> Field:
        for f in self.FIELDS:
            if self.param_name(f.key) == name:
                return f
        raise VehicleError(f"effects ({self.kind}): no parameter {name!r}")

    def to_dict(self) -> dict:
        d = {"type": self.kind}
        d.update({f.key: float(self.values[f.key]) for f in self.FIELDS})
        d.update({k: v for k, v in self.options.items()})
        return d

    def with_parameters(self, values: Mapping[str, float]) -> "Effect":
        d = self.to_dict()
        for f in self.FIELDS:
            name = self.param_name(f.key)
            if name in values:
                d[f.key] = float(values[name])
        from uvsim.forces import make_term

        return make_term(d, context=f"effects ({self.kind})")

    def check_values(self, values):
        """Each overridden field within its physically sensible range (as in the file)."""
        for f in self.FIELDS:
            name = self.param_name(f.key)
            if name in values:
                v = np.asarray(values[name], float)
                ok = ((v > f.lo) if f.lo_open else (v >= f.lo)) & (v <= f.hi)
                bad = first_violation(v, ok, name)
                if bad:
                    lb = "(" if f.lo_open else "["
                    raise VehicleError(f"parameter {bad} {f.unit}: outside the physically sensible range "
                                       f"{lb}{f.lo:g}, {f.hi:g}] for {f.doc} (effects ({self.kind}).{f.key})")

    # -- helpers for prepare -----------------------------------------------------
    def p(self, params: Mapping[str, Any], key: str, n: int) -> np.ndarray:
        """Field ``key`` as an array (n,), taking a calibration override if present."""
        name = self.param_name(key)
        v = params[name] if name in params else self.values[key]
        return np.broadcast_to(np.asarray(v, dtype=float), (n,))

    def __repr__(self):
        inner = ", ".join(f"{k}={v:g}" for k, v in self.values.items())
        return f"{type(self).__name__}({inner})"


def check_number(raw, f: Field, where: str) -> float:
    """Validate one field value; raise :class:`VehicleError` naming the field."""
    v = finite_number(raw, f"{where}.{f.key}", error=VehicleError, unit=f.unit)
    lo_ok = v > f.lo if f.lo_open else v >= f.lo
    if not lo_ok or v > f.hi:
        lb = "(" if f.lo_open else "["
        raise VehicleError(
            f"{where}.{f.key} = {v:g} {f.unit}: outside the physically sensible range "
            f"{lb}{f.lo:g}, {f.hi:g}] for {f.doc}"
        )
    return v
