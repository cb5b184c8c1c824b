"""The ``uvsim`` command line.

Each sub-command lives in its own module under :mod:`uvsim.commands` and exposes
``register(subparsers)``, which adds its parser and sets ``func`` to a callable
``func(args) -> int``.  Library errors (:class:`uvsim.errors.UvsimError`) are
reported on stderr as one line and exit with status 2; nothing in the library
calls ``sys.exit``.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from uvsim.errors import UvsimError

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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="uvsim",
        description="Underwater vehicle simulation and model calibration.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except UvsimError as exc:
        print(f"uvsim {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
