"""Checkpoints of long computations: atomic, fingerprinted, announced on resume.

A :class:`Checkpoint` is one file holding the state of one *kind* of computation (the
GA, a refinement, ...) for one *problem*, identified by a fingerprint of everything the
result depends on (:func:`fingerprint` of settings, data and vehicle)::

    ck = Checkpoint(path, kind="ga", key=fingerprint({...}), what="the GA")
    state = ck.load() if resuming else None   # logs "resuming from <path>: generation 3 of 30"
    ...
    ck.save(state, progress="generation 4 of 30")  # after each step

* Writes are atomic: the state goes to a temporary file in the same directory, is
  flushed to disk and then renamed over the checkpoint (``os.replace``), so a kill at
  any moment leaves either the previous or the new checkpoint, never a torn one.
* Loading checks that the file is a uvsim checkpoint of the same kind and problem;
  otherwise :class:`uvsim.errors.CheckpointError` says which and what must match.
* The resume is announced on the ``uvsim`` logger (INFO): ``resuming from PATH:
  PROGRESS``; the CLI prints these lines.

The state is pickled: a checkpoint is a local file of your own runs, not a format to
exchange (never load one from an untrusted source).  A state that restores the random
generators (``random.getstate()``, ``np.random.get_state()``) makes the resumed run
bit-identical to an uninterrupted one.
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import pickle
from pathlib import Path
from typing import Any

from uvsim.errors import CheckpointError

#: Format version of the checkpoint envelope.
VERSION = 2
_MAGIC = "uvsim-checkpoint"

log = logging.getLogger("uvsim")


def fingerprint(obj: Any) -> str:
    """Stable 16-hex-digit hash of a JSON-able description (settings, data, vehicle)."""
    return hashlib.sha256(json.dumps(obj, sort_keys=True, default=str).encode()).hexdigest()[:16]


class Checkpoint:
    """One checkpoint file (see module docstring).

    Parameters
    ----------
    path : file to write / read.
    kind : name of the computation (``"ga"``, ``"refinement"``); a checkpoint of another
        kind is refused on load.
    key : fingerprint of the problem; a checkpoint of another problem is refused on load.
    what : how messages name the computation (default ``kind``).
    must_match : what the user must keep equal to resume (for the mismatch message).
    """

    def __init__(self, path, *, kind: str, key: str, what: str | None = None, must_match: str = ""):
        self.path = Path(path)
        self.kind = kind
        self.key = key
        self.what = what or kind
        self.must_match = must_match

    def exists(self) -> bool:
        return self.path.is_file()

    def save(self, state: Any, *, progress: str = "") -> None:
        """Write ``state`` atomically; ``progress`` (e.g. ``"generation 4 of 30"``) is
        stored with it and shown when resuming."""
        payload = {"format": _MAGIC, "version": VERSION, "kind": self.kind, "key": self.key,
                   "progress": progress, "state": state}
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}.tmp")
        try:
            with open(tmp, "wb") as fh:
                pickle.dump(payload, fh, protocol=pickle.HIGHEST_PROTOCOL)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, self.path)
        except OSError as exc:
            raise CheckpointError(f"checkpoint {self.path}: cannot write ({exc.strerror or exc})") from None
        finally:
            if tmp.exists():
                tmp.unlink()

    def read(self) -> dict:
        """The envelope ``{kind, key, progress, state, ...}`` after format checks only."""
        p = self.path
        if not p.is_file():
            raise CheckpointError(f"checkpoint {p} does not exist")
        try:
            with open(p, "rb") as fh:
                payload = pickle.load(fh)
        except Exception as exc:  # a truncated, foreign or corrupted file raises many types
            raise CheckpointError(f"checkpoint {p} cannot be read: {type(exc).__name__}: {exc}"[:400]) from None
        if not isinstance(payload, dict) or payload.get("format") != _MAGIC:
            raise CheckpointError(f"checkpoint {p} cannot be read: not a uvsim checkpoint")
        if payload.get("version") != VERSION:
            raise CheckpointError(f"checkpoint {p} has format version {payload.get('version')}; this uvsim reads "
                                  f"version {VERSION} (start the computation again)")
        return payload

    def load(self) -> Any:
        """The saved state, after checking kind and problem; logs ``resuming from ...``."""
        payload = self.read()
        if payload["kind"] != self.kind:
            raise CheckpointError(f"checkpoint {self.path} holds a {payload['kind']!r} state, not {self.kind!r} "
                                  f"({self.what})")
        if payload["key"] != self.key:
            hint = f"; resume needs the same {self.must_match}" if self.must_match else ""
            raise CheckpointError(f"checkpoint {self.path} was written for different settings, data or vehicle "
                                  f"(problem fingerprint {payload['key']}, this run {self.key}){hint}")
        log.info("resuming from %s: %s%s", self.path, self.what,
                 f", {payload['progress']}" if payload.get("progress") else "")
        return payload["state"]
