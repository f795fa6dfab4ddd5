"""The ``printwatch`` command: everything the plugin can do, offline.

Each subcommand lives in its own module under ``octoprint_printwatch.commands``
with two functions, ``add_parser(subparsers)`` and ``run(args) -> int``; the
modules are imported only when needed so ``printwatch --help`` stays fast.
Errors the user can fix (:class:`~octoprint_printwatch.core.errors.PrintWatchError`)
print one line on stderr and exit with status 2, never a traceback.
"""
from __future__ import annotations

import argparse
import importlib
import sys
from typing import Sequence

from .core.errors import PrintWatchError

#: Subcommand modules, in the order ``--help`` lists them.
COMMAND_MODULES = (
    "layers",
    "inject",
    "render",
    "simulate",
    "evaluate",
    "calibrate",
    "board",
    "demo",
)


def _available_commands():
    for name in COMMAND_MODULES:
        try:
            yield importlib.import_module(f"{__package__}.commands.{name}")
        except ModuleNotFoundError as exc:
            # A command whose module is not written yet is simply not offered;
            # a missing dependency *inside* a command module is a real error.
            if exc.name != f"{__package__}.commands.{name}":
                raise


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="printwatch",
        description="PrintWatch: camera-based failure detection for FFF prints (offline tools).",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    subparsers.required = True
    for module in _available_commands():
        sub = module.add_parser(subparsers)
        sub.set_defaults(_run=module.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args._run(args) or 0)
    except PrintWatchError as exc:
        print(f"printwatch {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"printwatch {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
