"""docs/cli/ is what the parsers print (issue 47: reference generated from the code)."""
from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

from uvsim.cli import reference_pages

DOCS = Path(__file__).resolve().parents[1] / "docs" / "cli"


def _generated_on() -> str:
    m = re.search(r"on Python (\d+\.\d+)", (DOCS / "README.md").read_text())
    return m.group(1) if m else "?"


@pytest.mark.skipif(_generated_on() != f"{sys.version_info[0]}.{sys.version_info[1]}",
                    reason="argparse's layout differs between Python versions; the pages say which generated them")
def test_the_cli_pages_are_what_the_parsers_print():
    pages = reference_pages()
    assert sorted(pages) == sorted(p.name for p in DOCS.glob("*.md")), "regenerate: python -m uvsim.cli_reference"
    for name, text in pages.items():
        assert (DOCS / name).read_text() == text, f"docs/cli/{name} is stale: python -m uvsim.cli_reference"


def test_every_command_has_a_page_and_no_page_is_long():
    pages = reference_pages()
    for command in ("simulate", "calibrate", "diagnose", "export", "import", "vehicle", "maneuver"):
        assert f"{command}.md" in pages and f"`uvsim {command}`" in pages["README.md"]
    assert all(len(t.splitlines()) <= 400 for t in pages.values())


def test_the_command_line_starts_without_the_fitting_machinery():
    """Every command's parser (``uvsim --help``) reads its defaults from light modules
    (uvsim.fit_settings); importing the fits, scipy.signal and scipy.optimize cost 1.2 s of
    every command's start (structure checked here; the time itself is not a test's business)."""
    import subprocess

    code = ("import sys, uvsim.cli as c; c.build_parser(); "
            "print(' '.join(m for m in ('scipy.signal', 'scipy.optimize', 'scipy.stats', 'uvsim.fitting.fitter', "
            "'uvsim.diagnosis.core', 'uvsim.calibration.calibrator') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "", f"imported when the parser is built: {out}"
