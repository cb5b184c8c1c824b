"""The force-term registry: plug-in name -> term class, and building a term from its
vehicle-file dictionary.

:func:`register` adds a class under a name (scipy.integrate-style name-or-class
registry); :func:`build_term` builds a registered term from ``{"type": NAME, ...}``,
checking its keys against :func:`accepted_keys`.  The built-in term modules register
themselves when first needed (:func:`registered`, :func:`build_term`).

This module imports no term code, so it sits below :mod:`uvsim.forces.base`:
:meth:`uvsim.forces.base.ForceTerm.with_parameters` rebuilds a term through it without
importing its own package.  :mod:`uvsim.forces` re-exports these names and adds
:func:`uvsim.forces.make_term`, which also passes a ready term through.
"""
from __future__ import annotations

import inspect
from typing import Any, Callable

from uvsim.errors import VehicleError
from uvsim.schema import check_keys, did_you_mean

#: name -> registered class (a :class:`uvsim.forces.base.ForceTerm` subclass)
_REGISTRY: dict[str, Callable[..., Any]] = {}


def register(name: str):
    """Class decorator registering a :class:`ForceTerm` under ``name``."""

    def deco(cls):
        _REGISTRY[name] = cls
        cls.kind = name
        return cls

    return deco


def registered() -> list[str]:
    _load_builtin()
    return sorted(_REGISTRY)


def build_term(spec, *, context: str = "effects"):
    """Build a registered term from a dict ``{"type": name, ...}``.

    The mapping's other keys must be ones the class accepts (:func:`accepted_keys`);
    raises :class:`uvsim.errors.VehicleError` naming ``context`` for a non-mapping, a
    missing or unknown type, an unknown key or a value the constructor refuses."""
    _load_builtin()
    if not isinstance(spec, dict):
        raise VehicleError(f"{context}: expected a mapping with a 'type' key, got {spec!r}"[:300])
    if "type" not in spec:
        near = [k for k in spec if did_you_mean("type", [k])]
        hint = f" (is {near[0]!r} a misspelt 'type'?)" if near else f" (keys found: {', '.join(map(str, spec))})"
        raise VehicleError(f"{context}: missing 'type' (the name of the plug-in){hint}; known types: "
                           f"{', '.join(sorted(_REGISTRY))}")
    kind = spec["type"]
    cls = _REGISTRY.get(kind) if isinstance(kind, str) else None
    if cls is None:
        raise VehicleError(f"{context}: unknown term type {kind!r}{did_you_mean(kind, _REGISTRY)}; "
                           f"known: {', '.join(sorted(_REGISTRY))}")
    kwargs = {k: v for k, v in spec.items() if k != "type"}
    keys = accepted_keys(cls)
    if keys is not None:
        check_keys(kwargs, keys, f"{context} ({kind})", error=VehicleError)
    try:
        return cls(**kwargs)
    except TypeError as exc:
        raise VehicleError(f"{context} ({kind}): {exc}") from None
    except VehicleError as exc:
        raise VehicleError(f"{context}: {exc}") from None


def accepted_keys(cls) -> list[str] | None:
    """The vehicle-file keys a term class accepts: its ``accepted_keys()`` if it defines
    one, else the keyword parameters of its constructor; None when the constructor takes
    ``**kwargs`` and checks its keys itself."""
    own = getattr(cls, "accepted_keys", None)
    if callable(own):
        return list(own())
    params = list(inspect.signature(cls.__init__).parameters.values())[1:]
    if any(p.kind is p.VAR_KEYWORD for p in params):
        return None
    return [p.name for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]


_BUILTIN_MODULES = ["uvsim.forces.restoring", "uvsim.forces.damping", "uvsim.forces.actuators", "uvsim.effects",
                    "uvsim.sam.buildup", "uvsim.sam.subsystems"]
_loaded = False


def _load_builtin() -> None:
    global _loaded
    if _loaded:
        return
    import importlib

    _loaded = True
    for name in _BUILTIN_MODULES:
        importlib.import_module(name)
