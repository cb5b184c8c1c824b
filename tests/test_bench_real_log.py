"""``uvsim bench --only real-log``: issue 46's real-log figures (the docs' real-log command, its joint
stage, and the diagnosis) measured as a user runs them."""
from __future__ import annotations

import pytest

from uvsim.benchmarks import available, real_log
from uvsim.errors import UvsimError


def test_the_area_is_named_and_not_in_a_plain_bench():
    mods = available()
    assert mods["real-log"] is real_log and not real_log.DEFAULT
    assert set(real_log.describe(True)) == set(real_log.DESCRIPTIONS)
    assert "QUICK" in real_log.describe(True)["real_log_command_s"]


def test_a_command_that_writes_no_report_is_an_error(tmp_path):
    with pytest.raises(UvsimError, match="uvsim diagnose exited 2 without a report"):
        real_log._command(["diagnose", "--data", str(tmp_path / "missing"), "--no-progress"], tmp_path / "r.json")


@pytest.mark.slow
def test_the_quick_figures(tmp_path):
    res = real_log.run(quick=True)
    assert set(res) == set(real_log.DESCRIPTIONS)
    assert 0 < res["real_log_joint_stage_s"] < res["real_log_command_s"] and res["real_log_diagnose_s"] > 0
