"""The ``skidnav`` command: parse arguments, call the subcommand, turn user errors into one line.

A full disk is the user's to fix too: every writer of skidnav reports it in one line naming its
file (:func:`skidnav.files.atomic.writing`), and :func:`main` turns one that escaped them (an
append to a log or journal written by a library) into one line as well.
"""

from __future__ import annotations

import errno
import importlib
import logging
import shlex
import sys
from collections.abc import Sequence
from typing import Any

from skidnav.commands.parsing import OneLineParser
from skidnav.commands.verbs import HELP
from skidnav.errors import EXIT_RUNS_FAILED, Interrupted, RunsFailedError, UserError
from skidnav.experiments.provenance import skidnav_version

COMMANDS: dict[str, str | dict[str, str]] = {
    "run": "skidnav.commands.run",
    "report": "skidnav.commands.report",
    "tune": "skidnav.commands.tune",
    "study": {
        "continuity": "skidnav.commands.continuity",
        "generalise": "skidnav.commands.generalise",
        "transfer": "skidnav.commands.transfer",
        "kinematic": "skidnav.commands.kinematic",
        "search": "skidnav.commands.search",
        "reproduce": "skidnav.commands.reproduce",
    },
    "world": {
        "map": "skidnav.commands.map",
        "simulate": "skidnav.commands.simulate",
        "floors": "skidnav.commands.floors",
        "barn": "skidnav.commands.barn",
    },
    "robot": "skidnav.commands.robot",
    "camera": "skidnav.commands.camera",
}
"""The command tree: a verb → the module that adds it (``add_parser(subparsers)``), or a group
→ its verbs and their modules (``skidnav study continuity …``)."""
DISK_FULL = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG})
"""``errno`` of a write that found no room: no space left, over quota, file too large."""


def requested_modules(argv: Sequence[str]) -> dict[str, str | dict[str, str]]:
    """The part of :data:`COMMANDS` to import for ``argv``: only the named verb's module (in a
    group, only the named verb's), so that e.g. ``skidnav robot sim-server`` does not import
    OpenCV or scikit-learn; all of them (of the group) when none is named (``--help``, a typo),
    so argparse can list them."""
    words = [word for word in argv if not word.startswith("-")]
    if not words or words[0] not in COMMANDS:
        return COMMANDS
    entry = COMMANDS[words[0]]
    if isinstance(entry, dict) and len(words) > 1 and words[1] in entry:
        return {words[0]: {words[1]: entry[words[1]]}}
    return {words[0]: entry}


def _top_parser() -> tuple[OneLineParser, Any]:
    """The ``skidnav`` parser with its own options, and its (empty) verbs."""
    parser = OneLineParser(
        prog="skidnav", description="Model-based RL navigation for skid-steer robots."
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    parser.add_argument(
        "--version", action="version", version=f"skidnav {skidnav_version()}",
        help="print the installed version and exit",
    )  # fmt: skip
    return parser, parser.add_subparsers(dest="command", required=True)


def build_parser(commands: dict[str, str | dict[str, str]] = COMMANDS) -> OneLineParser:
    """The argument parser with the verbs of ``commands`` (default: every one), their modules
    imported."""
    parser, subparsers = _top_parser()
    for name, entry in commands.items():
        if isinstance(entry, str):
            importlib.import_module(entry).add_parser(subparsers)
            continue
        group = subparsers.add_parser(name, help=HELP[name], description=HELP[name])
        verbs = group.add_subparsers(dest=f"{name}_command", required=True)
        for module_name in entry.values():
            importlib.import_module(module_name).add_parser(verbs)
    return parser


def listing_parser() -> OneLineParser:
    """The parser when no verb is named (``skidnav --help``, ``--version``, a typo): every verb
    and group of :data:`COMMANDS` listed with its line of help
    (:data:`~skidnav.commands.verbs.HELP`), no command module imported, so it answers in a
    fraction of a second."""
    parser, subparsers = _top_parser()
    for name in COMMANDS:
        subparsers.add_parser(name, help=HELP[name])
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the process exit code (0 ok, 1 failed runs, 2 user error, 130
    interrupted)."""
    arguments = sys.argv[1:] if argv is None else list(argv)
    requested = requested_modules(arguments)
    parser = listing_parser() if requested is COMMANDS else build_parser(requested)
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
    except KeyboardInterrupt as interrupt:
        print(interrupted_line(interrupt, arguments), file=sys.stderr)
        return 130


def interrupted_line(interrupt: KeyboardInterrupt, arguments: Sequence[str]) -> str:
    """What ``skidnav`` prints when stopped by Ctrl-C (or SIGTERM, in ``skidnav run``): for a
    sweep, how many runs were saved where and the command that resumes it (the same one).

    >>> print(interrupted_line(Interrupted(7, 18, "runs/q"), ["run", "configs/q.toml"]))
    skidnav: interrupted: 7 of 18 runs saved in runs/q; resume with: skidnav run configs/q.toml
    """
    if not isinstance(interrupt, Interrupted):
        return "skidnav: interrupted"
    return f"skidnav: interrupted: {interrupt}; resume with: {shlex.join(['skidnav', *arguments])}"


if __name__ == "__main__":
    sys.exit(main())
