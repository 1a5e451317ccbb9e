"""The argument parser of every ``skidnav`` command: its errors are one line, and an option is
only ever its whole name.

argparse prints a usage block and then ``prog: error: …``; skidnav's rule for bad input is one
line naming the problem and exit code 2, so every parser and subparser of the command line is an
:class:`OneLineParser` (subparsers inherit their parent's class). argparse also takes any
unambiguous prefix of an option for the option (``--secret X`` for ``--secret-file X``, ``--ep``
for ``--episodes``); no skidnav parser does: a word an option does not spell out is an unknown
argument, and the words after it are not printed (:func:`~skidnav.errors.unknown_arguments`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import NoReturn

from skidnav.arguments import StrictParser
from skidnav.arguments import positive_number as positive_number


class OneLineParser(StrictParser):
    """An argument parser whose errors are the one line ``skidnav: error: …`` (exit code 2),
    and which takes no abbreviation of an option (:class:`~skidnav.arguments.StrictParser`).

    The subcommand's path is named in the line (``skidnav: error: robot run: …``), except for the
    top-level parser. A command group called without its verb (bare ``skidnav``, ``skidnav
    study``) prints its usage, which lists the verbs, before that line.
    """

    def error(self, message: str) -> NoReturn:
        if self._subparsers is not None and message.startswith(MISSING_ARGUMENTS):
            self.print_usage(sys.stderr)
        command = self.prog.removeprefix("skidnav").strip()
        where = f"{command}: " if command else ""
        self.exit(2, f"skidnav: error: {where}{message}\n")


MISSING_ARGUMENTS = "the following arguments are required"
"""How argparse's message for a missing required argument (a group's verb among them) starts."""


def path_argument(text: str) -> Path:
    """A path, for an argument's ``type``: an empty one is refused (``Path("")`` would be the
    working directory, where a command would then write).

    >>> path_argument("runs/a")
    PosixPath('runs/a')
    >>> path_argument("")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: expected a path, got an empty one
    """
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a path, got an empty one")
    return Path(text)


def comma_integers(text: str) -> list[int]:
    """Comma-separated integers, for an argument's ``type`` (their range is the config's to
    check).

    >>> comma_integers("0,200")
    [0, 200]
    >>> comma_integers("0,x")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: expected comma-separated integers, got '0,x'
    """
    words = [word.strip() for word in text.split(",")]
    if not all(word.isascii() and word.isdigit() for word in words):
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text[:40]!r}")
    return [int(word) for word in words]
