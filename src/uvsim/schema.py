"""Key contracts of the YAML inputs: unknown keys are errors with a did-you-mean.

Vehicle files (:mod:`uvsim.vehicle`), dataset manifests (:mod:`uvsim.logs`) and the
plug-in sections (damping models, effects, thrust curves, SAM subsystems) each declare
the keys they accept; :func:`check_keys` rejects anything else, naming the file, the
section, the unknown key, the closest known key (``difflib.get_close_matches``) and the
accepted keys.  So ``rb:`` instead of ``r_b:`` is an error, not a silent default of 0.

Free-form metadata belongs under a ``meta:`` key (vehicle files and manifests), which
is never interpreted.  The value checks (numbers, units, physical ranges) stay with the
code that reads each field: it knows the units and the physics.
"""
from __future__ import annotations

import difflib
import math
from typing import Any, Iterable, Mapping

from uvsim.errors import UvsimError

#: Similarity (difflib ratio) above which a known key is suggested for an unknown one.
SUGGEST_CUTOFF = 0.7


def did_you_mean(name: Any, choices: Iterable[Any]) -> str:
    """``" (did you mean 'r_b'?)"`` for the closest of ``choices``, or ``""``.

    The comparison ignores case, so ``Mass`` suggests ``mass``; equally close choices
    are all named (``I_xzz``: ``'I_zz' or 'I_xz'``)."""
    names = [str(c) for c in choices]
    lower = {n.lower(): n for n in names}
    key = str(name).lower()
    scored = sorted(((difflib.SequenceMatcher(None, key, c).ratio(), c) for c in lower), key=lambda x: -x[0])
    best = [c for r, c in scored if r >= SUGGEST_CUTOFF and r >= scored[0][0] - 1e-9] if scored else []
    if not best:
        return ""
    return f" (did you mean {' or '.join(repr(lower[c]) for c in best)}?)"


def unknown_key_message(where: str, key: Any, allowed: Iterable[Any], hint: str = "", noun: str = "key") -> str:
    """The message of an unknown key: where, the key, a suggestion and what is accepted."""
    allowed = [str(a) for a in allowed]
    return (f"{where}: unknown {noun} {str(key)!r}{did_you_mean(key, allowed)}; expected "
            f"{', '.join(allowed) if allowed else 'no keys'}{hint}")


def check_keys(mapping: Mapping, allowed: Iterable[Any], where: str, *, error: type = UvsimError,
               hint: str = "") -> None:
    """Raise ``error`` for the first key of ``mapping`` not in ``allowed``.

    Parameters
    ----------
    mapping : the section read from YAML (its keys are checked, in file order).
    allowed : the accepted keys, in the order the message lists them.
    where : file and section, e.g. ``"sam.yaml: rigid_body"``.
    error : the :class:`uvsim.errors.UvsimError` subclass to raise.
    hint : appended to the message (e.g. where free-form metadata goes).
    """
    allowed = list(allowed)
    known = set(allowed)
    for key in mapping:
        if key not in known:
            raise error(unknown_key_message(where, key, allowed, hint))


def require_mapping(value: Any, where: str, *, error: type = UvsimError, example: str = "",
                    none_ok: bool = True) -> dict:
    """``value`` as a dict (``{}`` for None when ``none_ok``); raises ``error`` naming
    ``where`` for anything else (a list, a number, text)."""
    if value is None and none_ok:
        return {}
    if not isinstance(value, Mapping):
        ex = f" such as {example}" if example else ""
        raise error(f"{where}: expected a mapping{ex}, got {type(value).__name__} {value!r}"[:300])
    return dict(value)


def is_whole_number(value: Any) -> bool:
    """``value`` is an integer (Python or numpy), not a bool and not a float such as 4.5 or 2.0
    that a setting would otherwise truncate in silence."""
    import numbers

    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def finite_number(value: Any, where: str, *, error: type = UvsimError, bool_ok: bool = True,
                  unit: str | None = None) -> float:
    """``value`` as a finite float; else ``error`` naming ``where``: "expected a number, got ..."
    (also for ``true`` / ``false`` unless ``bool_ok``) or "expected a finite number, got ...",
    with `` (unit)`` after "number" when ``unit`` is given."""
    u = f" ({unit})" if unit else ""
    if not bool_ok and isinstance(value, bool):
        raise error(f"{where}: expected a number{u}, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise error(f"{where}: expected a number{u}, got {value!r}") from None
    if not math.isfinite(v):
        raise error(f"{where}: expected a finite number{u}, got {v}")
    return v


def whole_number(value: Any, where: str, *, minimum: int | None = None, maximum: int | None = None,
                 error: type = UvsimError, hint: str = "") -> int:
    """``value`` as an int when it is a whole number (:func:`is_whole_number`) within
    ``minimum..maximum``; else ``error`` naming ``where``, the range and ``hint`` (what to do).
    A float such as 2.0, a string or a bool is refused, never truncated or parsed in silence."""
    lo = "" if minimum is None else f" >= {minimum}"
    hi = "" if maximum is None else f"{' and' if lo else ''} <= {maximum}"
    if not is_whole_number(value):
        raise error(f"{where} {value!r}: expected a whole number{lo}{hi} (not truncated in silence){hint}")
    if (minimum is not None and value < minimum) or (maximum is not None and value > maximum):
        raise error(f"{where} {value!r}: expected a whole number{lo}{hi}{hint}")
    return int(value)


def real_number(value: Any, where: str, *, error: type = UvsimError, unit: str | None = None) -> float:
    """``value`` as a finite float when it is a number (int, float, numpy; not a bool or a
    string, which :func:`finite_number` would parse); else ``error`` naming ``where``."""
    import numbers

    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        u = f" ({unit})" if unit else ""
        raise error(f"{where}: expected a number{u}, got {type(value).__name__} {value!r}"[:300])
    return finite_number(value, where, error=error, unit=unit)


#: Most worker processes per CPU of the machine (``os.cpu_count()``) accepted for ``workers``:
#: each process holds a copy of the runs and the model, and beyond one per CPU more only adds
#: start-up time (``--workers 1000`` took 35 s on 2 CPUs to run a 4 x 1 GA that takes 0.5 s
#: serially); 4 per CPU leaves room for machines whose cores are hyper-threaded or idle in I/O.
MAX_WORKERS_PER_CPU = 4


def check_workers(value: Any, where: str = "workers", *, error: type = UvsimError, none_ok: bool = False) -> int | None:
    """``workers`` checked: a whole number from 1 to MAX_WORKERS_PER_CPU x the machine's CPUs
    (None when ``none_ok``); else ``error`` naming ``where`` and the machine's CPU count."""
    import os

    if value is None and none_ok:
        return None
    cpus = os.cpu_count() or 1
    return whole_number(value, where, minimum=1, maximum=MAX_WORKERS_PER_CPU * cpus, error=error,
                        hint=f" (this machine has {cpus} CPUs; more processes than "
                             f"{MAX_WORKERS_PER_CPU} per CPU only add start-up time and memory)")
