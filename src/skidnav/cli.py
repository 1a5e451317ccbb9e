"""The ``skidnav`` command: parse arguments, call the subcommand, turn user errors into one line.

A full disk is the user's to fix too: every writer of skidnav reports it in one line naming its
file (:func:`skidnav.atomicfile.writing`), and :func:`main` turns one that escaped them (an
append to a log or journal written by a library) into one line as well.
"""

from __future__ import annotations

import errno
import importlib
import logging
import sys
from collections.abc import Sequence

from skidnav.commands.parsing import OneLineParser
from skidnav.errors import EXIT_RUNS_FAILED, RunsFailedError, UserError

SUBCOMMAND_MODULES = {
    "map": "skidnav.commands.map",
    "simulate": "skidnav.commands.simulate",
    "run": "skidnav.commands.run",
    "tune": "skidnav.commands.tune",
    "report": "skidnav.commands.report",
    "reproduce": "skidnav.commands.reproduce",
    "robot": "skidnav.commands.robot",
    "camera": "skidnav.commands.camera",
    "floors": "skidnav.commands.floors",
    "transfer": "skidnav.commands.transfer",
    "generalise": "skidnav.commands.generalise",
    "kinematic": "skidnav.commands.kinematic",
    "continuity": "skidnav.commands.continuity",
    "search": "skidnav.commands.search",
}
"""Subcommand name → the module that adds it (``add_parser(subparsers)``)."""
DISK_FULL = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG})
"""``errno`` of a write that found no room: no space left, over quota, file too large."""


def requested_modules(argv: Sequence[str]) -> list[str]:
    """The subcommand modules to import for ``argv``: only the named subcommand's, so that e.g.
    ``skidnav robot sim-server`` does not import OpenCV or scikit-learn; all of them when no
    known subcommand is named (``--help``, a typo), so argparse can list them."""
    words = [word for word in argv if not word.startswith("-")]
    if words and words[0] in SUBCOMMAND_MODULES:
        return [SUBCOMMAND_MODULES[words[0]]]
    return list(SUBCOMMAND_MODULES.values())


def build_parser(modules: Sequence[str] = tuple(SUBCOMMAND_MODULES.values())) -> OneLineParser:
    """The argument parser with the subcommands of ``modules`` (default: every one)."""
    parser = OneLineParser(
        prog="skidnav", description="Model-based RL navigation for skid-steer robots."
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    subparsers = parser.add_subparsers(dest="command", required=True)
    for module_name in modules:
        importlib.import_module(module_name).add_parser(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the process exit code (0 ok, 1 failed runs, 2 user error, 130
    interrupted)."""
    arguments = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(requested_modules(arguments))
    args = parser.parse_args(arguments)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    try:
        return int(args.func(args) or 0)
    except UserError as error:
        print(f"skidnav: error: {error}", file=sys.stderr)
        return 2
    except RunsFailedError as error:
        print(f"skidnav: error: {error}", file=sys.stderr)
        return EXIT_RUNS_FAILED
    except OSError as error:
        if error.errno not in DISK_FULL:
            raise
        where = f"{error.filename}: " if error.filename else ""
        print(f"skidnav: error: {where}cannot write ({error.strerror})", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("skidnav: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
