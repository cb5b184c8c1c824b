"""Force-term plug-ins and their registry.

``make_term({"type": NAME, ...})`` builds a registered term from its vehicle-file
dictionary; :func:`register` adds a class under a name (scipy.integrate-style
name-or-class registry).  Built-ins: ``restoring``, ``diagonal`` damping,
``actuators``; later modules add their own (effects, component build-up).

The plug-in interface is :mod:`uvsim.forces.base` and the registry itself
:mod:`uvsim.forces.registry` (below the interface, so a term can rebuild itself through
it); this package re-exports both and adds :func:`make_term`.
"""
from __future__ import annotations

from uvsim.forces.base import Context, ForceTerm, param
from uvsim.forces.registry import _REGISTRY, accepted_keys, build_term, register, registered  # noqa: F401


def make_term(spec, *, context: str = "effects") -> ForceTerm:
    """Build a term from a dict ``{"type": name, ...}`` or return a ``ForceTerm`` as is."""
    if isinstance(spec, ForceTerm):
        return spec
    return build_term(spec, context=context)


__all__ = ["Context", "ForceTerm", "make_term", "param", "register", "registered"]
