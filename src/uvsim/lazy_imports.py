"""A package's names imported when first used (PEP 562, as scipy's subpackages do), so that
importing one light submodule does not import the whole package (``uvsim --help`` would read
the fitting machinery and scipy.signal: 1.2 s of every command's start)."""
from __future__ import annotations

import importlib
from typing import Callable, Mapping


def lazy_getattr(package: str, names: Mapping[str, str]) -> Callable[[str], object]:
    """A module ``__getattr__`` for ``package``: ``names`` maps each public name to the
    submodule that defines it."""

    def __getattr__(name: str):
        if name in names:
            return getattr(importlib.import_module(names[name]), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    return __getattr__
