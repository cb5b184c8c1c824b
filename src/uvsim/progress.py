"""Progress of the long stages of a command (the GA, a fit, a simulation, ...), on stderr.

One :class:`Progress` per command, in one of three modes:

* ``"bars"`` (stderr is a terminal, or ``--progress``): a tqdm bar for a stage that counts its
  steps (GA generations, joint-fit iterations, simulation steps); a stage without a count is
  a line, as below;
* ``"lines"`` (stderr is not a terminal: CI logs, ``nohup``, a notebook's captured stderr):
  exactly one line per stage, begun when the stage starts and ended when it ends, never a
  bar's redraws::

      uvsim calibrate: GA of surge, sway: 60 individuals x 30 generations ... done in 25.8 s

  (a line written in between, e.g. a note, ends the begun line; the stage then ends on a
  line of its own: ``uvsim calibrate: GA ... done in 25.8 s``);
* ``"off"`` (``--no-progress``): nothing.

The library's functions take ``progress=``: None or False (nothing), True (bars), a
Progress, or a callable(message) that receives each stage's name when it starts and every
:meth:`Progress.say` (:func:`as_progress`).  Light on purpose: imported when ``uvsim``
starts; tqdm only when a bar is drawn.
"""
from __future__ import annotations

import logging
import sys
import time

MODES = ("bars", "lines", "off")

#: The stage whose line is begun on its stream and not yet ended (one per process).
_open: list = [None]
#: tqdm bars being drawn (a line is then written with tqdm.write, above them).
_bars: list = []


def _end_open_line(out) -> None:
    st = _open[0]
    if st is not None and st.out is out:
        _open[0] = None
        out.write("\n")
        out.flush()


def write_line(text: str, stream=None) -> None:
    """Write ``text`` as a whole line on ``stream`` (default stderr): after a begun stage line
    is ended, above the bars being drawn."""
    out = sys.stderr if stream is None else stream
    _end_open_line(out)
    if _bars:
        from tqdm.auto import tqdm

        tqdm.write(text, file=out)
    else:
        print(text, file=out, flush=True)


class LineHandler(logging.Handler):
    """A logging handler writing each record with :func:`write_line` (the CLI's notes)."""

    def emit(self, record) -> None:
        try:
            write_line(self.format(record))
        except Exception:  # noqa: BLE001  (logging's contract: never raise from a handler)
            self.handleError(record)


def seconds(dt: float) -> str:
    return f"{dt:.1f} s" if dt < 100 else f"{dt:.0f} s"


class Progress:
    """The progress of one command (module docstring).

    ``command``: the name after ``uvsim`` in each line; ``mode``: bars, lines or off;
    ``stream``: where to write (default: stderr at the time of writing); ``sink``: a
    callable(message) receiving the stages' names and the notes instead (the mode then only
    says whether it is off)."""

    def __init__(self, command: str = "", mode: str = "lines", stream=None, sink=None):
        if mode not in MODES:
            raise ValueError(f"progress mode {mode!r}: expected one of {MODES}")
        self.command, self.mode, self.stream, self.sink = command, mode, stream, sink

    @classmethod
    def for_command(cls, command: str, setting=None, stream=None) -> "Progress":
        """The progress of ``uvsim COMMAND``: ``setting`` None (the default: bars when stderr is
        a terminal, else lines), True (``--progress``: bars), False (``--no-progress``: off)."""
        out = sys.stderr if stream is None else stream
        if setting is None:
            mode = "bars" if _isatty(out) else "lines"
        else:
            mode = "bars" if setting else "off"
        return cls(command, mode, stream)

    @property
    def on(self) -> bool:
        return self.mode != "off"

    @property
    def out(self):
        return sys.stderr if self.stream is None else self.stream

    def line(self, text: str) -> str:
        return f"uvsim {self.command}: {text}" if self.command else text

    def say(self, message: str) -> None:
        """A note between stages (e.g. what a step could not use), one line; nothing when off."""
        if not self.on:
            return
        if self.sink is not None:
            self.sink(message)
        else:
            write_line(self.line(message), self.stream)

    __call__ = say  # usable where a callable(message) is expected

    def stage(self, name: str, total: int | None = None, unit: str = "it", short: str | None = None,
              leave: bool = True) -> "Stage":
        """A stage, used as a context manager: ``with progress.stage("GA ...", total=31) as st:
        ... st.update()``.  ``total``: steps it counts (a bar in bars mode); ``short``: the
        bar's label (default ``name``); ``leave``: keep the finished bar on screen."""
        return Stage(self, name, total, unit, short, leave)


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


#: Progress that does nothing (``progress=None``).
OFF = Progress(mode="off")


def as_progress(progress) -> Progress:
    """``progress=`` of a library function as a :class:`Progress`: None or False -> off, True ->
    bars, a Progress -> itself, a callable(message) -> stage names and notes to it."""
    if progress is None or progress is False:
        return OFF
    if progress is True:
        return Progress(mode="bars")
    if isinstance(progress, Progress):
        return progress
    if callable(progress):
        return Progress(mode="lines", sink=progress)
    raise TypeError(f"progress {progress!r}: expected None, True, False, a Progress or a callable(message)")


class Stage:
    """One stage of a :class:`Progress` (:meth:`Progress.stage`); ``summary``: text added to
    its end line, e.g. ``"7109 evaluations"``."""

    def __init__(self, progress: Progress, name: str, total, unit: str, short, leave: bool):
        self.progress, self.name, self.total, self.unit = progress, name, total, unit
        self.short, self.leave = short or name, leave
        self.summary = ""
        self.bar = None
        self.t0 = None
        self.out = progress.out
        self._closed = False

    def __enter__(self) -> "Stage":
        self.t0 = time.perf_counter()
        p = self.progress
        if not p.on:
            return self
        if p.sink is not None:
            p.sink(self.name)
        elif p.mode == "bars" and self.total is not None:
            from tqdm.auto import tqdm

            _end_open_line(self.out)
            self.bar = tqdm(total=self.total, desc=self.short, unit=self.unit, leave=self.leave, file=self.out)
            _bars.append(self.bar)
        else:
            _end_open_line(self.out)
            sys.stdout.flush()  # what the command printed before comes first in a shared log
            self.out.write(p.line(self.name) + " ...")
            self.out.flush()
            _open[0] = self
        return self

    def update(self, n: int = 1, **postfix) -> None:
        """``n`` more steps done (a bar's postfix from the keywords)."""
        if self.bar is not None:
            if postfix:
                self.bar.set_postfix(postfix, refresh=False)
            self.bar.update(n)

    def set(self, n: int, **postfix) -> None:
        """``n`` steps done in all."""
        if self.bar is not None:
            if postfix:
                self.bar.set_postfix(postfix, refresh=False)
            self.bar.n = n
            self.bar.refresh()

    def __exit__(self, exc_type, exc, tb) -> bool:
        self.close(exc_type)
        return False

    def close(self, exc_type=None) -> None:
        if self._closed:
            return
        self._closed = True
        if self.bar is not None:
            self.bar.close()
            _bars.remove(self.bar)
            return
        p = self.progress
        if not p.on or p.sink is not None:
            return
        dt = seconds(time.perf_counter() - self.t0)
        if exc_type is None:
            end = f"done in {dt}" + (f" ({self.summary})" if self.summary else "")
        elif issubclass(exc_type, (KeyboardInterrupt, SystemExit)):
            end = f"interrupted after {dt}"
        else:
            end = f"failed after {dt}"
        if _open[0] is self:
            _open[0] = None
            self.out.write(f" {end}\n")
            self.out.flush()
        else:
            write_line(p.line(f"{self.name} ... {end}"), p.stream)
