"""The argument parser of every ``skidnav`` command: its errors are one line.

argparse prints a usage block and then ``prog: error: …``; skidnav's rule for bad input is one
line naming the problem and exit code 2, so every parser and subparser of the command line is an
:class:`OneLineParser` (subparsers inherit their parent's class).
"""

from __future__ import annotations

import argparse
import math
from typing import NoReturn


class OneLineParser(argparse.ArgumentParser):
    """An argument parser whose errors are the one line ``skidnav: error: …`` (exit code 2).

    The subcommand's path is named in the line (``skidnav: error: robot run: …``), except for the
    top-level parser.
    """

    def error(self, message: str) -> NoReturn:
        command = self.prog.removeprefix("skidnav").strip()
        where = f"{command}: " if command else ""
        self.exit(2, f"skidnav: error: {where}{message}\n")


def positive_number(text: str) -> float:
    """A finite number > 0, for an argument's ``type`` (``nan``, ``inf``, 0 refused in one line).

    >>> positive_number("2.5")
    2.5
    >>> positive_number("nan")
    Traceback (most recent call last):
    ...
    argparse.ArgumentTypeError: expected a finite number > 0, got 'nan'
    """
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not 0 < value < math.inf:
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value
