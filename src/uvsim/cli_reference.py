"""Write docs/cli/ from the command-line parsers: ``python -m uvsim.cli_reference [DIR]``
(default ``docs/cli`` under the current directory). See :func:`uvsim.cli.reference_pages`."""
from __future__ import annotations

import sys
from pathlib import Path

from uvsim.cli import reference_pages


def write(folder: Path) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.glob("*.md"):
        old.unlink()
    written = []
    for name, text in reference_pages().items():
        (folder / name).write_text(text)
        written.append(folder / name)
    return written


if __name__ == "__main__":  # pragma: no cover
    for path in write(Path(sys.argv[1] if len(sys.argv) > 1 else "docs/cli")):
        print(path)
