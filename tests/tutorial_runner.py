"""Run a tutorial page (docs/tutorials/*.md) as a user would, and check what it shows.

A tutorial is read block by block, in order, in one scratch directory:

* ```` ```console ```` blocks: lines starting with ``$ `` are shell commands (a trailing
  ``\\`` continues a command on the next line); ``uvsim`` is this checkout's command. A
  command must exit 0 unless it ends with ``# exit N``. The lines after a command, up to
  the next command, are what it prints: each of them must appear in the command's output,
  in that order, after numbers are replaced by a placeholder (so a page shows real output
  without pinning the last digit); a line ``...`` stands for any lines, ``...`` inside a
  line for any text.
* ```` ```python ```` blocks are whole scripts: each runs in a Python process of its own,
  after the blocks before it, and must not raise.
* ```` <!-- file: NAME --> ```` just before a block writes the block's text to ``NAME``
  instead of running it (a vehicle file the user would type).
* ```` <!-- tutorial: slow --> ```` anywhere marks a page that runs commands end to end for
  more than a few seconds: it runs in ``make test-all`` (``make test`` stays under 5 minutes).

The scratch directory has ``src`` and ``examples`` linked to the checkout's, so the
pages' paths to shipped data (``src/uvsim/data/...``) are those of a fresh clone.
"""
from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TUTORIALS = ROOT / "docs" / "tutorials"

_BLOCK = re.compile(r"(?:<!--\s*file:\s*(?P<file>\S+)\s*-->\s*\n)?^[ \t]*```(?P<lang>[a-z]*)[ \t]*\n"
                    r"(?P<body>.*?)\n[ \t]*```[ \t]*$", re.S | re.M)
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_EXIT = re.compile(r"#\s*exit\s+(\d+)\s*$")


@dataclass
class Step:
    kind: str                      # console | python | file
    text: str                      # command, code or file content
    name: str = ""                 # file name (kind "file")
    expected: list[str] = field(default_factory=list)   # console: lines it prints
    exit_code: int = 0


def is_slow(page: Path) -> bool:
    return "<!-- tutorial: slow -->" in page.read_text()


def steps(page: Path) -> list[Step]:
    """The page's steps, in order."""
    out: list[Step] = []
    for m in _BLOCK.finditer(page.read_text()):
        body, lang = m.group("body"), m.group("lang")
        if m.group("file"):
            out.append(Step("file", body + "\n", name=m.group("file")))
        elif lang == "python":
            out.append(Step("python", body))
        elif lang == "console":
            out.extend(_console_steps(body))
    return out


def _console_steps(body: str) -> list[Step]:
    found: list[Step] = []
    lines = body.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("$ "):
            cmd = line[2:]
            while cmd.endswith("\\") and i + 1 < len(lines):
                i += 1
                cmd = cmd[:-1] + " " + lines[i].strip()
            m = _EXIT.search(cmd)
            found.append(Step("console", cmd, exit_code=int(m.group(1)) if m else 0))
        elif found and line.strip():
            found[-1].expected.append(line)
        i += 1
    return found


def normalise(line: str) -> str:
    return " ".join(_NUMBER.sub("N", line).split())


def missing_lines(expected: list[str], printed: str) -> list[str]:
    """The expected lines not found, in order, in what was printed ([] when all are)."""
    got = [normalise(x) for x in printed.splitlines()]
    pos = 0
    for want in expected:
        if want.strip() == "...":
            continue
        w = re.compile(".*".join(map(re.escape, normalise(want).split("..."))) + r"\Z")
        while pos < len(got) and not w.match(got[pos]):
            pos += 1
        if pos == len(got):
            return [want]
        pos += 1
    return []


def run_page(page: Path, workdir: Path) -> None:
    """Run every step of ``page`` in ``workdir``; raise AssertionError at the first that
    does not do what the page says."""
    for name in ("src", "examples"):
        (workdir / name).symlink_to(ROOT / name)
    bindir = workdir / ".bin"
    bindir.mkdir()
    uvsim = bindir / "uvsim"
    uvsim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m uvsim.cli "$@"\n')
    uvsim.chmod(0o755)
    env = dict(os.environ, PATH=f"{bindir}{os.pathsep}{os.environ.get('PATH', '')}",
               PYTHONPATH=str(ROOT / "src"), MPLBACKEND="Agg", COLUMNS="120", PYTHONUNBUFFERED="1")
    for step in steps(page):
        if step.kind == "file":
            (workdir / step.name).write_text(step.text)
        elif step.kind == "python":
            proc = subprocess.run([sys.executable, "-c", step.text], cwd=workdir,
                                  env=env, capture_output=True, text=True)
            assert proc.returncode == 0, f"{page.name}: python block failed:\n{step.text}\n{proc.stderr[-3000:]}"
        else:
            proc = subprocess.run(["bash", "-c", "set -o pipefail; " + step.text], cwd=workdir, env=env,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            printed = proc.stdout                  # stdout and stderr as a terminal shows them
            assert proc.returncode == step.exit_code, (
                f"{page.name}: `{step.text}` exited {proc.returncode}, the page says "
                f"{step.exit_code}:\n{printed[-3000:]}")
            miss = missing_lines(step.expected, printed)
            assert not miss, (f"{page.name}: `{step.text}` did not print the page's line "
                              f"{miss[0]!r}; it printed:\n{printed[-3000:]}")
