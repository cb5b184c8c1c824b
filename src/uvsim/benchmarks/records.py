"""The JSON-lines record files of the scenario benchmarks: one finished case per line, written
as it finishes, so that an interrupted benchmark resumes where it stopped."""
from __future__ import annotations

import json
from pathlib import Path
from typing import Callable

from uvsim.errors import UvsimError


def load_records(path: Path | None, key: Callable[[dict], tuple], say=None, noun: str = "case") -> dict:
    """{key(record): record} of the records already in ``path`` (none when it is None or
    missing); a line that is not a record is an error naming the file and line."""
    done: dict = {}
    if path is None or not path.exists():
        return done
    for line_no, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip():
            continue
        try:
            rec = json.loads(line)
            done[key(rec)] = rec
        except (json.JSONDecodeError, KeyError) as exc:
            raise UvsimError(f"{path}, line {line_no}: not a benchmark record ({exc}); delete the line or the file "
                             "to start again") from None
    if done and say is not None:
        say(f"resuming from {path}: {len(done)} {noun}(s) already done")
    return done


def append_record(path: Path | None, rec: dict) -> None:
    """Append one finished record to ``path`` (nothing when it is None)."""
    if path is not None:
        with path.open("a") as fh:
            fh.write(json.dumps(rec) + "\n")
