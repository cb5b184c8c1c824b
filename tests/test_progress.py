"""Progress of the long stages (issue 46, :mod:`uvsim.progress`): bars on a terminal, one line per
stage on stderr otherwise, nothing with ``--no-progress``; stdout never changes."""
from __future__ import annotations

import io
import logging
import re

import pytest

from contract_data import write_tiny_dataset
from uvsim.cli import main
from uvsim.progress import OFF, Progress, as_progress, write_line

LINE = re.compile(r"^uvsim (\w+): (.+) \.\.\. (done in|failed after|interrupted after) [\d.]+ s( \(.*\))?$")


class _Tty(io.StringIO):
    def isatty(self):
        return True


def _lines(stream) -> list[str]:
    return stream.getvalue().splitlines()


# ------------------------------------------------------------------------------ the facility
def test_lines_mode_writes_one_line_per_stage():
    out = io.StringIO()
    p = Progress("calibrate", "lines", out)
    with p.stage("GA of surge: 12 individuals x 3 generations", total=4) as st:
        for _ in range(4):
            st.update(1, best="0.1")  # counted steps draw nothing without a bar
        st.summary = "48 evaluations"
    with p.stage("joint fit"):
        pass
    lines = _lines(out)
    assert len(lines) == 2, lines
    assert re.match(r"uvsim calibrate: GA of surge: 12 individuals x 3 generations \.\.\. done in \d+\.\d s "
                    r"\(48 evaluations\)$", lines[0]), lines
    assert LINE.match(lines[1]) and "joint fit" in lines[1]
    assert "\r" not in out.getvalue()


def test_a_failing_stage_says_so_and_a_note_ends_the_begun_line():
    out = io.StringIO()
    p = Progress("diagnose", "lines", out)
    with pytest.raises(ValueError):
        with p.stage("fit 1: current:3d"):
            raise ValueError("no")
    with p.stage("fit 2: tether:3d"):
        p.say("tether:3d: taken from the checkpoint")
    lines = _lines(out)
    assert LINE.match(lines[0]) and "failed after" in lines[0]
    # the note is a line of its own; the stage then ends on a whole line, never glued to the note
    assert lines[1] == "uvsim diagnose: fit 2: tether:3d ..."
    assert lines[2] == "uvsim diagnose: tether:3d: taken from the checkpoint"
    assert LINE.match(lines[3]) and lines[3].startswith("uvsim diagnose: fit 2: tether:3d ... done in")


def test_a_log_record_or_error_line_ends_the_begun_line(capsys):
    p = Progress("calibrate", "lines")
    from uvsim.progress import LineHandler

    handler = LineHandler()
    log = logging.getLogger("uvsim.test_progress")
    log.addHandler(handler)
    log.propagate = False
    try:
        with p.stage("joint fit"):
            log.warning("resuming from x.ckpt")
            write_line("uvsim calibrate: a note")
    finally:
        log.removeHandler(handler)
    err = capsys.readouterr().err.splitlines()
    assert err[:3] == ["uvsim calibrate: joint fit ...", "resuming from x.ckpt", "uvsim calibrate: a note"], err
    assert LINE.match(err[3])


def test_off_prints_nothing_and_bars_draw_on_a_terminal():
    out = io.StringIO()
    p = Progress("calibrate", "off", out)
    with p.stage("GA", total=3) as st:
        st.update(3)
    p.say("a note")
    assert out.getvalue() == ""
    tty = _Tty()
    bars = Progress.for_command("calibrate", None, tty)
    assert bars.mode == "bars"
    with bars.stage("GA of surge: 12 individuals x 3 generations", total=3, short="GA") as st:
        st.update(3)
    drawn = tty.getvalue()
    assert "GA" in drawn and "3/3" in drawn and "uvsim calibrate:" not in drawn


def test_the_default_mode_follows_the_stream_and_the_options():
    assert Progress.for_command("x", None, io.StringIO()).mode == "lines"   # CI log, nohup, captured stderr
    assert Progress.for_command("x", None, _Tty()).mode == "bars"
    assert Progress.for_command("x", True, io.StringIO()).mode == "bars"   # --progress
    assert Progress.for_command("x", False, _Tty()).mode == "off"          # --no-progress


def test_the_librarys_progress_arguments():
    assert as_progress(None) is OFF and as_progress(False) is OFF
    assert as_progress(True).mode == "bars"
    said = []
    p = as_progress(said.append)                 # a callable: each stage's name as it starts, and the notes
    with p.stage("fit 1: current:3d"):
        p.say("a note")
    assert said == ["fit 1: current:3d", "a note"]
    with pytest.raises(TypeError):
        as_progress("yes")


# ------------------------------------------------------------------------------ commands
@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    return write_tiny_dataset(tmp_path_factory.mktemp("progress") / "ds", seconds=5.0)


def _calibrate(tiny, tmp_path, capsys, *extra):
    rc = main(["calibrate", "--data", str(tiny), "--vehicle", "bluerov2_heavy_initial", "--dof", "surge",
               "--population", "8", "--generations", "2", "--max-iter", "5", "--out", str(tmp_path / "fit.yaml"),
               *extra])
    out, err = capsys.readouterr()
    return rc, out, err


def _no_times(text: str) -> str:
    return re.sub(r"\d+\.\d+ s\b", "N s", text)


def test_calibrate_off_a_terminal_prints_one_line_per_stage_and_nothing_with_no_progress(tiny, tmp_path, capsys):
    rc, out, err = _calibrate(tiny, tmp_path, capsys)
    lines = err.splitlines()
    assert "\r" not in err and all(LINE.match(s) for s in lines), err
    stages = [LINE.match(s).group(2) for s in lines]
    assert stages[0] == "GA of surge: 8 individuals x 2 generations"
    assert stages[1].startswith("joint fit of ") and "at most 5 iterations" in stages[1]
    assert stages[2].startswith("free simulations of the 3 runs")
    assert len(stages) == 3, stages
    rc_off, out_off, err_off = _calibrate(tiny, tmp_path, capsys, "--no-progress")
    assert err_off == "" and rc_off == rc
    assert _no_times(out_off) == _no_times(out)  # the report on stdout is the same
    assert "uvsim calibrate:" not in out


def test_diagnose_says_its_stages_on_stderr_not_stdout(tiny, capsys):
    argv = ["diagnose", "--data", str(tiny), "--vehicle", "bluerov2_heavy", "--only", "current", "--max-iter", "3",
            "--max-effects", "1"]
    assert main(argv) == 0
    out, err = capsys.readouterr()
    stages = [LINE.match(s).group(2) for s in err.splitlines()]
    assert stages[0].startswith("validation cost of the baseline")
    assert any(s.startswith("fit 1: current:") for s in stages)
    assert stages[-1].startswith("validation before / after")
    assert "uvsim diagnose:" not in out and "VERDICT" in out
    assert main(argv + ["--quiet"]) == 0  # --quiet: the same as --no-progress
    out_quiet, err_quiet = capsys.readouterr()
    assert err_quiet == "" and _no_times(out_quiet) == _no_times(out)
