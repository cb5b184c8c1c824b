"""File-system contracts: input files that can be read, output paths that can be written.

Inputs.  :func:`read_text` reads a text input (vehicle YAML, manifest) and turns every
way it can fail - missing, a directory, no permission, not UTF-8 text (a binary file) -
into the caller's :class:`uvsim.errors.UvsimError` subclass naming the file and what
was expected.

Outputs.  The commands check every output path *before* any work starts
(:func:`check_output_file`, :func:`check_output_dir`), so a long calibration never
fails at its end because ``--out`` points under a file or into a read-only directory.
A path is accepted when it is not an existing directory (for a file) or file (for a
directory), no component of its parent is a file, and a file can actually be created
in its nearest existing ancestor directory (a real test write, since permission bits
say nothing for root or for read-only file systems).  Nothing is left behind: the
probe file is removed and no directory is created by the check.
"""
from __future__ import annotations

import functools
import os
import tempfile
from pathlib import Path

from uvsim.errors import UvsimError


class OutputPathError(UvsimError, ValueError):
    """An output path (``--out``, ``--json``, ``--checkpoint``, ``--plots``, ...) cannot be written."""


#: Byte-order marks of encodings other than UTF-8 (codecs module), by name.
_BOMS = ((b"\xff\xfe\x00\x00", "UTF-32"), (b"\x00\x00\xfe\xff", "UTF-32"), (b"\xff\xfe", "UTF-16"),
         (b"\xfe\xff", "UTF-16"))


def not_text(head: bytes) -> str | None:
    """Why the bytes ``head`` (the start of a file) are not UTF-8 text, or None: a UTF-16/32
    byte-order mark (Excel's "Unicode text", PowerShell's default), or NUL bytes (binary data; a
    file of NULs would otherwise read as an empty table)."""
    for bom, name in _BOMS:
        if head.startswith(bom):
            return f"it is {name}-encoded; save it as UTF-8"
    nul = head.find(b"\x00")
    if nul >= 0:
        return f"byte {nul} is a NUL byte: binary data"
    return None


def read_text(path, *, error: type = UvsimError, what: str = "file") -> str:
    """The UTF-8 text of ``path``; every failure raises ``error`` naming the file.

    Parameters
    ----------
    path : file to read.
    error : :class:`UvsimError` subclass to raise.
    what : what the file should be, for messages (``"vehicle file"``, ``"manifest"``).
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except FileNotFoundError:
        raise error(f"{p}: {what} does not exist") from None
    except IsADirectoryError:
        raise error(f"{p}: is a directory, expected a {what}") from None
    except PermissionError:
        raise error(f"{p}: permission denied reading the {what}") from None
    except OSError as exc:
        raise error(f"{p}: cannot read the {what}: {exc.strerror or exc}") from None
    why = not_text(raw[:4096])
    if why:
        raise error(f"{p}: not a text file ({why}); expected a {what} in UTF-8 text")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{p}: not a text file (byte {exc.start} is not UTF-8); expected a {what} "
                    "in UTF-8 text") from None


@functools.lru_cache(maxsize=None)
def _unique_key_loader(fast: bool = False):
    """A ``yaml.SafeLoader`` that refuses a mapping with the same key twice (YAML 1.2 requires
    unique keys, sec. 3.2.1.1; PyYAML silently keeps the last one). ``fast``: on libyaml's parser
    (``yaml.CSafeLoader``, where PyYAML was built with it), the same constructor."""
    import yaml

    class UniqueKeyLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader) if fast else yaml.SafeLoader):
        def construct_mapping(self, node, deep=False):
            seen = {}
            for key_node, _ in node.value:
                key = self.construct_object(key_node, deep=True)
                try:
                    first = seen.setdefault(key, key_node.start_mark.line)
                except TypeError:  # an unhashable key: PyYAML's own error follows
                    break
                if first != key_node.start_mark.line:
                    raise yaml.constructor.ConstructorError(
                        None, None, f"duplicate key {key!r} (first at line {first + 1}); YAML keeps only the last "
                        "one, so uvsim refuses the file: remove one of them", key_node.start_mark)
            return super().construct_mapping(node, deep=deep)

    return UniqueKeyLoader


def safe_load(text: str):
    """``yaml.safe_load(text)`` on libyaml's parser where PyYAML was built with it (ten times
    faster on a vehicle file; the same documents); an error is raised by PyYAML's own parser, so
    its wording does not depend on the build."""
    import yaml

    try:
        return yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))  # noqa: S506 (safe)
    except yaml.YAMLError:
        return yaml.safe_load(text)


def load_yaml(path, *, error: type = UvsimError, what: str = "YAML file"):
    """Read and parse a YAML file (:func:`read_text`; ``yaml.safe_load``'s rules, and a key twice
    in one mapping is refused); a syntax error raises ``error`` in one line with the file, line
    and column."""
    import yaml

    text = read_text(path, error=error, what=what)
    try:
        return yaml.load(text, Loader=_unique_key_loader(fast=True))  # noqa: S506 (a SafeLoader subclass)
    except yaml.YAMLError:
        pass
    try:  # the error again from PyYAML's own parser, whose messages and marks the docs show
        return yaml.load(text, Loader=_unique_key_loader())  # noqa: S506
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" line {mark.line + 1}, column {mark.column + 1}:" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        context = getattr(exc, "context", None)
        raise error(f"{path}: not valid YAML:{where} {problem}" + (f" ({context})" if context else "")) from None


def plain(x):
    """``x`` with numpy scalars and arrays turned into Python types, recursively through
    dicts (keys as str), lists and tuples: what ``yaml.safe_dump`` and ``json`` accept."""
    import numpy as np

    if isinstance(x, dict):
        return {str(k): plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [plain(v) for v in x]
    if isinstance(x, np.ndarray):
        return plain(x.tolist())
    if isinstance(x, np.generic):
        return x.item()
    return x


def _nearest_existing(p: Path) -> Path:
    """The path itself or its closest existing ancestor."""
    cur = p
    while not cur.exists() and cur != cur.parent:
        cur = cur.parent
    return cur


def _probe_writable(directory: Path, option: str, target: Path) -> None:
    try:
        fd, name = tempfile.mkstemp(prefix=".uvsim-write-test-", dir=directory)
    except OSError as exc:
        raise OutputPathError(f"{option} {target}: cannot create files in {directory} "
                              f"({exc.strerror or exc}); expected a writable directory") from None
    os.close(fd)
    os.unlink(name)


def _check_parents(p: Path, option: str) -> Path:
    base = _nearest_existing(p.parent)
    if not base.is_dir():
        raise OutputPathError(f"{option} {p}: {base} is a file, not a directory; expected a path whose "
                              "parent directories are directories (or do not exist yet)")
    return base


def check_output_file(path, option: str) -> Path:
    """Check that file ``path`` can be written (see module docstring); returns it as a Path.

    Raises
    ------
    OutputPathError
        Naming ``option`` (e.g. ``"--out"``), the path and the reason.
    """
    if path is None or str(path).strip() == "":
        raise OutputPathError(f"{option}: empty path; expected a file name")
    p = Path(path)
    if p.is_dir():
        raise OutputPathError(f"{option} {p}: is a directory; expected a file name")
    base = _check_parents(p, option)
    if p.exists():
        try:
            with open(p, "ab"):
                pass
        except OSError as exc:
            raise OutputPathError(f"{option} {p}: exists and cannot be overwritten "
                                  f"({exc.strerror or exc})") from None
        return p
    _probe_writable(base, option, p)
    return p


def check_not_an_input(path, option: str, inputs) -> None:
    """Refuse an output ``path`` that is one of the ``inputs`` ({option: path}) under another
    name (the same file through ``./``, another relative path or a symbolic link): writing it
    would destroy the data the command reads."""
    if path is None:
        return
    out = Path(path)
    for in_option, in_path in dict(inputs).items():
        if in_path is None or not Path(in_path).exists():
            continue
        same = out.exists() and os.path.samefile(out, in_path)
        if same or os.path.realpath(out) == os.path.realpath(in_path):
            raise OutputPathError(f"{option} {out}: is the input file {in_option} {in_path}; writing it would "
                                  "overwrite the data this command reads: choose another name")


def check_output_dir(path, option: str) -> Path:
    """Check that directory ``path`` exists or can be created, and that files can be
    written in it (see module docstring); returns it as a Path."""
    if path is None or str(path).strip() == "":
        raise OutputPathError(f"{option}: empty path; expected a directory")
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise OutputPathError(f"{option} {p}: is a file; expected a directory (existing or to be created)")
    base = p if p.is_dir() else _check_parents(p, option)
    _probe_writable(base, option, p)
    return p
