"""The ``uvsim`` command line.

Each sub-command lives in its own module under :mod:`uvsim.commands` and exposes
``register(subparsers)``, which adds its parser and sets ``func`` to a callable
``func(args) -> int``.  Library errors (:class:`uvsim.errors.UvsimError`) and
operating-system errors (disk full, ...) are reported on stderr as one line and exit
with status 2; nothing in the library calls ``sys.exit``.

Interrupts: SIGINT (Ctrl-C) and SIGTERM both unwind the command (so worker pools are
stopped and checkpoints stay consistent), print one line and exit with 130 (SIGINT) or
143 (SIGTERM).  Messages the library logs on the ``uvsim`` logger at INFO level (e.g.
``resuming from CKPT: the GA, generation 3 of 30 done``) are printed on stderr.
"""
from __future__ import annotations

import argparse
import importlib
import logging
import os
import signal
import sys
import threading

from uvsim.errors import UvsimError
from uvsim.heap import keep_freed_memory
from uvsim.progress import LineHandler, write_line

#: Modules that contribute sub-commands, in the order they appear in ``--help``.
COMMAND_MODULES = [
    "uvsim.commands.demo",
    "uvsim.commands.vehicle",
    "uvsim.commands.simulate",
    "uvsim.commands.import_",
    "uvsim.commands.export",
    "uvsim.commands.bench",
    "uvsim.commands.hydro",
    "uvsim.commands.maneuver",
    "uvsim.commands.calibrate",
    "uvsim.commands.diagnose",
    "uvsim.commands.scenario",
]


class DefaultsHelpFormatter(argparse.HelpFormatter):
    """``--help`` shows each option's default (``(default: 80)``) unless its text states it,
    the default is no value (None, False) or the option is a flag (``store_true`` /
    ``store_false``: its default is the flag's absence, not a value)."""

    def _get_help_string(self, action):
        text = action.help or ""
        if ("default" in text.lower() or not action.option_strings or action.default in (None, False)
                or action.default is argparse.SUPPRESS or action.nargs == 0):
            return text
        return f"{text} (default: %(default)s)"


class Parser(argparse.ArgumentParser):
    """uvsim's parsers: defaults shown in ``--help`` (:class:`DefaultsHelpFormatter`); the
    sub-command parsers are of this class too (``add_subparsers`` uses the parent's class)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", DefaultsHelpFormatter)
        super().__init__(*args, **kwargs)


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="uvsim",
        description="Underwater vehicle simulation and model calibration.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def _commands(parser: argparse.ArgumentParser, prefix: str = "uvsim"):
    """``(command line, parser)`` of every command and sub-command, in ``--help`` order."""
    yield prefix, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _commands(sub, f"{prefix} {name}")


def reference_pages(width: int = 100) -> dict[str, str]:
    """docs/cli/: one page per top-level command with its and its sub-commands' ``--help``,
    and ``README.md``, the index; ``{file name: text}``, generated from the parsers
    (``tests/test_cli_reference.py`` fails when the pages and the parsers differ: regenerate
    them with ``python -m uvsim.cli_reference``, do not edit them)."""
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(width)  # argparse wraps at the terminal's width
    try:
        pages: dict[str, list[str]] = {}
        top = build_parser()
        index = ["# Command-line reference\n",
                 "Generated from the parsers (what `uvsim CMD --help` prints) by `python -m uvsim.cli_reference` "
                 f"on Python {sys.version_info[0]}.{sys.version_info[1]}. How to use each command: the "
                 "tutorials and guides listed in the README, \"Documentation\".\n",
                 f"```\n{top.format_help().rstrip()}\n```\n", "| command | page |", "|---|---|"]
        for line, parser in list(_commands(top))[1:]:
            name = line.split()[1]
            if name not in pages:
                pages[name] = []
                index.append(f"| `uvsim {name}` | [{name}.md]({name}.md) |")
            pages[name].append(f"## `{line}`\n\n```\n{parser.format_help().rstrip()}\n```\n")
        out = {f"{name}.md": f"# `uvsim {name}`\n\nGenerated from the parser; [index](README.md).\n\n" + "\n".join(body)
               for name, body in pages.items()}
        out["README.md"] = "\n".join(index) + "\n"
        return out
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old


class Terminated(KeyboardInterrupt):
    """SIGTERM received: unwinds the command like Ctrl-C does."""


def _raise_terminated(signum, frame):
    raise Terminated()


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    keep_freed_memory()  # this process and the workers it forks (uvsim.heap)
    in_main = threading.current_thread() is threading.main_thread()
    old_term = signal.signal(signal.SIGTERM, _raise_terminated) if in_main else None
    logger = logging.getLogger("uvsim")
    handler = LineHandler()  # on stderr, ending a begun progress line first (uvsim.progress)
    handler.setFormatter(logging.Formatter(f"uvsim {args.command}: %(message)s"))
    old_level = logger.level
    logger.addHandler(handler)
    logger.setLevel(logging.INFO)
    try:
        return int(args.func(args) or 0)
    except UvsimError as exc:
        text = " ".join(line.strip() for line in str(exc).splitlines())  # one line
        write_line(f"uvsim {args.command}: error: {text}")
        return 2
    except BrokenPipeError:  # the reader of stdout left (``uvsim vehicle show X | head``): stop quietly
        try:  # Python docs, "Note on SIGPIPE": point stdout at devnull so the exit's flush is silent
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        except (OSError, ValueError):  # no file descriptor (stdout replaced in-process)
            pass
        return 141  # 128 + SIGPIPE, what a shell reports for a pipe its reader closed
    except OSError as exc:  # e.g. disk full while writing an output
        where = f"{exc.filename}: " if exc.filename else ""
        write_line(f"uvsim {args.command}: error: {where}{exc.strerror or exc}")
        return 2
    except KeyboardInterrupt as exc:
        term = isinstance(exc, Terminated)
        write_line(f"uvsim {args.command}: interrupted ({'SIGTERM' if term else 'SIGINT'})")
        return 143 if term else 130
    finally:
        logger.removeHandler(handler)
        logger.setLevel(old_level)
        if in_main:
            signal.signal(signal.SIGTERM, old_term)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
