"""Force-term plug-ins and their registry.

``make_term({"type": NAME, ...})`` builds a registered term from its vehicle-file
dictionary; :func:`register` adds a class under a name (scipy.integrate-style
name-or-class registry).  Built-ins: ``restoring``, ``diagonal`` damping,
``actuators``; later modules add their own (effects, component build-up).
"""
from __future__ import annotations

import inspect
from typing import Callable

from uvsim.errors import VehicleError
from uvsim.forces.base import Context, ForceTerm, param
from uvsim.schema import check_keys, did_you_mean

_REGISTRY: dict[str, Callable[..., ForceTerm]] = {}


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


def make_term(spec, *, context: str = "effects") -> ForceTerm:
    """Build a term from a dict ``{"type": name, ...}`` or return a ``ForceTerm`` as is."""
    if isinstance(spec, ForceTerm):
        return spec
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


__all__ = ["Context", "ForceTerm", "make_term", "param", "register", "registered"]
