"""The ``skidnav`` command: parse arguments, call the subcommand, turn user errors into one line."""

from __future__ import annotations

import argparse
import importlib
import logging
import sys
from collections.abc import Sequence

from skidnav.errors import UserError

SUBCOMMAND_MODULES = (
    "skidnav.commands.map",
    "skidnav.commands.simulate",
    "skidnav.commands.run",
    "skidnav.commands.tune",
    "skidnav.commands.report",
    "skidnav.commands.reproduce",
    "skidnav.commands.robot",
    "skidnav.commands.camera",
)


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser with every installed subcommand."""
    parser = argparse.ArgumentParser(
        prog="skidnav", description="Model-based RL navigation for skid-steer robots."
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    subparsers = parser.add_subparsers(dest="command", required=True)
    for module_name in SUBCOMMAND_MODULES:
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as error:
            if error.name == module_name:
                continue
            raise
        module.add_parser(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the process exit code (0 ok, 2 user error, 130 interrupted)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    try:
        return int(args.func(args) or 0)
    except UserError as error:
        print(f"skidnav: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("skidnav: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
