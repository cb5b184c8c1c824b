"""Every tutorial in docs/tutorials runs as the page says (issue 47: the docs cannot drift
from the code). The pages' rules are in ``tutorial_runner``."""
from __future__ import annotations

import pytest

from tutorial_runner import TUTORIALS, is_slow, missing_lines, run_page, steps

PAGES = sorted(TUTORIALS.glob("*.md"))
#: Guides whose examples are console blocks run the same way.
GUIDES = sorted(p for p in TUTORIALS.parent.glob("*.md") if "```console" in p.read_text())
JOBS = ("simulate", "calibrate_tank", "calibrate_real_logs", "diagnose", "export_gazebo", "own_vehicle")


@pytest.mark.parametrize("page", [pytest.param(p, id=p.stem, marks=[pytest.mark.slow] if is_slow(p) else [])
                                  for p in PAGES + GUIDES])
def test_the_tutorial_runs_as_written(page, tmp_path):
    run_page(page, tmp_path)


def test_there_is_a_tutorial_per_job_and_each_runs_something():
    assert sorted(p.stem for p in PAGES if p.stem != "README") == sorted(JOBS)
    for page in PAGES:
        if page.stem != "README":
            assert any(s.kind in ("console", "python") for s in steps(page)), page.name


def test_the_output_check_fails_on_output_the_page_does_not_show():
    printed = "verdict: better\n  x   m   0.036 -> 0.0024   -93 %\nVERDICT (exit 0) better"
    assert missing_lines(["...", "x m 0.5 -> 0.1 -12 %", "VERDICT (exit 0) better"], printed) == []
    assert missing_lines(["VERDICT (exit 3) trade-off"], printed) == ["VERDICT (exit 3) trade-off"]
    assert missing_lines(["VERDICT (exit 0) better", "verdict: better"], printed)   # order matters
    assert missing_lines(["  x m ... -> ... %"], printed) == []                      # "..." inside a line
    assert missing_lines(["  y m ... -> ... %"], printed)


def test_no_user_doc_page_is_longer_than_400_lines():
    """Measurement records go to docs/records/; a guide longer than this is two guides."""
    docs = TUTORIALS.parent
    long = {str(p.relative_to(docs)): n for p in docs.rglob("*.md") if "records" not in p.parts
            and (n := len(p.read_text().splitlines())) > 400}
    assert not long, long
