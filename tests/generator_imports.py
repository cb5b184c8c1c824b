"""The truth generators are written apart from the fitting code: what their sources import and
what generating a dataset loads (tests/test_calibration_structural.py, tests/test_field_logs_generator.py)."""
from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

#: What a truth generator may import from uvsim outside uvsim.scenarios: errors, file helpers, the log writer
#: and the progress lines (uvsim.progress imports nothing of uvsim).
ALLOWED = {"uvsim.errors", "uvsim.files", "uvsim.logs", "uvsim.progress"}
#: Modules that generating a dataset must not load.
FITTING = ("uvsim.fitting", "uvsim.calibration", "uvsim.measurements", "uvsim.signals", "uvsim.diagnosis",
           "uvsim.thrusters")


def uvsim_imports_outside_scenarios(path: Path) -> set:
    """The uvsim modules the source file ``path`` imports, outside uvsim.scenarios."""
    used = set()
    for node in ast.walk(ast.parse(Path(path).read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("uvsim"):
            used.add(node.module)
        elif isinstance(node, ast.Import):
            used.update(a.name for a in node.names if a.name.startswith("uvsim"))
    return {m for m in used if not m.startswith("uvsim.scenarios")}


def fitting_modules_loaded(generate: str) -> list:
    """The fitting modules loaded by a fresh interpreter that runs the statement ``generate``
    (``pathlib``, ``tempfile`` imported)."""
    code = (f"import json, sys, tempfile, pathlib; {generate}; "
            f"print(json.dumps(sorted(m for m in sys.modules if m.startswith({FITTING!r}))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])
